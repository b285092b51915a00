#version 460
// shadows_penumbra: penumbra detection (Ray Tracing Gems ch. 13, 13.4.2): per light, the
// variation dv = max - min of the four cached visibility values (0 where fully lit or fully
// shadowed, more sensitive than a variance), then its 5x5 maximum, which spreads a detection
// over the neighbourhood so thin penumbrae are not missed.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_ring0;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D in_ring1;
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D in_ring2;
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D in_ring3;
layout(set = 1, binding = 4, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 5, rgba16f) uniform writeonly image2D out_dv_raw;
layout(set = 1, binding = 6, rgba16f) uniform writeonly image2D out_dv_max;

#include "common/shadows_common.glsl"

vec4 variation(ivec2 q) {
    vec4 a = imageLoad(in_ring0, q), b = imageLoad(in_ring1, q), c = imageLoad(in_ring2, q), d = imageLoad(in_ring3, q);
    return max(max(a, b), max(c, d)) - min(min(a, b), min(c, d));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 raw = variation(px);
    vec4 m = raw;
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            ivec2 q = clamp(px + ivec2(dx, dy), ivec2(0), ivec2(frame.size) - 1);
            if (imageLoad(g_ids, q).x != NO_INSTANCE) m = max(m, variation(q));
        }
    }
    imageStore(out_dv_raw, px, raw);
    imageStore(out_dv_max, px, m);
}
