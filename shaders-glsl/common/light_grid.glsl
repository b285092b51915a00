// The light grid (src/world/light_grid.rs): a world-space grid whose cells list the resampled
// punctual lights that reach them, with a CDF per cell over a bound of what each delivers
// there. Lights a cell does not list deliver nothing to any point in it, so drawing from the
// list is unbiased; common/light_sampling.glsl draws from all resampled lights by power where
// a point is outside the grid.
//
// The hybrid frame also learns what each cell sees. The lights are sorted into groups by where
// they are (a coarse grid over the same bounds), and gi (compiled with LIGHT_GRID_LEARN) counts,
// per cell and group, its shadow rays toward the group's lights and those that reach them
// (light_grid_learn). light_grid_update.comp then scales each entry's bound by a factor of its
// group's visibility from the cell (light_grid_visibility_factor) and rebuilds the cell's CDF
// before the next frame's passes draw from it; and the resampling targets
// (common/light_reservoir.glsl) take the same factor (NeeSample.seen, light_grid_seen):
// resampling tends toward its target whatever the candidates were drawn by, so a bright light
// behind a wall would otherwise still win most draws that find it. A group pools the rays of
// all its lights: one light among hundreds is drawn too rarely to be learned on its own. Every
// listed light keeps a share (LIGHT_GRID_VISIBILITY_FLOOR), so the choice and the resampling
// stay unbiased.
//
// The emissive triangles are not listed in the cells; they are sorted into the same groups by
// where they lie (EmitterGroups, src/world/light_grid.rs), light_grid_update.comp builds per
// cell a CDF over the groups by their power x the cell's visibility factor, and gi draws an
// emitter candidate's group from it, then a triangle of the group by power
// (light_grid_emitter_pick).
#ifndef LIGHT_GRID_GLSL
#define LIGHT_GRID_GLSL

#include "lights.glsl"

#define NO_LIGHT 0xffffffffu

struct LightGridHeader {
    vec3 lo;
    uint cell_count;  // 0: no grid
    vec3 inv_cell;
    uint group_count;  // light groups: the visibility buffer holds cell_count x group_count
    uvec3 dims;
    uint pad1;
};

struct LightGridEntry {
    uint light;   // index into lights[]
    float cdf;    // of the cell's list; its last entry has exactly 1
    float pmf;
    float bound;  // what the light can deliver to the cell, before visibility (unnormalised)
    uint group;   // the light's group
};

// Per cell and light group, what the shadow rays from the cell toward the group's lights
// found: the running estimate of the share that something blocks (0 until measured), and this
// frame's count of rays and of those blocked (atomics; light_grid_update.comp folds them into
// the estimate and zeroes them). Counted as blocked rather than reached so that all zeros is
// "nothing learned", what a rebuild of the grid resets the buffer to with a fill
// (src/world/lights.rs).
struct LightGridVisibility {
    float hidden;
    uint rays;
    uint blocked;
    // In slot j of a cell: the cell's CDF over the emitters' listed groups up to the j-th
    // (emitter_groups[j]), by power x visibility; 0 until light_grid_update builds it.
    float emitters_cdf;
};

// The groups by position, into which the emissive triangles are sorted. Rust:
// world::light_grid::EMITTER_GROUPS.
#define LIGHT_GRID_EMITTER_GROUPS 64u

// A group that holds emitters: its stretch of emitter_group_entries, its share of the
// emitters' power, and which group it is.
struct EmitterGroup {
    uint first;
    uint count;
    float share;
    uint group;
};

// An emissive triangle of a group, with the group's CDF by power.
struct EmitterGroupEntry {
    uint emitter;  // index into emitters[]
    float cdf;
    float pmf;
};

// Light groups along each side of the grid's bounds (the groups by position, then the
// directional lights' own). Rust: world::light_grid::GROUPS_PER_SIDE.
#define LIGHT_GRID_GROUPS_PER_SIDE 4u

// Each listed light keeps at least this share of its bound, however rarely its group is seen
// from the cell, so a light visible from a corner of a cell is still drawn there.
#define LIGHT_GRID_VISIBILITY_FLOOR 0.01

// What a light's learned visibility scales its weight by, in the CDF and the resampling targets.
float light_grid_visibility_factor(LightGridVisibility v) {
    return LIGHT_GRID_VISIBILITY_FLOOR + (1.0 - LIGHT_GRID_VISIBILITY_FLOOR) * (1.0 - v.hidden);
}

layout(set = 0, binding = 22, scalar) readonly buffer EmitterGroups {
    uint emitter_group_count;  // the groups listed: those that hold emitters
    uint emitter_groups_pad[3];
    EmitterGroup emitter_groups[LIGHT_GRID_EMITTER_GROUPS];
    EmitterGroupEntry emitter_group_entries[];
};

// Per cell, (first entry, entry count).
layout(set = 0, binding = 19, scalar) readonly buffer LightGrid {
    LightGridHeader light_grid;
    uvec2 light_grid_cells[];
};
// Written by light_grid_update.comp only (LIGHT_GRID_WRITE).
#ifdef LIGHT_GRID_WRITE
layout(set = 0, binding = 20, scalar) buffer LightGridEntries { LightGridEntry light_grid_entries[]; };
#else
layout(set = 0, binding = 20, scalar) readonly buffer LightGridEntries { LightGridEntry light_grid_entries[]; };
#endif
#if defined(LIGHT_GRID_WRITE) || defined(LIGHT_GRID_LEARN)
layout(set = 0, binding = 21, scalar) buffer LightGridVisibilities { LightGridVisibility light_grid_visibility[]; };
#else
layout(set = 0, binding = 21, scalar) readonly buffer LightGridVisibilities { LightGridVisibility light_grid_visibility[]; };
#endif

// The index of point p's cell; false where there is no grid or p lies outside it (NaN
// included).
bool light_grid_cell_index(vec3 p, out uint index) {
    index = 0u;
    if (light_grid.cell_count == 0u) return false;
    vec3 c = (p - light_grid.lo) * light_grid.inv_cell;
    if (!(all(greaterThanEqual(c, vec3(0.0))) && all(lessThan(c, vec3(light_grid.dims))))) return false;
    uvec3 i = min(uvec3(c), light_grid.dims - 1u);
    index = (i.z * light_grid.dims.y + i.y) * light_grid.dims.x + i.x;
    return true;
}

// A light of cell `index` (its entries `cell`) by the CDF, u in [0, 1), and the probability of
// that choice; NO_LIGHT when the cell lists none (no resampled light reaches it). `seen`: the
// factor its learned visibility puts on resampling targets (light_grid_seen's, read from the
// chosen entry without a search).
uint light_grid_pick(uint index, uvec2 cell, float u, out float pmf, out float seen) {
    pmf = 0.0;
    seen = 1.0;
    if (cell.y == 0u) return NO_LIGHT;
    uint lo = cell.x;
    uint hi = cell.x + cell.y - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (light_grid_entries[mid].cdf > u) hi = mid; else lo = mid + 1u;
    }
    pmf = light_grid_entries[lo].pmf;
    uint key = index * light_grid.group_count + light_grid_entries[lo].group;
    seen = light_grid_visibility_factor(light_grid_visibility[key]);
    return light_grid_entries[lo].light;
}

// The index into light_grid_visibility of punctual light `light` seen from point p: p's cell
// and the light's group. False when p is outside the grid or its cell does not list the light
// (a shadowed light among them). A cell lists its lights in index order
// (src/world/light_grid.rs), so the light's entry, which names its group, is found by bisection.
bool light_grid_visibility_key(vec3 p, uint light, out uint key) {
    key = 0u;
    uint index;
    if (light < frame.chain_punctual || light == NO_LIGHT || !light_grid_cell_index(p, index)) return false;
    uvec2 cell = light_grid_cells[index];
    if (cell.y == 0u) return false;
    uint lo = cell.x;
    uint hi = cell.x + cell.y - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (light_grid_entries[mid].light < light) lo = mid + 1u; else hi = mid;
    }
    if (light_grid_entries[lo].light != light) return false;
    key = index * light_grid.group_count + light_grid_entries[lo].group;
    return true;
}

// The factor light `light`'s learned visibility from p's cell puts on its resampling target; 1
// where nothing is learned (a light the cell does not list, a point outside the grid, the
// reference, which runs no update and so keeps every estimate at 1).
float light_grid_seen(vec3 p, uint light) {
    uint key;
    if (!light_grid_visibility_key(p, light, key)) return 1.0;
    return light_grid_visibility_factor(light_grid_visibility[key]);
}

// Whether point p lies in a cell of the light grid whose CDF over the emitters' groups
// light_grid_update has built (`index`: the cell), so that light_grid_emitter_pick can draw
// there.
bool light_grid_emitter_cell(vec3 p, out uint index) {
    uint listed = emitter_group_count;
    // Built, the CDF ends in exactly 1.
    return listed > 0u && light_grid_cell_index(p, index) &&
           light_grid_visibility[index * light_grid.group_count + listed - 1u].emitters_cdf == 1.0;
}

// An emissive triangle (index into emitters[]) for a point of cell `index` (one that
// light_grid_emitter_cell found), u in [0, 1): its group by the cell's CDF over the groups
// (power x what the cell sees of them), then a triangle of the group by power; and the
// probability of that choice among the emitters (0 and NO_LIGHT should rounding find no
// triangle).
uint light_grid_emitter_pick(uint index, float u, out float pmf) {
    pmf = 0.0;
    uint base = index * light_grid.group_count;
    uint lo = 0u;
    uint hi = emitter_group_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (light_grid_visibility[base + mid].emitters_cdf > u) hi = mid; else lo = mid + 1u;
    }
    float below = lo == 0u ? 0.0 : light_grid_visibility[base + lo - 1u].emitters_cdf;
    float p_group = light_grid_visibility[base + lo].emitters_cdf - below;
    EmitterGroup g = emitter_groups[lo];
    if (!(p_group > 0.0) || g.count == 0u) return NO_LIGHT;
    // The rest of u picks the triangle.
    float v = clamp((u - below) / p_group, 0.0, 0.99999994);
    uint a = g.first;
    uint b = g.first + g.count - 1u;
    while (a < b) {
        uint mid = (a + b) / 2u;
        if (emitter_group_entries[mid].cdf > v) b = mid; else a = mid + 1u;
    }
    pmf = p_group * emitter_group_entries[a].pmf;
    return emitter_group_entries[a].emitter;
}

// The group of a light at point q (an emissive triangle's sampled point; the grid's cells list
// punctual lights only, but the groups are regions of the bounds, so an emitter's light is
// learned per cell and group like theirs): as world::light_grid groups the punctual lights.
uint light_grid_group_at(vec3 q) {
    vec3 group_size = vec3(light_grid.dims) / (light_grid.inv_cell * float(LIGHT_GRID_GROUPS_PER_SIDE));
    vec3 g = clamp(floor((q - light_grid.lo) / group_size), vec3(0.0), vec3(float(LIGHT_GRID_GROUPS_PER_SIDE - 1u)));
    uvec3 i = uvec3(g);
    return (i.z * LIGHT_GRID_GROUPS_PER_SIDE + i.y) * LIGHT_GRID_GROUPS_PER_SIDE + i.x;
}

// The index into light_grid_visibility of light at point q seen from point p; false where p is
// outside the grid.
bool light_grid_point_key(vec3 p, vec3 q, out uint key) {
    uint index;
    key = 0u;
    if (!light_grid_cell_index(p, index)) return false;
    key = index * light_grid.group_count + light_grid_group_at(q);
    return true;
}

// light_grid_seen for an emitter's point q seen from p.
float light_grid_seen_point(vec3 p, vec3 q) {
    uint key;
    if (!light_grid_point_key(p, q, key)) return 1.0;
    return light_grid_visibility_factor(light_grid_visibility[key]);
}

#ifdef LIGHT_GRID_LEARN
void light_grid_count(uint key, bool reached) {
    atomicAdd(light_grid_visibility[key].rays, 1u);
    if (!reached) atomicAdd(light_grid_visibility[key].blocked, 1u);
}

// Counts a shadow ray from point p toward punctual light `light`, and whether it reached it,
// for p's cell and the light's group.
void light_grid_learn(vec3 p, uint light, bool reached) {
    uint key;
    if (light_grid_visibility_key(p, light, key)) light_grid_count(key, reached);
}

// The same for a shadow ray from p toward an emitter's point q.
void light_grid_learn_point(vec3 p, vec3 q, bool reached) {
    uint key;
    if (light_grid_point_key(p, q, key)) light_grid_count(key, reached);
}
#endif

#endif
