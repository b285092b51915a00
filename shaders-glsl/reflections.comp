#version 460
// reflections: the specular lobe, ray traced. Per pixel `rays` directions drawn from the GGX
// distribution of visible normals (a perfect mirror reflects exactly); each hit is shaded with
// its emission and a light sample toward a light chosen by power (with a shadow ray); rays that
// escape see the environment; the radiance cache adds the hit's indirect light. A glossy lobe
// also takes a light sample of the emitters and the environment per ray, combined with the
// ray by the power heuristic: a sun or a small emitter is a narrow, bright target that the
// lobe's own rays find too rarely (and the denoiser's outlier clamp then cuts the rare hits
// that do: the highlight went missing). Surfaces
// rougher than the cut-off trace nothing and take the specular estimate the gi pass made from
// its own samples (gi.specular); under the cut-off gi.specular holds the lobe's share of the
// resampled punctual lights, which no ray can hit, and is added. The output is the lobe's
// contribution (Fresnel and shadowing included), ready to add; the hit distance goes alongside
// for the denoiser. What transmissive and blended surfaces let through (one path through the
// glass, transmitted_radiance; the view ray continued past a blend, behind_blend) is a signal
// of its own, out_let_through, with where it was seen: its history follows that, the
// reflection's its own hit, and each has its denoiser.
#extension GL_GOOGLE_include_directive : require
#include "common/trace.glsl"
#include "common/brdf.glsl"
#include "common/transmission.glsl"
#include "common/light_sampling.glsl"
#include "common/area_lights.glsl"
#include "common/gbuffer.glsl"
#include "common/ray_offset.glsl"
#define RC_BINDING 10
// A mirror shows the cache's answer at its reflection's hit unfiltered: read it blended.
#define RC_BLEND_FIRST
#include "common/radiance_cache.glsl"
#include "common/pass_through.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D g_normal;
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D g_base_color;
layout(set = 1, binding = 4, rgba8) uniform readonly image2D g_metal_rough;
layout(set = 1, binding = 5, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 6, rgba32f) uniform readonly image2D in_specular;
layout(set = 1, binding = 7, rgba32f) uniform writeonly image2D out_radiance;
layout(set = 1, binding = 8, r32f) uniform writeonly image2D out_hit_distance;
// rgb what the surface lets through, alpha where along the view ray it was seen (1x1 and
// unwritten unless params.let_through).
layout(set = 1, binding = 9, rgba32f) uniform writeonly image2D out_let_through;

layout(push_constant) uniform Params {
    uint rays;                // specular rays per pixel
    float roughness_cutoff;   // rougher surfaces use the environment fallback
    uint seed;
    uint bounces;             // with the cache off: path vertices traced from a hit (gi's)
    uint let_through;         // 1: some surface lets light through; write out_let_through
} params;

#define SALT_REFLECTIONS 0x72656600u
// Below this roughness the surface is a mirror: one exact reflection, no sampling.
#define MIRROR_ROUGHNESS 0.01

// Radiance leaving hit h (surface s) toward -dir: emission (times `emission_weight`, its MIS
// weight against a light sample), a light sample, and what the surface reflects from other
// surfaces, from the radiance cache (with the cache off, the path traced on for as many
// vertices as gi traces).
vec3 shade_hit(Hit h, HitSurface s, vec3 dir, float emission_weight, inout Rng rng) {
    vec3 radiance = emitter_visible_side(h.instance, h.primitive, dir) ? s.mat.emissive * emission_weight : vec3(0.0);
    uint vertices = rc.enabled != 0u ? RC_VERTICES : max(params.bounces, 1u);
    return radiance + rc_radiance_leaving(s, dir, h.t, 0u, vertices, true, rc_copy_written(frame.frame_index), rng);
}

// Light through a transmissive surface toward v (KHR_materials_transmission): one path through
// it, as the reference traces it (common/transmission.glsl), shaded where it leaves the glass,
// and for thin-walled glass a light sample through it.
// Inside a volume the interface reflects or lets the path out (Beer-Lambert absorbing on the
// way); a further transmissive surface adds what it reflects and is passed through. The weight
// excludes the surface's transmitted share, which the caller applies.
// `seen_at`: how far the path went before it stopped at an opaque surface, where what it saw
// lies (near enough) on the view ray's line: through thin-walled glass, which does not bend a
// ray, or out of a volume in the direction it went in (a slab shifts the line a little and
// does not turn it). The denoiser and TAA reproject what the glass lets through by it. 0 where
// the path escaped, or left a volume turned (a lens: what it shows moves its own way).
#define TRANSMISSION_EVENTS 8u
// A path leaving a volume within about 2.5 degrees of the view ray counts as not turned.
#define UNTURNED_COS 0.999
// Up to this many punctual lights, each is sampled through thin-walled glass.
#define GLASS_LIGHTS 8u
vec3 transmitted_radiance(vec3 p, vec3 n, vec3 ng, vec3 v, float depth, BrdfInput m, MaterialInfo mi, inout Rng rng,
                          out float seen_at) {
    seen_at = 0.0;
    m.dielectric_f0 = dielectric_f0(mi.ior);
    bool thin = mi.thickness <= 0.0;
    TransmissionSample ts = transmission_sample(m, thin, mi.ior, n, v, rng_next2(rng));
    vec3 weight = ts.weight;
    vec3 origin = offset_ray_origin(p, -ng, depth);
    vec3 dir = ts.l;
    vec3 absorption = thin ? vec3(0.0) : volume_absorption(mi);
    vec3 emitted = vec3(0.0);  // by the glass surfaces passed on the way
    // Punctual lights behind thin-walled glass, through its transmitted lobe (the bulb in a glass
    // shade): no ray can hit one, so light samples are the only way to them. Each of a few
    // lights is sampled (a light chosen by power would rarely be the bulb close behind the
    // glass, and then with a weight the denoiser clamps); of more, one chosen by power. Other
    // lights are reached by the path below.
    bool every_light = frame.light_count <= GLASS_LIGHTS;
    uint samples = thin ? (every_light ? frame.light_count : 1u) : 0u;
    [[dont_unroll]] for (uint k = 0u; k < samples; ++k) {
        NeeSample ls = every_light ? sample_punctual_light(k, p, rng_next2(rng), 1.0) : light_sample(p, rng_next3(rng));
        if (ls.pdf == 0.0 && dot(ls.weight, ls.weight) > 0.0 && dot(ls.dir, ng) < 0.0) {
            vec3 f = thin_transmission_eval_cos(m, n, v, ls.dir);
            if (dot(f, f) > 0.0) {
                emitted += f * ls.weight * trace_transmittance(origin, ls.dir, 0.0, shadow_ray_tmax(ls.dist), RAY_MASK_ALL);
            }
        }
    }
    if (dot(weight, weight) <= 0.0) return emitted;
    float travelled = 0.0;  // the path's length from p
    for (uint event = 0u; event < TRANSMISSION_EVENTS; ++event) {
        Hit h = trace_closest(origin, dir, 0.0, 1e6, RAY_MASK_ALL);
        if (h.instance == NO_HIT) return emitted + weight * env_eval(dir);
        travelled += h.t;
        if (any(greaterThan(absorption, vec3(0.0)))) weight *= exp(-absorption * h.t);
        HitSurface s = hit_surface(h.instance, h.primitive, h.bary, dir);
        MaterialInfo hm = materials[s.material];
        float through = s.mat.transmission * (1.0 - s.mat.metallic);
        // What the surface sends back along the path: all it reflects, glass included (the
        // light glass does not let through; the path goes on with what it does). A volume's
        // inner side reflects by the interface sample below instead.
        bool inner_side = hm.thickness > 0.0 && !s.front;
        if (through <= 0.0 || !inner_side) {
            emitted += weight * shade_hit(h, s, dir, 1.0, rng);
        } else if (emitter_visible_side(h.instance, h.primitive, dir)) {
            emitted += weight * s.mat.emissive;
        }
        if (through <= 0.0) {
            seen_at = thin || dot(dir, -v) > UNTURNED_COS ? travelled : 0.0;
            return emitted;
        }
        BrdfInput hm_brdf = BrdfInput(s.mat.base_color.rgb, s.mat.metallic, s.mat.roughness, dielectric_f0(hm.ior));
        TransmissionSample next;
        if (inner_side) {
            next = interface_sample(s.mat.roughness, hm.ior, s.normal, -dir, rng_next3(rng));
            if (next.crossed) absorption = vec3(0.0);
        } else {
            next = transmission_sample(hm_brdf, hm.thickness <= 0.0, hm.ior, s.normal, -dir, rng_next2(rng));
            next.weight *= through;
            if (hm.thickness > 0.0) {
                absorption = volume_absorption(hm);
                thin = false;
            }
        }
        weight *= next.weight;
        if (dot(weight, weight) <= 0.0) return emitted;
        origin = offset_ray(s.position, next.crossed ? -s.normal_geo : s.normal_geo);
        dir = next.l;
    }
    return emitted;
}

// What a blended surface lets through toward v: the view ray continued past it, through further
// blended surfaces with the chance of their uncovered share, shaded where it stops, `seen_at`
// beyond p (0 where the ray escaped).
#define BLEND_LAYERS 4u
vec3 behind_blend(vec3 p, vec3 ng, vec3 v, float depth, inout Rng rng, out float seen_at) {
    seen_at = 0.0;
    vec3 origin = offset_ray_origin(p, -ng, depth);
    vec3 dir = -v;
    float travelled = 0.0;
    for (uint layer = 0u; layer < BLEND_LAYERS; ++layer) {
        Hit h = trace_closest(origin, dir, 0.0, 1e6, RAY_MASK_ALL);
        if (h.instance == NO_HIT) return env_eval(dir);
        travelled += h.t;
        HitSurface s = hit_surface(h.instance, h.primitive, h.bary, dir);
        bool blended = (materials[s.material].flags & MATERIAL_BLEND) != 0u;
        if (!blended || layer + 1u == BLEND_LAYERS || rng_next(rng) < s.mat.base_color.a) {
            seen_at = travelled;
            return shade_hit(h, s, dir, 1.0, rng);
        }
        origin = offset_ray(s.position, -s.normal_geo);
    }
    return vec3(0.0);
}

// The glossy lobe's light sample of the emitters and the environment (area_light_sample), with
// a shadow ray that passes see-through surfaces, weighted against the lobe's own ray by the
// power heuristic.
vec3 area_light_estimate(vec3 origin, vec3 n, vec3 ng, vec3 v, BrdfInput m, float share, inout Rng rng) {
    NeeSample ls = area_light_sample(origin, rng_next3(rng), share);
    if (!(ls.pdf > 0.0) || dot(ls.dir, ng) <= 0.0) return vec3(0.0);
    vec3 f = brdf_eval_specular_cos(m, n, v, ls.dir);
    if (dot(f, f) <= 0.0) return vec3(0.0);
    float pdf = ggx_vndf_pdf(max(dot(n, v), 1e-4), max(dot(n, normalize(v + ls.dir)), 0.0), ggx_alpha(m.roughness));
    vec3 seen = trace_transmittance(origin, ls.dir, 0.0, shadow_ray_tmax(ls.dist), RAY_MASK_ALL);
    return ls.weight * f * seen * mis_power(ls.pdf, pdf);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    if (imageLoad(g_ids, px).x == NO_INSTANCE) {
        imageStore(out_radiance, px, vec4(0.0));
        imageStore(out_hit_distance, px, vec4(0.0));
        if (params.let_through != 0u) imageStore(out_let_through, px, vec4(0.0));
        return;
    }
    float depth = imageLoad(g_depth, px).r;
    vec3 n = imageLoad(g_normal, px).xyz;
    vec3 ng = imageLoad(g_normal_geo, px).xyz;
    vec3 p = world_position(px, depth);
    vec3 v = -camera_ray_dir(vec2(px) + 0.5 - frame.jitter);
    vec4 mr = imageLoad(g_metal_rough, px);
    MaterialInfo mi = materials[imageLoad(g_ids, px).y];
    BrdfInput m = BrdfInput(imageLoad(g_base_color, px).rgb, mr.x, mr.y, dielectric_f0(mi.ior));
    vec3 f0 = brdf_f0(m);
    float n_dot_v = max(dot(n, v), 1e-4);
    Rng rng = rng_init(uvec2(px), frame.frame_index, params.seed ^ SALT_REFLECTIONS);

    // Glass: what it lets through goes to out_let_through (composite leaves its share out of
    // the diffuse lobe). Opaque surfaces draw no numbers for it: their streams are as before.
    float transmitted = mr.w * (1.0 - m.metallic);
    float seen_at = 0.0;
    vec3 through = transmitted > 0.0 ? transmitted * transmitted_radiance(p, n, ng, v, depth, m, mi, rng, seen_at) : vec3(0.0);
    // A blended surface covers the share alpha of the pixel (composite scales its own light by
    // it); the rest shows what lies behind, added here.
    float cover = 1.0;
    vec3 behind = vec3(0.0);
    float behind_at = 0.0;
    if ((mi.flags & MATERIAL_BLEND) != 0u) {
        cover = imageLoad(g_base_color, px).a;
        if (cover < 1.0) behind = (1.0 - cover) * behind_blend(p, ng, v, depth, rng, behind_at);
    }
    // What the pixel shows through the surface, and where its history is: that of the larger
    // of what lies behind a blend and what comes through the glass.
    if (params.let_through != 0u) {
        float at = luminance(behind) >= luminance(cover * through) ? behind_at : seen_at;
        imageStore(out_let_through, px, vec4(cover * through + behind, at));
    }

    if (m.roughness > params.roughness_cutoff) {
        imageStore(out_radiance, px, vec4(cover * imageLoad(in_specular, px).rgb, 1.0));
        imageStore(out_hit_distance, px, vec4(0.0));
        return;
    }
    vec3 origin = offset_ray_origin(p, ng, depth);
    mat3 basis = orthonormal_basis(n);
    vec3 v_local = vec3(dot(v, basis[0]), dot(v, basis[1]), n_dot_v);
    float alpha = ggx_alpha(m.roughness);
    uint count = max(params.rays, 1u);
    bool mirror = m.roughness < MIRROR_ROUGHNESS;
    // The area lights' share of the light table: 0 where there are none (or on a mirror, whose
    // lobe no light sample can hit), and then no numbers are drawn for them and the streams are
    // as before.
    float area_share = mirror ? 0.0 : area_light_share();
    vec3 sum = vec3(0.0);
    float dist_sum = 0.0, hits = 0.0;
    for (uint i = 0u; i < count; ++i) {
        if (area_share > 0.0) sum += area_light_estimate(origin, n, ng, v, m, area_share, rng);
        vec3 l, weight;
        float pdf = 0.0;  // the ray's solid-angle density (0: a mirror's delta lobe)
        if (mirror) {
            l = reflect(-v, n);
            weight = fresnel_schlick(f0, n_dot_v);
        } else {
            // Visible-normal sampling: the estimate f cos / pdf of the GGX lobe reduces to
            // F(v.h) G2(v, l) / G1(v).
            vec3 h_local = sample_ggx_vndf(v_local, alpha, rng_next2(rng));
            vec3 l_local = reflect(-v_local, h_local);
            if (l_local.z <= 0.0) continue;
            l = normalize(basis * l_local);
            vec3 h = normalize(basis * h_local);
            float n_dot_l = l_local.z;
            float g2 = smith_visibility(n_dot_l, n_dot_v, alpha) * 4.0 * n_dot_l * n_dot_v;
            weight = fresnel_schlick(f0, dot(v, h)) * g2 / ggx_g1(n_dot_v, alpha);
            pdf = ggx_vndf_pdf(n_dot_v, h_local.z, alpha);
        }
        if (dot(l, ng) <= 0.0) continue;
        // Straight on through see-through surfaces (a window seen in a mirror shows what lies
        // behind it); the hit distance runs to where the ray stops.
        HitSurface s;
        float travelled;
        Hit h = trace_closest_through(origin, l, weight, rng, s, travelled);
        if (h.instance == NO_HIT) {
            float w = area_share > 0.0 ? mis_power(pdf, light_pdf_environment(l) / area_share) : 1.0;
            sum += weight * env_eval(l) * w;
        } else {
            float w = area_share > 0.0 ? mis_power(pdf, light_pdf_emitter(h.instance, h.primitive, origin, s.position) / area_share) : 1.0;
            sum += weight * shade_hit(h, s, l, w, rng);
            dist_sum += travelled;
            hits += 1.0;
        }
    }
    vec3 reflected = sum / float(count);
    imageStore(out_radiance, px, vec4(cover * (reflected + imageLoad(in_specular, px).rgb), 1.0));
    imageStore(out_hit_distance, px, vec4(hits > 0.0 ? dist_sum / hits : 0.0));
}
