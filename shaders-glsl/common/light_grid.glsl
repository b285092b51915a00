// The light grid (src/world/light_grid.rs): a world-space grid whose cells list the resampled
// punctual lights that reach them, with a CDF per cell over a bound of what each delivers
// there. Lights a cell does not list deliver nothing to any point in it, so drawing from the
// list is unbiased; common/light_sampling.glsl draws from all resampled lights by power where
// a point is outside the grid.
#ifndef LIGHT_GRID_GLSL
#define LIGHT_GRID_GLSL

#define NO_LIGHT 0xffffffffu

struct LightGridHeader {
    vec3 lo;
    uint cell_count;  // 0: no grid
    vec3 inv_cell;
    uint pad0;
    uvec3 dims;
    uint pad1;
};

struct LightGridEntry {
    uint light;  // index into lights[]
    float cdf;   // of the cell's list; its last entry has exactly 1
    float pmf;
};

// Per cell, (first entry, entry count).
layout(set = 0, binding = 19, scalar) readonly buffer LightGrid {
    LightGridHeader light_grid;
    uvec2 light_grid_cells[];
};
layout(set = 0, binding = 20, scalar) readonly buffer LightGridEntries { LightGridEntry light_grid_entries[]; };

// The cell of point p; false where there is no grid or p lies outside it (NaN included).
bool light_grid_cell(vec3 p, out uvec2 cell) {
    cell = uvec2(0u);
    if (light_grid.cell_count == 0u) return false;
    vec3 c = (p - light_grid.lo) * light_grid.inv_cell;
    if (!(all(greaterThanEqual(c, vec3(0.0))) && all(lessThan(c, vec3(light_grid.dims))))) return false;
    uvec3 i = min(uvec3(c), light_grid.dims - 1u);
    cell = light_grid_cells[(i.z * light_grid.dims.y + i.y) * light_grid.dims.x + i.x];
    return true;
}

// A light of the cell by its CDF, u in [0, 1), and the probability of that choice; NO_LIGHT
// when the cell lists none (no resampled light reaches it).
uint light_grid_pick(uvec2 cell, float u, out float pmf) {
    pmf = 0.0;
    if (cell.y == 0u) return NO_LIGHT;
    uint lo = cell.x;
    uint hi = cell.x + cell.y - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (light_grid_entries[mid].cdf > u) hi = mid; else lo = mid + 1u;
    }
    pmf = light_grid_entries[lo].pmf;
    return light_grid_entries[lo].light;
}

#endif
