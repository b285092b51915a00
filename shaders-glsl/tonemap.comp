#version 460
// tonemap: exposure, then the ACES filmic fit of Narkowicz (2015), then sRGB encoding into an
// 8-bit image for display and PNG output.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/color.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D in_color;
layout(set = 1, binding = 1, rgba8) uniform writeonly image2D out_color;

vec3 aces_fit(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec3 c = imageLoad(in_color, px).rgb * frame.exposure;
    imageStore(out_color, px, vec4(linear_to_srgb(aces_fit(c)), 1.0));
}
