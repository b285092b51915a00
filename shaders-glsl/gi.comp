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
// - direct light on the diffuse lobe from the environment: a sample of the environment alone
//   (the punctual lights are shaded by composite with ray-traced shadows, the emitters and the
//   other punctual lights resampled below: a draw that could pick one would be wasted there)
//   and the bounce ray escaping, combined with the power heuristic;
// - direct light from the punctual lights past the chain's (frame.chain_punctual; composite shades those
//   with the shadows chain's visibility) and from the emissive triangles: one light per pixel
//   resampled from candidates and last frame's choice (common/light_reservoir.glsl), whatever
//   the number of lights; its diffuse lobe goes into the diffuse signal and its specular lobe
//   into gi.specular, a punctual light's on every surface (the reflections pass adds it under
//   the cut-off, where its rays cannot hit a punctual light), an emitter's on rough ones (under
//   the cut-off the reflection rays find it). The bounce ray hitting an emitter adds no direct
//   light (the reservoir has it). The reservoir goes to gi.reservoir for the next frame, and
//   where last frame's choice, lit then, is now in shadow (an occluder the frame was not told
//   of), what it brought goes to gi.light_lost, so that the denoiser and TAA let go of it too;
// - indirect light (the bounce ray goes straight on through see-through surfaces, as the light
//   sample's shadow ray does, and through volumes of glass: common/pass_through.glsl): at the
//   bounce ray's hit, next-event
//   estimation toward a light chosen by power (any kind, with a shadow ray), and the light that
//   surface reflects from other surfaces from the radiance cache (every further bounce); with
//   `bounces` > 1 the path first continues by BSDF sampling, with a light sample at each
//   vertex, and the cache answers at the last one. Where the cache cannot answer (a corner, a
//   cell still empty, or the cache off) the path traces on.
//
// At half rate (`params.rate` 2) the pixels of a checkerboard that alternates every frame are
// traced, at quarter rate (4) one pixel of each 2x2 block, the four in turn
// (common/gi_fill.glsl); each of the others is marked for gi_fill, which gives it the mean of
// its traced neighbours that show the same surface; a pixel without one (an edge, a thin
// object) is traced as well. The denoiser's temporal stage then sees every pixel's own samples
// every other (fourth) frame. An untraced pixel hands its reprojected reservoir on unchanged,
// so a reservoir gains candidates every other (fourth) frame and keeps its choice in between.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// The shadow rays toward resampled lights teach the light grid what its cells see.
#define LIGHT_GRID_LEARN
#include "common/trace.glsl"
#include "common/brdf.glsl"
#include "common/light_sampling.glsl"
#include "common/gbuffer.glsl"
#include "common/ray_offset.glsl"
#include "common/light_reservoir.glsl"
#include "common/gi_fill.glsl"
#include "common/pass_through.glsl"
#define RC_BINDING 15
#include "common/radiance_cache.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D g_normal;
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 3, rgba16f) uniform readonly image2D g_base_color;
layout(set = 1, binding = 4, rgba8) uniform readonly image2D g_metal_rough;
layout(set = 1, binding = 5, rg32ui) uniform readonly uimage2D g_ids;
// Reprojection of last frame's reservoirs (1x1 placeholders when no light is resampled).
layout(set = 1, binding = 6, rg32f) uniform readonly image2D g_motion;
layout(set = 1, binding = 7, rg32f) uniform readonly image2D prev_depth;
layout(set = 1, binding = 8, rgba16f) uniform readonly image2D prev_normal_geo;
layout(set = 1, binding = 9, rg32ui) uniform readonly uimage2D prev_ids;
layout(set = 1, binding = 10, rgba32f) uniform readonly image2D prev_reservoir;
layout(set = 1, binding = 11, rgba32f) uniform writeonly image2D out_radiance;
layout(set = 1, binding = 12, rgba32f) uniform writeonly image2D out_specular;
layout(set = 1, binding = 13, rgba32f) uniform writeonly image2D out_reservoir;
// Luminance of what last frame's resampled light, visible then and occluded now, brought to the
// diffuse (x) and specular (y) signals; 1x1 like the reservoir when no light is resampled.
layout(set = 1, binding = 14, rg32f) uniform writeonly image2D out_light_lost;

layout(push_constant) uniform Params {
    uint bounces;            // vertices traced after the primary surface before the cache answers
    uint seed;
    float roughness_cutoff;  // the reflections pass's: rougher surfaces get gi.specular
    uint rate;               // pixels per traced pixel: 1, 2 or 4 (see main)
    uint resampled_emitters; // 0: no emitter, or every one a mesh light of the shadows chain
} params;

#define SALT_GI 0x67690000u

// Last frame's reservoir where this pixel's surface was, re-targeted here; empty after a cut, a
// light change, or where that pixel showed another surface.
// The stored texel, as it was; an empty reservoir's where there is none.
vec4 previous_reservoir_texel(ivec2 px, uint id, float z, vec3 ng) {
    vec4 empty = reservoir_pack(reservoir_empty());
    if ((frame.flags & (FRAME_RESET_HISTORY | FRAME_LIGHTS_CHANGED)) != 0u) return empty;
    ivec2 q = ivec2(floor(vec2(px) + 0.5 - imageLoad(g_motion, px).xy));
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) return empty;
    if (!reservoir_consistent(id, z, ng, imageLoad(prev_ids, q).x, imageLoad(prev_depth, q).r,
                              imageLoad(prev_normal_geo, q).xyz)) {
        return empty;
    }
    return imageLoad(prev_reservoir, q);
}
LightReservoir previous_reservoir(ivec2 px, uint id, float z, vec3 ng, ShadingPoint sp) {
    return reservoir_unpack(previous_reservoir_texel(px, id, z, ng), sp);
}

// The lobes gi gathers at pixel `px`: a diffuse one (some albedo left by the metalness) and a
// specular one (rougher than the reflection cut-off).
bool has_diffuse(ivec2 px) {
    vec3 albedo = imageLoad(g_base_color, px).rgb * (1.0 - imageLoad(g_metal_rough, px).x);
    return max(albedo.r, max(albedo.g, albedo.b)) > 0.0;
}
bool has_rough(ivec2 px) { return imageLoad(g_metal_rough, px).y > params.roughness_cutoff; }

// Traces pixel `px`'s samples and writes its outputs but gi.light_lost, which it returns (x
// diffuse, y specular; at a reduced rate an untraced pixel shares its pair's).
vec2 shade(ivec2 px) {
    vec4 mr = imageLoad(g_metal_rough, px);
    bool rough = has_rough(px);
    bool diffuse = has_diffuse(px);
    bool resampled = reservoirs_present(params.resampled_emitters != 0u);
    uvec2 ids = imageLoad(g_ids, px).xy;
    // (A smooth metal takes only the resampled punctual lights' specular lobe here.)
    if (ids.x == NO_INSTANCE || !(diffuse || rough || resampled_lights_present())) {
        imageStore(out_radiance, px, vec4(0.0));
        imageStore(out_specular, px, vec4(0.0));
        if (resampled) imageStore(out_reservoir, px, reservoir_pack(reservoir_empty()));
        return vec2(0.0);
    }
    BrdfInput m = BrdfInput(imageLoad(g_base_color, px).rgb, mr.x, mr.y, dielectric_f0(materials[ids.y].ior));
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

    // Direct light. Sampled from the shadow ray's own origin: direction and distance measured
    // from the surface point would overshoot by the offset, and the shadow ray would hit the
    // emitter it aims at. Three shadow rays at most, then the bounce, from one call site (the
    // compute backend inlines its traversal at every call, and each copy lengthens a CPU
    // driver's compile; an unrolled loop would copy it again):
    //   0: a sample of the environment alone (the other lights are composite's or the
    //      reservoir's);
    //   1: the frame's resampled-light candidate, tested before it is merged;
    //   2: last frame's resampled light, re-tested where it wins the merge;
    //   3: the bounce, cosine-weighted about the shading normal, kept above the geometric
    //      surface (nothing to gather for a smooth metal, which is here only for the resampled
    //      lights), straight on through see-through surfaces as the shadow rays go, and into
    //      and out of volumes of glass (pass_on; each surface it passes sends it round again).
    ShadingPoint sp = ShadingPoint(origin, n, ng, v, m, rough);
    LightReservoir r = reservoir_empty();
    LightReservoir prev = reservoir_empty();
    if (resampled) {
        r = reservoir_candidates(sp, rng);
        prev = previous_reservoir(px, ids.x, depth, ng, sp);
    }
    NeeSample chosen = nee_none();  // the resampled light's sample, once found visible
    vec2 lost = vec2(0.0);          // gi.light_lost
    // Whether the environment sends light (else nothing to draw toward it).
    bool env_lit = light_table.entry_count > 0u && light_entries[light_table.env_entry].pmf > 0.0;
    vec3 dir = vec3(0.0);           // the bounce's direction
    float pdf = 0.0;                // and its density
    Passage way = passage_start(origin, dir);  // its way past see-through surfaces and glass
    Hit bounce_hit;                 // where it stopped (NO_HIT: escaped, or not traced)
    bounce_hit.instance = NO_HIT;
    HitSurface s;
    [[dont_unroll]] for (uint k = 0u; k < 4u; ++k) {
        NeeSample ls = nee_none();
        float cos_l = 0.0;
        bool traced = true;
        vec3 o = way.from, d = way.dir;
        float tmax = 1e6;
        if (k == 3u) {
            if (way.steps == 0u) {
                way.dir = dir = orthonormal_basis(n) * sample_cosine_hemisphere(rng_next2(rng));
                pdf = max(dot(n, dir), 0.0) * INV_PI;
                if (!((diffuse || rough) && dot(dir, ng) > 0.0 && pdf > 0.0)) break;
            }
            o = way.from;
            d = way.dir;
        } else {
            if (k == 0u) {
                // The numbers are drawn either way, so scenes without an environment keep their
                // streams.
                vec3 u = rng_next3(rng);
                if (!env_lit) continue;
                ls = sample_environment(u.yz, 1.0);
                if (!(ls.pdf > 0.0)) continue;
            } else if (k == 1u) {
                if (!(r.w_sum > 0.0)) continue;
                ls = reservoir_light_sample(sp, r.light, r.u, true);
            } else {
                // (Without resampled lights no random number is drawn here, so those scenes keep
                // the random streams, and so the images, they had before the reservoirs.)
                if (!resampled) continue;
                // An occluded candidate of this frame has weight 0 here, only its count.
                if (!reservoir_merge(r, prev.light, prev.u, prev.w_sum, prev.p_hat, prev.m, rng_next(rng))) continue;
                ls = reservoir_light_sample(sp, r.light, r.u, true);
            }
            cos_l = max(dot(n, ls.dir), 0.0);
            traced = dot(ls.weight, ls.weight) > 0.0 && dot(ls.dir, ng) > 0.0 && cos_l > 0.0;
            o = origin;
            d = ls.dir;
            tmax = shadow_ray_tmax(ls.dist);
        }
        Hit h;
        h.instance = NO_HIT;
        if (traced) h = trace_ray(o, d, 0.0, tmax, RAY_MASK_ALL, k < 3u);
        if (k == 3u) {
            bounce_hit = h;
            if (h.instance == NO_HIT) break;
            s = hit_surface(h.instance, h.primitive, h.bary, way.dir);
            if (pass_on(s, h.t, way, rng)) --k;  // the loop's increment brings it back to the bounce
            continue;
        }
        // What passes the see-through surfaces on the way scales the sample.
        vec3 unshadowed = ls.weight;
        ls.weight = traced && h.instance == NO_HIT ? ls.weight * hit_transmittance : vec3(0.0);
        bool visible = dot(ls.weight, ls.weight) > 0.0;
        if (k > 0u && traced) {
            if (reservoir_punctual(r.light)) light_grid_learn(origin, r.light, visible);
            else light_grid_learn_point(origin, origin + ls.dir * ls.dist, visible);
        }
        if (k == 0u) {
            if (!visible) continue;
            float w = mis_power(ls.pdf, cos_l * INV_PI);
            l_sum += ls.weight * cos_l * INV_PI * brdf_diffuse_weight(m, n, v, ls.dir) * w;
            if (rough) spec_sum += ls.weight * brdf_eval_specular_cos(m, n, v, ls.dir) * w;
        } else if (visible) {
            chosen = ls;
        } else {
            // Last frame's choice, lit then (an occluded one is carried with weight 0), is in
            // shadow now: what it would have brought is what the histories hold and must lose.
            if (k == 2u && traced) {
                vec3 le = unshadowed * reservoir_weight(r);
                lost = vec2(luminance(le * cos_l * INV_PI * brdf_diffuse_weight(m, n, v, ls.dir)),
                            luminance(le * brdf_eval_specular_cos(m, n, v, ls.dir)));
                if (!diffuse) lost.x = 0.0;
                if (!(rough || reservoir_punctual(r.light))) lost.y = 0.0;
            }
            // Carried forward with weight 0: its candidates still count in M.
            r.w_sum = 0.0;
        }
    }
    if (resampled) {
        float w = reservoir_weight(r);
        if (w > 0.0) {
            vec3 le = chosen.weight * w;
            float cos_l = max(dot(n, chosen.dir), 0.0);
            l_sum += le * cos_l * INV_PI * brdf_diffuse_weight(m, n, v, chosen.dir);
            if (rough || reservoir_punctual(r.light)) spec_sum += le * brdf_eval_specular_cos(m, n, v, chosen.dir);
        }
        imageStore(out_reservoir, px, reservoir_pack(r));
    }

    if (pdf > 0.0 && dot(dir, ng) > 0.0 && (diffuse || rough)) {
        vec3 lobe = brdf_diffuse_weight(m, n, v, dir);
        vec3 bounce = vec3(0.0);
        // With cosine sampling, the Lambert lobe's (1/pi) L cos / pdf is L itself. Past a volume
        // of glass, which no light sample crosses, the sky and the emitters count as they would
        // if one did: the light sample's share is left out there, and with it the light that
        // glass focuses from a sun or a small emitter (a caustic, which one sample a pixel would
        // show as a blob after the denoiser; the reference has it).
        if (bounce_hit.instance == NO_HIT) {
            bounce = env_eval(way.dir) * (env_lit ? mis_power(pdf, env_pdf(way.dir)) : 1.0);
        } else {
            // An emitter the reservoirs can draw is theirs; one they cannot (no power in the
            // table) only this ray finds.
            if (emitter_visible_side(bounce_hit.instance, bounce_hit.primitive, way.dir) &&
                !(light_pdf_emitter(bounce_hit.instance, bounce_hit.primitive, origin, s.position) > 0.0)) {
                bounce += s.mat.emissive;
            }
            uint traced = max(params.bounces, 1u);
            uint vertices = rc.enabled != 0u ? max(traced, RC_VERTICES) : traced;
            bounce += rc_radiance_leaving(s, way.dir, bounce_hit.t, traced - 1u, vertices, true,
                                          rc_copy_written(frame.frame_index), rng);
        }
        bounce *= way.weight;
        l_sum += lobe * bounce;
        if (rough) spec_sum += bounce * brdf_eval_specular_cos(m, n, v, dir) / pdf;
    }
    imageStore(out_radiance, px, vec4(diffuse ? l_sum : vec3(0.0), 1.0));
    imageStore(out_specular, px, vec4(spec_sum, 1.0));
    return lost;
}

// At a reduced rate, what gi_fill needs to fill untraced pixel `px` (common/gi_fill.glsl): its
// neighbours on this frame's lattice that show the same surface, and its signals. A neighbour shows
// it when it is the same instance (two floors either side of a wall seen edge-on meet on screen at
// one depth and normal) with the lobes this pixel gathers (its signals are zero for a lobe it
// lacks), the shading normals are within 25 degrees, and each point lies within 1% of its depth of
// the other's tangent plane. The specular signal is the rough lobe's, and where punctual lights are
// resampled also their specular lobe on every surface; a neighbour on the other side of the
// reflection cut-off would bring the rough lobe to a pixel whose reflection rays cover it, or lack
// it. 0 where no neighbour qualifies (the pixel is traced instead) or where the pixel needs no fill
// (no surface, or no signal to gather: shade() writes its zeros).
uint fill_sources(ivec2 px) {
    uint id = imageLoad(g_ids, px).x;
    bool diffuse = has_diffuse(px), rough = has_rough(px);
    bool specular = rough || resampled_lights_present();
    if (id == NO_INSTANCE || !(diffuse || specular)) return 0u;
    float depth = imageLoad(g_depth, px).r;
    vec3 n = imageLoad(g_normal, px).xyz;
    vec3 p = world_position(px, depth);
    uint sources = 0u;
    for (int i = 0; i < GI_FILL_NEIGHBOURS; ++i) {
        ivec2 q = px + GI_FILL_OFFSETS[i];
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
        if (!gi_fill_on_lattice(q, params.rate, frame.frame_index)) continue;
        if (imageLoad(g_ids, q).x != id || (diffuse && !has_diffuse(q)) || (specular && has_rough(q) != rough)) continue;
        vec3 nq = imageLoad(g_normal, q).xyz;
        float depth_q = imageLoad(g_depth, q).r;
        vec3 d = world_position(q, depth_q) - p;
        if (dot(n, nq) < 0.9 || abs(dot(d, n)) > 0.01 * depth || abs(dot(d, nq)) > 0.01 * depth_q) continue;
        sources |= 1u << i;
    }
    if (sources == 0u) return 0u;
    return sources | (diffuse ? GI_FILL_DIFFUSE : 0u) | (specular ? GI_FILL_SPECULAR : 0u);
}

// An untraced pixel's reservoir for the next frame: last frame's where it shows the same
// surface, unchanged (the next frame traces the pixel and merges it with its own candidates).
void carry_reservoir(ivec2 px) {
    vec4 texel = previous_reservoir_texel(px, imageLoad(g_ids, px).x, imageLoad(g_depth, px).r,
                                          imageLoad(g_normal_geo, px).xyz);
    imageStore(out_reservoir, px, texel);
}

// At full rate one invocation per pixel. At a reduced rate one per horizontal pair of pixels:
// it traces the pair's pixel on this frame's lattice first (at quarter rate, every other row
// has none), then marks each other pixel for gi_fill or, where that cannot fill it, traces it
// too. The pixels are shaded from one call site in a loop: the compute backend inlines its
// traversal at every call, and a second copy would lengthen a CPU driver's compile.
void main() {
    uint rate = params.rate;
    bool reduced = rate > 1u;
    ivec2 g = ivec2(gl_GlobalInvocationID.xy);
    ivec2 first = reduced ? ivec2(2 * g.x, g.y) : g;
    ivec2 second = first + ivec2(1, 0);
    bool second_first = reduced && gi_fill_on_lattice(second, rate, frame.frame_index);
    vec2 lost = vec2(0.0);
    [[dont_unroll]] for (uint k = 0u; k < (reduced ? 2u : 1u); ++k) {
        ivec2 px = (k == 0u) != second_first ? first : second;
        if (any(greaterThanEqual(px, ivec2(frame.size)))) continue;
        if (reduced && !gi_fill_on_lattice(px, rate, frame.frame_index)) {
            uint sources = fill_sources(px);
            if (sources != 0u) {
                imageStore(out_radiance, px, vec4(0.0, 0.0, 0.0, -float(sources)));
                imageStore(out_specular, px, vec4(0.0));
                if (reservoirs_present(params.resampled_emitters != 0u)) {
                    carry_reservoir(px);
                    imageStore(out_light_lost, px, vec4(lost, 0.0, 0.0));
                }
                continue;
            }
        }
        lost = shade(px);
        if (reservoirs_present(params.resampled_emitters != 0u)) imageStore(out_light_lost, px, vec4(lost, 0.0, 0.0));
    }
}
