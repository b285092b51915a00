// The one material model: glTF metallic-roughness as Lambert diffuse plus a GGX specular lobe
// with height-correlated Smith visibility and Schlick Fresnel. Every pass and the reference
// path tracer evaluate light through these functions.
#ifndef BRDF_GLSL
#define BRDF_GLSL

#define PI 3.14159265358979
#define INV_PI 0.31830988618379

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
};

vec3 brdf_f0(BrdfInput m) { return mix(vec3(0.04), m.base_color, m.metallic); }
vec3 brdf_diffuse_albedo(BrdfInput m) { return m.base_color * (1.0 - m.metallic); }

// f(v, l) * cos(theta_l); n, v, l unit vectors, v and l pointing away from the surface.
vec3 brdf_eval_cos(BrdfInput m, vec3 n, vec3 v, vec3 l) {
    float n_dot_l = dot(n, l);
    float n_dot_v = dot(n, v);
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) return vec3(0.0);
    vec3 h = normalize(v + l);
    float alpha = ggx_alpha(m.roughness);
    vec3 f = fresnel_schlick(brdf_f0(m), dot(v, h));
    vec3 spec = f * ggx_d(max(dot(n, h), 0.0), alpha) * smith_visibility(n_dot_l, n_dot_v, alpha);
    vec3 diff = (1.0 - f) * brdf_diffuse_albedo(m) * INV_PI;
    return (diff + spec) * n_dot_l;
}

#endif
