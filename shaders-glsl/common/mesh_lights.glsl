// Mesh lights: small emissive meshes that take the shadows chain's channels the punctual
// lights leave free (world::lights::chain_emitters; one material, no emissive texture, at most
// 8 triangles). As for a sphere light (Ray Tracing Gems ch. 13), the chain's adaptive shadow
// rays give the share of the light that arrives, to points drawn on the mesh by area, and
// composite multiplies it into the unshadowed light, which for a polygon of uniform radiance
// has a closed form: the irradiance is Le times the polygon's vector form factor projected on
// the normal (Lambert; Arvo 1995), once the polygon is clipped to the hemisphere above the
// surface.
#ifndef MESH_LIGHTS_GLSL
#define MESH_LIGHTS_GLSL

#include "light_sampling.glsl"

// A point drawn with `u` uniformly by area on the mesh light of `count` emitters from `first`,
// seen from `origin`: its direction, distance and geometry term (the emitter's cosine over the
// squared distance); 0 where that point's side does not emit toward `origin`.
float mesh_light_point(uint first, uint count, vec3 origin, vec2 u, out vec3 dir, out float dist) {
    float total = 0.0;
    for (uint t = 0u; t < count; ++t) total += emitters[first + t].area;
    // The triangle whose stretch of the area holds u.x, and u.x rescaled within it, so that
    // the low-discrepancy points stay well spread over the whole mesh.
    float x = u.x * total;
    uint t = 0u;
    for (; t + 1u < count && x >= emitters[first + t].area; ++t) x -= emitters[first + t].area;
    u.x = clamp(x / max(emitters[first + t].area, 1e-30), 0.0, 0.99999994);
    vec2 bary;
    NeeSample s = emitter_point(emitters[first + t], origin, u, bary);
    dir = s.dir;
    dist = s.dist;
    return s.weight.x / emitters[first + t].area;
}

// The solid-angle-weighted direction integral of a spherical polygon's edge from a to b (seen
// from the origin): theta times the unit normal of the great circle through them.
vec3 form_factor_edge(vec3 a, vec3 b) {
    vec3 na = a / max(length(a), 1e-12);
    vec3 nb = b / max(length(b), 1e-12);
    vec3 c = cross(na, nb);
    float s = length(c);
    if (s < 1e-7) return vec3(0.0);
    return acos(clamp(dot(na, nb), -1.0, 1.0)) * c / s;
}

// The vector form factor, int w cos dw over the triangle (a, b, c) relative to the shading
// point, clipped to dot(n, w) >= 0 (at most a quadrilateral), oriented toward the triangle.
vec3 triangle_form_factor(vec3 n, vec3 a, vec3 b, vec3 c) {
    vec3 tri[3] = vec3[3](a, b, c);
    vec3 poly[4];
    uint k = 0u;
    for (uint i = 0u; i < 3u; ++i) {
        vec3 p0 = tri[i];
        vec3 p1 = tri[(i + 1u) % 3u];
        float d0 = dot(n, p0);
        float d1 = dot(n, p1);
        if (d0 >= 0.0) poly[k++] = p0;
        if ((d0 >= 0.0) != (d1 >= 0.0) && k < 4u) poly[k++] = mix(p0, p1, d0 / (d0 - d1));
    }
    if (k < 3u) return vec3(0.0);
    vec3 f = vec3(0.0);
    for (uint i = 0u; i < k; ++i) f += form_factor_edge(poly[i], poly[(i + 1u) % k]);
    f *= 0.5;
    // The winding decides the sign. The clipped polygon lies above the surface, so its
    // projection on n (the irradiance) is positive. (Oriented toward the unclipped triangle's
    // centroid instead, which may lie below the surface, a triangle across the horizon took
    // light away.)
    return dot(f, n) < 0.0 ? -f : f;
}

// The mesh light's vector form factor at point p for normal n: int w cos dw over what of its
// emitting sides lies above the surface. Its projection on n times the emission is the
// irradiance; its direction is where the light arrives from on average.
vec3 mesh_light_form_factor(uint first, uint count, vec3 p, vec3 n) {
    vec3 f = vec3(0.0);
    for (uint t = 0u; t < count; ++t) {
        Emitter e = emitters[first + t];
        vec3 a = e.p0 - p;
        // One-sided: a point behind the emitting side gets nothing.
        if ((e.flags & EMITTER_DOUBLE_SIDED) == 0u && dot(e.normal, a) >= 0.0) continue;
        f += triangle_form_factor(n, a, a + e.e1, a + e.e2);
    }
    return f;
}

// The mesh light's radiance (one material, no texture: its emissive factor).
vec3 mesh_light_emission(uint first) {
    return materials[instances[emitters[first].instance].material].emissive_factor;
}

#endif
