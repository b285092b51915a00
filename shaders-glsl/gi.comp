#version 460
// gi: diffuse global illumination, demodulated so the denoiser keeps texture detail: per pixel
// one cosine-sampled bounce plus one light sample. The output is the diffuse lobe's integral
// without its albedo, (1/pi) int L w(v, l) cos with w = brdf_diffuse_weight (the model's
// Fresnel or energy coupling, which depends on both directions and so must be inside the
// integral): composite multiplies by the albedo, which makes it exactly the BRDF's diffuse lobe.
//
// On surfaces rougher than the reflection cut-off, where the reflections pass traces no rays,
// the same samples also estimate the specular lobe (gi.specular, not demodulated): a broad
// lobe is well served by cosine-weighted directions, and without it a rough dielectric would
// lose the few percent of light its specular lobe reflects.
//
// What it covers, so that nothing is counted twice (see composite.comp):
// - direct light on the diffuse lobe from emissive triangles and the environment: a light
//   sample (punctual lights, which composite shades with ray-traced shadows, are skipped when
//   chosen) and the bounce ray hitting an emitter or escaping, combined with the power
//   heuristic;
// - indirect light: at the bounce ray's hit, next-event estimation toward a light chosen by
//   power (any kind, with a shadow ray), and the light that surface reflects from other
//   surfaces from the radiance cache (every further bounce); with `bounces` > 1 the path first
//   continues by BSDF sampling, with a light sample at each vertex, and the cache answers at the
//   last one. Where the cache cannot answer (a corner, a cell still empty, or the cache off)
//   the path traces on.
#extension GL_GOOGLE_include_directive : require
#include "common/trace.glsl"
#include "common/brdf.glsl"
#include "common/light_sampling.glsl"
#include "common/gbuffer.glsl"
#include "common/ray_offset.glsl"
#define RC_BINDING 8
#include "common/radiance_cache.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D g_normal;
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D g_base_color;
layout(set = 1, binding = 4, rgba8) uniform readonly image2D g_metal_rough;
layout(set = 1, binding = 5, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 6, rgba32f) uniform writeonly image2D out_radiance;
layout(set = 1, binding = 7, rgba32f) uniform writeonly image2D out_specular;

layout(push_constant) uniform Params {
    uint bounces;            // vertices traced after the primary surface before the cache answers
    uint seed;
    float roughness_cutoff;  // the reflections pass's: rougher surfaces get gi.specular
} params;

#define SALT_GI 0x67690000u

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec3 albedo = imageLoad(g_base_color, px).rgb * (1.0 - imageLoad(g_metal_rough, px).x);
    vec4 mr = imageLoad(g_metal_rough, px);
    bool rough = mr.y > params.roughness_cutoff;
    bool diffuse = max(albedo.r, max(albedo.g, albedo.b)) > 0.0;
    if (imageLoad(g_ids, px).x == NO_INSTANCE || !(diffuse || rough)) {
        imageStore(out_radiance, px, vec4(0.0));
        imageStore(out_specular, px, vec4(0.0));
        return;
    }
    BrdfInput m = BrdfInput(imageLoad(g_base_color, px).rgb, mr.x, mr.y);
    Rng rng = rng_init(uvec2(px), frame.frame_index, params.seed ^ SALT_GI);
    float depth = imageLoad(g_depth, px).r;
    vec3 n = imageLoad(g_normal, px).xyz;
    vec3 ng = imageLoad(g_normal_geo, px).xyz;
    vec3 p = world_position(px, depth);
    vec3 origin = offset_ray_origin(p, ng, depth);
    vec3 v = -camera_ray_dir(vec2(px) + 0.5 - frame.jitter);
    vec3 spec_sum = vec3(0.0);
    // Estimates of the incident radiance integral (1/pi) int L cos: the Lambert lobe without
    // its albedo.
    vec3 l_sum = vec3(0.0);

    // Direct light from emitters and the environment, light-sampled. Sampled from the shadow
    // ray's own origin: direction and distance measured from the surface point would overshoot
    // by the offset, and the shadow ray would hit the emitter it aims at.
    NeeSample ls = light_sample(origin, rng_next3(rng));
    if (ls.pdf > 0.0 && dot(ls.dir, ng) > 0.0) {
        float cos_l = max(dot(n, ls.dir), 0.0);
        if (cos_l > 0.0 && !trace_any(origin, ls.dir, 0.0, shadow_ray_tmax(ls.dist), RAY_MASK_ALL)) {
            float w = mis_power(ls.pdf, cos_l * INV_PI);
            l_sum += ls.weight * cos_l * INV_PI * brdf_diffuse_weight(m, n, v, ls.dir) * w;
            if (rough) spec_sum += ls.weight * brdf_eval_specular_cos(m, n, v, ls.dir) * w;
        }
    }

    // The bounce: cosine-weighted about the shading normal, kept above the geometric surface.
    vec3 dir = orthonormal_basis(n) * sample_cosine_hemisphere(rng_next2(rng));
    float pdf = max(dot(n, dir), 0.0) * INV_PI;
    if (dot(dir, ng) > 0.0 && pdf > 0.0) {
        vec3 lobe = brdf_diffuse_weight(m, n, v, dir);
        vec3 bounce = vec3(0.0);
        Hit h = trace_closest(origin, dir, 0.0, 1e6, RAY_MASK_ALL);
        // With cosine sampling, the Lambert lobe's (1/pi) L cos / pdf is L itself.
        if (h.instance == NO_HIT) {
            bounce = env_eval(dir) * mis_power(pdf, light_pdf_environment(dir));
        } else {
            HitSurface s = hit_surface(h.instance, h.primitive, h.bary, dir);
            if (emitter_visible_side(h.instance, h.primitive, dir)) {
                float lp = light_pdf_emitter(h.instance, h.primitive, origin, s.position);
                bounce += s.mat.emissive * mis_power(pdf, lp);
            }
            uint traced = max(params.bounces, 1u);
            uint vertices = rc.enabled != 0u ? max(traced, RC_VERTICES) : traced;
            bounce += rc_radiance_leaving(s, dir, h.t, traced - 1u, vertices, true,
                                          rc_copy_written(frame.frame_index), rng);
        }
        l_sum += lobe * bounce;
        if (rough) spec_sum += bounce * brdf_eval_specular_cos(m, n, v, dir) / pdf;
    }
    imageStore(out_radiance, px, vec4(diffuse ? l_sum : vec3(0.0), 1.0));
    imageStore(out_specular, px, vec4(spec_sum, 1.0));
}
