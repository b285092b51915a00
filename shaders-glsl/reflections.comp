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
// glass, as the reference traces it; the view ray continued past a blend) is a signal of its
// own, out_let_through, with where it was seen: its history follows that, the reflection's its
// own hit, and each has its denoiser. A reflection ray that meets a volume of glass goes on
// through it too (a glass ball seen in a mirror).
//
// Every ray of the pixel goes through one trace_ray call and every hit it shades through one
// shade_hit call, in one loop over the pixel's jobs: lavapipe inlines a whole traversal (and
// shade_hit's path through the radiance cache) at each call site, and with the eight sites
// this pass had, its first compile on a cold shader cache took minutes.
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

// Most events on a path through glass (refractions, reflections inside a volume, glass passed).
#define TRANSMISSION_EVENTS 8u
// A path leaving a volume within about 2.5 degrees of the view ray counts as not turned.
#define UNTURNED_COS 0.999
// Up to this many punctual lights, each is sampled through thin-walled glass.
#define GLASS_LIGHTS 8u
// Most blended surfaces the view ray is continued past.
#define BLEND_LAYERS 4u

// The pixel's surface, from the G-buffer.
struct Pixel {
    vec3 p;
    vec3 n;
    vec3 ng;
    vec3 v;
    float depth;
    BrdfInput m;
    float ior;
    bool thin;          // thin-walled glass (no volume)
    vec3 absorption;    // its volume's Beer-Lambert coefficient
    float transmitted;  // the share of its light the glass lets through
    float cover;        // the share a blended surface covers (1 for others)
    vec3 origin;        // where reflection rays start
    float area_share;   // the area lights' share of the light table (0: no area-light samples)
};

// What a ray is for, and so what its hit does.
#define RAY_SHADOW 0u   // a light sample's shadow ray: adds `weight` times what passes
#define RAY_GLASS 1u    // a path through glass: shades what it meets, passes transmissive surfaces
#define RAY_BLEND 2u    // the view ray continued past blended surfaces, shaded where it stops
#define RAY_REFLECT 3u  // a reflection ray, straight on through see-through surfaces (pass_through)

// Where a ray's light goes.
#define TO_GLASS 0u       // what the glass lets through
#define TO_BEHIND 1u      // what shows past a blend
#define TO_REFLECTION 2u  // the reflection (summed over its rays)

struct Ray {
    uint kind;
    uint target;
    vec3 origin;
    vec3 dir;
    float tmax;
    vec3 weight;      // of the light the ray finds
    float pdf;        // a reflection ray's solid-angle density, for MIS (0: a mirror's delta lobe)
    uint steps;       // surfaces passed, or a glass path's events
    float travelled;  // from where the job began
    vec3 absorption;  // inside a volume: its Beer-Lambert coefficient
    bool thin;        // a glass path that has entered no volume
};

Ray ray_new(uint kind, uint target, vec3 origin, vec3 dir, float tmax, vec3 weight) {
    return Ray(kind, target, origin, dir, tmax, weight, 0.0, 0u, 0.0, vec3(0.0), true);
}

// Light samples taken through thin-walled glass: punctual lights behind it (the bulb in a glass
// shade) reach the path only so, as no ray can hit one. Each of a few lights is sampled (a light
// chosen by power would rarely be the bulb close behind the glass, and then with a weight the
// denoiser clamps); of more, one chosen by power. The path reaches other lights.
uint glass_light_samples(Pixel px) {
    if (px.transmitted <= 0.0 || !px.thin) return 0u;
    return frame.light_count <= GLASS_LIGHTS ? frame.light_count : 1u;
}

// The path through the glass (common/transmission.glsl), weighted by the share it lets through.
bool start_glass_path(Pixel px, inout Ray ray, inout Rng rng) {
    TransmissionSample ts = transmission_sample(px.m, px.thin, px.ior, px.n, px.v, rng_next2(rng));
    if (dot(ts.weight, ts.weight) <= 0.0) return false;
    vec3 weight = px.cover * px.transmitted * ts.weight;
    ray = ray_new(RAY_GLASS, TO_GLASS, offset_ray_origin(px.p, -px.ng, px.depth), ts.l, 1e6, weight);
    ray.thin = px.thin;
    ray.absorption = px.absorption;
    return true;
}

// Light sample k through thin-walled glass (glass_light_samples).
bool start_glass_light(Pixel px, uint k, inout Ray ray, inout Rng rng) {
    NeeSample ls = frame.light_count <= GLASS_LIGHTS ? sample_punctual_light(k, px.p, rng_next2(rng), 1.0)
                                                     : light_sample(px.p, rng_next3(rng));
    if (!(ls.pdf == 0.0 && dot(ls.weight, ls.weight) > 0.0 && dot(ls.dir, px.ng) < 0.0)) return false;
    vec3 f = thin_transmission_eval_cos(px.m, px.n, px.v, ls.dir);
    if (dot(f, f) <= 0.0) return false;
    vec3 origin = offset_ray_origin(px.p, -px.ng, px.depth);
    ray = ray_new(RAY_SHADOW, TO_GLASS, origin, ls.dir, shadow_ray_tmax(ls.dist), px.cover * px.transmitted * f * ls.weight);
    return true;
}

// The glossy lobe's light sample of the emitters and the environment (area_light_sample), with
// a shadow ray that passes see-through surfaces, weighted against the lobe's own ray by the
// power heuristic.
bool start_area_light(Pixel px, inout Ray ray, inout Rng rng) {
    NeeSample ls = area_light_sample(px.origin, rng_next3(rng), px.area_share);
    if (!(ls.pdf > 0.0) || dot(ls.dir, px.ng) <= 0.0) return false;
    vec3 f = brdf_eval_specular_cos(px.m, px.n, px.v, ls.dir);
    if (dot(f, f) <= 0.0) return false;
    float n_dot_v = max(dot(px.n, px.v), 1e-4);
    float pdf = ggx_vndf_pdf(n_dot_v, max(dot(px.n, normalize(px.v + ls.dir)), 0.0), ggx_alpha(px.m.roughness));
    ray = ray_new(RAY_SHADOW, TO_REFLECTION, px.origin, ls.dir, shadow_ray_tmax(ls.dist), ls.weight * f * mis_power(ls.pdf, pdf));
    return true;
}

// A reflection ray: the mirror direction, or visible-normal sampling of the GGX lobe, whose
// estimate f cos / pdf reduces to F(v.h) G2(v, l) / G1(v).
bool start_reflection(Pixel px, inout Ray ray, inout Rng rng) {
    float n_dot_v = max(dot(px.n, px.v), 1e-4);
    vec3 l, weight;
    float pdf = 0.0;
    if (px.m.roughness < MIRROR_ROUGHNESS) {
        l = reflect(-px.v, px.n);
        weight = fresnel_schlick(brdf_f0(px.m), n_dot_v);
    } else {
        mat3 basis = orthonormal_basis(px.n);
        vec3 v_local = vec3(dot(px.v, basis[0]), dot(px.v, basis[1]), n_dot_v);
        float alpha = ggx_alpha(px.m.roughness);
        vec3 h_local = sample_ggx_vndf(v_local, alpha, rng_next2(rng));
        vec3 l_local = reflect(-v_local, h_local);
        if (l_local.z <= 0.0) return false;
        l = normalize(basis * l_local);
        vec3 h = normalize(basis * h_local);
        float n_dot_l = l_local.z;
        float g2 = smith_visibility(n_dot_l, n_dot_v, alpha) * 4.0 * n_dot_l * n_dot_v;
        weight = fresnel_schlick(brdf_f0(px.m), dot(px.v, h)) * g2 / ggx_g1(n_dot_v, alpha);
        pdf = ggx_vndf_pdf(n_dot_v, h_local.z, alpha);
    }
    if (dot(l, px.ng) <= 0.0) return false;
    ray = ray_new(RAY_REFLECT, TO_REFLECTION, px.origin, l, 1e6, weight);
    ray.pdf = pdf;
    return true;
}

// A glass path's next event at the transmissive surface s it met: from inside a volume the
// interface reflects or lets it out; from outside it passes through (thin glass) or refracts
// into the volume. False where the path ends.
bool glass_event(inout Ray ray, HitSurface s, inout Rng rng) {
    MaterialInfo hm = materials[s.material];
    TransmissionSample next;
    if (hm.thickness > 0.0 && !s.front) {
        next = interface_sample(s.mat.roughness, hm.ior, s.normal, -ray.dir, rng_next3(rng));
        if (next.crossed) ray.absorption = vec3(0.0);
    } else {
        BrdfInput m = BrdfInput(s.mat.base_color.rgb, s.mat.metallic, s.mat.roughness, dielectric_f0(hm.ior));
        next = transmission_sample(m, hm.thickness <= 0.0, hm.ior, s.normal, -ray.dir, rng_next2(rng));
        next.weight *= s.mat.transmission * (1.0 - s.mat.metallic);
        if (hm.thickness > 0.0) {
            ray.absorption = volume_absorption(hm);
            ray.thin = false;
        }
    }
    ray.kind = RAY_GLASS;
    ray.weight *= next.weight;
    ray.origin = offset_ray(s.position, next.crossed ? -s.normal_geo : s.normal_geo);
    ray.dir = next.l;
    return dot(ray.weight, ray.weight) > 0.0 && ++ray.steps < TRANSMISSION_EVENTS;
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, ivec2(frame.size)))) return;
    if (imageLoad(g_ids, pixel).x == NO_INSTANCE) {
        imageStore(out_radiance, pixel, vec4(0.0));
        imageStore(out_hit_distance, pixel, vec4(0.0));
        if (params.let_through != 0u) imageStore(out_let_through, pixel, vec4(0.0));
        return;
    }
    Pixel px;
    px.depth = imageLoad(g_depth, pixel).r;
    px.n = imageLoad(g_normal, pixel).xyz;
    px.ng = imageLoad(g_normal_geo, pixel).xyz;
    px.p = world_position(pixel, px.depth);
    px.v = -camera_ray_dir(vec2(pixel) + 0.5 - frame.jitter);
    vec4 mr = imageLoad(g_metal_rough, pixel);
    MaterialInfo mi = materials[imageLoad(g_ids, pixel).y];
    vec4 base_color = imageLoad(g_base_color, pixel);
    px.m = BrdfInput(base_color.rgb, mr.x, mr.y, dielectric_f0(mi.ior));
    px.ior = mi.ior;
    px.thin = mi.thickness <= 0.0;
    px.absorption = px.thin ? vec3(0.0) : volume_absorption(mi);
    // Glass: what it lets through goes to out_let_through (composite leaves its share out of
    // the diffuse lobe). A blended surface covers the share alpha of the pixel (composite scales
    // its own light by it); the rest shows what lies behind, also let through.
    px.transmitted = mr.w * (1.0 - px.m.metallic);
    px.cover = (mi.flags & MATERIAL_BLEND) != 0u ? base_color.a : 1.0;
    px.origin = offset_ray_origin(px.p, px.ng, px.depth);
    bool reflects = px.m.roughness <= params.roughness_cutoff;
    // The area lights' share of the light table: 0 where there are none (or on a mirror, whose
    // lobe no light sample can hit), and then no numbers are drawn for them.
    px.area_share = reflects && px.m.roughness >= MIRROR_ROUGHNESS ? area_light_share() : 0.0;
    Rng rng = rng_init(uvec2(pixel), frame.frame_index, params.seed ^ SALT_REFLECTIONS);

    // The jobs, in order: the path through glass and its light samples, the view ray past a
    // blend, then per reflection ray its area-light sample and the ray. Opaque surfaces draw no
    // numbers for the first two.
    uint glass_jobs = px.transmitted > 0.0 ? 1u + glass_light_samples(px) : 0u;
    uint blend_jobs = px.cover < 1.0 ? 1u : 0u;
    uint count = max(params.rays, 1u);
    uint jobs = glass_jobs + blend_jobs + (reflects ? 2u * count : 0u);

    vec3 found[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));  // by target
    float seen_at = 0.0, behind_at = 0.0;  // where along the view ray each was seen
    float dist_sum = 0.0, hits = 0.0;      // the reflection rays' hit distances
    Ray ray;
    bool tracing = false;
    uint job = 0u;
    [[dont_unroll]] while (tracing || job < jobs) {
        if (!tracing) {
            if (job < glass_jobs) {
                tracing = job == 0u ? start_glass_path(px, ray, rng) : start_glass_light(px, job - 1u, ray, rng);
            } else if (job < glass_jobs + blend_jobs) {
                ray = ray_new(RAY_BLEND, TO_BEHIND, offset_ray_origin(px.p, -px.ng, px.depth), -px.v, 1e6, vec3(1.0 - px.cover));
                tracing = true;
            } else if (((job - glass_jobs - blend_jobs) & 1u) == 0u) {
                tracing = px.area_share > 0.0 && start_area_light(px, ray, rng);
            } else {
                tracing = start_reflection(px, ray, rng);
            }
            ++job;
            continue;
        }
        Hit h = trace_ray(ray.origin, ray.dir, 0.0, ray.tmax, RAY_MASK_ALL, ray.kind == RAY_SHADOW);
        if (ray.kind == RAY_SHADOW || h.instance == NO_HIT) {
            tracing = false;
            if (ray.kind == RAY_SHADOW) {
                if (h.instance == NO_HIT) found[ray.target] += ray.weight * hit_transmittance;
                continue;
            }
            // Escaped: the environment, weighted against the area-light sample for a glossy lobe.
            bool mis = ray.kind == RAY_REFLECT && px.area_share > 0.0;
            float w = mis ? mis_power(ray.pdf, light_pdf_environment(ray.dir) / px.area_share) : 1.0;
            found[ray.target] += ray.weight * env_eval(ray.dir) * w;
            continue;
        }
        ray.travelled += h.t;
        HitSurface s = hit_surface(h.instance, h.primitive, h.bary, ray.dir);
        float through = s.mat.transmission * (1.0 - s.mat.metallic);
        bool volume = materials[s.material].thickness > 0.0;
        // What the hit does: shade it (with this weight on its emission), and where the ray
        // goes on (`tracing`, and after shading a glass event where `glass_next`).
        bool shade = true, glass_next = false;
        float emission_weight = 1.0;
        if (ray.kind == RAY_REFLECT) {
            if (ray.steps < PASS_THROUGH_MAX && pass_through(s, ray.dir, ray.weight, rng)) {
                ++ray.steps;
                ray.origin = offset_ray(s.position, -s.normal_geo);
                continue;
            }
            if (px.area_share > 0.0) {
                float light_pdf = light_pdf_emitter(h.instance, h.primitive, px.origin, s.position);
                emission_weight = mis_power(ray.pdf, light_pdf / px.area_share);
            }
            dist_sum += ray.travelled;
            hits += 1.0;
            // A volume of glass shows what it reflects (shaded here) and what comes through it.
            glass_next = through > 0.0 && volume && s.front;
            ray.steps = 0u;
        } else if (ray.kind == RAY_BLEND) {
            bool blended = (materials[s.material].flags & MATERIAL_BLEND) != 0u;
            if (blended && ray.steps + 1u < BLEND_LAYERS && rng_next(rng) >= s.mat.base_color.a) {
                ++ray.steps;
                ray.origin = offset_ray(s.position, -s.normal_geo);
                continue;
            }
            behind_at = ray.travelled;
        } else {
            if (any(greaterThan(ray.absorption, vec3(0.0)))) ray.weight *= exp(-ray.absorption * h.t);
            // Every surface sends back all it reflects, glass included (the light it does not
            // let through; the path goes on with what it does). A volume's inner side reflects
            // by its interface event instead, and only its emission is added here.
            bool inner_side = volume && !s.front;
            shade = through <= 0.0 || !inner_side;
            if (!shade && emitter_visible_side(h.instance, h.primitive, ray.dir)) found[ray.target] += ray.weight * s.mat.emissive;
            glass_next = through > 0.0;
            // Where the path stops, what it saw lies (near enough) on the view ray's line if
            // the glass did not turn it: through thin glass, or out of a volume in the
            // direction it went in (a slab shifts the line a little). 0 for a lens.
            if (!glass_next && ray.target == TO_GLASS) seen_at = ray.thin || dot(ray.dir, -px.v) > UNTURNED_COS ? ray.travelled : 0.0;
        }
        if (shade) found[ray.target] += ray.weight * shade_hit(h, s, ray.dir, emission_weight, rng);
        tracing = glass_next && glass_event(ray, s, rng);
    }

    // What the pixel shows through the surface, and where its history is: that of the larger
    // of what lies behind a blend and what comes through the glass.
    if (params.let_through != 0u) {
        vec3 glass = found[TO_GLASS], behind = found[TO_BEHIND];
        float at = luminance(behind) >= luminance(glass) ? behind_at : seen_at;
        imageStore(out_let_through, pixel, vec4(glass + behind, at));
    }
    vec3 specular = imageLoad(in_specular, pixel).rgb;
    vec3 reflected = reflects ? found[TO_REFLECTION] / float(count) : vec3(0.0);
    imageStore(out_radiance, pixel, vec4(px.cover * (reflected + specular), 1.0));
    imageStore(out_hit_distance, pixel, vec4(hits > 0.0 ? dist_sum / hits : 0.0));
}
