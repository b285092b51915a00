// The compute backend's traversal of the project's two-level BVH (src/accel/bvh): the GLSL
// twin of src/accel/bvh/traverse.rs, which documents the algorithm and is the reference the
// tests compare against. Included by trace.glsl under RT_COMPUTE_BVH.
//
// Written for SIMD execution (lavapipe runs 8 invocations per AVX2 vector, with masks for
// divergent control flow): one loop for both levels with one stack, and one step of every
// kind per iteration (a triangle, a pop, a node, an instance entry), so lanes at different
// levels or in leaves of different sizes advance together instead of waiting for each other's
// nested loops. The stack lives in module-scope arrays indexed only dynamically: arrays
// passed as inout parameters are copied whole on every call (and scalarised by spirv-opt).
#ifndef BVH_TRAVERSE_GLSL
#define BVH_TRAVERSE_GLSL

// The packed rows of src/accel/bvh (its mod.rs documents the layout): the top level's rows,
// whose row 0 holds the root reference and the first row of the bottom levels, then the
// pooled bottom levels. References are kind << 28 | row offset within their tree (kind 0:
// inner node, n: leaf of n records).
layout(set = 0, binding = 8, std430) readonly restrict buffer BvhRows { uvec4 bvh_rows[]; };

#define BVH_KIND_SHIFT 28u
#define BVH_OFFSET_MASK 0x0fffffffu
#define BVH_NONE 0xffffffffu
#define BVH_NODE_ROWS 2u
#define BVH_TRIANGLE_ROWS 3u
#define BVH_INSTANCE_ROWS 4u
#define BVH_INSTANCE_ALPHA_TESTED 1u
#define BVH_INSTANCE_TRANSLATED 2u
// One stack for both levels: the builder keeps their depths within it (src/accel/bvh/layout.rs
// STACK_SIZE).
#define BVH_STACK_SIZE 64
#define BVH_BOX_FAR_SCALE 1.0000004
#define BVH_MIN_DIR 1e-20

struct BvhRay {
    vec3 origin;
    vec3 inv_dir;
    ivec3 k;     // x, y, z axis permutation; dir[k.z] is the largest component
    vec3 shear;  // sx, sy, sz
};

BvhRay bvh_ray(vec3 origin, vec3 dir) {
    BvhRay r;
    r.origin = origin;
    // Tiny components become +-BVH_MIN_DIR with the component's sign bit (copysign).
    vec3 tiny = uintBitsToFloat((floatBitsToUint(dir) & 0x80000000u) | floatBitsToUint(BVH_MIN_DIR));
    vec3 safe = mix(dir, tiny, lessThan(abs(dir), vec3(BVH_MIN_DIR)));
    r.inv_dir = 1.0 / safe;
    vec3 ad = abs(dir);
    int kz = ad.x >= ad.y ? (ad.x >= ad.z ? 0 : 2) : (ad.y >= ad.z ? 1 : 2);
    int kx = (kz + 1) % 3;
    int ky = (kz + 2) % 3;
    if (dir[kz] < 0.0) {
        int tmp = kx;
        kx = ky;
        ky = tmp;
    }
    r.k = ivec3(kx, ky, kz);
    r.shear = vec3(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
    return r;
}

// Entry distance, or -1 when the box is missed within [tmin, tmax].
float bvh_hit_box(BvhRay r, vec3 lo, vec3 hi, float tmin, float tmax) {
    vec3 n = mix(hi, lo, greaterThanEqual(r.inv_dir, vec3(0.0)));
    vec3 f = mix(lo, hi, greaterThanEqual(r.inv_dir, vec3(0.0)));
    vec3 tn = (n - r.origin) * r.inv_dir;
    vec3 tf = (f - r.origin) * r.inv_dir * BVH_BOX_FAR_SCALE;
    float near = max(tmin, max(tn.x, max(tn.y, tn.z)));
    float far = min(tmax, min(tf.x, min(tf.y, tf.z)));
    return near <= far ? near : -1.0;
}

// px*qy - py*qx with one rounding (Kahan's difference of products with fused multiply-adds):
// its sign is exact, so an edge that came out 0 gets the same sign as the f64 reference.
float bvh_edge_exact(float px, float py, float qx, float qy) {
    precise float w = py * qx;
    precise float e = fma(-py, qx, w);
    precise float f = fma(px, qy, -w);
    return f + e;
}

// Watertight ray/triangle test (Woop, Benthin, Wald 2013). Returns t, or -1 on a miss.
float bvh_hit_triangle(BvhRay r, vec3 v0, vec3 v1, vec3 v2, float tmin, float tmax, out vec2 bary, out bool front) {
    vec3 a = v0 - r.origin;
    vec3 b = v1 - r.origin;
    vec3 c = v2 - r.origin;
    float ax = a[r.k.x] - r.shear.x * a[r.k.z], ay = a[r.k.y] - r.shear.y * a[r.k.z];
    float bx = b[r.k.x] - r.shear.x * b[r.k.z], by = b[r.k.y] - r.shear.y * b[r.k.z];
    float cx = c[r.k.x] - r.shear.x * c[r.k.z], cy = c[r.k.y] - r.shear.y * c[r.k.z];
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if (u == 0.0 || v == 0.0 || w == 0.0) {
        u = bvh_edge_exact(cx, cy, bx, by);
        v = bvh_edge_exact(ax, ay, cx, cy);
        w = bvh_edge_exact(bx, by, ax, ay);
    }
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return -1.0;
    float det = u + v + w;
    if (det == 0.0) return -1.0;
    float rcp = 1.0 / det;
    float t = (u * r.shear.z * a[r.k.z] + v * r.shear.z * b[r.k.z] + w * r.shear.z * c[r.k.z]) * rcp;
    if (!(tmin <= t && t <= tmax)) return -1.0;
    bary = vec2(v * rcp, w * rcp);
    front = det > 0.0;
    return t;
}

vec3 bvh_xform_point(vec4 m[3], vec3 p) { return vec3(dot(m[0], vec4(p, 1.0)), dot(m[1], vec4(p, 1.0)), dot(m[2], vec4(p, 1.0))); }
vec3 bvh_xform_vector(vec4 m[3], vec3 d) { return vec3(dot(m[0].xyz, d), dot(m[1].xyz, d), dot(m[2].xyz, d)); }


// The traversal stack: child references and their entry distances.
uint bvh_stack_ref[BVH_STACK_SIZE];
float bvh_stack_t[BVH_STACK_SIZE];

// A traversal's state besides the ray's hit record and the stack.
struct BvhState {
    BvhRay r;       // the ray in the current tree's space
    uint cur;       // the reference to take next, or BVH_NONE to pop
    int sp;         // stack depth
    uint base;      // the current tree's first row: 0 in the top level
    // While inside an instance: the stack depth at its entry (entries below belong to the top
    // level) and its record's row. -1 in the top level.
    int inst_sp;
    uint inst_row;
    bool inst_alpha;
    // The leaf being tested: triangle records at rows tri_next..tri_end.
    uint tri_next;
    uint tri_end;
};

// The references of both children of the node record n0, n1 (relative to its tree).
uvec2 bvh_children(uvec4 n0, uvec4 n1, uint leaf_rows) {
    uint kind_a = (n0.w >> 24u) & 0xfu;
    uint a = (kind_a << BVH_KIND_SHIFT) | n1.w;
    uint b = ((n0.w >> 28u) << BVH_KIND_SHIFT) | (n1.w + (kind_a == 0u ? BVH_NODE_ROWS : kind_a * leaf_rows));
    return uvec2(a, b);
}

// Inner node s.cur, whose record is n0, n1: decodes both quantised child boxes, continues at
// the nearer child hit and pushes the farther.
void bvh_visit_record(inout BvhState s, uvec4 n0, uvec4 n1, float tmin, float closest) {
    vec3 grid_origin = uintBitsToFloat(n0.xyz);
    vec3 grid_step = uintBitsToFloat(((uvec3(n0.w) >> uvec3(0u, 8u, 16u)) & 0xffu) << 23u);
    vec3 a_lo = grid_origin + vec3(n1.xyz & 0xffu) * grid_step;
    vec3 b_lo = grid_origin + vec3((n1.xyz >> 8u) & 0xffu) * grid_step;
    vec3 a_hi = grid_origin + vec3((n1.xyz >> 16u) & 0xffu) * grid_step;
    vec3 b_hi = grid_origin + vec3(n1.xyz >> 24u) * grid_step;
    float ta = bvh_hit_box(s.r, a_lo, a_hi, tmin, closest);
    float tb = bvh_hit_box(s.r, b_lo, b_hi, tmin, closest);
    uvec2 ab = bvh_children(n0, n1, s.inst_sp >= 0 ? BVH_TRIANGLE_ROWS : BVH_INSTANCE_ROWS);
    uint a = ab.x;
    uint b = ab.y;
    s.cur = ta >= 0.0 ? a : (tb >= 0.0 ? b : BVH_NONE);
    if (ta >= 0.0 && tb >= 0.0) {
        bool b_first = tb < ta;
        bvh_stack_ref[s.sp] = b_first ? a : b;
        bvh_stack_t[s.sp] = b_first ? ta : tb;
        ++s.sp;
        s.cur = b_first ? b : a;
    }
}

void bvh_visit(inout BvhState s, float tmin, float closest) {
    uint at = s.base + s.cur;
    bvh_visit_record(s, bvh_rows[at], bvh_rows[at + 1u], tmin, closest);
}

// The instance record at row `at` (top level): the traversal continues in its mesh, in object
// space, from the mesh's root.
void bvh_enter(inout BvhState s, uint at, vec3 origin, vec3 dir, uint mask, uint blas_base) {
    s.cur = BVH_NONE;
    uvec4 meta = bvh_rows[at + 3u];
    uint flags = meta.w >> 8u;
    if ((meta.w & mask & 0xffu) == 0u) return;
    if ((flags & BVH_INSTANCE_TRANSLATED) != 0u) {
        // s.r is the world ray here; only its origin moves.
        s.r.origin = origin + uintBitsToFloat(uvec3(bvh_rows[at].w, bvh_rows[at + 1u].w, bvh_rows[at + 2u].w));
    } else {
        vec4 m[3] = vec4[3](uintBitsToFloat(bvh_rows[at]), uintBitsToFloat(bvh_rows[at + 1u]),
                            uintBitsToFloat(bvh_rows[at + 2u]));
        s.r = bvh_ray(bvh_xform_point(m, origin), bvh_xform_vector(m, dir));
    }
    s.inst_sp = s.sp;
    s.inst_row = at;
    s.inst_alpha = (flags & BVH_INSTANCE_ALPHA_TESTED) != 0u;
    s.base = blas_base + meta.x;
    s.cur = meta.y;
    // A mesh that is one leaf: test it from the next iteration on.
    if (s.cur >= (1u << BVH_KIND_SHIFT)) {
        s.tri_next = s.base + (s.cur & BVH_OFFSET_MASK);
        s.tri_end = s.tri_next + (s.cur >> BVH_KIND_SHIFT) * BVH_TRIANGLE_ROWS;
        s.cur = BVH_NONE;
    }
}

// Leaf s.cur: a bottom-level leaf's triangles become the ones to test; a top-level leaf is one
// instance record, entered.
void bvh_leaf(inout BvhState s, vec3 origin, vec3 dir, uint mask, uint blas_base) {
    uint at = s.base + (s.cur & BVH_OFFSET_MASK);
    if (s.inst_sp < 0) {
        bvh_enter(s, at, origin, dir, mask, blas_base);
        return;
    }
    s.tri_next = at;
    s.tri_end = at + (s.cur >> BVH_KIND_SHIFT) * BVH_TRIANGLE_ROWS;
    s.cur = BVH_NONE;
}

// Tests the triangle at s.tri_next and moves past it; records an accepted hit in best (with its
// instance record's row) and returns true. `alpha`: whether this call site tests candidates on
// alpha-tested instances (a constant: a site without them compiles without the test).
bool bvh_test_triangle(inout BvhState s, float tmin, inout float closest, inout Hit best, inout uint best_instance,
                       bool first_hit, bool alpha) {
    vec2 bary;
    bool front;
    uint row = s.tri_next;
    s.tri_next += BVH_TRIANGLE_ROWS;
    float t = bvh_hit_triangle(s.r, uintBitsToFloat(bvh_rows[row].xyz), uintBitsToFloat(bvh_rows[row + 1u].xyz),
                               uintBitsToFloat(bvh_rows[row + 2u].xyz), tmin, closest, bary, front);
    if (t < 0.0) return false;
    // Only now the primitive index: most tests miss, and every word loaded costs.
    uint prim = bvh_rows[row].w;
    if (alpha && s.inst_alpha && !hit_alpha_accept(bvh_rows[s.inst_row + 3u].z, prim, bary, first_hit)) return false;
    closest = t;
    best_instance = s.inst_row;
    best.primitive = prim;
    best.t = t;
    best.bary = bary;
    best.front_face = front;
    return true;
}

Hit bvh_trace(vec3 origin, vec3 dir, float tmin, float tmax, uint mask, bool first_hit) {
    hit_begin_query(dir);
    BvhRay world = bvh_ray(origin, dir);
    Hit best;
    best.instance = NO_HIT;
    // Row of the best hit's instance record: its custom index is read once, at the end.
    uint best_instance = BVH_NONE;
    float closest = tmax;
    uvec2 head = bvh_rows[0].xy;
    uint blas_base = head.y;
    BvhState s = BvhState(world, head.x, 0, 0u, -1, 0u, false, 0u, 0u);
    // The loop's first steps, taken before it: every ray starts at the same root, whose record
    // is always at row 1 (and, when it is one instance, a copy of its mesh's root node at row
    // 5). lavapipe loads a word from a constant address once for all invocations, not once
    // per invocation.
    if (s.cur < (1u << BVH_KIND_SHIFT)) {
        bvh_visit_record(s, bvh_rows[1], bvh_rows[2], tmin, closest);
    } else if (s.cur != BVH_NONE) {
        bvh_enter(s, 1u, origin, dir, mask, blas_base);
        if (s.cur < (1u << BVH_KIND_SHIFT)) bvh_visit_record(s, bvh_rows[5], bvh_rows[6], tmin, closest);
    }
    while (true) {
        // Up to two triangles per iteration: leaves hold about two (a quad is two triangles). The
        // second test leaves alpha-tested instances to the next iteration, so that each traversal
        // inlines the alpha test once.
        if (s.tri_next < s.tri_end && bvh_test_triangle(s, tmin, closest, best, best_instance, first_hit, true) &&
            first_hit) break;
        if (s.tri_next < s.tri_end && !s.inst_alpha &&
            bvh_test_triangle(s, tmin, closest, best, best_instance, first_hit, false) && first_hit) break;
        if (s.tri_next < s.tri_end) continue;
        if (s.cur == BVH_NONE) {
            // Pop, dropping entries the closest hit has passed; leave the instance once only
            // top-level entries remain.
            while (s.sp > 0 && bvh_stack_t[s.sp - 1] > closest) --s.sp;
            if (s.sp <= s.inst_sp) {
                s.r = world;
                s.base = 0u;
                s.inst_sp = -1;
            }
            if (s.sp == 0) break;
            --s.sp;
            s.cur = bvh_stack_ref[s.sp];
        }
        if (s.cur < (1u << BVH_KIND_SHIFT)) bvh_visit(s, tmin, closest);
        if (s.cur != BVH_NONE && s.cur >= (1u << BVH_KIND_SHIFT)) bvh_leaf(s, origin, dir, mask, blas_base);
    }
    if (best_instance != BVH_NONE) best.instance = bvh_rows[best_instance + 3u].z;
    return best;
}

bool trace_any(vec3 origin, vec3 dir, float tmin, float tmax, uint mask) {
    return bvh_trace(origin, dir, tmin, tmax, mask, true).instance != NO_HIT;
}

Hit trace_closest(vec3 origin, vec3 dir, float tmin, float tmax, uint mask) {
    return bvh_trace(origin, dir, tmin, tmax, mask, false);
}

Hit trace_ray(vec3 origin, vec3 dir, float tmin, float tmax, uint mask, bool first_hit) {
    return bvh_trace(origin, dir, tmin, tmax, mask, first_hit);
}

#endif
