// Shared by the SVGF passes (svgf_temporal, svgf_variance, svgf_atrous): settings, the
// reprojection validity test, and the edge-stopping weights of Schied et al. 2017.
#ifndef SVGF_GLSL
#define SVGF_GLSL

#include "color.glsl"


// Settings, one block for every SVGF pass (src/passes/svgf/mod.rs `SvgfSettings`).
layout(push_constant) uniform SvgfParams {
    float alpha;          // minimum colour blend weight of the new frame
    float moments_alpha;  // minimum moments blend weight
    float sigma_z;        // depth edge-stopping, scaled by the depth gradient
    float sigma_n;        // normal edge-stopping exponent
    float sigma_l;        // luminance edge-stopping, scaled by the standard deviation
    float history_cap;    // longest history, frames
    float clamp_sigma;    // outlier clamp: luminance above mean + clamp_sigma * std dev
    int step;             // a-trous step (1, 2, 4, ...)
} svgf;

bool finite3(vec3 c) { return !any(isnan(c)) && !any(isinf(c)); }

// Can the previous frame's sample at `prev_px` stand for this pixel? Same instance, similar
// depth (relative to how fast depth changes here) and similar geometric normal (Falcor's
// tests).
bool svgf_consistent(float z, float z_prev, float fwidth_z, vec3 ng, vec3 ng_prev, uint id, uint id_prev) {
    if (id != id_prev) return false;
    if (abs(z - z_prev) / (fwidth_z + 1e-2) > 10.0) return false;
    return dot(ng, ng_prev) > 0.9;
}

// Depth weight: the difference against how much depth may change over the offset on this
// pixel's own surface (fwidth from the rasteriser times the offset's length).
float svgf_weight_depth(float z_p, float z_q, float fwidth_z, float offset_length) {
    return exp(-abs(z_p - z_q) / (svgf.sigma_z * fwidth_z * offset_length + 1e-4));
}

// Normal weight on the shading normal (gbuffer.normal: the interpolated vertex normal, with the
// normal map where the material has one), never the face normal: neighbouring faces of a
// smooth, coarsely tessellated surface differ by several degrees, and with sigma_n 128 the
// weight across their edge (0.08 at 11 degrees) would filter every triangle on its own and
// leave each with its own residual noise: the surface would look faceted. The normal-mapped
// normal rather than the bare vertex normal because the demodulated signals are shaded with
// it (gi.comp, reflections.comp) and composite does not shade them again: filtering across
// normal-map detail would blur the detail out of the area, environment and indirect light.
float svgf_weight_normal(vec3 n_p, vec3 n_q) { return pow(max(0.0, dot(n_p, n_q)), svgf.sigma_n); }

// sigma_l = infinity switches luminance edge-stopping off (the impulse-response test does).
float svgf_weight_luminance(float l_p, float l_q, float std_dev) {
    if (isinf(svgf.sigma_l)) return 1.0;
    return exp(-abs(l_p - l_q) / (svgf.sigma_l * std_dev + 1e-6));
}

#endif
