// Light through transmissive surfaces (KHR_materials_transmission, _ior, _volume), for the
// reference path tracer. glTF's dielectric is fresnel_mix(specular, mix(diffuse, btdf, T)): the
// specular layer reflects F, and of the light it lets through the share T passes the surface
// through the same GGX microfacets, tinted by baseColor, instead of scattering diffusely.
// - Thin-walled surfaces (no volume) let it through without bending: the transmitted lobe is
//   the specular lobe's shape mirrored through the surface plane.
// - Surfaces that bound a volume refract it by their IOR (Walter et al. 2007, rough dielectric
//   microfacets sampled by visible normals), and inside the volume Beer-Lambert absorbs it.
//   Seen from inside, the surface is a bare interface: it reflects F (1 under total internal
//   reflection) and lets the rest out.
// Radiance is not rescaled by (eta_t / eta_i)^2 at refractions: cameras and lights are outside
// every volume, so each path that enters one leaves it, and the factors cancel.
#ifndef TRANSMISSION_GLSL
#define TRANSMISSION_GLSL

#include "brdf.glsl"

// The glTF model's diffuse lobe times cos(theta_l), the part transmission replaces.
vec3 brdf_diffuse_cos(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    float n_dot_l = dot(n, l);
    if (n_dot_l <= 0.0 || dot(n, v) <= 0.0) return vec3(0.0);
    return brdf_diffuse_albedo(m) * INV_PI * brdf_diffuse_weight(m, n, v, l) * n_dot_l;
}

// What a transmissive surface reflects, f cos: the material without the transmitted share of
// its diffuse lobe.
vec3 reflection_eval_cos(BrdfInput m, float transmission, vec3 n, vec3 v, vec3 l) {
    return brdf_eval_cos(m, n, v, l) - transmission * brdf_diffuse_cos(m, n, v, l);
}

// The chance that the path goes through the surface: the transmitted share of the light
// glTF's model lets past its specular layer at this view, (1 - metallic) T (1 - F(n.v)).
// Only a variance choice, like brdf_spec_probability.
float transmitted_share(BrdfInput m, float transmission, vec3 n, vec3 v) {
    return transmission * (1.0 - m.metallic) * (1.0 - fresnel_dielectric(m, max(dot(n, v), 0.0)));
}

// Schlick's Fresnel for light crossing an interface at microfacet cosine cos_i, with
// eta = n_incident / n_transmitted; 1 under total internal reflection. Schlick takes the angle
// on the optically thinner side, so the interface reflects the same from both sides (and from
// outside it is glTF's F at v.h).
float fresnel_interface(float f0, float cos_i, float eta) {
    float sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if (sin2_t >= 1.0) return 1.0;
    float c = eta > 1.0 ? sqrt(1.0 - sin2_t) : cos_i;
    return f0 + (1.0 - f0) * pow(1.0 - c, 5.0);
}

struct TransmissionSample {
    vec3 l;        // direction leaving the surface (unit)
    vec3 weight;   // f cos / pdf of the event, before the choice of the transmitted lobe
    bool crossed;  // the path passed to the other side of the surface
};

// No direction: the drawn microfacet sent the light the wrong way (or v is below the surface).
TransmissionSample transmission_none(vec3 v) {
    TransmissionSample s;
    s.l = -v;
    s.weight = vec3(0.0);
    s.crossed = false;
    return s;
}

// What visible-normal sampling leaves of f cos / pdf besides Fresnel: G2(v, l) / G1(v).
float vndf_shadowing(float n_dot_l, float n_dot_v, float alpha) {
    return smith_visibility(n_dot_l, n_dot_v, alpha) * 4.0 * n_dot_v * n_dot_l / ggx_g1(n_dot_v, alpha);
}

// The transmitted lobe at an outside hit for view v at normal n (both on the ray's side):
// thin-walled, straight through; else refracted into the volume. weight 0 when the drawn
// microfacet sends the light the wrong way.
TransmissionSample transmission_sample(BrdfInput m, bool thin_walled, float ior, vec3 n, vec3 v, vec2 u) {
    TransmissionSample s = transmission_none(v);
    float n_dot_v = dot(n, v);
    if (n_dot_v <= 0.0) return s;
    mat3 frame = orthonormal_basis(n);
    vec3 v_local = vec3(dot(v, frame[0]), dot(v, frame[1]), n_dot_v);
    float alpha = ggx_alpha(m.roughness);
    vec3 h = sample_ggx_vndf(v_local, alpha, u);
    float v_dot_h = dot(v_local, h);
    vec3 l_local;
    float f;
    if (thin_walled) {
        vec3 r = reflect(-v_local, h);
        l_local = vec3(r.xy, -r.z);
        f = fresnel_dielectric(m, v_dot_h);
    } else {
        f = fresnel_interface(m.dielectric_f0, v_dot_h, 1.0 / ior);
        l_local = refract(-v_local, h, 1.0 / ior);
    }
    if (l_local.z >= 0.0 || f >= 1.0) return s;
    s.l = normalize(frame * l_local);
    s.crossed = true;
    // (1 - F) G2 / G1 for either lobe.
    s.weight = (1.0 - f) * m.base_color * vndf_shadowing(-l_local.z, n_dot_v, alpha);
    return s;
}

// Thin-walled transmission toward l, on the far side of the surface from v: the transmitted lobe
// is the specular lobe mirrored through the surface plane (transmission_sample), so its value
// and density are the specular lobe's at l's mirror image, with 1 - F for F and tinted by
// baseColor. For light samples through rough thin-walled glass. f cos, before the share
// transmission (1 - metallic) that the caller applies.
vec3 thin_transmission_eval_cos(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    vec3 mirrored = l - 2.0 * dot(n, l) * n;
    float n_dot_l = dot(n, mirrored);
    float n_dot_v = dot(n, v);
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) return vec3(0.0);
    vec3 h = normalize(v + mirrored);
    float alpha = ggx_alpha(m.roughness);
    float f = fresnel_dielectric(m, dot(v, h));
    return (1.0 - f) * m.base_color * ggx_d(max(dot(n, h), 0.0), alpha) * smith_visibility(n_dot_l, n_dot_v, alpha) *
           n_dot_l;
}

// Solid-angle density of transmission_sample producing l on a thin-walled surface.
float thin_transmission_pdf(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    vec3 mirrored = l - 2.0 * dot(n, l) * n;
    float n_dot_v = dot(n, v);
    if (dot(n, mirrored) <= 0.0 || n_dot_v <= 0.0) return 0.0;
    return ggx_vndf_pdf(n_dot_v, max(dot(n, normalize(v + mirrored)), 0.0), ggx_alpha(m.roughness));
}

// The bare interface seen from inside a volume: reflect with probability F (total internal
// reflection included), else leave it. n faces the inside (the ray's side).
TransmissionSample interface_sample(float roughness, float ior, vec3 n, vec3 v, vec3 u) {
    TransmissionSample s = transmission_none(v);
    float n_dot_v = dot(n, v);
    if (n_dot_v <= 0.0) return s;
    mat3 frame = orthonormal_basis(n);
    vec3 v_local = vec3(dot(v, frame[0]), dot(v, frame[1]), n_dot_v);
    float alpha = ggx_alpha(roughness);
    vec3 h = sample_ggx_vndf(v_local, alpha, u.xy);
    float f = fresnel_interface(dielectric_f0(ior), dot(v_local, h), ior);
    vec3 l_local;
    if (u.z < f) {
        l_local = reflect(-v_local, h);
        if (l_local.z <= 0.0) return s;
    } else {
        l_local = refract(-v_local, h, ior);
        if (l_local.z >= 0.0) return s;
        s.crossed = true;
    }
    s.l = normalize(frame * l_local);
    // F or 1 - F is the chance of the event taken: what remains is G2 / G1.
    s.weight = vec3(vndf_shadowing(abs(l_local.z), n_dot_v, alpha));
    return s;
}

#endif
