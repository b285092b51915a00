#version 460
// svgf_temporal_<signal>: temporal accumulation of one demodulated signal, its history
// reprojected with the surface's motion (common/svgf_temporal.glsl).
#extension GL_GOOGLE_include_directive : require
#include "common/svgf_temporal.glsl"
