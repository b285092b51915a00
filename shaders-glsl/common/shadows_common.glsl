// Shared by the adaptive soft-shadow passes (shadows, shadows_penumbra, shadows_tent_h/_v,
// shadows_filter), after Ray Tracing Gems ch. 13 (Boksansky, Wimmer, Bittner): visibility of
// up to four lights, one per RGBA channel: the punctual lights first, then mesh lights
// (common/mesh_lights.glsl), the four of both that world::lights::chain_lights ranks first.
// Punctual lights with a radius (sphere for point lights, disk for spots) and mesh lights are
// area lights and get adaptive sample counts, filtering and a 4-frame history; punctual lights
// without one are hard: one ray, no filtering.
#ifndef SHADOWS_COMMON_GLSL
#define SHADOWS_COMMON_GLSL

#include "scene.glsl"

#define SHADOW_LIGHTS 4

layout(push_constant) uniform ShadowParams {
    uint s_max;          // most shadow rays per pixel and light (5 standard, 8 high)
    float delta;         // penumbra threshold on the filtered visibility variation
    float eta;           // variation at which the filter reaches its widest (9 taps)
    float budget;        // the image's summed variation above which s_max is lowered
    uint forced_blocks;  // 1: 8x8 blocks rotating over 4 frames are always sampled
    uint tent_axis;      // shadows_tent: 0 horizontal, 1 vertical
    uint tinted;         // shadows: 1 when some thin glass is tinted (shadows.tint is written)
    uvec4 mesh_first_emitter;  // per channel, a mesh light's first emitter
    uvec4 mesh_triangles;      // per channel, a mesh light's triangles (0: not a mesh light)
} sp;

// The channels of the punctual lights (the first ones).
uint punctual_channels() { return frame.chain_punctual; }

// Which channels are soft (a punctual light with a radius, or a mesh light): a bool each.
bvec4 soft_lights() {
    bvec4 s = bvec4(false);
    for (uint i = 0u; i < uint(SHADOW_LIGHTS); ++i) {
        s[i] = i < punctual_channels() ? lights[i].radius > 0.0 : sp.mesh_triangles[i] > 0u;
    }
    return s;
}

// Eq. 13.7: the previous depth at the reprojected position belongs to this surface when
// |1 - z_prev / z| < c1 + c2 (1 - |n_z|), n_z the camera-space normal's z (oblique surfaces
// tolerate more), c1 = 0.003, c2 = 0.017.
bool depth_consistent(float z, float z_prev, vec3 normal_world) {
    float nz = abs(dot(normal_world, frame.inv_view[2].xyz));
    return abs(1.0 - z_prev / max(z, 1e-6)) < 0.003 + 0.017 * (1.0 - nz);
}

#endif
