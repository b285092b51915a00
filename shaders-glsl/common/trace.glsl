// The trace interface. Every ray-traced pass includes this file and is compiled twice:
//   RT_RAY_QUERY   : rayQueryEXT against the TLAS/BLAS (VK_KHR_ray_query);
//   RT_COMPUTE_BVH : a stack traversal of the project's own two-level BVH (bvh_traverse.glsl).
// Both report the same hits: instance = the instance id (custom index), primitive = triangle
// index in the mesh's index buffer, t along the (unnormalised) direction, barycentrics of
// vertices 1 and 2, and whether the triangle was seen counter-clockwise (front face).
// Candidates on alpha-masked instances pass through hit_alpha_accept (hit.glsl).
// trace_transmittance is a shadow ray that crosses see-through surfaces (blended ones, thin-walled
// glass) and returns the light that passes them: 0 where an opaque surface blocks it.
// trace_ray(..., first_hit) is both in one: with first_hit, any hit ends the ray (its t and
// barycentrics are then of whichever hit that was). Every call of a trace function inlines a
// whole traversal when lavapipe compiles the shader, so a shader that traces several kinds of
// ray in a loop through one trace_ray call compiles several times faster.
#ifndef TRACE_GLSL
#define TRACE_GLSL

#include "hit.glsl"

#define RAY_MASK_ALL 0xffu
#define NO_HIT 0xffffffffu

struct Hit {
    uint instance;  // NO_HIT when nothing was hit
    uint primitive;
    float t;
    vec2 bary;
    bool front_face;
};

#if defined(RT_RAY_QUERY)

#extension GL_EXT_ray_query : require
layout(set = 0, binding = 8) uniform accelerationStructureEXT scene_tlas;

// Runs a query to completion, confirming alpha-masked candidates that pass the alpha test
// (`shadow`: as a shadow query, hit_alpha_accept). (A macro: GLSL cannot pass a rayQueryEXT to
// a function as inout.)
#define TRACE_RUN(q, shadow)                                                                      \
    while (rayQueryProceedEXT(q)) {                                                               \
        if (rayQueryGetIntersectionTypeEXT(q, false) == gl_RayQueryCandidateIntersectionTriangleEXT) { \
            uint cand_inst = rayQueryGetIntersectionInstanceCustomIndexEXT(q, false);             \
            uint cand_prim = rayQueryGetIntersectionPrimitiveIndexEXT(q, false);                  \
            vec2 cand_bary = rayQueryGetIntersectionBarycentricsEXT(q, false);                    \
            if (hit_alpha_accept(cand_inst, cand_prim, cand_bary, shadow)) rayQueryConfirmIntersectionEXT(q); \
        }                                                                                         \
    }

bool trace_any(vec3 origin, vec3 dir, float tmin, float tmax, uint mask) {
    hit_begin_query(dir);
    rayQueryEXT q;
    rayQueryInitializeEXT(q, scene_tlas, gl_RayFlagsTerminateOnFirstHitEXT, mask, origin, tmin, dir, tmax);
    TRACE_RUN(q, true);
    return rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionTriangleEXT;
}

Hit trace_ray(vec3 origin, vec3 dir, float tmin, float tmax, uint mask, bool first_hit) {
    hit_begin_query(dir);
    rayQueryEXT q;
    uint flags = first_hit ? gl_RayFlagsTerminateOnFirstHitEXT : gl_RayFlagsNoneEXT;
    rayQueryInitializeEXT(q, scene_tlas, flags, mask, origin, tmin, dir, tmax);
    TRACE_RUN(q, first_hit);
    Hit h;
    if (rayQueryGetIntersectionTypeEXT(q, true) != gl_RayQueryCommittedIntersectionTriangleEXT) {
        h.instance = NO_HIT;
        return h;
    }
    h.instance = rayQueryGetIntersectionInstanceCustomIndexEXT(q, true);
    h.primitive = rayQueryGetIntersectionPrimitiveIndexEXT(q, true);
    h.t = rayQueryGetIntersectionTEXT(q, true);
    h.bary = rayQueryGetIntersectionBarycentricsEXT(q, true);
    h.front_face = rayQueryGetIntersectionFrontFaceEXT(q, true);
    return h;
}

Hit trace_closest(vec3 origin, vec3 dir, float tmin, float tmax, uint mask) {
    return trace_ray(origin, dir, tmin, tmax, mask, false);
}

#elif defined(RT_COMPUTE_BVH)

#include "bvh_traverse.glsl"

#else
#error "compile with RT_RAY_QUERY or RT_COMPUTE_BVH"
#endif

vec3 trace_transmittance(vec3 origin, vec3 dir, float tmin, float tmax, uint mask) {
    return trace_any(origin, dir, tmin, tmax, mask) ? vec3(0.0) : hit_transmittance;
}

#endif
