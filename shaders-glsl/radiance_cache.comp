#version 460
// radiance_cache: keeps the world-space radiance cache (common/radiance_cache.glsl) and shows it.
//
// Mode 0, the update (one invocation per slot): a live cell loses a frame of life and dies at
// zero; a new one adopts the queries' winning proposal of its point; then, chosen with odds
// budget / (live cells last frame), it traces one cosine-weighted ray from its point and adds
// what comes back (a light sample at the hit plus the cache there, or the path traced on where
// the cache cannot answer) to its running mean, written to this frame's copy of the radiance.
// Cells fed by cells carry every bounce; the mean's window (max_samples) bounds the lag, and a
// frame whose lights changed (FRAME_LIGHTS_CHANGED) starts every mean anew.
//
// A change the frame does not announce (an object that moves between a light and the room) is
// caught where it shows: before its sample, a cell checks what its last one saw at the path's
// first vertex (RcCell.record). If that light sample's shadow ray now ends otherwise, or the
// cell that answered there restarted since and now holds a clearly different value, and that
// part of the sample weighs enough against the cell's mean, the mean starts anew (and the
// cell, young again, traces deep). Means fed by cells cannot let go faster than the loop of
// cells feeding cells (about window / (1 - what a bounce keeps) frames; a white room keeps most
// of it); restarts spread along the loop instead, one bounce a frame. A static scene never
// restarts: the same ray through the same scene ends the same, and cells restart only then.
//
// Mode 1, the view (one invocation per pixel): what the cache holds at each G-buffer surface,
// for dumps and the viewer (radiance_cache.irradiance: rgb = C, a = samples), and where a cell
// there restarted on a change this frame, or everywhere where a tenth of the cells did
// (radiance_cache.changed), which tells SVGF's temporal pass and TAA that the history there
// holds light that is gone.
#extension GL_GOOGLE_include_directive : require
#include "common/trace.glsl"
#include "common/brdf.glsl"
#include "common/light_sampling.glsl"
#include "common/gbuffer.glsl"
#include "common/ray_offset.glsl"
#define RC_BINDING 5
#define RC_RECORD_FIRST
#include "common/radiance_cache.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 2, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D out_irradiance;
layout(set = 1, binding = 4, r32f) uniform writeonly image2D out_changed;

layout(push_constant) uniform Params {
    uint mode;  // 0: update, 1: view
    uint seed;
} params;

#define SALT_RADIANCE_CACHE 0x72630000u

// A change restarts a cell's mean when the part of its last sample that changed carries this
// share of the mean's luminance: smaller changes are left to the mean's window.
#define RC_RESTART_SHARE 0.1
// A restarted cell that answered the last sample changed it if its value moved by this share.
#define RC_RESTART_MOVED 0.5
// Where more than this share of the cells updated this frame restarted, the change is taken to
// be one of the scene's light as a whole, as a change of the lights that the frame announces
// is: every pixel's diffuse and TAA histories let go (radiance_cache.changed everywhere). About
// half the cells of a region whose light changed notice it, and a history that no cell around
// it flagged kept the old light for its whole window. A moving object restarts a few cells a
// frame (the default scene's ball: at most 0.75% of those updated, over 64 frames); a box
// closing around a light restarts a third in the first frame and an eighth in the second (an
// eighth, then a fourteenth, where gi resamples the light; README, "Stability where methods
// fail").
#define RC_CHANGED_EVERYWHERE 0.1

// Whether what cell's last sample saw at its first vertex changed (see the top): false unless
// that sample was taken last frame.
bool changed(RcCell cell, uint read, float mean) {
    if (cell.record.x != frame.frame_index) return false;
    if (cell.shadow_from.w > 0.0) {
        Hit h = trace_ray(cell.shadow_from.xyz, cell.shadow_dir.xyz, 0.0, cell.shadow_from.w, RAY_MASK_ALL, true);
        bool reached = h.instance == NO_HIT;
        if (reached != (cell.shadow_dir.w > 0.0) && abs(cell.shadow_dir.w) > RC_RESTART_SHARE * mean) return true;
    }
    if (cell.record.y == 0u) return false;
    // Last frame's copy of the answering cell: fewer samples than it had then, but some, means
    // it restarted (or a new cell took the slot, which then differs the same way); none, that
    // it is dying, which leaves what it answered as true as it was.
    vec4 now = rc_cells[cell.record.y - 1u].radiance[read];
    vec2 then = unpackHalf2x16(cell.record.z);  // its luminance, its weighted share
    float moved = abs(luminance(now.rgb) - then.x);
    return now.a > 0.0 && now.a < uintBitsToFloat(cell.record.w) && moved > RC_RESTART_MOVED * max(luminance(now.rgb), then.x) &&
           then.y > RC_RESTART_SHARE * mean;
}

// What this update's sample saw at its first vertex (rc_first), for the next update's check.
void remember_first_vertex(uint slot, bool sampled) {
    uint f = frame.frame_index;
    if (!sampled) {
        rc_cells[slot].record = uvec4(f + 1u, 0u, 0u, 0u);
        rc_cells[slot].shadow_from.w = 0.0;
        return;
    }
    rc_cells[slot].shadow_from = vec4(rc_first.from, rc_first.light > 0.0 ? rc_first.tmax : 0.0);
    rc_cells[slot].shadow_dir = vec4(rc_first.dir, rc_first.reached ? rc_first.light : -rc_first.light);
    bool answered = rc_first.slot != RC_NONE;
    rc_cells[slot].record = uvec4(f + 1u, answered ? rc_first.slot + 1u : 0u,
                                  packHalf2x16(min(vec2(rc_first.value, rc_first.share), vec2(65504.0))),
                                  floatBitsToUint(rc_first.samples));
}

void update(uint slot) {
    uint f = frame.frame_index;
    if (slot == 0u) {
        // Nobody else touches the next frame's counters now.
        rc.live[(f + 1u) % 3u] = 0u;
        rc.updated[(f + 1u) % 3u] = 0u;
        rc.restarted[(f + 1u) % 3u] = 0u;
    }
    uint key = rc_keys[slot];
    if (key == RC_EMPTY) return;
    RcCell cell = rc_cells[slot];
    uint write = rc_copy_written(f), read = write ^ 1u;
    // A cell dies in two frames, so that other cells' updates, which may look it up while this
    // one runs, see the same thing whichever runs first: first its copy of this frame goes
    // empty (nobody uses an empty cell), then, unless a query revived it meanwhile, its slot is
    // freed: back to all zeros, the state a new cell starts in.
    if (cell.point.w <= 0.0) {
        rc_cells[slot] = RcCell(vec4[2](vec4(0.0), vec4(0.0)), vec4(0.0), vec4(0.0), vec4(0.0), uvec2(0u), 0u, vec4(0.0),
                                vec4(0.0), uvec4(0u));
        rc_keys[slot] = RC_EMPTY;
        return;
    }
    float life = cell.point.w - 1.0;
    rc_cells[slot].point.w = life;
    if (life <= 0.0) {
        rc_cells[slot].radiance[write] = vec4(0.0);
        return;
    }
    atomicAdd(rc.live[f % 3u], 1u);
    vec4 mean = cell.radiance[read];
    if (cell.normal.w == 0.0) {
        // Adopt the winning proposal of the queries so far (none yet: wait for one).
        if (cell.proposal.x == 0u) return;
        uint position = ~cell.proposal.x & 0xffffffu;
        vec3 local = vec3(float(position >> 16), float(position >> 8 & 255u), float(position & 255u)) / 255.0;
        // Lifted off the surface by more than the quantisation's error (at most sqrt(3)/510 of
        // a cell): a point a hair behind its surface would trace every ray into the back of it.
        cell.point.xyz = cell.bounds.xyz + local * cell.bounds.w;
        cell.normal = vec4(rc_unpack_normal(~cell.proposal.y & 0xffffffu), 1.0);
        cell.point.xyz += cell.normal.xyz * (cell.bounds.w * RC_POINT_LIFT);
        rc_cells[slot].point.xyz = cell.point.xyz;
        rc_cells[slot].normal = cell.normal;
    }
    // The lights changed since last frame: every cell's mean, and last frame's copy that the
    // estimate would read deeper cells from, hold the old light. The mean starts anew and the
    // estimate traces its path on without the cache; a cell not updated this frame is empty
    // until it is (queries of it trace on meanwhile).
    bool relit = (frame.flags & FRAME_LIGHTS_CHANGED) != 0u;
    if (relit) mean = vec4(0.0);
    // The random stream follows the key, not the slot the key happened to land in.
    Rng rng = rng_init(uvec2(key, 0x5a5au), f, params.seed ^ SALT_RADIANCE_CACHE);
    uint live_before = max(rc.live[(f + 2u) % 3u], 1u);
    if (rng_next(rng) * float(live_before) < float(rc.budget)) {
        atomicAdd(rc.updated[f % 3u], 1u);
        if (!relit && changed(cell, read, luminance(mean.rgb))) {
            atomicAdd(rc.restarted[f % 3u], 1u);
            rc_cells[slot].restart = f + 1u;
            mean = vec4(0.0);
        }
        bool sampled = false;
        vec3 n = cell.normal.xyz;
        vec3 origin = offset_ray(cell.point.xyz, n);
        vec3 dir = orthonormal_basis(n) * sample_cosine_hemisphere(rng_next2(rng));
        vec3 estimate = vec3(0.0);
        if (dot(dir, n) > 0.0) {
            // Straight on through see-through surfaces and through glass, like every ray of the
            // paths. The sky past a volume of glass is the cell's too, since the querying
            // vertex's light sample does not cross one: at the weight it would take against a
            // light sample that did (a sun's caustic left out, as in gi).
            Passage way = passage_start(origin, dir);
            HitSurface s;
            float travelled;
            Hit h = trace_closest_through(way, rng, s, travelled);
            if (h.instance == NO_HIT && way.turned) {
                estimate = way.weight * env_eval(way.dir) * mis_power(max(dot(n, dir), 0.0) * INV_PI, env_pdf(way.dir));
            }
            if (h.instance != NO_HIT) {
                // Cosine sampling: (1/pi) L cos / pdf is L.
                // A young cell (or any, right after the lights changed) traces its path deep
                // without the cache: the cells it would read are young too, and their truncated
                // light would stay in its mean for the whole window.
                bool deep = relit || mean.a < RC_YOUNG_SAMPLES;
                uint vertices = deep ? RC_VERTICES_DEEP : RC_VERTICES;
                estimate = way.weight * rc_radiance_leaving(s, way.dir, h.t, deep ? vertices : 0u, vertices, false, read, rng);
                sampled = true;
            }
        }
        remember_first_vertex(slot, sampled);
        if (any(isnan(estimate)) || any(isinf(estimate))) estimate = vec3(0.0);
        float samples = min(mean.a + 1.0, float(rc.max_samples));
        mean = vec4(mix(mean.rgb, estimate, 1.0 / samples), samples);
    }
    rc_cells[slot].radiance[write] = mean;
}

// Whether a cell around p restarted this frame: one of the four of its lattice square
// (rc_lattice, as rc_blend reads). About half the cells of a region whose light changed notice
// it, so one cell's restart stands for its neighbours' surfaces too; a still scene restarts
// none.
bool restarted_near(vec3 p, vec3 n) {
    RcLattice lattice = rc_lattice(p, n);
    bool any_restarted = false;
    [[unroll]] for (int i = 0; i < 4; ++i) {
        uint slot = rc_find_key(rc_cell_key(rc_lattice_cell(lattice, i), lattice.cell, lattice.bucket), false);
        any_restarted = any_restarted || slot != RC_NONE && rc_cells[slot].restart == frame.frame_index + 1u;
    }
    return any_restarted;
}

void view(ivec2 px) {
    if (imageLoad(g_ids, px).x == NO_INSTANCE) {
        imageStore(out_irradiance, px, vec4(0.0));
        imageStore(out_changed, px, vec4(0.0));
        return;
    }
    vec3 p = world_position(px, imageLoad(g_depth, px).r);
    uint slot = rc_find(p, imageLoad(g_normal_geo, px).xyz, false);
    imageStore(out_irradiance, px, slot == RC_NONE ? vec4(0.0) : rc_cells[slot].radiance[rc_copy_written(frame.frame_index)]);
    // No cell restarted this frame (a still scene, always): none to look for around p.
    uint restarted = rc.restarted[frame.frame_index % 3u];
    bool everywhere = float(restarted) > RC_CHANGED_EVERYWHERE * float(max(rc.updated[frame.frame_index % 3u], 1u));
    bool here = everywhere || restarted != 0u && restarted_near(p, imageLoad(g_normal_geo, px).xyz);
    imageStore(out_changed, px, vec4(here ? 1.0 : 0.0));
}

void main() {
    if (params.mode == 0u) {
        uint slot = gl_WorkGroupID.x * 64u + gl_LocalInvocationIndex;
        if (slot < rc.capacity) update(slot);
    } else {
        ivec2 px = ivec2(gl_GlobalInvocationID.xy);
        if (all(lessThan(px, ivec2(frame.size)))) view(px);
    }
}
