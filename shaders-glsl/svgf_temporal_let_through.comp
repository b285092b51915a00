#version 460
// svgf_temporal_let_through: temporal accumulation of what glass and blended surfaces let
// through (reflections.let_through), its history fetched where what shows through was
// (common/svgf_temporal.glsl, SVGF_LET_THROUGH).
#extension GL_GOOGLE_include_directive : require
#define SVGF_LET_THROUGH
#include "common/svgf_temporal.glsl"
