// The one material model: glTF metallic-roughness, Lambert diffuse plus a GGX specular lobe with
// height-correlated Smith visibility and Schlick Fresnel. Every pass and the reference path
// tracer evaluate light through these functions; src/world/brdf.rs mirrors them on the CPU.
//
// How the two lobes share the light is the model (brdf_model, src/world/brdf.rs BrdfModel):
// - BRDF_MODEL_GLTF (the default): glTF 2.0 Appendix B exactly. The dielectric is
//   fresnel_mix(Lambert, GGX) with F = F0 + (1 - F0) (1 - |v.h|)^5 (F0 = 0.04 unless
//   KHR_materials_ior says otherwise), the metal is the GGX layer
//   with Schlick Fresnel on baseColor, and the material is their mix by metallic. Its specular
//   part is one GGX lobe with Schlick Fresnel at F0 = mix(0.04, baseColor, metallic); its
//   diffuse part is baseColor (1 - metallic) / pi weighted by 1 - F_dielectric(v.h).
// - BRDF_MODEL_COUPLED: the diffuse lobe weighted by (1 - E(v)) (1 - E(l)) / (1 - E_avg), E the
//   specular lobe's directional albedo (a table): reciprocal and energy-conserving, where the
//   specification's weighting reflects more than it receives at grazing views of glossy white
//   dielectrics (1.2 at a view cosine of 0.2, roughness 0.3).
#ifndef BRDF_GLSL
#define BRDF_GLSL

#extension GL_EXT_scalar_block_layout : require
#include "sampling.glsl"
#include "color.glsl"

#define BRDF_MODEL_GLTF 0u
#define BRDF_MODEL_COUPLED 1u

// The model, then (A, B) with E(mu, roughness; F0) = F0 A + B over a 32 x 32 grid (roughness
// rows of view cosines), then 32 cosine-weighted averages per roughness.
#define BRDF_TABLE_SIZE 32
layout(set = 0, binding = 17, scalar) readonly buffer BrdfData {
    uint brdf_model;
    uint brdf_reserved;
    vec2 brdf_energy[];
};

// Roughness below this is treated as this (a perfect mirror has no finite GGX density).
#define MIN_ALPHA 1e-3

float ggx_alpha(float roughness) { return max(roughness * roughness, MIN_ALPHA); }

vec3 fresnel_schlick(vec3 f0, float cos_theta) {
    float k = pow(1.0 - clamp(cos_theta, 0.0, 1.0), 5.0);
    return f0 + (1.0 - f0) * k;
}

float ggx_d(float n_dot_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

// Height-correlated Smith visibility V = G2 / (4 n.l n.v).
float smith_visibility(float n_dot_l, float n_dot_v, float alpha) {
    float a2 = alpha * alpha;
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-12);
}

struct BrdfInput {
    vec3 base_color;
    float metallic;
    float roughness;
    // The dielectric's reflectance at normal incidence, dielectric_f0 of the material's IOR
    // (KHR_materials_ior; glTF's 0.04 at the default 1.5) in every pass and the reference.
    float dielectric_f0;
};

// glTF's dielectric F0 without KHR_materials_ior (the brdf tests' harness).
#define GLTF_DIELECTRIC_F0 0.04

float dielectric_f0(float ior) {
    float r = (ior - 1.0) / (ior + 1.0);
    return r * r;
}

vec3 brdf_f0(BrdfInput m) { return mix(vec3(m.dielectric_f0), m.base_color, m.metallic); }
vec3 brdf_diffuse_albedo(BrdfInput m) { return m.base_color * (1.0 - m.metallic); }

// Bilinear (A, B) at view cosine mu and roughness.
vec2 brdf_energy_ab(float mu, float roughness) {
    float x = clamp(mu, 0.0, 1.0) * float(BRDF_TABLE_SIZE - 1);
    float y = clamp(roughness, 0.0, 1.0) * float(BRDF_TABLE_SIZE - 1);
    int i = min(int(x), BRDF_TABLE_SIZE - 2);
    int j = min(int(y), BRDF_TABLE_SIZE - 2);
    vec2 t = vec2(x - float(i), y - float(j));
    int row0 = j * BRDF_TABLE_SIZE, row1 = row0 + BRDF_TABLE_SIZE;
    vec2 top = mix(brdf_energy[row0 + i], brdf_energy[row0 + i + 1], t.x);
    vec2 bottom = mix(brdf_energy[row1 + i], brdf_energy[row1 + i + 1], t.x);
    return mix(top, bottom, t.y);
}

// The specular lobe's directional albedo for a view at cosine mu.
vec3 brdf_specular_albedo(BrdfInput m, float mu) {
    vec2 ab = brdf_energy_ab(mu, m.roughness);
    return brdf_f0(m) * ab.x + ab.y;
}

// Its cosine-weighted average over all views.
vec3 brdf_specular_albedo_avg(BrdfInput m) {
    float y = clamp(m.roughness, 0.0, 1.0) * float(BRDF_TABLE_SIZE - 1);
    int j = min(int(y), BRDF_TABLE_SIZE - 2);
    int base = BRDF_TABLE_SIZE * BRDF_TABLE_SIZE;
    vec2 ab = mix(brdf_energy[base + j], brdf_energy[base + j + 1], y - float(j));
    return brdf_f0(m) * ab.x + ab.y;
}

// The dielectric's Fresnel at cosine v.h, which splits light between the glTF model's diffuse
// and specular layers.
float fresnel_dielectric(BrdfInput m, float v_dot_h) {
    return m.dielectric_f0 + (1.0 - m.dielectric_f0) * pow(1.0 - clamp(v_dot_h, 0.0, 1.0), 5.0);
}

// The diffuse lobe divided by Lambert's brdf_diffuse_albedo / pi: the weight the model gives
// diffuse light arriving from l and leaving toward v. The gi pass integrates incident light
// with it and composite multiplies by the albedo alone, so the demodulated diffuse signal is
// exact for either model.
vec3 brdf_diffuse_weight(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    if (brdf_model == BRDF_MODEL_COUPLED) {
        return (1.0 - brdf_specular_albedo(m, max(dot(n, v), 0.0))) * (1.0 - brdf_specular_albedo(m, max(dot(n, l), 0.0))) /
               max(1.0 - brdf_specular_albedo_avg(m), vec3(1e-4));
    }
    return vec3(1.0 - fresnel_dielectric(m, dot(v, normalize(v + l))));
}

// The specular lobe alone: f_spec(v, l) * cos(theta_l).
vec3 brdf_eval_specular_cos(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    float n_dot_l = dot(n, l);
    float n_dot_v = dot(n, v);
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) return vec3(0.0);
    vec3 h = normalize(v + l);
    float alpha = ggx_alpha(m.roughness);
    vec3 f = fresnel_schlick(brdf_f0(m), dot(v, h));
    return f * ggx_d(max(dot(n, h), 0.0), alpha) * smith_visibility(n_dot_l, n_dot_v, alpha) * n_dot_l;
}

// f(v, l) * cos(theta_l); n, v, l unit vectors, v and l pointing away from the surface.
vec3 brdf_eval_cos(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    float n_dot_l = dot(n, l);
    float n_dot_v = dot(n, v);
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) return vec3(0.0);
    vec3 h = normalize(v + l);
    float alpha = ggx_alpha(m.roughness);
    vec3 f = fresnel_schlick(brdf_f0(m), dot(v, h));
    vec3 spec = f * ggx_d(max(dot(n, h), 0.0), alpha) * smith_visibility(n_dot_l, n_dot_v, alpha);
    vec3 diff = brdf_diffuse_albedo(m) * INV_PI * brdf_diffuse_weight(m, n, v, l);
    return (diff + spec) * n_dot_l;
}

// ---- Sampling ---------------------------------------------------------------------------------
// brdf_sample draws l from a mixture of the two lobes: the GGX visible-normal distribution
// reflected about the sampled microfacet (specular) and the cosine hemisphere (diffuse), with
// the specular lobe chosen with probability brdf_spec_probability. brdf_pdf is the mixture's
// solid-angle density, which is what multiple importance sampling compares against light pdfs.

// Smith masking G1 of GGX for a direction at cosine n_dot_w to the normal.
float ggx_g1(float n_dot_w, float alpha) {
    float a2 = alpha * alpha;
    return 2.0 * n_dot_w / (n_dot_w + sqrt(a2 + (1.0 - a2) * n_dot_w * n_dot_w));
}

// Density of l = reflect(-v, m) when m is drawn from the visible normals of v:
// D_v(m) / (4 v.m) = G1(v) D(m) / (4 n.v).
float ggx_vndf_pdf(float n_dot_v, float n_dot_h, float alpha) {
    return ggx_g1(n_dot_v, alpha) * ggx_d(n_dot_h, alpha) / (4.0 * n_dot_v);
}

// Probability of drawing from the specular lobe: the lobes' weights at normal-ish incidence,
// Fresnel for the specular one and (1 - Fresnel) * diffuse albedo for the diffuse one (either
// model). Only a variance choice: brdf_pdf is the same mixture, and any value in (0, 1) for
// lobes that can both contribute keeps the estimate unbiased. A lobe that cannot contribute
// (diffuse of a metal) gets probability 0.
float brdf_spec_probability(BrdfInput m, float n_dot_v) {
    vec3 f = fresnel_schlick(brdf_f0(m), n_dot_v);
    float s = luminance(f);
    float d = luminance((1.0 - f) * brdf_diffuse_albedo(m));
    return s + d > 0.0 ? s / (s + d) : 0.5;
}

// Solid-angle density of brdf_sample producing l (0 below either horizon).
float brdf_pdf(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    float n_dot_l = dot(n, l);
    float n_dot_v = dot(n, v);
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) return 0.0;
    float p_spec = brdf_spec_probability(m, n_dot_v);
    vec3 h = normalize(v + l);
    float spec = ggx_vndf_pdf(n_dot_v, max(dot(n, h), 0.0), ggx_alpha(m.roughness));
    return p_spec * spec + (1.0 - p_spec) * n_dot_l * INV_PI;
}

struct BrdfSample {
    vec3 l;       // sampled direction (unit, away from the surface)
    float pdf;    // brdf_pdf(l); 0 when no direction was produced (below the horizon)
    vec3 weight;  // brdf_eval_cos(l) / pdf, the path throughput factor
};

// Draws a direction for view v at normal n from three uniform numbers (u.z picks the lobe).
BrdfSample brdf_sample(BrdfInput m, vec3 n, vec3 v, vec3 u) {
    BrdfSample s;
    s.l = n;
    s.pdf = 0.0;
    s.weight = vec3(0.0);
    float n_dot_v = dot(n, v);
    if (n_dot_v <= 0.0) return s;
    mat3 frame = orthonormal_basis(n);
    vec3 l_local;
    if (u.z < brdf_spec_probability(m, n_dot_v)) {
        vec3 v_local = vec3(dot(v, frame[0]), dot(v, frame[1]), n_dot_v);
        vec3 h = sample_ggx_vndf(v_local, ggx_alpha(m.roughness), u.xy);
        l_local = reflect(-v_local, h);
    } else {
        l_local = sample_cosine_hemisphere(u.xy);
    }
    // Visible normals can reflect the view below the horizon: that sample is lost (its share
    // of the density is the part of brdf_pdf's specular term that integrates below it).
    if (l_local.z <= 0.0) return s;
    s.l = normalize(frame * l_local);
    s.pdf = brdf_pdf(m, n, v, s.l);
    if (s.pdf > 0.0) s.weight = brdf_eval_cos(m, n, v, s.l) / s.pdf;
    return s;
}

#endif
