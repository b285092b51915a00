// Emitters and the environment alone, for a lobe whose punctual lights are shaded elsewhere:
// the reflections pass's glossy lobe (composite and gi.specular have them). A draw that could
// pick a punctual light would be wasted there. (gi draws the emitters from its reservoirs and
// samples the environment alone.) The sampler draws the table's entries past the punctual
// ones, by power among themselves. Their share of the table's power is area_light_share() (0:
// nothing to draw), and this sampler's densities are the table's divided by it, which is what
// MIS against it must use: light_pdf_emitter and light_pdf_environment over the share. A file
// of its own, so that the shaders that do not use it keep their SPIR-V (a CPU driver caches
// pipelines by it).
#ifndef AREA_LIGHTS_GLSL
#define AREA_LIGHTS_GLSL

#include "common/light_sampling.glsl"

float area_light_share() {
    if (light_table.entry_count == 0u) return 0.0;
    uint first = light_table.first_emitter_entry;
    return first == 0u ? 1.0 : 1.0 - light_entries[first - 1u].cdf;
}

NeeSample area_light_sample(vec3 p, vec3 u, float share) {
    // u.x lands uniformly on the area lights' stretch of the CDF, [1 - share, 1).
    uint entry = max(light_entry_search(1.0 - share + u.x * share), light_table.first_emitter_entry);
    LightEntry e = light_entries[entry];
    if (!(e.pmf > 0.0)) return nee_none();
    if (e.kind == LIGHT_KIND_EMITTER) return sample_emitter(e.index, p, u.yz, e.pmf / share);
    return sample_environment(u.yz, e.pmf / share);
}

#endif
