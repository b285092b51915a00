#version 460
// svgf_temporal_specular behind the reflections pass: as svgf_temporal, with a narrow lobe's
// history reprojected from where the reflected object was (common/svgf_temporal.glsl).
#extension GL_GOOGLE_include_directive : require
#define SVGF_REFLECTION_MOTION
#include "common/svgf_temporal.glsl"
