// Direct light from the punctual lights past the first SHADOWED_LIGHTS, whatever their number:
// one light chosen per pixel by resampled importance sampling (RIS, Talbot et al. 2005; the
// candidate step of ReSTIR DI), then shadowed by one ray in the caller.
//
// - Candidates: RIS_CANDIDATES lights drawn from the power CDF of the light table
//   (light_sampling.glsl), restricted to those lights. Punctual lights are the table's first
//   entries, in light order (src/render/lights.rs), so the restriction is a sub-range of the
//   CDF: u is mapped into [cdf of entry SHADOWED_LIGHTS - 1, cdf of the last punctual entry).
//   A sphere or disk light's candidate carries a point on it, as in every other light sample.
// - Target p_hat: the luminance of the unshadowed contribution f(v, l) cos Le, full BRDF, so
//   that distance, range, spot cone, the cosine and the specular lobe all steer the choice.
// - Weight: with w_i = p_hat(x_i) / p(x_i), the chosen y is kept with probability w_y / sum w,
//   and f(y) Le(y) (sum w / M) / p_hat(y) is an unbiased estimate of the lights' sum (no
//   candidate has p = 0 where p_hat > 0).
// The cost per pixel is RIS_CANDIDATES CDF searches (log N each) and BRDF evaluations, and one
// shadow ray, however many lights there are. Visibility is not in p_hat: every chosen sample
// is shadowed by its own ray, so a light behind a wall can be chosen (noise) but never shine
// through it (no leak).
#ifndef MANY_LIGHTS_GLSL
#define MANY_LIGHTS_GLSL

#include "light_sampling.glsl"
#include "brdf.glsl"

// Candidates per pixel (the ReSTIR paper uses 32; RTXDI's fast preset 4 local lights). 8 keeps
// the BRDF evaluations below one shadow ray's cost on a CPU device.
#define RIS_CANDIDATES 8u

// Whether some light is left to the resampled path.
bool many_lights_present() { return frame.light_count > SHADOWED_LIGHTS; }

// The chosen light for shading point `origin` (the shadow ray's origin) with shading normal n,
// geometric normal ng and view direction v: `weight` is already the RIS estimate's factor, so
// f(v, dir) cos * weight is the estimate (or nee_none() when no candidate contributes).
NeeSample many_light_sample(vec3 origin, BrdfInput m, vec3 n, vec3 ng, vec3 v, inout Rng rng) {
    if (!many_lights_present() || light_table.entry_count == 0u) return nee_none();
    uint last = frame.light_count - 1u;
    float lo = light_entries[SHADOWED_LIGHTS - 1u].cdf;
    float hi = light_entries[last].cdf;
    if (!(hi > lo)) return nee_none();  // the remaining lights have no power
    NeeSample chosen = nee_none();
    float w_sum = 0.0, w_chosen = 0.0;
    for (uint k = 0u; k < RIS_CANDIDATES; ++k) {
        vec3 u = rng_next3(rng);
        uint entry = light_entry_search(lo + u.x * (hi - lo));
        // Rounding can put lo + u (hi - lo) on hi itself; such a draw selects nothing.
        if (entry < SHADOWED_LIGHTS || entry > last) continue;
        float pmf = light_entries[entry].pmf / (hi - lo);
        NeeSample s = sample_punctual_light(entry, origin, u.yz, pmf);
        if (dot(s.dir, ng) <= 0.0) continue;
        // p_hat / p: the sample's weight already divides its radiance by its density.
        float w = luminance(brdf_eval_cos(m, n, v, s.dir) * s.weight);
        if (!(w > 0.0) || isinf(w)) continue;
        w_sum += w;
        if (rng_next(rng) * w_sum < w) {
            chosen = s;
            w_chosen = w;
        }
    }
    if (w_chosen <= 0.0) return nee_none();
    chosen.weight *= (w_sum / float(RIS_CANDIDATES)) / w_chosen;
    return chosen;
}

#endif
