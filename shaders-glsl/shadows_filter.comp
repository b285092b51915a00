#version 460
// shadows_filter: the visibility filter of Ray Tracing Gems ch. 13 (13.4.5). Per area light:
// the temporal term is the box mean of the four cached frames; the spatial term a
// cross-bilateral Gaussian of 1x1 to 9x9 taps whose width grows linearly with the penumbra
// measure dv_bar (widest at eta), rejecting taps that fail the depth test of Eq. 13.7 or whose
// normal differs (n.n' <= 0.9). The chapter describes a 2D filter (its code runs it as two 1D
// passes); here it is one 2D pass, at most 81 taps, and only inside penumbrae. Hard lights pass
// through unfiltered.
// dv_bar = (tent-filtered dv + raw dv) / 2: the chapter averages the raw term over 4 frames;
// the raw dv here already spans the 4 cached frames. The pass also sums dv_bar over the image,
// which next frame's shadows pass compares with the budget. The temporal term comes from
// shadows_penumbra, which reads the ring anyway: a tap here reads one texel for it, not four.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_ring0;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D in_mean;   // the ring's mean (shadows_penumbra)
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D in_dv_raw;
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D in_dv;
layout(set = 1, binding = 4, rg32f) uniform readonly image2D g_depth;
layout(set = 1, binding = 5, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 6, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 7, rgba16f) uniform writeonly image2D out_visibility;
layout(set = 1, binding = 8, rgba16f) uniform writeonly image2D out_dv;      // dv_bar per light
layout(set = 1, binding = 9, rgba16f) uniform writeonly image2D out_kernel;  // filter width per light (1..9)
layout(set = 1, binding = 10, r32ui) uniform uimage2D out_budget;            // sum of dv_bar x 64 (texel 0,0)

#include "common/shadows_common.glsl"

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 current = imageLoad(in_ring0, px);
    if (imageLoad(g_ids, px).x == NO_INSTANCE) {
        imageStore(out_visibility, px, current);
        imageStore(out_dv, px, vec4(0.0));
        imageStore(out_kernel, px, vec4(0.0));
        return;
    }
    bvec4 soft = soft_lights();
    vec4 dv_bar = 0.5 * (imageLoad(in_dv, px) + imageLoad(in_dv_raw, px));
    vec4 width = 1.0 + 2.0 * floor(4.0 * clamp(dv_bar / sp.eta, 0.0, 1.0) + 0.5);
    for (uint i = 0u; i < 4u; ++i) {
        if (!soft[i]) {
            dv_bar[i] = 0.0;
            width[i] = 1.0;
        }
    }
    float total = dv_bar.x + dv_bar.y + dv_bar.z + dv_bar.w;
    if (total > 0.0) imageAtomicAdd(out_budget, ivec2(0), uint(total * 64.0 + 0.5));

    float z = imageLoad(g_depth, px).r;
    vec3 n = imageLoad(g_normal_geo, px).xyz;
    vec4 mean = imageLoad(in_mean, px);
    vec4 result = current;
    for (uint i = 0u; i < 4u; ++i) {
        if (!soft[i]) continue;
        int radius = int(width[i] - 1.0) / 2;
        float sigma = max(float(radius) * 0.5, 0.5);
        float sum = mean[i], wsum = 1.0;
        for (int dy = -radius; dy <= radius; ++dy) {
            for (int dx = -radius; dx <= radius; ++dx) {
                if (dx == 0 && dy == 0) continue;
                ivec2 q = px + ivec2(dx, dy);
                if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
                if (imageLoad(g_ids, q).x == NO_INSTANCE) continue;
                if (!depth_consistent(z, imageLoad(g_depth, q).r, n)) continue;
                if (dot(n, imageLoad(g_normal_geo, q).xyz) <= 0.9) continue;
                float w = exp(-0.5 * float(dx * dx + dy * dy) / (sigma * sigma));
                sum += w * imageLoad(in_mean, q)[i];
                wsum += w;
            }
        }
        result[i] = sum / wsum;
    }
    imageStore(out_visibility, px, result);
    imageStore(out_dv, px, dv_bar);
    imageStore(out_kernel, px, width);
}
