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

// The packed rows of src/accel/bvh (its mod.rs documents the layout): row 0 holds the top
// level's root reference and the first row of the bottom levels; references are
// kind << 28 | row offset within their tree (kind 0: inner node, n: leaf of n records).
layout(set = 0, binding = 8, std430) readonly restrict buffer BvhRows { uvec4 bvh_rows[]; };

#define BVH_KIND_SHIFT 28u
#define BVH_OFFSET_MASK 0x0fffffffu
#define BVH_NONE 0xffffffffu
#define BVH_NODE_ROWS 2u
#define BVH_TRIANGLE_ROWS 3u
#define BVH_INSTANCE_ROWS 4u
#define BVH_INSTANCE_ALPHA_TESTED 1u
// Each level's tree is at most STACK_SIZE deep (src/accel/bvh/layout.rs); one stack holds both.
#define BVH_STACK_SIZE 128
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

Hit bvh_trace(vec3 origin, vec3 dir, float tmin, float tmax, uint mask, bool first_hit) {
    BvhRay world = bvh_ray(origin, dir);
    BvhRay r = world;
    Hit best;
    best.instance = NO_HIT;
    // Row of the best hit's instance record: its custom index is read once, at the end.
    uint best_instance = BVH_NONE;
    float closest = tmax;
    int sp = 0;
    uvec2 head = bvh_rows[0].xy;
    uint cur = head.x;
    uint blas_base = head.y;
    // The current tree's first row: 0 in the top level.
    uint base = 0u;
    // While inside an instance: the stack depth at its entry (entries below belong to the top
    // level) and its record's row. -1 in the top level.
    int inst_sp = -1;
    uint inst_row = 0u;
    bool inst_alpha = false;
    // The leaf being tested: triangle records at rows tri_next..tri_end.
    uint tri_next = 0u;
    uint tri_end = 0u;
    while (true) {
        if (tri_next < tri_end) {
            vec2 bary;
            bool front;
            float t = bvh_hit_triangle(r, uintBitsToFloat(bvh_rows[tri_next].xyz),
                                       uintBitsToFloat(bvh_rows[tri_next + 1u].xyz),
                                       uintBitsToFloat(bvh_rows[tri_next + 2u].xyz), tmin, closest, bary, front);
            if (t >= 0.0) {
                uint prim = bvh_rows[tri_next].w;
                if (!inst_alpha || hit_alpha_accept(bvh_rows[inst_row + 3u].z, prim, bary)) {
                    closest = t;
                    best_instance = inst_row;
                    best.primitive = prim;
                    best.t = t;
                    best.bary = bary;
                    best.front_face = front;
                    if (first_hit) break;
                }
            }
            tri_next += BVH_TRIANGLE_ROWS;
        }
        if (tri_next < tri_end) continue;
        if (cur == BVH_NONE) {
            // Pop, dropping entries the closest hit has passed; leave the instance once only
            // top-level entries remain.
            while (sp > 0 && bvh_stack_t[sp - 1] > closest) --sp;
            if (sp <= inst_sp) {
                r = world;
                base = 0u;
                inst_sp = -1;
            }
            if (sp == 0) break;
            --sp;
            cur = bvh_stack_ref[sp];
        }
        if (cur < (1u << BVH_KIND_SHIFT)) {
            // Inner node: decode both quantised child boxes, enter the nearer child hit, push
            // the farther.
            uint at = base + cur;
            uvec4 n0 = bvh_rows[at];
            uvec4 n1 = bvh_rows[at + 1u];
            vec3 grid_origin = uintBitsToFloat(n0.xyz);
            vec3 grid_step = uintBitsToFloat(((uvec3(n0.w) >> uvec3(0u, 8u, 16u)) & 0xffu) << 23u);
            vec3 a_lo = grid_origin + vec3(n1.xyz & 0xffu) * grid_step;
            vec3 b_lo = grid_origin + vec3((n1.xyz >> 8u) & 0xffu) * grid_step;
            vec3 a_hi = grid_origin + vec3((n1.xyz >> 16u) & 0xffu) * grid_step;
            vec3 b_hi = grid_origin + vec3(n1.xyz >> 24u) * grid_step;
            float ta = bvh_hit_box(r, a_lo, a_hi, tmin, closest);
            float tb = bvh_hit_box(r, b_lo, b_hi, tmin, closest);
            uint kind_a = (n0.w >> 24u) & 0xfu;
            uint leaf_rows = inst_sp >= 0 ? BVH_TRIANGLE_ROWS : BVH_INSTANCE_ROWS;
            uint a = (kind_a << BVH_KIND_SHIFT) | n1.w;
            uint b = ((n0.w >> 28u) << BVH_KIND_SHIFT) | (n1.w + (kind_a == 0u ? BVH_NODE_ROWS : kind_a * leaf_rows));
            cur = ta >= 0.0 ? a : (tb >= 0.0 ? b : BVH_NONE);
            if (ta >= 0.0 && tb >= 0.0) {
                bool b_first = tb < ta;
                bvh_stack_ref[sp] = b_first ? a : b;
                bvh_stack_t[sp] = b_first ? ta : tb;
                ++sp;
                cur = b_first ? b : a;
            }
        }
        if (cur != BVH_NONE && cur >= (1u << BVH_KIND_SHIFT)) {
            uint at = base + (cur & BVH_OFFSET_MASK);
            uint kind = cur >> BVH_KIND_SHIFT;
            cur = BVH_NONE;
            if (inst_sp >= 0) {
                tri_next = at;
                tri_end = at + kind * BVH_TRIANGLE_ROWS;
            } else {
                // A top-level leaf is one instance record: continue at its mesh's root, in
                // object space.
                uvec4 meta = bvh_rows[at + 3u];
                if ((meta.w & mask & 0xffu) != 0u) {
                    vec4 m[3] = vec4[3](uintBitsToFloat(bvh_rows[at]), uintBitsToFloat(bvh_rows[at + 1u]),
                                        uintBitsToFloat(bvh_rows[at + 2u]));
                    r = bvh_ray(bvh_xform_point(m, origin), bvh_xform_vector(m, dir));
                    inst_sp = sp;
                    inst_row = at;
                    inst_alpha = ((meta.w >> 8u) & BVH_INSTANCE_ALPHA_TESTED) != 0u;
                    base = blas_base + meta.x;
                    cur = meta.y;
                }
            }
        }
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

#endif
