#version 460
// svgf_atrous_diffuse_specular_<i>: one a-trous iteration of the frame's diffuse and specular
// signals together, sharing each tap's depth and normal weights (common/svgf_atrous.glsl).
#extension GL_GOOGLE_include_directive : require
#define SVGF_PAIR
#include "common/svgf_atrous.glsl"
