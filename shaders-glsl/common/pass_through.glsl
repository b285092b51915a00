// Closest-hit rays of the real-time passes through see-through surfaces, as their shadow rays
// cross them (common/hit.glsl) and the reference's paths do (pathtrace.comp): a ray that meets
// one goes straight on with a chance, else it stops there. Without this, gi's bounce saw only
// what glass reflects, and the bounce's share of the light behind it (multiple importance
// sampling splits the sky between the bounce and the light sample, which does cross) went
// missing: a plane under a clear pane lit by a white sky read 0.19 of the reference.
#ifndef PASS_THROUGH_GLSL
#define PASS_THROUGH_GLSL

#include "trace.glsl"
#include "brdf.glsl"
#include "transmission.glsl"
#include "sampling.glsl"
#include "ray_offset.glsl"

// Most see-through surfaces one ray passes.
#define PASS_THROUGH_MAX 4u

// Whether the ray along `dir` that hit `s` goes straight on, drawn as the reference draws it:
// - a blended surface: with the chance 1 - alpha, weight 1 (stopping, the surface is shaded
//   whole, which covers the share alpha);
// - thin-walled glass of any roughness (the real-time shadow rays cross rough glass straight
//   too, its energy not its blur): with the chance of its transmitted share, scaled by what
//   passes over that chance; stopping, it shades only what it reflects, so the ray's weight
//   takes 1 / (1 - chance).
// Other surfaces draw no random number.
bool pass_through(HitSurface s, vec3 dir, inout vec3 weight, inout Rng rng) {
    if ((materials[s.material].flags & MATERIAL_BLEND) != 0u) return rng_next(rng) >= s.mat.base_color.a;
    if (!(s.mat.transmission > 0.0 && s.mat.thin_walled)) return false;
    BrdfInput m = BrdfInput(s.mat.base_color.rgb, s.mat.metallic, s.mat.roughness, dielectric_f0(s.mat.ior));
    float chance = min(transmitted_share(m, s.mat.transmission, s.normal, -dir), 0.999);
    if (!(chance > 0.0)) return false;
    if (rng_next(rng) < chance) {
        float f = fresnel_dielectric(m, abs(dot(dir, s.normal_geo)));
        weight *= (1.0 - f) * m.base_color * (s.mat.transmission * (1.0 - m.metallic) / chance);
        return true;
    }
    weight /= 1.0 - chance;
    return false;
}

// A closest-hit ray on its way past the surfaces it may pass: straight on through see-through
// ones (pass_through), and into and out of a volume of glass, refracted and absorbed as the
// reference's paths go (pathtrace.comp). Without the volumes, gi's bounce and the radiance
// cache's paths saw only what a glass ball reflects, and a floor under one went dark.
struct Passage {
    vec3 from;        // where the next segment starts
    vec3 dir;         // and its direction
    vec3 weight;      // what the surfaces passed let through
    vec3 absorption;  // inside a volume: its Beer-Lambert coefficient
    uint steps;       // surfaces passed and glass events
    bool turned;      // it went through a volume, which no light sample crosses
};

Passage passage_start(vec3 from, vec3 dir) { return Passage(from, dir, vec3(1.0), vec3(0.0), 0u, false); }

// Most glass events on a passage (refractions, reflections inside a volume), as the
// reflections pass allows its paths through glass.
#define PASSAGE_EVENTS 8u

// Whether the ray of passage `p` that met `s` after a segment of length `t` goes on (`p` then
// holds its next segment) or stops at `s`, to be shaded there with `p.weight`. At a volume's
// outer side it enters with the chance of the transmitted share, as pass_through crosses thin
// glass (stopping, `s` shades only what it reflects, and the weight takes 1 / (1 - chance));
// inside, the bare interface reflects it or lets it out. A passage that ends inside a volume
// (its events spent) has weight 0, as has one whose drawn microfacet sent it the wrong way.
bool pass_on(HitSurface s, float t, inout Passage p, inout Rng rng) {
    if (any(greaterThan(p.absorption, vec3(0.0)))) p.weight *= exp(-p.absorption * t);
    if (!(s.mat.transmission > 0.0 && !s.mat.thin_walled)) {
        if (p.steps >= PASS_THROUGH_MAX || !pass_through(s, p.dir, p.weight, rng)) return false;
        ++p.steps;
        p.from = offset_ray(s.position, -s.normal_geo);
        return true;
    }
    TransmissionSample next;
    if (s.front) {
        BrdfInput m = BrdfInput(s.mat.base_color.rgb, s.mat.metallic, s.mat.roughness, dielectric_f0(s.mat.ior));
        float chance = min(transmitted_share(m, s.mat.transmission, s.normal, -p.dir), 0.999);
        if (p.steps >= PASSAGE_EVENTS || !(chance > 0.0)) return false;
        if (rng_next(rng) >= chance) {
            p.weight /= 1.0 - chance;
            return false;
        }
        next = transmission_sample(m, false, s.mat.ior, s.normal, -p.dir, rng_next2(rng));
        next.weight *= s.mat.transmission * (1.0 - s.mat.metallic) / chance;
        p.absorption = s.mat.absorption;
        p.turned = true;
    } else {
        // Inside, with its events spent: the passage ends here, unlit.
        if (p.steps >= PASSAGE_EVENTS) {
            p.weight = vec3(0.0);
            return false;
        }
        next = interface_sample(s.mat.roughness, s.mat.ior, s.normal, -p.dir, rng_next3(rng));
        if (next.crossed) p.absorption = vec3(0.0);
    }
    ++p.steps;
    p.weight *= next.weight;
    p.from = offset_ray(s.position, next.crossed ? -s.normal_geo : s.normal_geo);
    p.dir = next.l;
    return dot(p.weight, p.weight) > 0.0;
}

// The closest hit of passage `p` (pass_on), which ends holding the last segment; `s` is the
// surface where the ray stopped (unset when it escaped) and `travelled` the distance to it. One
// trace call site in a loop: the compute backend inlines a traversal at every call site.
Hit trace_closest_through(inout Passage p, inout Rng rng, out HitSurface s, out float travelled) {
    Hit h;
    travelled = 0.0;
    [[dont_unroll]] for (;;) {
        h = trace_closest(p.from, p.dir, 0.0, 1e6, RAY_MASK_ALL);
        if (h.instance == NO_HIT) break;
        travelled += h.t;
        s = hit_surface(h.instance, h.primitive, h.bary, p.dir);
        if (!pass_on(s, h.t, p, rng)) break;
    }
    return h;
}

#endif
