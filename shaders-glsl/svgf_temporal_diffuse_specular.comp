#version 460
// svgf_temporal_diffuse_specular: temporal accumulation of the frame's diffuse and specular
// signals in one dispatch, sharing the G-buffer's and the window's loads; a narrow lobe's
// specular history follows the reflected object (common/svgf_temporal.glsl).
#extension GL_GOOGLE_include_directive : require
#define SVGF_PAIR
#include "common/svgf_temporal.glsl"
