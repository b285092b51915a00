#version 460
// shadows_penumbra: penumbra detection (Ray Tracing Gems ch. 13, 13.4.2): per light, the
// variation dv = max - min of the four cached visibility values (0 where fully lit or fully
// shadowed, more sensitive than a variance), then its 5x5 maximum, which spreads a detection
// over the neighbourhood so thin penumbrae are not missed. It also writes the four values'
// mean, which shadows_filter reads at each of its taps.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;  // the tile below assumes 8x8

layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_ring0;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D in_ring1;
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D in_ring2;
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D in_ring3;
layout(set = 1, binding = 4, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 5, rgba16f) uniform writeonly image2D out_dv_raw;
layout(set = 1, binding = 6, rgba16f) uniform writeonly image2D out_dv_max;
layout(set = 1, binding = 7, rgba16f) uniform writeonly image2D out_mean;  // the ring's mean, shadows_filter's temporal term

#include "common/shadows_common.glsl"

vec4 variation(ivec2 q, out vec4 mean) {
    vec4 a = imageLoad(in_ring0, q), b = imageLoad(in_ring1, q), c = imageLoad(in_ring2, q), d = imageLoad(in_ring3, q);
    mean = 0.25 * (a + b + c + d);
    return max(max(a, b), max(c, d)) - min(min(a, b), min(c, d));
}

// The workgroup's 5x5 windows cover a 12x12 tile: each texel's variation (on a surface; 0
// elsewhere, which no maximum picks) is computed once into shared memory, where each tap had
// loaded its four ring texels and its ids (125 loads a pixel, now about 16), and the maximum
// is taken along rows, then along columns (10 reads of the tile, not 25). On lavapipe at
// 640x360 the pass went from 25 to 20-22 ms (the tile with 25 reads: no faster).
#define RADIUS 2
#define TILE_SIDE (8 + 2 * RADIUS)
shared vec4 tile_dv[TILE_SIDE * TILE_SIDE];
shared vec4 row_max[TILE_SIDE * 8];  // per tile row, the maximum over each pixel's 5 columns

void main() {
    ivec2 origin = ivec2(gl_WorkGroupID.xy) * 8 - RADIUS;
    for (uint i = gl_LocalInvocationIndex; i < TILE_SIDE * TILE_SIDE; i += 64u) {
        ivec2 q = clamp(origin + ivec2(i % TILE_SIDE, i / TILE_SIDE), ivec2(0), ivec2(frame.size) - 1);
        vec4 unused;
        tile_dv[i] = imageLoad(g_ids, q).x != NO_INSTANCE ? variation(q, unused) : vec4(0.0);
    }
    barrier();
    for (uint i = gl_LocalInvocationIndex; i < TILE_SIDE * 8; i += 64u) {
        uint first = (i / 8u) * TILE_SIDE + i % 8u;
        vec4 m = tile_dv[first];
        for (uint dx = 1u; dx <= 2u * RADIUS; ++dx) m = max(m, tile_dv[first + dx]);
        row_max[i] = m;
    }
    barrier();  // before any invocation returns: the whole workgroup must reach both
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 mean;
    vec4 raw = variation(px, mean);
    vec4 m = raw;
    ivec2 t = ivec2(gl_LocalInvocationID.xy);
    for (int dy = 0; dy <= 2 * RADIUS; ++dy) m = max(m, row_max[(t.y + dy) * 8 + t.x]);
    imageStore(out_dv_raw, px, raw);
    imageStore(out_dv_max, px, m);
    imageStore(out_mean, px, mean);
}
