// svgf_atrous (svgf_atrous.comp: one signal; svgf_atrous_diffuse_specular.comp: the frame's two,
// SVGF_PAIR): one iteration of the edge-avoiding a-trous wavelet filter, a 5x5 B3-spline kernel
// with holes (step 2^i), weighted by depth (scaled by the surface's depth slope), shading normal
// (sigma_n; see svgf_normal_exponent) and luminance (scaled by the 3x3-prefiltered standard
// deviation). Colour is filtered with the weights, variance (from the colour's alpha) with their
// squares, so the next iteration stops at the right edges.
//
// The pair filters diffuse and specular in one dispatch: each tap's guide texel (depth, normal,
// whether there is a surface; svgf_guide) is loaded and its depth and normal weights computed
// once for both, and the filter costs little more than one signal's. A reflection signal's
// footprint narrows with the roughness (svgf_footprint): a mirror's reflection stays sharp.
#ifndef SVGF_ATROUS_GLSL
#define SVGF_ATROUS_GLSL

#extension GL_EXT_control_flow_attributes : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"
#include "common/svgf.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// Colour in rgb, the standard deviation of its luminance in alpha (svgf_temporal, or the
// previous iteration; svgf_pack). load_signal and store_signal work with the variance.
#ifdef SVGF_PAIR
#define SIGNALS 2
layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_diffuse;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D in_specular;
layout(set = 1, binding = 2, r32f) uniform readonly image2D in_diffuse_history_length;
layout(set = 1, binding = 3, r32f) uniform readonly image2D in_specular_history_length;
layout(set = 1, binding = 4, rgba32f) uniform readonly image2D in_guide;
layout(set = 1, binding = 5, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 6, rgba8) uniform readonly image2D g_metal_rough;
layout(set = 1, binding = 7, rgba16f) uniform writeonly image2D out_diffuse;
layout(set = 1, binding = 8, rgba16f) uniform writeonly image2D out_specular;

vec4 load_signal(int s, ivec2 q) {
    return svgf_unpack(s == 0 ? imageLoad(in_diffuse, q) : imageLoad(in_specular, q));
}

float load_history_length(int s, ivec2 q) {
    return (s == 0 ? imageLoad(in_diffuse_history_length, q) : imageLoad(in_specular_history_length, q)).r;
}

void store_signal(int s, ivec2 q, vec4 v) {
    if (s == 0) imageStore(out_diffuse, q, svgf_pack(v.rgb, v.a));
    else imageStore(out_specular, q, svgf_pack(v.rgb, v.a));
}
#else
#define SIGNALS 1
layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_color;
layout(set = 1, binding = 1, r32f) uniform readonly image2D in_history_length;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D in_guide;
layout(set = 1, binding = 3, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 4, rgba16f) uniform writeonly image2D out_color;

vec4 load_signal(int s, ivec2 q) { return svgf_unpack(imageLoad(in_color, q)); }
float load_history_length(int s, ivec2 q) { return imageLoad(in_history_length, q).r; }

void store_signal(int s, ivec2 q, vec4 v) { imageStore(out_color, q, svgf_pack(v.rgb, v.a)); }
#endif

const float B3[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

bool inside(ivec2 q) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(frame.size))); }

// 3x3 Gaussian of signal s's variance: one noisy variance sample would otherwise stop the filter.
float prefiltered_variance(int s, ivec2 px) {
    const float g[2] = float[2](1.0 / 4.0, 1.0 / 8.0);
    float sum = 0.0, wsum = 0.0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (!inside(q)) continue;
            float w = g[abs(dx)] * g[abs(dy)] * 4.0;
            sum += w * load_signal(s, q).a;
            wsum += w;
        }
    }
    return sum / wsum;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 g = imageLoad(in_guide, px);
    vec4 c_p[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) c_p[s] = load_signal(s, px);
    if (!svgf_guide_surface(g)) {
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) store_signal(s, px, c_p[s]);
        return;
    }
    // The three edge-stopping weights of svgf.glsl multiplied as one exponential per tap and
    // signal.
    float l[SIGNALS], inv_l_scale[SIGNALS], footprint[SIGNALS], wsum[SIGNALS];
    vec4 sum[SIGNALS];  // colour, and variance weighted by the squared weights
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        l[s] = luminance(c_p[s].rgb);
        float std_dev = sqrt(max(0.0, prefiltered_variance(s, px)));
        // sigma_l = infinity switches luminance edge-stopping off (the impulse-response test).
        inv_l_scale[s] = isinf(svgf.sigma_l) ? 0.0 : 1.0 / (svgf.sigma_l * std_dev + 1e-6);
        footprint[s] = 1.0;
        sum[s] = c_p[s];
        wsum[s] = 1.0;
    }
#ifdef SVGF_PAIR
    if ((svgf.flags & SVGF_SHARP_SPECULAR) != 0u) footprint[1] = svgf_footprint(imageLoad(g_metal_rough, px).y);
#endif
    // Iterations after the first (which feeds the history) leave converged signals as they are:
    // no footprint keeps the centre alone. Without any signal left to filter, no taps at all.
    bool filtered = false;
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        if (svgf.step > 1 && svgf_converged(c_p[s], load_history_length(s, px))) footprint[s] = 0.0;
        filtered = filtered || footprint[s] > 0.0;
    }
    if (!filtered) {
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) store_signal(s, px, c_p[s]);
        return;
    }
    float z_scale = svgf.sigma_z * imageLoad(g_depth, px).g * float(svgf.step);
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            if (dx == 0 && dy == 0) continue;
            ivec2 q = px + ivec2(dx, dy) * svgf.step;
            if (!inside(q)) continue;
            vec4 gq = imageLoad(in_guide, q);
            if (!svgf_guide_surface(gq)) continue;
            float k = B3[abs(dx)] * B3[abs(dy)] / (B3[0] * B3[0]);
            float e_geometry = svgf_depth_exponent(g.w, gq.w, 1.0 / (z_scale * length(vec2(dx, dy)) + 1e-4)) +
                               svgf_normal_exponent(g.xyz, gq.xyz);
            [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
                vec4 c_q = load_signal(s, q);
                float w = footprint[s] * k * exp(-e_geometry - abs(l[s] - luminance(c_q.rgb)) * inv_l_scale[s]);
                sum[s] += vec4(w * c_q.rgb, w * w * c_q.a);
                wsum[s] += w;
            }
        }
    }
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        store_signal(s, px, vec4(sum[s].rgb / wsum[s], sum[s].a / (wsum[s] * wsum[s])));
    }
}

#endif
