#version 460
// shadows_tent: one axis of the 13x13 tent filter over the max-filtered penumbra variation
// (Ray Tracing Gems ch. 13, 13.4.2): it smooths the sample-count decisions so they do not
// flicker. Run twice (shadows_tent_h, shadows_tent_v).
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_dv;
layout(set = 1, binding = 1, rgba16f) uniform writeonly image2D out_dv;

#include "common/shadows_common.glsl"

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    ivec2 axis = sp.tent_axis == 0u ? ivec2(1, 0) : ivec2(0, 1);
    vec4 sum = vec4(0.0);
    float wsum = 0.0;
    for (int k = -6; k <= 6; ++k) {
        ivec2 q = clamp(px + axis * k, ivec2(0), ivec2(frame.size) - 1);
        float w = 7.0 - float(abs(k));
        sum += w * imageLoad(in_dv, q);
        wsum += w;
    }
    imageStore(out_dv, px, sum / wsum);
}
