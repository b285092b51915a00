#version 460
// svgf_atrous_<signal>_<i>: one a-trous iteration of one signal (common/svgf_atrous.glsl).
#extension GL_GOOGLE_include_directive : require
#include "common/svgf_atrous.glsl"
