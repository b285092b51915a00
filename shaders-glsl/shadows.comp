#version 460
// shadows: visibility of the first four punctual lights, and of the mesh lights in the channels
// they leave free, from every G-buffer surface, through the trace interface (Ray Tracing Gems
// ch. 13, adaptive sampling).
// - Hard lights (radius 0): one shadow ray every frame, stored as is.
// - Area lights (sphere, disk or mesh light): a per-pixel sample count 1..s_max carried from
//   frame to frame (+1 while the filtered penumbra measure of last frame is above delta and the count
//   below s_max; -1 once it is below delta and the count has not changed for 4 frames),
//   s_max wherever reprojection fails (then all four cached frames are overwritten). A pixel
//   outside any penumbra is sampled only when its 8x8 block's turn comes (every 4th frame)
//   and otherwise reuses its reprojected visibility. The global budget lowers s_max when the
//   image's summed penumbra measure exceeds it. Sample points come from an R2 sequence indexed
//   by (frame mod 4, the pixel's place in its 3x3 block, sample), like the chapter's Poisson
//   sets.
// - Lights out of range at a pixel (range window 0) are culled: visibility 1, no rays.
// - Tinted glass: the visibility is grey (the mean of the channels that pass), and the colour
//   goes beside it in `tint` (common/shadow_tint.glsl), carried with the visibility it belongs
//   to: a soft light's reused visibility keeps the tint of the frame that traced it.
// Writes the 4-frame visibility ring (ring0 = this frame), sample counts, stability counters
// and the tint.
#extension GL_GOOGLE_include_directive : require
#include "common/trace.glsl"
#include "common/gbuffer.glsl"
#include "common/light_sampling.glsl"
#include "common/shadow_tint.glsl"
#include "common/mesh_lights.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 2, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 3, rg32f) uniform readonly image2D g_motion;
layout(set = 1, binding = 4, rg32f) uniform readonly image2D prev_depth;
layout(set = 1, binding = 5, rgba16f) uniform readonly image2D prev_ring0;
layout(set = 1, binding = 6, rgba16f) uniform readonly image2D prev_ring1;
layout(set = 1, binding = 7, rgba16f) uniform readonly image2D prev_ring2;
layout(set = 1, binding = 8, rgba16f) uniform readonly image2D prev_sample_count;
layout(set = 1, binding = 9, rgba16f) uniform readonly image2D prev_stable;
layout(set = 1, binding = 10, rgba16f) uniform readonly image2D prev_dv;      // last frame's filtered variation
layout(set = 1, binding = 11, r32ui) uniform readonly uimage2D prev_budget;   // last frame's summed variation x 64
layout(set = 1, binding = 12, rgba32ui) uniform readonly uimage2D prev_tint;
layout(set = 1, binding = 13, rgba16f) uniform writeonly image2D out_ring0;
layout(set = 1, binding = 14, rgba16f) uniform writeonly image2D out_ring1;
layout(set = 1, binding = 15, rgba16f) uniform writeonly image2D out_ring2;
layout(set = 1, binding = 16, rgba16f) uniform writeonly image2D out_ring3;
layout(set = 1, binding = 17, rgba16f) uniform writeonly image2D out_sample_count;   // sample count per light (0: culled)
layout(set = 1, binding = 18, rgba16f) uniform writeonly image2D out_stable;  // frames the count has not changed
layout(set = 1, binding = 19, rgba32ui) uniform writeonly uimage2D out_tint;   // common/shadow_tint.glsl

#include "common/shadows_common.glsl"

// The chapter's 4x4 rotation of forced 8x8 blocks: block (bx, by) is sampled when this equals
// frame mod 4.
const uint FORCED[16] = uint[16](0u, 3u, 2u, 1u, 2u, 1u, 0u, 3u, 0u, 3u, 2u, 1u, 1u, 2u, 0u, 3u);

// Low-discrepancy point n of the R2 sequence (Roberts 2018), shifted on the torus by `shift`.
vec2 r2(uint n, vec2 shift) { return fract(shift + float(n) * vec2(0.7548776662, 0.5698402910)); }

// The shift of the pixel's 3x3 block: the same every frame, so the ring's four frames and the
// block's nine pixels still take 36 consecutive points of one sequence, well spread; unrelated
// between blocks, so that the few points a pixel has do not miss the same parts of every light
// everywhere. With one shift for the whole image, the penumbra of tests/soft_shadows.rs's
// panel read 0.961 of the reference's light (1.009 shifted), and a box-shaped light that emits
// on both sides lit the floor 3.7% too brightly: its points fell on its visible faces more
// often than their share of the light, in every block alike.
vec2 block_shift(ivec2 px) {
    uint h = pcg_hash(uint(px.x / 3) + pcg_hash(uint(px.y / 3)));
    return vec2(float(h & 0xffffu), float(h >> 16u)) * (1.0 / 65536.0);
}

// Fraction of the shadow rays toward `count` points of the light on channel i that reach it,
// per colour: a ray through see-through surfaces counts with what passes them. Points that send
// no light here (the back of a disk or of a one-sided emitter, outside a spot's cone, a mesh
// light's points below the surface `ng`) say nothing about occlusion and are left out; with
// none left (`tested` false) a punctual light is unoccluded by definition (it sends nothing
// anyway), and a mesh light is the caller's to decide. A mesh light's points are drawn by
// each triangle's share of its light and weigh by what each brings unshadowed over that
// density (mesh_light_point): the ratio of the shadowed to the unshadowed estimate from the
// same points, which is what scales composite's closed form right where near and far parts of
// a large panel are hidden differently (counted alike, the penumbra of
// `tests/soft_shadows.rs`'s panel read 0.926 of the reference's light).
vec3 trace_visibility(uint i, vec3 origin, vec3 ng, ivec2 px, uint count, out bool tested) {
    uint set = ((frame.frame_index & 3u) * 9u + uint(px.y % 3) * 3u + uint(px.x % 3)) * count;
    vec2 shift = block_shift(px);
    bool mesh = i >= punctual_channels();
    vec3 visible = vec3(0.0);
    float tried = 0.0;
    float share[MESH_LIGHT_MAX_TRIANGLES];
    if (mesh && !mesh_light_shares(sp.mesh_first_emitter[i], sp.mesh_triangles[i], origin, ng, share)) {
        tested = false;
        return vec3(1.0);
    }
    for (uint k = 0u; k < count; ++k) {
        // Sampled from the ray's origin, so direction and length are the ray's own.
        NeeSample s = nee_none();
        float weight = 1.0;
        if (mesh) {
            weight = mesh_light_point(sp.mesh_first_emitter[i], sp.mesh_triangles[i], origin, ng, share, r2(set + k, shift),
                                      s.dir, s.dist);
            if (!(weight > 0.0)) continue;
        } else {
            s = sample_punctual_light(i, origin, r2(set + k, shift), 1.0);
            if (dot(s.weight, s.weight) == 0.0) continue;
        }
        tried += weight;
        float tmax = s.dist >= LIGHT_FAR ? 1e30 : s.dist * (1.0 - 1e-4);
        visible += weight * trace_transmittance(origin, s.dir, 0.0, tmax, RAY_MASK_ALL);
    }
    tested = tried > 0.0;
    return tested ? visible / tried : vec3(1.0);
}

float grey(vec3 c) { return (c.r + c.g + c.b) / 3.0; }

// Without tinted glass the tint is a 1x1 zero: written once, read by nobody.
void store_tint(ivec2 px, uvec4 tint) {
    if (sp.tinted != 0u || px == ivec2(0)) imageStore(out_tint, px, sp.tinted != 0u ? tint : uvec4(0u));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    if (imageLoad(g_ids, px).x == NO_INSTANCE) {
        vec4 one = vec4(1.0);
        imageStore(out_ring0, px, one);
        imageStore(out_ring1, px, one);
        imageStore(out_ring2, px, one);
        imageStore(out_ring3, px, one);
        imageStore(out_sample_count, px, vec4(0.0));
        imageStore(out_stable, px, vec4(0.0));
        store_tint(px, uvec4(0u));
        return;
    }
    vec2 depth_and_change = imageLoad(g_depth, px).rg;  // view depth, its fwidth
    float depth = depth_and_change.x;
    vec3 ng = imageLoad(g_normal_geo, px).xyz;
    vec3 p = world_position(px, depth);
    vec3 origin = offset_ray_origin(p, ng, depth);

    // Reprojection (Eq. 13.7), to the nearest previous pixel. Where Eq. 13.7 refuses it, the
    // depth may still be this surface's: TAA's jitter puts last frame's sample of q up to a
    // pixel and a half from where this one's lies (the motion vectors leave the jitter out),
    // and on a surface seen at a grazing angle the depth changes by more than the test's
    // tolerance within that reach. Every such refusal restarted the count at s_max, frame
    // after frame on a still camera (the far floor of `tests/soft_shadows.rs`'s spot test,
    // 861 of its 4,553 pixels). So the depth's own change over that offset (from the
    // G-buffer's fwidth of the depth) is allowed as well.
    vec2 prev_pos = vec2(px) + 0.5 - imageLoad(g_motion, px).xy;
    ivec2 q = ivec2(floor(prev_pos));
    bool reprojected = false;
    if ((frame.flags & FRAME_RESET_HISTORY) == 0u && all(greaterThanEqual(q, ivec2(0))) &&
        all(lessThan(q, ivec2(frame.size)))) {
        float z_prev = imageLoad(prev_depth, q).r;
        vec2 offset = abs(vec2(q) + 0.5 - frame.prev_jitter - (prev_pos - frame.jitter));
        // On a plane the inverse depth, not the depth, changes linearly across the screen.
        float change = depth_and_change.y;
        float inv_per_pixel = change / (depth * max(depth - change, 1e-3 * depth));
        float inv_prev = 1.0 / max(z_prev, 1e-6), inv = 1.0 / max(depth, 1e-6);
        float reach = inv_per_pixel * max(offset.x, offset.y);
        reprojected = depth_consistent(depth, z_prev, ng) ||
                      depth_consistent(depth, 1.0 / max(inv_prev + clamp(inv - inv_prev, -reach, reach), 1e-6), ng);
    }
    vec4 r0 = reprojected ? imageLoad(prev_ring0, q) : vec4(0.0);
    vec4 r1 = reprojected ? imageLoad(prev_ring1, q) : vec4(0.0);
    vec4 r2v = reprojected ? imageLoad(prev_ring2, q) : vec4(0.0);
    vec4 count = reprojected ? imageLoad(prev_sample_count, q) : vec4(0.0);
    vec4 stable = reprojected ? imageLoad(prev_stable, q) : vec4(0.0);
    vec4 dv = reprojected ? imageLoad(prev_dv, q) : vec4(1.0);

    // The global budget: lower s_max in proportion when last frame's penumbrae were too wide.
    float summed = float(imageLoad(prev_budget, ivec2(0)).x) / 64.0;
    uint s_max = summed > sp.budget ? max(1u, uint(float(sp.s_max) * sp.budget / summed)) : sp.s_max;
    ivec2 block = px / 8;
    bool forced = sp.forced_blocks != 0u && FORCED[(block.y & 3) * 4 + (block.x & 3)] == (frame.frame_index & 3u);

    vec4 vis = vec4(1.0);
    uvec4 tint = uvec4(0u);
    vec4 state = vec4(0.0);
    bvec4 soft = soft_lights();
    for (uint i = 0u; i < uint(SHADOW_LIGHTS); ++i) {
        bool mesh = i >= punctual_channels();
        if (mesh && sp.mesh_triangles[i] == 0u) break;
        vec3 unshadowed = mesh ? vec3(1.0) : sample_punctual(lights[i], p).radiance;
        if (dot(unshadowed, unshadowed) == 0.0) {
            // Culled by range (or outside a spot's cone): no light, no rays. Unoccluded by
            // definition, as where no point of a light sends any (trace_visibility): a 0 here
            // would make the cone's or range's edge a shadow edge, and TAA's jitter, moving
            // pixels across it, a penumbra that drew s_max rays a frame along it (a band of the
            // default scene's walls) and the filter's widest kernel. The ring forgets what was
            // there before, as a hard light's does.
            vis[i] = 1.0;
            r0[i] = 1.0;
            r1[i] = 1.0;
            r2v[i] = 1.0;
            continue;
        }
        bool tested;
        if (!soft[i]) {
            vec3 through = trace_visibility(i, origin, ng, px, 1u, tested);
            vis[i] = grey(through);
            tint[i] = shadow_tint_encode(through);
            state[i] = 1.0;
            continue;
        }
        // Sample count with hysteresis.
        float s = count[i];
        if (!reprojected) {
            s = float(s_max);
            stable[i] = 0.0;
        } else if (dv[i] > sp.delta && s < float(s_max)) {
            s += 1.0;
            stable[i] = 0.0;
        } else if (dv[i] < sp.delta && stable[i] >= 4.0 && s > 1.0) {
            s -= 1.0;
            stable[i] = 0.0;
        } else {
            stable[i] += 1.0;
        }
        s = clamp(s, 1.0, float(s_max));
        state[i] = s;
        bool sample_now = !reprojected || dv[i] > sp.delta || forced;
        if (sample_now) {
            vec3 through = trace_visibility(i, origin, ng, px, uint(s), tested);
            vis[i] = grey(through);
            tint[i] = shadow_tint_encode(through);
            if (mesh && !tested) {
                // Every point drawn lay below the surface or behind the emitting side, which
                // happens where the mesh light straddles the surface's plane (a wall beside a
                // ceiling panel). The closed form may still see a sliver of it above, which no
                // ray has tested: keep what was known there (nothing at first, so that no light
                // shines through a wall untested), not a guess whose swings between frames the
                // penumbra detection would take for a penumbra (they kept such walls at s_max).
                vis[i] = reprojected ? r0[i] : 0.0;
                tint[i] = reprojected && sp.tinted != 0u ? imageLoad(prev_tint, q)[i] : 0u;
            }
        } else {
            vis[i] = r0[i];
            if (sp.tinted != 0u) tint[i] = imageLoad(prev_tint, q)[i];
        }
        if (!reprojected) {
            // Nothing cached is valid: every slot of the ring takes the new estimate.
            r0[i] = vis[i];
            r1[i] = vis[i];
            r2v[i] = vis[i];
        }
    }
    // Hard lights keep no history: their ring holds this frame everywhere.
    for (uint i = 0u; i < 4u; ++i) {
        if (!soft[i]) {
            r0[i] = vis[i];
            r1[i] = vis[i];
            r2v[i] = vis[i];
        }
    }
    imageStore(out_ring0, px, vis);
    imageStore(out_ring1, px, r0);
    imageStore(out_ring2, px, r1);
    imageStore(out_ring3, px, r2v);
    imageStore(out_sample_count, px, state);
    imageStore(out_stable, px, stable);
    store_tint(px, tint);
}
