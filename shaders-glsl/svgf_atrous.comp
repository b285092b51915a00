#version 460
// svgf_atrous: one iteration of the edge-avoiding a-trous wavelet filter: a 5x5 B3-spline
// kernel with holes (step 2^i), weighted by depth (scaled by the surface's depth slope), shading
// normal (power sigma_n; see svgf_weight_normal) and luminance (scaled by the 3x3-prefiltered standard deviation). Colour is
// filtered with the weights, variance with their squares, so the next iteration stops at the
// right edges. Every neighbour's weight is scaled by the pixel's footprint (the colour's alpha,
// from svgf_temporal: narrow for a sharp reflection).
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D in_color;
layout(set = 1, binding = 1, r32f) uniform readonly image2D in_variance;
layout(set = 1, binding = 2, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D g_normal;  // shading normal (gbuffer.normal)
layout(set = 1, binding = 4, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 5, rgba32f) uniform writeonly image2D out_color;
layout(set = 1, binding = 6, r32f) uniform writeonly image2D out_variance;

#include "common/svgf.glsl"

const float B3[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

bool inside(ivec2 q) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(frame.size))); }

// 3x3 Gaussian of the variance: one noisy variance sample would otherwise stop the filter.
float prefiltered_variance(ivec2 px) {
    const float g[2] = float[2](1.0 / 4.0, 1.0 / 8.0);
    float sum = 0.0, wsum = 0.0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (!inside(q)) continue;
            float w = g[abs(dx)] * g[abs(dy)] * 4.0;
            sum += w * imageLoad(in_variance, q).r;
            wsum += w;
        }
    }
    return sum / wsum;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 c_p = imageLoad(in_color, px);
    float var_p = imageLoad(in_variance, px).r;
    if (imageLoad(g_ids, px).x == NO_INSTANCE) {
        imageStore(out_color, px, c_p);
        imageStore(out_variance, px, vec4(var_p));
        return;
    }
    vec2 zf = imageLoad(g_depth, px).rg;
    float z = zf.x;
    vec3 n = imageLoad(g_normal, px).xyz;
    float l = luminance(c_p.rgb);
    float std_dev = sqrt(max(0.0, prefiltered_variance(px)));
    // The temporal stage's footprint (alpha): 0 for a mirror's reflection, which stays sharp.
    float footprint = c_p.a;
    vec3 sum_c = c_p.rgb;
    float sum_v = var_p;
    float wsum = 1.0;
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            if (dx == 0 && dy == 0) continue;
            ivec2 off = ivec2(dx, dy) * svgf.step;
            ivec2 q = px + off;
            if (!inside(q) || imageLoad(g_ids, q).x == NO_INSTANCE) continue;
            vec3 c_q = imageLoad(in_color, q).rgb;
            float k = B3[abs(dx)] * B3[abs(dy)] / (B3[0] * B3[0]);
            float w = footprint * k * svgf_weight_depth(z, imageLoad(g_depth, q).r, zf.y, length(vec2(off))) *
                      svgf_weight_normal(n, imageLoad(g_normal, q).xyz) *
                      svgf_weight_luminance(l, luminance(c_q), std_dev);
            sum_c += w * c_q;
            sum_v += w * w * imageLoad(in_variance, q).r;
            wsum += w;
        }
    }
    imageStore(out_color, px, vec4(sum_c / wsum, c_p.a));
    imageStore(out_variance, px, vec4(sum_v / (wsum * wsum)));
}
