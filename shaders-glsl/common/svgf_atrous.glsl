// svgf_atrous (svgf_atrous.comp: one signal; svgf_atrous_diffuse_specular.comp: the frame's two,
// SVGF_PAIR): one iteration of the edge-avoiding a-trous wavelet filter, a 3x3 kernel
// [1/4 1/2 1/4]^2 with holes (step 2^i), weighted by depth (scaled by the surface's depth slope),
// shading normal (sigma_n; see svgf_normal_exponent) and luminance (scaled by the standard
// deviation, prefiltered in the first iteration). Colour is filtered with the weights, variance
// (from the colour's alpha) with their squares, so the next iteration stops at the right edges.
//
// 3x3 rather than Schied et al.'s 5x5 B3 spline because the filter is bound by its loads:
// 8 taps a signal instead of 24. The variance is prefiltered over the 3x3 neighbourhood as in
// the paper in the first iteration, whose taps those are, and not after (main). On
// lavapipe the four iterations cost 40% less than with the 5x5 kernel, at the same or lower
// error after 64 frames. Four 3x3 iterations reach 15 pixels, four 5x5 ones 30: where that
// mattered, a pixel without history, svgf_temporal starts it from its 7x7 window's mean. A
// fifth iteration (step 16) let a moved light's glow bleed across the stability suite's room
// for a frame (README, "A 3x3 a-trous kernel").
//
// The pair filters diffuse and specular in one dispatch: each tap's guide texel (depth, normal,
// whether there is a surface: gbuffer.normal) is loaded and its depth and normal weights computed
// once for both, and the filter costs little more than one signal's. A reflection signal's
// footprint narrows with the roughness (svgf_footprint): a mirror's reflection stays sharp, as
// does what smooth glass or a blended surface lets through (a lone signal's footprint, which
// svgf_temporal_let_through writes; 1 for any other).
#ifndef SVGF_ATROUS_GLSL
#define SVGF_ATROUS_GLSL

#extension GL_EXT_control_flow_attributes : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"
#include "common/svgf.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// Colour in rgb, the standard deviation of its luminance in alpha (svgf_temporal, or the
// previous iteration; svgf_pack). svgf_unpack and store_signal work with the variance.
#ifdef SVGF_PAIR
#define SIGNALS 2
layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_diffuse;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D in_specular;
// svgf_temporal.centre: the depth's fwidth, the specular footprint, the history lengths (svgf_centre).
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D in_centre;
layout(set = 1, binding = 3, rgba32f) uniform readonly image2D g_normal;  // shading normal, view depth (0: no surface)
// svgf_temporal's give-back (read at step 1 only, where flagged; a 1x1 zero image after).
layout(set = 1, binding = 4, rgba16f) uniform readonly image2D in_diffuse_clamped;
layout(set = 1, binding = 5, rgba16f) uniform readonly image2D in_specular_clamped;
layout(set = 1, binding = 6, rgba16f) uniform writeonly image2D out_diffuse;
layout(set = 1, binding = 7, rgba16f) uniform writeonly image2D out_specular;

vec4 load_texel(int s, ivec2 q) { return s == 0 ? imageLoad(in_diffuse, q) : imageLoad(in_specular, q); }

vec3 load_clamped(int s, ivec2 q) {
    return (s == 0 ? imageLoad(in_diffuse_clamped, q) : imageLoad(in_specular_clamped, q)).rgb;
}

void store_texel(int s, ivec2 q, vec4 texel) {
    if (s == 0) imageStore(out_diffuse, q, texel);
    else imageStore(out_specular, q, texel);
}
#else
#define SIGNALS 1
layout(set = 1, binding = 0, rgba16f) uniform readonly image2D in_color;
// svgf_temporal.centre: the depth's fwidth, the history length in z (svgf_centre).
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D in_centre;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D g_normal;  // shading normal, view depth (0: no surface)
// svgf_temporal's give-back (read at step 1 only, where flagged; a 1x1 zero image after).
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D in_clamped;
layout(set = 1, binding = 4, rgba16f) uniform writeonly image2D out_color;

vec4 load_texel(int s, ivec2 q) { return imageLoad(in_color, q); }
vec3 load_clamped(int s, ivec2 q) { return imageLoad(in_clamped, q).rgb; }

void store_texel(int s, ivec2 q, vec4 texel) { imageStore(out_color, q, texel); }
#endif

// Colour and variance `v` of a pixel whose history is `history_length` frames long, flagged
// converged for the next iteration (svgf_flag).
void store_signal(int s, ivec2 q, vec4 v, float history_length) {
    vec4 texel = svgf_pack(v.rgb, v.a);
    store_texel(s, q, svgf_converged(v, history_length) ? svgf_flag(texel) : texel);
}

// The 3x3 kernel [1/4 1/2 1/4]^2 with holes, as weights relative to the centre's.
const float KERNEL[2] = float[2](1.0, 0.5);
#define TAPS 8

bool inside(ivec2 q) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(frame.size))); }

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 g = imageLoad(g_normal, px);
    vec4 texel_p[SIGNALS], c_p[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        texel_p[s] = load_texel(s, px);
        c_p[s] = svgf_unpack(texel_p[s]);
    }
    if (!svgf_guide_surface(g)) {
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) store_texel(s, px, texel_p[s]);
        return;
    }
    vec4 centre = imageLoad(in_centre, px);
    float footprint[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) footprint[s] = s == SIGNALS - 1 ? centre.y : 1.0;
    // Iterations after the first (which feeds the history) leave converged signals as they are
    // (flagged by the iteration before): no footprint keeps the centre alone. Without any
    // signal left to filter, no taps at all; but at step 1 the taps are loaded anyway, for the
    // shares of the give-back (a signal without footprint, smooth glass's let-through light,
    // lost what the clamp took: 2.5% of a reflecting pane's light).
    bool filtered = svgf.step == 1;
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        if (svgf.step > 1 && svgf_flagged(texel_p[s])) footprint[s] = 0.0;
        filtered = filtered || footprint[s] > 0.0;
    }
    if (!filtered) {
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) store_texel(s, px, texel_p[s]);
        return;
    }
    // Each tap is loaded once: its geometry exponent (depth and normal, and the kernel as
    // -log k) and, at step 1, the variance's prefilter first; then the luminance weight, which
    // needs the variance. (No `continue` in this loop: with one, the iteration cost
    // twice as much on lavapipe, most likely because the taps then stayed in memory rather
    // than in registers; not confirmed in its compiled code.)
    float z_scale = svgf.sigma_z * centre.x * float(svgf.step);
    float e_geometry[TAPS];
    vec4 c_q[TAPS][SIGNALS];
    float var_sum[SIGNALS], var_wsum = 1.0;  // the prefilter at step 1
    // At step 1 the taps are the 8 neighbours, among which svgf_temporal handed out what its
    // outlier clamp took from each: this pixel takes its shares from those on its surface that
    // gave any (flagged), and adds them to what it filters (common/svgf_temporal.glsl, the
    // give-back). After step 1 a flagged tap has converged, and is left out (below).
    vec3 given[SIGNALS];
    bool settled[TAPS][SIGNALS];  // after step 1: the tap has converged
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        var_sum[s] = c_p[s].a;
        given[s] = vec3(0.0);
    }
    [[unroll]] for (int i = 0; i < TAPS; ++i) {
        int j = i < 4 ? i : i + 1;  // the centre, 4, is not a tap
        ivec2 d = ivec2(j % 3, j / 3) - 1;
        ivec2 q = px + d * svgf.step;
        e_geometry[i] = 1.0 / 0.0;
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
            c_q[i][s] = vec4(0.0);
            settled[i][s] = false;
        }
        vec4 gq = inside(q) ? imageLoad(g_normal, q) : vec4(0.0);
        if (svgf_guide_surface(gq)) {
            float e = svgf_depth_exponent(g.w, gq.w, 1.0 / (z_scale * length(vec2(d)) + 1e-4)) +
                      svgf_normal_exponent(g.xyz, gq.xyz);
            float k = KERNEL[abs(d.x)] * KERNEL[abs(d.y)];
            e_geometry[i] = e - log(k);
            var_wsum += k;
            bool same = svgf.step == 1 && svgf_same_surface(g, gq);
            [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
                vec4 texel = load_texel(s, q);
                c_q[i][s] = svgf_unpack(texel);
                var_sum[s] += k * c_q[i][s].a;
                if (same && svgf_flagged(texel)) given[s] += load_clamped(s, q);
                settled[i][s] = svgf.step > 1 && svgf_flagged(texel);
            }
        }
    }
    // The variance is prefiltered at step 1 only, where the taps are its 3x3 neighbours. The
    // later iterations take the pixel's own: the first iteration has already averaged it over
    // those neighbours (its squared weights), and a prefilter of their own loaded a second 3x3
    // neighbourhood, a fifth of each iteration's cost, for an error that `bench sweep` measured
    // the same without it (README, "The variance prefiltered once").
    float variance[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) variance[s] = svgf.step == 1 ? var_sum[s] / var_wsum : c_p[s].a;
    // A converged tap is left out: it keeps its own value in this iteration, so light that this
    // pixel took from it would not flow back, and a pixel whose noise has not converged is more
    // often one that has just taken a bright sample: with converged taps in, the iterations
    // after the first lost about 1% of the diffuse box's light (README, "Converged taps are
    // left out").
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        float l = luminance(c_p[s].rgb);
        float std_dev = sqrt(max(0.0, variance[s]));
        // sigma_l = infinity switches luminance edge-stopping off (the impulse-response test).
        float inv_l_scale = isinf(svgf.sigma_l) ? 0.0 : 1.0 / (svgf.sigma_l * std_dev + 1e-6);
        vec4 sum = c_p[s];  // colour, and variance weighted by the squared weights
        float wsum = 1.0;
        [[unroll]] for (int i = 0; i < TAPS; ++i) {
            float w = settled[i][s] ? 0.0 : footprint[s] * exp(-e_geometry[i] - abs(l - luminance(c_q[i][s].rgb)) * inv_l_scale);
            sum += vec4(w * c_q[i][s].rgb, w * w * c_q[i][s].a);
            wsum += w;
        }
        store_signal(s, px, vec4(sum.rgb / wsum + given[s], sum.a / (wsum * wsum)), centre[2 + s]);
    }
}

#endif
