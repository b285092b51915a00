#version 460
// light_grid_update: before the frame's rays, one invocation per cell of the light grid
// (common/light_grid.glsl) folds last frame's shadow-ray counts of each light group into the
// cell's visibility estimate of that group, then rebuilds the cell's CDF over bound x
// visibility (light_grid_visibility_factor). A cell then spends its draws on the lights its points can
// see: a wall between a cell and a room full of lights without a range leaves those listed
// (the grid knows only distances) but rarely drawn.
//
// And it rebuilds the cell's CDF over the groups the emissive triangles are sorted into, by
// each group's share of their power x the cell's visibility factor for it: gi draws an emitter
// candidate's group from it (light_grid_emitter_pick).
//
// It also writes what it learned as an image, for dumps: row c holds cell c's estimate for each
// group (-1 past the grid's cells).
#extension GL_GOOGLE_include_directive : require
#define LIGHT_GRID_WRITE
#include "common/scene.glsl"
#include "common/light_grid.glsl"

layout(local_size_x = 64) in;

layout(set = 1, binding = 0, r32f) uniform writeonly image2D out_visibility;

// The estimate's memory, in rays: the share hidden is (what it was x LIGHT_GRID_MEMORY_RAYS +
// rays blocked) / (LIGHT_GRID_MEMORY_RAYS + rays). A frame with many more rays than this replaces
// it, so a group drawn often follows a moving occluder within a frame or two; a group drawn a
// few times a frame averages over frames.
#define LIGHT_GRID_MEMORY_RAYS 4.0

void main() {
    uint c = gl_GlobalInvocationID.x;
    ivec2 size = imageSize(out_visibility);
    if (c >= uint(size.y)) return;
    if (c >= light_grid.cell_count) {
        for (int g = 0; g < size.x; ++g) imageStore(out_visibility, ivec2(g, c), vec4(-1.0));
        return;
    }
    uint groups = light_grid.group_count;
    for (uint g = 0u; g < groups; ++g) {
        LightGridVisibility v = light_grid_visibility[c * groups + g];
        if (v.rays > 0u) {
            v.hidden = (v.hidden * LIGHT_GRID_MEMORY_RAYS + float(v.blocked)) / (LIGHT_GRID_MEMORY_RAYS + float(v.rays));
            v.rays = v.blocked = 0u;
            light_grid_visibility[c * groups + g] = v;
        }
        imageStore(out_visibility, ivec2(g, c), vec4(1.0 - v.hidden));
    }
    // The emitters' listed groups, in the cell's first slots. The last one's CDF is exactly 1
    // (every listed group has power), which is also how gi tells that it was built.
    uint listed = emitter_group_count;
    float emitters_total = 0.0;
    for (uint j = 0u; j < listed; ++j) {
        EmitterGroup eg = emitter_groups[j];
        emitters_total += eg.share * light_grid_visibility_factor(light_grid_visibility[c * groups + eg.group]);
    }
    float emitters_acc = 0.0;
    for (uint j = 0u; j < listed; ++j) {
        EmitterGroup eg = emitter_groups[j];
        emitters_acc += eg.share * light_grid_visibility_factor(light_grid_visibility[c * groups + eg.group]);
        light_grid_visibility[c * groups + j].emitters_cdf = j + 1u == listed ? 1.0 : emitters_acc / emitters_total;
    }

    uvec2 cell = light_grid_cells[c];
    uint end = cell.x + cell.y;
    float total = 0.0;
    for (uint i = cell.x; i < end; ++i) {
        LightGridEntry e = light_grid_entries[i];
        total += e.bound * light_grid_visibility_factor(light_grid_visibility[c * groups + e.group]);
    }
    float acc = 0.0;
    for (uint i = cell.x; i < end; ++i) {
        LightGridEntry e = light_grid_entries[i];
        float w = e.bound * light_grid_visibility_factor(light_grid_visibility[c * groups + e.group]);
        acc += w;
        light_grid_entries[i].pmf = w / total;
        light_grid_entries[i].cdf = i + 1u == end ? 1.0 : acc / total;
    }
}
