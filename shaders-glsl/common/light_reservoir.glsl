// Direct light from the punctual lights past the chain's (frame.chain_punctual) and from the emissive
// triangles, whatever their number: resampled importance sampling with a per-pixel reservoir
// kept across frames (the candidate and temporal steps of ReSTIR DI, Bitterli et al. 2020).
// gi.comp drives it and traces its shadow rays.
//
// - A sample is an entry of the light table (a punctual light's is its index; an emissive
//   triangle's comes after them) and the two numbers u that place a point on it (sphere and
//   disk lights, triangles; the other lights ignore u), so it means the same thing at any
//   shading point.
// - Candidates: RIS_CANDIDATES, each an emissive triangle (with the probability of the
//   emitters' share of the two kinds' power; its group of the light grid by power x what the
//   point's cell has learned to see of it, then a triangle of the group by power:
//   light_grid_emitter_pick) or a resampled light from the shading point's
//   cell of the light grid (common/light_grid.glsl: the resampled lights that reach it, weighed
//   by what they can deliver there), or by power from all of them outside the grid.
// - Target p_hat: the luminance of the unshadowed contribution f(v, l) cos Le per unit of u,
//   so that distance, range, spot cone, the emitter's cosine and area, the surface's cosine
//   and both lobes steer the choice, times what the light grid has learned of how often the
//   light's group is seen from the pixel's cell (light_grid_seen; an emissive triangle's group
//   is the region its sampled point lies in: light_grid_seen_point). For a triangle Le is its
//   material's emissive factor, without the texture (a texture read per candidate; a target
//   need only be positive wherever the contribution is), and f only the lobes gi keeps of an
//   emitter's light: the diffuse one, and the specular one where the surface is rougher than
//   the reflections' cut-off (under it the reflection rays find the emitters).
// - This pixel's own visibility is not in p_hat (a ray per candidate would cost what it saves), but it is in
//   what a reservoir carries forward: the frame's chosen candidate is shadow-tested before it is
//   merged, an occluded one enters with weight 0 (its candidates still count in M), and last
//   frame's choice is tested again when it wins (occluded: weight 0, count kept). So once a pixel has found a light it can see,
//   it keeps it until a better visible one turns up; a light behind a wall can be drawn (noise)
//   but never shine through it.
// - Unbiased contribution weight W = w_sum / (M p_hat(y)); the estimate is f Le(y) W, with the
//   emitter's texture. Merging last frame's reservoir uses the 1/M weights (biased where
//   neighbouring surfaces differ, which the reprojection test limits) with its M capped at
//   RESERVOIR_M_CAP, so an old choice cannot outweigh new candidates forever.
// The cost per pixel is RIS_CANDIDATES CDF searches (log N each) and BRDF evaluations and at
// most two shadow rays, however many lights there are.
#ifndef LIGHT_RESERVOIR_GLSL
#define LIGHT_RESERVOIR_GLSL

#extension GL_EXT_control_flow_attributes : require

#include "light_sampling.glsl"
#include "brdf.glsl"
#include "color.glsl"

// Candidates per pixel and frame (the ReSTIR paper uses 32; RTXDI's fast preset 4 local lights).
// Rust: render::plan::RIS_CANDIDATES.
#define RIS_CANDIDATES 8u
// Last frame's candidates count at most this many times the frame's own (the paper's 20x).
#define RESERVOIR_M_CAP (20.0 * float(RIS_CANDIDATES))

struct LightReservoir {
    uint light;    // index into lights[]; NO_LIGHT when empty
    vec2 u;        // the point on the light
    float w_sum;   // sum of the resampling weights merged
    float m;       // candidates behind it
    float p_hat;   // the target of the chosen sample at this pixel
};

LightReservoir reservoir_empty() { return LightReservoir(NO_LIGHT, vec2(0.0), 0.0, 0.0, 0.0); }

// Whether some punctual light is left to resampling.
bool resampled_lights_present() { return frame.light_count > frame.chain_punctual && light_table.entry_count > 0u; }

// The emissive triangles' share of the light table's power (0: none emits).
float emitter_share() {
    uint first = light_table.first_emitter_entry;
    uint end = light_table.env_entry;
    if (light_table.entry_count == 0u || first >= end) return 0.0;
    return light_entries[end - 1u].cdf - (first == 0u ? 0.0 : light_entries[first - 1u].cdf);
}

// Whether pixels keep reservoirs: some punctual light is resampled, or some triangle emits.
// `emitters`: whether any emissive triangle is left to them (some are the shadows chain's mesh
// lights, whose candidates weigh nothing here; with punctual lights resampled the chain has no
// channel free, so then none is).
bool reservoirs_present(bool emitters) { return resampled_lights_present() || (emitters && emitter_share() > 0.0); }

// Whether light-table entry `light` is an emissive triangle, or a resampled punctual light.
bool reservoir_emitter(uint light) {
    return light >= light_table.first_emitter_entry && light < light_table.env_entry;
}
bool reservoir_punctual(uint light) { return light >= frame.chain_punctual && light < frame.light_count; }

// The shading point a reservoir is evaluated at.
struct ShadingPoint {
    vec3 origin;  // the shadow ray's origin (offset off the surface)
    vec3 n;       // shading normal
    vec3 ng;      // geometric normal
    vec3 v;       // toward the viewer
    BrdfInput m;
    bool rough;   // rougher than the reflections' cut-off: gi keeps an emitter's specular lobe
};

// The light's sample for (light, u) at `sp` with its density in u taken as 1: `weight` is the
// radiance arriving per unit of u (sphere: times the cone's solid angle; triangle: times its
// area and cosine over the squared distance), nee_none() when the light is behind the
// surface. `exact`: a triangle's radiance with its texture, else its material's factor alone
// (the target's).
NeeSample reservoir_light_sample(ShadingPoint sp, uint light, vec2 u, bool exact) {
    NeeSample s;
    if (reservoir_emitter(light)) {
        uint index = light - light_table.first_emitter_entry;
        // A mesh light of the shadows chain is composite's: its candidates weigh nothing here.
        if ((emitters[index].flags & EMITTER_IN_CHAIN) != 0u) return nee_none();
        if (exact) {
            s = sample_emitter(index, sp.origin, u, 1.0);
        } else {
            Emitter e = emitters[index];
            vec2 bary;
            s = emitter_point(e, sp.origin, u, bary);
            s.weight *= materials[instances[e.instance].material].emissive_factor;
        }
    } else {
        s = sample_punctual_light(light, sp.origin, u, 1.0);
    }
    if (dot(s.dir, sp.ng) <= 0.0) return nee_none();
    return s;
}

// p_hat: luminance of f(v, l) cos Le for the sample (an emitter's: the lobes gi keeps of it),
// times what the light grid learned of the light's visibility from here (s.seen).
float reservoir_target(ShadingPoint sp, NeeSample s, bool emitter) {
    vec3 f = emitter && !sp.rough
                 ? brdf_diffuse_albedo(sp.m) * brdf_diffuse_weight(sp.m, sp.n, sp.v, s.dir) * (max(dot(sp.n, s.dir), 0.0) * INV_PI)
                 : brdf_eval_cos(sp.m, sp.n, sp.v, s.dir);
    float t = luminance(f * s.weight) * s.seen;
    return t > 0.0 && !isinf(t) ? t : 0.0;
}

// Adds a sample of resampling weight w (and the m candidates behind it) to r; `xi` in [0, 1)
// decides whether it replaces the chosen one, which the result says.
bool reservoir_merge(inout LightReservoir r, uint light, vec2 u, float w, float p_hat, float m, float xi) {
    r.m += m;
    if (!(w > 0.0)) return false;
    r.w_sum += w;
    if (xi * r.w_sum >= w) return false;
    r.light = light;
    r.u = u;
    r.p_hat = p_hat;
    return true;
}

// An emissive triangle's entry for u in [0, 1), by power among them, and the probability of
// choosing it among them. Needs emitter_share() > 0.
uint emitter_pick(float u, float share, out float pmf) {
    uint first = light_table.first_emitter_entry;
    float lo = first == 0u ? 0.0 : light_entries[first - 1u].cdf;
    // Rounding can put lo + u share just outside the emitters' stretch.
    uint entry = clamp(light_entry_search(lo + u * share), first, light_table.env_entry - 1u);
    pmf = light_entries[entry].pmf / share;
    return entry;
}

// An emissive triangle's entry for u in [0, 1), and the probability of choosing it among
// them: from the shading point's cell of the light grid by what it sees of each group of them
// (`in_cell`, `cell`: light_grid_emitter_cell; light_grid_emitter_pick), else (outside the
// grid, or before anything was built) by power. The groups leave the shadows chain's mesh
// lights out (their candidates weigh nothing here), the light table does not: so a single
// group is drawn from too.
uint emitter_pick_at(bool in_cell, uint cell, float u, float share, out float pmf) {
    if (in_cell) {
        uint e = light_grid_emitter_pick(cell, u, pmf);
        if (e != NO_LIGHT) return light_table.first_emitter_entry + e;
    }
    return emitter_pick(u, share, pmf);
}

// The frame's own reservoir: RIS_CANDIDATES candidates (emissive triangles by what the point's
// cell sees of them, punctual lights from the light grid), resampled by p_hat.
LightReservoir reservoir_candidates(ShadingPoint sp, inout Rng rng) {
    LightReservoir r = reservoir_empty();
    ResampledLights lights_here = ResampledLights(false, 0u, uvec2(0u), 0.0, 0.0);
    if (resampled_lights_present()) lights_here = resampled_lights_at(sp.origin);
    float emitters = emitter_share();
    // The chance that a candidate is a triangle: the emitters' part of the two kinds' power
    // (0 without emitters, which keeps the punctual lights' draws as they were).
    float p_emitter = emitters / (emitters + (lights_here.hi - lights_here.lo));
    uint emitter_cell;
    bool in_cell = light_grid_emitter_cell(sp.origin, emitter_cell);
    // Not unrolled: each copy of the body would lengthen a CPU driver's compile.
    [[dont_unroll]] for (uint k = 0u; k < RIS_CANDIDATES; ++k) {
        vec3 u = rng_next3(rng);
        float pmf, seen = 1.0;
        bool emitter = u.x < p_emitter;
        uint light = emitter ? emitter_pick_at(in_cell, emitter_cell, u.x / p_emitter, emitters, pmf)
                             : resampled_light_pick(lights_here, (u.x - p_emitter) / (1.0 - p_emitter), pmf, seen);
        pmf *= emitter ? p_emitter : 1.0 - p_emitter;
        float w = 0.0, p_hat = 0.0;
        if (light != NO_LIGHT && pmf > 0.0) {
            NeeSample s = reservoir_light_sample(sp, light, u.yz, false);
            s.seen = emitter ? light_grid_seen_point(sp.origin, sp.origin + s.dir * s.dist) : seen;
            p_hat = reservoir_target(sp, s, emitter);
            w = p_hat / pmf;
        }
        reservoir_merge(r, light, u.yz, w, p_hat, 1.0, rng_next(rng));
    }
    return r;
}

// Draws behind one light sample at a path vertex (light_sample_resampled), where lights are
// resampled at all. The denoised frame of builtin:many-lights lost 31, 24 and 20% of the light
// with 4, 8 and 16 draws by power (SVGF's outlier clamp takes the rare lucky samples of a
// sparse choice for fireflies); with the light grid, 6% with 8 and about as much with 4.
#define RIS_VERTEX_CANDIDATES 8u

// One light sample at a path vertex, any kind of light, chosen among RIS_VERTEX_CANDIDATES draws
// of light_sample (by power, the resampled lights from the light grid) by the luminance of
// their unshadowed contribution f cos Le; `f` is the chosen one's f cos. Resampled in primary sample space: every draw's u is uniform, so a
// draw's resampling weight is its target itself, and delta, area and environment lights mix
// without a common measure. `weight` includes the RIS factor, so pdf is no density to weigh
// against a BSDF sample's: it only tells whether a BSDF-sampled ray can reach the light (> 0) or
// not (0: a punctual light). Far fewer of its samples are wasted on lights
// that are far, out of range or behind the surface than with one draw by power, which matters
// where a path vertex sees few of many lights. With few lights (none resampled) it draws once,
// which is light_sample itself at its cost: four draws made gi 14% slower on the default scene
// (bench frame, 640x360), where they have little to choose from.
NeeSample light_sample_resampled(vec3 origin, BrdfInput m, vec3 n, vec3 ng, vec3 v, inout Rng rng, out vec3 f) {
    NeeSample chosen = nee_none();
    f = vec3(0.0);
    float w_sum = 0.0, p_chosen = 0.0;
    uint draws = resampled_lights_present() ? RIS_VERTEX_CANDIDATES : 1u;
    // Not unrolled: each copy of the body would lengthen a CPU driver's compile.
    [[dont_unroll]] for (uint k = 0u; k < draws; ++k) {
        NeeSample s = light_sample(origin, rng_next3(rng));
        if (dot(s.weight, s.weight) <= 0.0 || dot(s.dir, ng) <= 0.0) continue;
        vec3 fk = brdf_eval_cos(m, n, v, s.dir);
        float p_hat = luminance(fk * s.weight) * s.seen;
        if (!(p_hat > 0.0) || isinf(p_hat)) continue;
        w_sum += p_hat;
        // A lone draw is always kept; drawing no number for it keeps light_sample's random
        // stream, and so the images of scenes without resampled lights, as they were.
        if (draws == 1u || rng_next(rng) * w_sum < p_hat) {
            chosen = s;
            f = fk;
            p_chosen = p_hat;
        }
    }
    if (!(p_chosen > 0.0)) return nee_none();
    chosen.weight *= (w_sum / float(draws)) / p_chosen;
    return chosen;
}

// W: the chosen sample's unbiased contribution weight (0 for an empty reservoir).
float reservoir_weight(LightReservoir r) {
    return r.light != NO_LIGHT && r.p_hat > 0.0 && r.m > 0.0 ? r.w_sum / (r.m * r.p_hat) : 0.0;
}

// Stored as (light, W, M, u): what the next frame needs to merge it at another shading point.
vec4 reservoir_pack(LightReservoir r) {
    return vec4(uintBitsToFloat(r.light), reservoir_weight(r), r.m, uintBitsToFloat(packUnorm2x16(r.u)));
}

// Last frame's reservoir `texel`, re-targeted at `sp` (its M capped): ready to merge with weight
// p_hat W M. One that found no visible light (W = 0) still brings its count: dropping it would
// keep only the frames that found one, and so overestimate.
LightReservoir reservoir_unpack(vec4 texel, ShadingPoint sp) {
    LightReservoir r = reservoir_empty();
    if (!(texel.z > 0.0)) return r;
    r.m = min(texel.z, RESERVOIR_M_CAP);
    uint light = floatBitsToUint(texel.x);
    bool emitter = reservoir_emitter(light);
    if (!(emitter || reservoir_punctual(light)) || !(texel.y > 0.0)) return r;
    r.light = light;
    r.u = unpackUnorm2x16(floatBitsToUint(texel.w));
    NeeSample s = reservoir_light_sample(sp, light, r.u, false);
    s.seen = emitter ? light_grid_seen_point(sp.origin, sp.origin + s.dir * s.dist) : light_grid_seen(sp.origin, light);
    r.p_hat = reservoir_target(sp, s, emitter);
    r.w_sum = r.p_hat * texel.y * r.m;
    return r;
}

// Whether last frame's reservoir at a reprojected pixel belongs to the same surface: same
// instance, view depth within 10%, normals within about 25 degrees (ReSTIR's test).
bool reservoir_consistent(uint id, float z, vec3 ng, uint id_prev, float z_prev, vec3 ng_prev) {
    return id == id_prev && abs(z - z_prev) <= 0.1 * z && dot(ng, ng_prev) > 0.9;
}

#endif
