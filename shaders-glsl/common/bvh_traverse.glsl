// The compute backend's traversal of the project's two-level BVH (src/accel/bvh): the GLSL
// twin of src/accel/bvh/traverse.rs, which documents the algorithm and is the reference the
// tests compare against. Included by trace.glsl under RT_COMPUTE_BVH.
#ifndef BVH_TRAVERSE_GLSL
#define BVH_TRAVERSE_GLSL

// Records as in src/accel/bvh/layout.rs: integers ride in the w of a vec4 as float bits.
struct BvhNode {
    vec4 a_min;  // w: child A reference
    vec4 a_max;  // w: child B reference
    vec4 b_min;
    vec4 b_max;
};

struct BvhTriangle {
    vec4 v0;  // w: triangle index in the mesh's index buffer
    vec4 v1;
    vec4 v2;
};

struct BvhInstance {
    vec4 world_to_object[3];
    vec4 object_to_world[3];
    uint root_node;
    uint first_triangle;
    uint custom_index;
    uint mask;
    uint flags;
    uint mesh;
    uint material;
    uint pad;
};

layout(set = 0, binding = 8, std430) readonly buffer TlasNodes { BvhNode tlas_nodes[]; };
layout(set = 0, binding = 9, std430) readonly buffer TlasInstances { BvhInstance tlas_instances[]; };
layout(set = 0, binding = 10, std430) readonly buffer BlasNodes { BvhNode blas_nodes[]; };
layout(set = 0, binding = 11, std430) readonly buffer BlasTriangles { BvhTriangle blas_triangles[]; };

#define BVH_LEAF_BIT 0x80000000u
#define BVH_COUNT_SHIFT 27u
#define BVH_FIRST_MASK 0x07ffffffu
#define BVH_COUNT_MASK 0xfu
#define BVH_INSTANCE_ALPHA_TESTED 1u
// Both levels' trees are at most this deep (src/accel/bvh/layout.rs STACK_SIZE).
#define BVH_STACK_SIZE 64
#define BVH_BOX_FAR_SCALE 1.0000004
#define BVH_MIN_DIR 1e-20

struct BvhRay {
    vec3 origin;
    vec3 dir;
    vec3 inv_dir;
    ivec3 k;     // x, y, z axis permutation; dir[k.z] is the largest component
    vec3 shear;  // sx, sy, sz
};

BvhRay bvh_ray(vec3 origin, vec3 dir) {
    BvhRay r;
    r.origin = origin;
    r.dir = dir;
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
float bvh_hit_triangle(BvhRay r, BvhTriangle tri, float tmin, float tmax, out vec2 bary, out bool front) {
    vec3 a = tri.v0.xyz - r.origin;
    vec3 b = tri.v1.xyz - r.origin;
    vec3 c = tri.v2.xyz - r.origin;
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

// Tests both children; returns the reference to enter (pushing the farther when both are hit)
// or BVH_NONE.
#define BVH_NONE 0xffffffffu

uint bvh_visit(BvhNode node, BvhRay r, float tmin, float tmax,
               inout uint stack_ref[BVH_STACK_SIZE], inout float stack_t[BVH_STACK_SIZE], inout int sp) {
    float ta = bvh_hit_box(r, node.a_min.xyz, node.a_max.xyz, tmin, tmax);
    float tb = bvh_hit_box(r, node.b_min.xyz, node.b_max.xyz, tmin, tmax);
    uint a = floatBitsToUint(node.a_min.w);
    uint b = floatBitsToUint(node.a_max.w);
    if (ta >= 0.0 && tb >= 0.0) {
        if (tb < ta) {
            stack_ref[sp] = a; stack_t[sp] = ta; ++sp;
            return b;
        }
        stack_ref[sp] = b; stack_t[sp] = tb; ++sp;
        return a;
    }
    if (ta >= 0.0) return a;
    if (tb >= 0.0) return b;
    return BVH_NONE;
}

uint bvh_pop(inout uint stack_ref[BVH_STACK_SIZE], inout float stack_t[BVH_STACK_SIZE], inout int sp, float tmax) {
    while (sp > 0) {
        --sp;
        if (stack_t[sp] <= tmax) return stack_ref[sp];
    }
    return BVH_NONE;
}

// Walks one instance's mesh; updates `closest` and `best`. Returns true if it accepted a hit.
bool bvh_trace_mesh(BvhInstance inst, BvhRay r, float tmin, bool first_hit, inout float closest, inout Hit best) {
    uint stack_ref[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    int sp = 0;
    bool found = false;
    uint cur = 0u;
    while (cur != BVH_NONE) {
        if ((cur & BVH_LEAF_BIT) == 0u) {
            cur = bvh_visit(blas_nodes[inst.root_node + cur], r, tmin, closest, stack_ref, stack_t, sp);
            if (cur != BVH_NONE) continue;
        } else {
            uint first = cur & BVH_FIRST_MASK;
            uint count = ((cur >> BVH_COUNT_SHIFT) & BVH_COUNT_MASK) + 1u;
            for (uint i = first; i < first + count; ++i) {
                BvhTriangle tri = blas_triangles[inst.first_triangle + i];
                vec2 bary;
                bool front;
                float t = bvh_hit_triangle(r, tri, tmin, closest, bary, front);
                if (t < 0.0) continue;
                uint prim = floatBitsToUint(tri.v0.w);
                if ((inst.flags & BVH_INSTANCE_ALPHA_TESTED) != 0u && !hit_alpha_accept(inst.custom_index, prim, bary)) continue;
                closest = t;
                best.instance = inst.custom_index;
                best.primitive = prim;
                best.t = t;
                best.bary = bary;
                best.front_face = front;
                found = true;
                if (first_hit) return true;
            }
        }
        cur = bvh_pop(stack_ref, stack_t, sp, closest);
    }
    return found;
}

Hit bvh_trace(vec3 origin, vec3 dir, float tmin, float tmax, uint mask, bool first_hit) {
    BvhRay r = bvh_ray(origin, dir);
    Hit best;
    best.instance = NO_HIT;
    float closest = tmax;
    uint stack_ref[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    int sp = 0;
    uint cur = tlas_instances.length() > 0 ? 0u : BVH_NONE;
    while (cur != BVH_NONE) {
        if ((cur & BVH_LEAF_BIT) == 0u) {
            cur = bvh_visit(tlas_nodes[cur], r, tmin, closest, stack_ref, stack_t, sp);
            if (cur != BVH_NONE) continue;
        } else {
            uint first = cur & BVH_FIRST_MASK;
            uint count = ((cur >> BVH_COUNT_SHIFT) & BVH_COUNT_MASK) + 1u;
            for (uint i = first; i < first + count; ++i) {
                BvhInstance inst = tlas_instances[i];
                if ((inst.mask & mask) == 0u) continue;
                BvhRay local = bvh_ray(bvh_xform_point(inst.world_to_object, origin),
                                       bvh_xform_vector(inst.world_to_object, dir));
                if (bvh_trace_mesh(inst, local, tmin, first_hit, closest, best) && first_hit) return best;
            }
        }
        cur = bvh_pop(stack_ref, stack_t, sp, closest);
    }
    return best;
}

bool trace_any(vec3 origin, vec3 dir, float tmin, float tmax, uint mask) {
    return bvh_trace(origin, dir, tmin, tmax, mask, true).instance != NO_HIT;
}

Hit trace_closest(vec3 origin, vec3 dir, float tmin, float tmax, uint mask) {
    return bvh_trace(origin, dir, tmin, tmax, mask, false);
}

#endif
