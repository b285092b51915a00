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

// The closest hit along `dir` from `from`, going straight on through see-through surfaces
// (pass_through, at most PASS_THROUGH_MAX), `weight` scaled by what passes; `s` is the surface
// where the ray stopped (unset when it escaped) and `travelled` the distance to it. One trace
// call site in a loop: the compute backend inlines a traversal at every call site.
Hit trace_closest_through(vec3 from, vec3 dir, inout vec3 weight, inout Rng rng, out HitSurface s, out float travelled) {
    Hit h;
    travelled = 0.0;
    [[dont_unroll]] for (uint crossed = 0u;; ++crossed) {
        h = trace_closest(from, dir, 0.0, 1e6, RAY_MASK_ALL);
        if (h.instance == NO_HIT) break;
        travelled += h.t;
        s = hit_surface(h.instance, h.primitive, h.bary, dir);
        if (crossed == PASS_THROUGH_MAX || !pass_through(s, dir, weight, rng)) break;
        from = offset_ray(s.position, -s.normal_geo);
    }
    return h;
}

#endif
