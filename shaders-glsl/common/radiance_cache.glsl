// The radiance cache (src/passes/radiance_cache.rs): a world-space hash grid of cells that
// persists across frames and holds each cell's indirect irradiance, so a GI or reflection ray
// that ends on a surface can add the light that surface reflects from everything except the
// lights (which a light sample covers exactly) without tracing the rest of the path.
//
// What a cell holds, C = (1/pi) int L_r cos over the hemisphere of the cell's normal, where L_r
// is light *reflected* by other surfaces (their emission and the environment are left out:
// next-event estimation at the querying point covers them). A surface with BRDF f seen from v
// then reflects about C times its directional albedo: `rc_radiance_leaving` estimates that with
// one BRDF sample's weight.
//
// A cell is keyed by its position quantised to a cell size that doubles with the distance from
// the camera, and by the dominant axis and sign of the geometric normal (the two faces of a thin
// wall never share a cell). A query of an absent cell claims a slot for it (compare-and-swap on
// the key's checksum) and proposes its point and normal; the next update adopts the proposal
// that wins an atomic minimum and traces from there as long as the cell lives. A query from a
// point the adopted one cannot see (a floor cell that straddles a wall thinner than a cell) is
// refused by a visibility ray, and the caller traces on instead: light does not leak through
// walls.
//
// Determinism: the same frames give the same bits whatever the threads' order. Which query
// claims a slot first only moves a key between slots (lookups follow the key, the update's
// random stream follows the key); the adopted point is a minimum over all proposals; and the
// update reads other cells from last frame's copy of the radiance (two copies, by frame parity)
// while it writes this frame's.
//
// The includer defines RC_BINDING, the first of the three set-1 bindings the cache takes, and
// includes trace.glsl, brdf.glsl, light_sampling.glsl and ray_offset.glsl first; with
// RC_BLEND_FIRST (the reflections pass) the first vertex's answer is blended (rc_blend).
#ifndef RADIANCE_CACHE_GLSL
#define RADIANCE_CACHE_GLSL

#extension GL_EXT_control_flow_attributes : require

// A path vertex's light sample is resampled from a few draws (light_sample_resampled).
#include "light_reservoir.glsl"
#include "pass_through.glsl"

#ifndef RC_BINDING
#error "RC_BINDING: define the first set-1 binding of the radiance cache before including it"
#endif

// Cells stay this many frames after the last query from the screen (gi, reflections); the
// cache's own update queries do not keep them alive, or cells could keep each other alive.
#define RC_LIFE 12.0
// Linear probes after the home slot of a key.
#define RC_PROBES 8u
// A ray shorter than this many cells ends in a cell that may hold the ray's own origin (a
// corner): the caller traces on instead.
#define RC_MIN_CELLS 1.7320508
// The visibility ray between a query and a cell's point runs this many cells above both
// surfaces: a ray skimming a surface at a few ulps would often hit the surface itself.
#define RC_LIFT_CELLS 0.1
// An adopted point is lifted this many cells along its normal (see the update).
#define RC_POINT_LIFT (1.0 / 128.0)
#define RC_EMPTY 0u
// Vertices a path may trace where the cache cannot answer (corners, cells still empty).
#define RC_VERTICES 3u
// Vertices the update traces without the cache while no cell holds much light yet (a young
// cell, or every cell in a frame whose lights changed): deep enough that these first samples
// miss little of the bounce light that cells feeding cells carry later.
#define RC_VERTICES_DEEP 6u
// A cell is young until its mean holds this many samples.
#define RC_YOUNG_SAMPLES 4.0

struct RcCell {
    vec4 radiance[2];  // by frame parity: rgb: C, a: samples in the running mean
    vec4 point;        // xyz: where the update traces from, w: frames left to live
    vec4 normal;       // xyz: geometric normal there, w: 1 once adopted
    vec4 bounds;       // xyz: the cell's lowest corner, w: its size (for decoding proposals)
    uvec2 proposal;    // x: ~(rank << 24 | position), y: ~(rank << 24 | normal); 0: none
    uint restart;      // frame + 1 of the mean's last restart on a change (0: none)
    // What the update's last sample saw at its path's first vertex (RcFirstVertex), so that the
    // next update can tell whether it changed (radiance_cache.comp, `changed`):
    vec4 shadow_from;  // xyz: the light sample's shadow-ray origin, w: its length (0: none)
    vec4 shadow_dir;   // xyz: its direction, w: the sample's unshadowed luminance, negated if blocked
    uvec4 record;      // x: frame + 1 of the sample (0: none), y: slot + 1 of the cell that answered
                       // there (0: none), z: half2(that cell's luminance, its weighted share),
                       // w: that cell's samples then
};

// Written by the CPU when the cache is made (params), then counters of the update pass.
struct RcState {
    float cell;          // cell size at the camera
    float lod_distance;  // the cell size doubles at each multiple of this distance
    uint budget;         // cells updated per frame, at most
    uint max_samples;    // the running mean's window
    uint enabled;        // 0: every query misses (the frame traces as without a cache)
    uint capacity;       // slots, a power of two
    uint live[3];        // live cells counted by the update of frame f in live[f % 3]
    uint updated[3];     // cells updated by the update of frame f in updated[f % 3]
    uint restarted[3];   // cells whose mean restarted on a change (radiance_cache.comp)
};

layout(set = 1, binding = RC_BINDING, std430) coherent buffer RcKeys { uint rc_keys[]; };
layout(set = 1, binding = RC_BINDING + 1, std430) coherent buffer RcCells { RcCell rc_cells[]; };
layout(set = 1, binding = RC_BINDING + 2, std430) coherent buffer RcStateBuffer { RcState rc; };

uint rc_hash(uint v) { return pcg_hash(v); }

// Cell size at `p`: doubles with each multiple of lod_distance from the camera.
float rc_cell_size(vec3 p) {
    float level = floor(log2(1.0 + distance(p, frame.camera_pos) / rc.lod_distance));
    return rc.cell * exp2(level);
}

// 0..5: the dominant axis of n and its sign.
uint rc_normal_bucket(vec3 n) {
    vec3 a = abs(n);
    uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
    return axis * 2u + (n[axis] < 0.0 ? 1u : 0u);
}

// Home slot and checksum (never RC_EMPTY) of cell c of size `cell` and normal bucket `bucket`.
uvec2 rc_cell_key(ivec3 c, float cell, uint bucket) {
    uint h = rc_hash(floatBitsToUint(cell) ^ bucket);
    h = rc_hash(h ^ uint(c.x));
    h = rc_hash(h ^ uint(c.y));
    h = rc_hash(h ^ uint(c.z));
    uint check = rc_hash(h ^ 0x9e3779b9u) | 1u;
    return uvec2(h & (rc.capacity - 1u), check);
}

// Home slot and checksum of the cell holding (p, n).
uvec2 rc_key(vec3 p, vec3 n) {
    float cell = rc_cell_size(p);
    return rc_cell_key(ivec3(floor(p / cell)), cell, rc_normal_bucket(n));
}

#define RC_NONE 0xffffffffu

// The slot of the cell with key k (rc_key), claiming an empty one when `claim`. RC_NONE when
// absent (or the probes are full). A freed slot is all zeros (the update clears it), which is
// the state a new cell starts in.
uint rc_find_key(uvec2 k, bool claim) {
    for (uint i = 0u; i < RC_PROBES; ++i) {
        uint slot = (k.x + i) & (rc.capacity - 1u);
        uint seen = rc_keys[slot];
        if (seen == k.y) return slot;
        if (seen != RC_EMPTY) continue;
        if (!claim) return RC_NONE;
        uint prev = atomicCompSwap(rc_keys[slot], RC_EMPTY, k.y);
        if (prev == RC_EMPTY || prev == k.y) return slot;
    }
    return RC_NONE;
}

// The slot of the cell holding (p, n) (rc_find_key).
uint rc_find(vec3 p, vec3 n, bool claim) { return rc_find_key(rc_key(p, n), claim); }

// 12 + 12 bits: the octahedral map of a unit vector.
uint rc_pack_normal(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    uvec2 q = uvec2(clamp(e * 0.5 + 0.5, 0.0, 1.0) * 4095.0 + 0.5);
    return q.x << 12 | q.y;
}

vec3 rc_unpack_normal(uint v) {
    vec2 e = vec2(float(v >> 12 & 4095u), float(v & 4095u)) / 4095.0 * 2.0 - 1.0;
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

// A query's proposal of its point (8 bits per axis within the cell) and normal for a cell that
// has none yet. The rank, a hash of the quantised point, makes the winner a random one of the
// proposals rather than the one nearest a corner, and the same one whatever the threads' order.
void rc_propose(uint slot, vec3 p, vec3 n) {
    float cell = rc_cell_size(p);
    vec3 corner = floor(p / cell) * cell;
    uvec3 q = uvec3(clamp((p - corner) / cell, 0.0, 1.0) * 255.0 + 0.5);
    uint position = q.x << 16 | q.y << 8 | q.z;
    uint rank = rc_hash(position) >> 24;
    // Every query of this key writes the same corner and size.
    rc_cells[slot].bounds = vec4(corner, cell);
    atomicMax(rc_cells[slot].proposal.x, ~(rank << 24 | position));
    atomicMax(rc_cells[slot].proposal.y, ~(rank << 24 | rc_pack_normal(n)));
}

// The radiance copy that queries read in frame `frame_index`: the update writes copy
// frame_index & 1 and reads the other, which the last frame's update wrote.
uint rc_copy_written(uint frame_index) { return frame_index & 1u; }

// A cache answer that holds only if the cell's point sees the query: the visibility ray from
// `from` along `dir` for `len` must miss.
struct RcCandidate {
    uint slot;
    vec3 c;
    vec3 from;
    vec3 dir;
    float len;
    bool empty;  // no answer because the cell holds no light yet (its slot taken, no samples)
};

// The four cells around p in the plane of its normal's dominant axis (p's own among them),
// which rc_blend reads bilinearly and radiance_cache.comp's restart test asks: the cells whose
// centres' lattice square holds p.
struct RcLattice {
    float cell;     // the cells' size at p
    uint bucket;    // p's normal bucket
    uint u, v;      // the two in-plane axes
    ivec3 own;      // p's own cell
    ivec2 base;     // the square's first corner on the lattice of centres along u, v
    vec2 f;         // p's position in the square
};

RcLattice rc_lattice(vec3 p, vec3 n) {
    RcLattice l;
    l.cell = rc_cell_size(p);
    l.bucket = rc_normal_bucket(n);
    uint axis = l.bucket / 2u;
    l.u = axis == 0u ? 1u : 0u;
    l.v = axis == 2u ? 1u : 2u;
    vec3 g = p / l.cell;
    l.own = ivec3(floor(g));
    vec2 f = vec2(g[l.u], g[l.v]) - 0.5;
    l.base = ivec2(floor(f));
    l.f = f - vec2(l.base);
    return l;
}

// The square's corner i (0..3): its cell, and its bilinear weight at p.
ivec3 rc_lattice_cell(RcLattice l, int i) {
    ivec3 c = l.own;
    c[l.u] = l.base.x + (i & 1);
    c[l.v] = l.base.y + (i >> 1);
    return c;
}

float rc_lattice_weight(RcLattice l, int i) {
    return ((i & 1) == 1 ? l.f.x : 1.0 - l.f.x) * ((i >> 1) == 1 ? l.f.y : 1.0 - l.f.y);
}

// Blending, for queries whose answer a pixel shows unfiltered (a mirror's reflection): the
// cells are read bilinearly in the surface's plane, so that the reflection of a wall is not a
// mosaic of one value per cell. Of the four cells around p in the plane of its normal's
// dominant axis (p's own among them) a neighbour joins with its bilinear weight where it holds
// light, its point lies on p's plane (within half a cell), and its value is within a factor
// RC_BLEND_RANGE of p's own cell's: the blend smooths the cells' steps and noise, not a real edge
// of the indirect light. The same test keeps a lit room's cells out of a dark room's across a
// wall thinner than a cell, where a neighbour's point may lie behind the wall (only p's own
// cell's point is checked by a visibility ray). Four lookups, no ray.
#define RC_BLEND_RANGE 4.0
vec3 rc_blend(vec3 p, vec3 n, uint copy, vec3 home) {
    RcLattice lattice = rc_lattice(p, n);
    float home_l = luminance(home);
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    [[unroll]] for (int i = 0; i < 4; ++i) {
        ivec3 c = rc_lattice_cell(lattice, i);
        float w = rc_lattice_weight(lattice, i);
        vec3 value = home;
        if (c != lattice.own) {
            uint slot = rc_find_key(rc_cell_key(c, lattice.cell, lattice.bucket), false);
            if (slot == RC_NONE || rc_cells[slot].normal.w == 0.0) continue;
            vec4 radiance = rc_cells[slot].radiance[copy];
            float l = luminance(radiance.rgb);
            bool near_plane = abs(dot(rc_cells[slot].point.xyz - p, n)) <= 0.5 * lattice.cell;
            bool alike = l <= RC_BLEND_RANGE * home_l && home_l <= RC_BLEND_RANGE * l;
            if (!(radiance.a > 0.0) || !near_plane || !alike) continue;
            value = radiance.rgb;
        }
        sum += w * value;
        wsum += w;
    }
    return sum / wsum;  // p's own cell weighs at least 1/4
}

// The cache's C at surface point p (geometric normal n) reached by a ray of length t, from
// radiance copy `copy`, when the cache may answer: the cell exists, has samples, and the ray is
// long enough not to end in its own origin's cell. The answer holds if the cell's point sees p
// (the caller traces `a`'s visibility ray). `from_screen`: a gi or reflection query, which
// claims absent cells, proposes points and keeps cells alive. `blend`: the answer is
// rc_blend's.
bool rc_lookup(vec3 p, vec3 n, float t, bool from_screen, bool blend, uint copy, out RcCandidate a) {
    a = RcCandidate(RC_NONE, vec3(0.0), vec3(0.0), vec3(0.0, 0.0, 1.0), 0.0, false);
    if (rc.enabled == 0u || t < RC_MIN_CELLS * rc_cell_size(p)) return false;
    uint slot = rc_find(p, n, from_screen);
    if (slot == RC_NONE) return false;
    if (from_screen) {
        rc_cells[slot].point.w = RC_LIFE;
        if (rc_cells[slot].normal.w == 0.0) rc_propose(slot, p, n);
    }
    vec4 radiance = rc_cells[slot].radiance[copy];
    a.empty = rc_cells[slot].normal.w == 0.0 || radiance.a <= 0.0;
    if (a.empty) return false;
    a.slot = slot;
    float lift = RC_LIFT_CELLS * rc_cell_size(p);
    a.from = p + n * lift;
    vec3 d = rc_cells[slot].point.xyz + rc_cells[slot].normal.xyz * lift - a.from;
    a.len = length(d);
    a.dir = a.len > 1e-6 ? d / a.len : vec3(0.0, 0.0, 1.0);
    a.c = blend ? rc_blend(p, n, copy, radiance.rgb) : radiance.rgb;
    return true;
}

// A vertex smoother than this is specular: a light sample through its near-delta lobe almost
// never lands, so the light it reflects from emitters and the environment (a caustic: a mirror
// throwing the ceiling light onto the floor) is taken by its BRDF-sampled ray instead, and the
// cache, which answers with a diffuse surface's mean, is not asked there (the path traces on).
#define RC_SPECULAR_ROUGHNESS 0.15

// Rays of a vertex in rc_radiance_leaving, in the order traced.
#define RC_RAY_LIGHT 0u  // the light sample's shadow ray
#define RC_RAY_CELL 1u   // the visibility ray between the vertex and its cache cell's point
#define RC_RAY_NEXT 2u   // the BRDF-sampled ray to the next vertex

#ifdef RC_RECORD_FIRST
// What rc_radiance_leaving's first vertex saw, for the cache's update (RcCell.record): its
// light sample's shadow ray and unshadowed luminance (0: none), and the cell that answered
// there (RC_NONE: none) with its luminance and its weighted share of the estimate.
struct RcFirstVertex {
    vec3 from;
    float tmax;
    vec3 dir;
    float light;
    bool reached;
    uint slot;
    float value;
    float share;
    float samples;
};
RcFirstVertex rc_first;
#endif

// Light leaving surface s toward -dir, reached by a ray of length t, without s's own emission:
// a light sample at each vertex, and for the rest the cache from vertex `first_cached` on (0:
// s itself), tracing on by BRDF sampling where the cache cannot answer, `vertices` at most
// (RC_VERTICES_DEEP once a cell on the way holds nothing yet).
// Queries count as from the screen when `from_screen` and read radiance copy `copy`.
//
// Every ray goes through one trace_ray call in the inner loop: lavapipe inlines a whole
// traversal at each call site, and three sites made the shaders that use this take minutes to
// compile.
vec3 rc_radiance_leaving(HitSurface s, vec3 dir, float t, uint first_cached, uint vertices, bool from_screen,
                         uint copy, inout Rng rng) {
    vec3 radiance = vec3(0.0);
    vec3 throughput = vec3(1.0);
#ifdef RC_RECORD_FIRST
    rc_first = RcFirstVertex(vec3(0.0), 0.0, vec3(0.0, 0.0, 1.0), 0.0, false, RC_NONE, 0.0, 0.0, 0.0);
#endif
    for (uint vertex = 0u; vertex < vertices; ++vertex) {
        // Glass reflects only the light it does not let through: its diffuse lobe shrinks by
        // the transmitted share (exactly so for a dielectric; a transmissive metal's F0 tint
        // shrinks with it). What thin glass lets through, the BRDF-sampled ray below follows
        // (pass_on), into and out of a volume too.
        vec3 base = s.mat.base_color.rgb * (1.0 - s.mat.transmission);
        BrdfInput m = BrdfInput(base, s.mat.metallic, s.mat.roughness, dielectric_f0(s.mat.ior));
        vec3 v = -dir;
        vec3 leave = offset_ray(s.position, s.normal_geo);
        vec3 f;
        NeeSample ls = light_sample_resampled(leave, m, s.normal, s.normal_geo, v, rng, f);
        BrdfSample bs = brdf_sample(m, s.normal, v, rng_next3(rng));
        bool scatters = bs.pdf > 0.0 && dot(bs.l, s.normal_geo) > 0.0;
        // At a specular vertex each lobe meets the lights one way only: the diffuse lobe by the
        // light sample, the specular lobe by the BRDF-sampled ray (its share of that sample),
        // except a punctual light's, which no ray can hit.
        bool specular = s.mat.roughness < RC_SPECULAR_ROUGHNESS;
        if (specular && ls.pdf > 0.0) f = max(f - brdf_eval_specular_cos(m, s.normal, v, ls.dir), vec3(0.0));
        // What the specular lobe passes on to the light its BRDF-sampled ray meets.
        vec3 specular_carry = specular && scatters ? throughput * brdf_eval_specular_cos(m, s.normal, v, bs.l) / bs.pdf
                                                   : vec3(0.0);
        RcCandidate cached;
        cached.empty = false;
#ifdef RC_BLEND_FIRST
        bool blend = vertex == 0u;
#else
        bool blend = false;
#endif
        bool may_cache = scatters && !specular && vertex >= first_cached &&
                         rc_lookup(s.position, s.normal_geo, t, from_screen, blend, copy, cached);
        // A cell that holds no light yet (every cell in the first frame, a place just come into
        // view) cannot answer: the path traces on as deep as a young cell's update does, so
        // those frames miss little of the light beyond.
        if (cached.empty) vertices = max(vertices, RC_VERTICES_DEEP);
        bool answered = false, traced_next = false;
        Hit next;
        next.instance = NO_HIT;
        HitSurface next_surface;
        // The BRDF-sampled ray goes straight on through see-through surfaces and through
        // volumes of glass (by this site again: `way` moves past each), scaled by what passes.
        Passage way = passage_start(leave, bs.l);
        [[dont_unroll]] for (uint ray = RC_RAY_LIGHT; ray <= RC_RAY_NEXT; ++ray) {
            vec3 o = leave, d = ls.dir;
            float tmax = shadow_ray_tmax(ls.dist);
            if (ray == RC_RAY_LIGHT) {
                if (dot(f, f) <= 0.0) continue;
            } else if (ray == RC_RAY_CELL) {
                if (!may_cache) continue;
                o = cached.from;
                d = cached.dir;
                tmax = cached.len;
            } else {
                if (answered || !scatters || vertex + 1u == vertices) break;
                o = way.from;
                d = way.dir;
                tmax = 1e6;
            }
            // Light and cell rays cross see-through surfaces, scaled by what passes them.
            Hit h = trace_ray(o, d, 0.0, tmax, RAY_MASK_ALL, ray != RC_RAY_NEXT);
#ifdef LIGHT_GRID_LEARN
            // A resampled light's shadow ray teaches the light grid what this cell sees.
            if (ray == RC_RAY_LIGHT) light_grid_learn(leave, ls.light, h.instance == NO_HIT);
#endif
#ifdef RC_RECORD_FIRST
            if (vertex == 0u && ray == RC_RAY_LIGHT) {
                rc_first.from = o;
                rc_first.dir = d;
                rc_first.tmax = tmax;
                rc_first.light = luminance(f * ls.weight);
                rc_first.reached = h.instance == NO_HIT;
            } else if (vertex == 0u && ray == RC_RAY_CELL && h.instance == NO_HIT) {
                rc_first.slot = cached.slot;
                rc_first.value = luminance(cached.c);
                rc_first.share = luminance(bs.weight * cached.c);
                rc_first.samples = rc_cells[cached.slot].radiance[copy].a;
            }
#endif
            if (ray == RC_RAY_LIGHT && h.instance == NO_HIT) {
                // Full weight: a BRDF-sampled ray counts emission only through a specular lobe,
                // which the light sample then leaves out.
                radiance += throughput * f * ls.weight * hit_transmittance;
            } else if (ray == RC_RAY_CELL && h.instance == NO_HIT) {
                // The BRDF sample's weight estimates the directional albedo that reflects C.
                radiance += throughput * bs.weight * cached.c * hit_transmittance;
                answered = true;
            } else if (ray == RC_RAY_NEXT) {
                next = h;
                traced_next = true;
                if (h.instance == NO_HIT) continue;
                next_surface = hit_surface(h.instance, h.primitive, h.bary, d);
                if (pass_on(next_surface, h.t, way, rng)) --ray;  // the loop's increment brings it back to RC_RAY_NEXT
            }
        }
        specular_carry *= way.weight;
        if (next.instance == NO_HIT) {
            // Only a traced ray escapes: the environment, seen through a specular lobe. Past a
            // volume of glass, which the light sample does not cross, the rest of the sky comes
            // through the other lobe too, at the weight it would take against a light sample
            // that did (what glass focuses from a sun is left out, as in gi).
            if (traced_next) {
                vec3 sky = env_eval(way.dir);
                radiance += specular_carry * sky;
                if (way.turned) {
                    vec3 rest = throughput * bs.weight * way.weight - specular_carry;
                    radiance += rest * sky * mis_power(bs.pdf, env_pdf(way.dir));
                }
            }
            break;
        }
        throughput *= bs.weight * way.weight;
        dir = way.dir;
        t = next.t;
        s = next_surface;
        if (emitter_visible_side(next.instance, next.primitive, dir)) radiance += specular_carry * s.mat.emissive;
    }
    return radiance;
}

#endif
