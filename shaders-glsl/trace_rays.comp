#version 460
// trace_rays: traces a list of rays from a buffer (closest hit or any hit) and writes one hit
// record per ray. Used by the ray benchmark and the backend-agreement tests, so both backends
// are measured and compared on exactly the same rays.
#extension GL_GOOGLE_include_directive : require
#include "common/trace.glsl"

layout(local_size_x = 64) in;

struct Ray {
    vec3 origin;
    float tmin;
    vec3 dir;
    float tmax;
};

struct HitRecord {
    uint instance;  // NO_HIT on a miss
    uint primitive;
    float t;
    float u;
    float v;
    uint front_face;
    uint pad0;
    uint pad1;
};

layout(set = 1, binding = 0, scalar) readonly buffer Rays { Ray rays[]; };
layout(set = 1, binding = 1, scalar) writeonly buffer Hits { HitRecord hits[]; };

layout(push_constant) uniform Params {
    uint ray_count;
    uint any_hit;  // 1: shadow rays (trace_any), 0: closest hit
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.ray_count) return;
    Ray r = rays[i];
    HitRecord rec;
    rec.pad0 = 0u;
    rec.pad1 = 0u;
    if (params.any_hit != 0u) {
        bool hit = trace_any(r.origin, r.dir, r.tmin, r.tmax, RAY_MASK_ALL);
        rec.instance = hit ? 0u : NO_HIT;
        rec.primitive = 0u;
        rec.t = 0.0;
        rec.u = 0.0;
        rec.v = 0.0;
        rec.front_face = 0u;
    } else {
        Hit h = trace_closest(r.origin, r.dir, r.tmin, r.tmax, RAY_MASK_ALL);
        rec.instance = h.instance;
        rec.primitive = h.instance == NO_HIT ? 0u : h.primitive;
        rec.t = h.instance == NO_HIT ? 0.0 : h.t;
        rec.u = h.instance == NO_HIT ? 0.0 : h.bary.x;
        rec.v = h.instance == NO_HIT ? 0.0 : h.bary.y;
        rec.front_face = (h.instance != NO_HIT && h.front_face) ? 1u : 0u;
    }
    hits[i] = rec;
}
