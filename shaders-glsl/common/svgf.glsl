// Shared by the SVGF passes (svgf_temporal, svgf_atrous): settings, the reprojection validity
// test, the edge-stopping weights of Schied et al. 2017, and the guide texel they read them
// from.
#ifndef SVGF_GLSL
#define SVGF_GLSL

#include "color.glsl"
#include "gbuffer.glsl"

// Settings, one block for every SVGF pass (src/passes/svgf/mod.rs `SvgfSettings`).
layout(push_constant) uniform SvgfParams {
    float alpha;          // minimum colour blend weight of the new frame
    float moments_alpha;  // minimum moments blend weight
    float sigma_z;        // depth edge-stopping, scaled by the depth gradient
    float sigma_n;        // normal edge-stopping exponent
    float sigma_l;        // luminance edge-stopping, scaled by the standard deviation
    float history_cap;    // longest history, frames
    float clamp_sigma;    // outlier clamp: luminance above mean + clamp_sigma * std dev
    float converged;      // relative noise under which later a-trous iterations leave a pixel as it is
    int step;             // a-trous step (1, 2, 4, ...)
    uint flags;           // SVGF_SHARP_SPECULAR
} svgf;

// svgf_temporal: the specular signal is made of reflection rays: a narrow lobe's history follows
// the reflected object, and its footprint (svgf_footprint, handed to the a-trous iterations in
// svgf_centre) keeps its reflection sharp.
#define SVGF_SHARP_SPECULAR 1u

bool finite3(vec3 c) { return !any(isnan(c)) && !any(isinf(c)); }

// Can the previous frame's sample at `prev_px` stand for this pixel? Same instance, similar
// depth (relative to how fast depth changes here) and similar geometric normal (Falcor's
// tests).
bool svgf_consistent(float z, float z_prev, float fwidth_z, vec3 ng, vec3 ng_prev, uint id, uint id_prev) {
    if (id != id_prev) return false;
    if (abs(z - z_prev) / (fwidth_z + 1e-2) > 10.0) return false;
    return dot(ng, ng_prev) > 0.9;
}

// The edge-stopping weights are exponentials, exp(-e), of these exponents; the a-trous filter
// adds a tap's exponents and takes one exponential.

// Depth: the difference against how much depth may change over the offset on this pixel's own
// surface, `inv_scale` = 1 / (sigma_z fwidth(z) |offset| + 1e-4) (fwidth from the rasteriser).
float svgf_depth_exponent(float z_p, float z_q, float inv_scale) { return abs(z_p - z_q) * inv_scale; }

// Normal, on the shading normal (gbuffer.normal: the interpolated vertex normal, with the
// normal map where the material has one), never the face normal: neighbouring faces of a
// smooth, coarsely tessellated surface differ by several degrees, and with sigma_n 128 the
// weight across their edge (0.08 at 11 degrees) would filter every triangle on its own and
// leave each with its own residual noise: the surface would look faceted. The normal-mapped
// normal rather than the bare vertex normal because the demodulated signals are shaded with
// it (gi.comp, reflections.comp) and composite does not shade them again: filtering across
// normal-map detail would blur the detail out of the area, environment and indirect light.
//
// exp(-sigma_n (1 - n.n')) rather than Schied et al.'s pow(n.n', sigma_n): the two agree to
// first order where the normals agree (within 2% of each other up to 10 degrees), both are
// below 1e-7 beyond 30 degrees, and this one needs no logarithm per tap.
float svgf_normal_exponent(vec3 n_p, vec3 n_q) { return svgf.sigma_n * (1.0 - dot(n_p, n_q)); }

// Frames of history from which the temporal moments give the variance (svgf_temporal estimates
// it spatially before).
#define SVGF_MOMENTS_FRAMES 4.0

// Has signal colour `c` (variance in alpha) of a pixel with `history_length` frames converged:
// is the noise of its accumulated value, estimated as sqrt(variance / frames), below
// svgf.converged of its luminance? Then the a-trous iterations after the first leave it as it
// is: the variance is the per-frame sample's, which accumulation does not lower, so the filter
// would keep averaging a pixel whose history has already averaged the noise away, and only
// blur it (and cost as much as where it is needed). A pixel whose history is younger than the
// moments' (a disocclusion, a camera cut, a change of the lights) is never converged.
bool svgf_converged(vec4 c, float history_length) {
    return history_length >= SVGF_MOMENTS_FRAMES &&
           sqrt(max(c.a, 0.0) / history_length) < svgf.converged * luminance(c.rgb);
}

// How far the a-trous iterations may spread a reflection's light: all the way, but for a narrow
// lobe, whose reflection is as sharp as what it reflects (from nothing at roughness 0.05 to
// all of it at 0.35).
float svgf_footprint(float roughness) { return smoothstep(0.05, 0.35, roughness); }

// A filtered signal's texel (svgf_temporal's colour, every a-trous iteration's; rgba16f): the
// colour in rgb, the standard deviation of its luminance in alpha. Half precision because the
// filter is bound by its loads (8 taps per pixel and signal, each iteration): on lavapipe it cuts
// the denoiser by a third. The deviation rather than the variance because the variance of a
// bright signal (a light's reflection) would pass half's largest value, 65504; the colour is
// kept below it.
const float SVGF_HALF_MAX = 65504.0;

// The half-precision value nearest v (ties to even), as a float, so that the store's conversion
// to half is exact. Vulkan lets an implementation truncate instead, and lavapipe does: a history
// stored truncated, frame after frame, lost 0.7% of the light and raised the sweep's FLIP by 5%.
vec4 svgf_nearest_half(vec4 v) {
    ivec4 e;
    frexp(max(abs(v), vec4(6.103515625e-05)), e);  // below half's smallest normal, its spacing
    vec4 spacing = ldexp(vec4(1.0), e - 11);
    return roundEven(v / spacing) * spacing;
}

// Colour and luminance variance -> texel.
vec4 svgf_pack(vec3 c, float variance) {
    return svgf_nearest_half(vec4(min(c, vec3(SVGF_HALF_MAX)), min(sqrt(max(variance, 0.0)), SVGF_HALF_MAX)));
}

// Texel -> colour and luminance variance.
vec4 svgf_unpack(vec4 texel) { return vec4(texel.rgb, texel.a * texel.a); }

// What an a-trous iteration reads of the pixel it filters, besides its guide texel:
// svgf_temporal.centre, written by svgf_temporal, which has all of it at hand. x the view
// depth's fwidth, y the specular signal's footprint (svgf_footprint; a lone signal's, 1 but
// for what surfaces let through), z
// and w the diffuse and specular history lengths (a lone signal's in z), which the next frame's
// svgf_temporal reprojects too, in place of an r32f image per signal, so that the texel costs
// that pass no more stores. Each iteration loads this one texel where it loaded five (the
// fwidth from the G-buffer, the roughness and hit distance that make the footprint, a length
// per signal): at 1920x1080 on lavapipe the four iterations took about 12% less time, at
// 640x360 3-6% (README, "One texel for the pixel's own"). Half precision, as the signals:
// the depth weight's scale needs no more, and a length below 32 frames keeps 1/64 of one.
vec4 svgf_centre(float fwidth_z, float footprint, float diffuse_length, float specular_length) {
    return svgf_nearest_half(vec4(min(fwidth_z, SVGF_HALF_MAX), footprint, diffuse_length, specular_length));
}

// A flag on a pixel, carried by a filtered signal's texel as the sign of its deviation (at
// least SVGF_FLAG_MIN_DEVIATION, so that the sign survives a zero), which svgf_unpack's square
// leaves out, and which the a-trous taps load anyway. On svgf_temporal's colour: the pixel gives
// shares of what its outlier clamp took out to its neighbours (svgf_temporal.glsl, the
// give-back). On an a-trous iteration's: the pixel's signal has converged (svgf_converged), so
// the next iteration leaves it as it is and its neighbours leave it out (svgf_atrous.glsl).
const float SVGF_FLAG_MIN_DEVIATION = 1e-4;
vec4 svgf_flag(vec4 texel) { return vec4(texel.rgb, -max(texel.a, SVGF_FLAG_MIN_DEVIATION)); }
bool svgf_flagged(vec4 texel) { return texel.a < 0.0; }

// What the edge-stopping weights read of a neighbour, the guide texel, is gbuffer.normal: the
// shading normal in xyz and the view depth in w (0 where there is no surface, the clear value),
// so that each of the a-trous filter's taps loads one texel for its depth and normal weights.
// The rasteriser writes the depth beside the normal; until 2026-12-05 a pass of its own,
// svgf_guide, packed the two (and the ids) into a texel of its own, which cost a full-screen
// pass a frame (README, "The guide written by the rasteriser").
bool svgf_guide_surface(vec4 guide) { return guide.w > 0.0; }

// Are the surface pixels with guide texels a and b on one surface, for the outlier clamp's
// give-back (svgf_temporal, svgf_atrous): shading normals within 25 degrees, view depths within
// 5% of the nearer. Symmetric, so that the pixel that gives and the neighbours that take count
// the same neighbours.
bool svgf_same_surface(vec4 a, vec4 b) { return dot(a.xyz, b.xyz) > 0.9 && abs(a.w - b.w) < 0.05 * min(a.w, b.w); }

#endif
