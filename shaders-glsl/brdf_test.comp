#version 460
// brdf_test: a harness for tests/brdf.rs, not part of any frame. For one material and one view
// (normal +Z, view in the xz plane at cosine cos_view), mode 0 draws `count` directions with
// brdf_sample and mode 1 evaluates brdf_eval_cos and brdf_pdf at `count` given directions, so
// the test can compare where samples land with what the density says.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_scalar_block_layout : require
#include "common/brdf.glsl"

layout(local_size_x = 64) in;

// Mode 1: the directions to evaluate (xyz).
layout(set = 1, binding = 0, scalar) readonly buffer Directions { vec4 directions[]; };
// Two records per item. Mode 0: (l, pdf), (weight, 0); pdf 0 = no sample. Mode 1:
// (brdf_eval_cos, brdf_pdf), (0).
layout(set = 1, binding = 1, scalar) writeonly buffer Results { vec4 results[]; };

layout(push_constant) uniform Params {
    vec3 base_color;
    float metallic;
    float roughness;
    float cos_view;
    uint mode;
    uint count;
    uint seed;
} params;

#define SALT_BRDF_TEST 0x62726466u

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) return;
    BrdfInput m = BrdfInput(params.base_color, params.metallic, params.roughness, GLTF_DIELECTRIC_F0);
    vec3 n = vec3(0.0, 0.0, 1.0);
    vec3 v = vec3(sqrt(max(0.0, 1.0 - params.cos_view * params.cos_view)), 0.0, params.cos_view);
    if (params.mode == 0u) {
        Rng rng = rng_init(uvec2(i, 0u), params.seed, SALT_BRDF_TEST);
        BrdfSample s = brdf_sample(m, n, v, rng_next3(rng));
        results[2u * i] = vec4(s.l, s.pdf);
        results[2u * i + 1u] = vec4(s.weight, 0.0);
    } else {
        vec3 l = directions[i].xyz;
        results[2u * i] = vec4(brdf_eval_cos(m, n, v, l), brdf_pdf(m, n, v, l));
        results[2u * i + 1u] = vec4(0.0);
    }
}
