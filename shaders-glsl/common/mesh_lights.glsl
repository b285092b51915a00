// Mesh lights: small emissive meshes that take the shadows chain's channels the punctual
// lights leave free (world::lights::chain_emitters; one material, no emissive texture, at most
// MESH_LIGHT_MAX_TRIANGLES triangles). As for a sphere light (Ray Tracing Gems ch. 13), the
// chain's adaptive shadow rays give the share of the light that arrives, to points drawn on
// the mesh (each triangle by its share of the light), and composite multiplies it into the
// unshadowed light, which for a polygon of uniform radiance has a closed form: the irradiance
// is Le times the polygon's vector form factor projected on the normal (Lambert; Arvo 1995),
// once the polygon is clipped to the hemisphere above the surface.
#ifndef MESH_LIGHTS_GLSL
#define MESH_LIGHTS_GLSL

#include "light_sampling.glsl"

// The most triangles a mesh light has. Rust: world::lights::MAX_CHAIN_EMITTER_TRIANGLES.
#define MESH_LIGHT_MAX_TRIANGLES 8u

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

// Emitter triangle e's vector form factor at point p for normal n: int w cos dw over what of
// its emitting side lies above the surface (zero where that side faces away from p).
vec3 emitter_form_factor(Emitter e, vec3 p, vec3 n) {
    vec3 a = e.p0 - p;
    if ((e.flags & EMITTER_DOUBLE_SIDED) == 0u && dot(e.normal, a) >= 0.0) return vec3(0.0);
    return triangle_form_factor(n, a, a + e.e1, a + e.e2);
}

// The mesh light's vector form factor at point p for normal n: int w cos dw over what of its
// emitting sides lies above the surface. Its projection on n times the emission is the
// irradiance; its direction is where the light arrives from on average.
vec3 mesh_light_form_factor(uint first, uint count, vec3 p, vec3 n) {
    vec3 f = vec3(0.0);
    for (uint t = 0u; t < count; ++t) f += emitter_form_factor(emitters[first + t], p, n);
    return f;
}

// The share of the mesh light's unshadowed irradiance at `origin` (normal `ng`) that each of its
// triangles sends, from their form factors; false when none sends any.
bool mesh_light_shares(uint first, uint count, vec3 origin, vec3 ng, out float share[MESH_LIGHT_MAX_TRIANGLES]) {
    float total = 0.0;
    for (uint t = 0u; t < MESH_LIGHT_MAX_TRIANGLES; ++t) {
        share[t] = t < count ? max(dot(ng, emitter_form_factor(emitters[first + t], origin, ng)), 0.0) : 0.0;
        total += share[t];
    }
    if (!(total > 0.0)) return false;
    for (uint t = 0u; t < MESH_LIGHT_MAX_TRIANGLES; ++t) share[t] /= total;
    return true;
}

// A point of the mesh light for a shadow ray from `origin` (normal `ng`): a triangle drawn by its
// `share` of the light, a point on it uniformly by area with `u`. Returns the point's direction
// and distance, and its weight in the ratio of shadowed to unshadowed light: what it brings
// (both cosines over the squared distance) over the density it was drawn with, relative to the
// light (0 below the surface or behind the emitting side). Drawn by area over the whole mesh,
// most of a pixel's few points on a closed one-sided light fell on faces turned away, which say
// nothing: the penumbra of tests/soft_shadows.rs's octahedron read 0.913 of the reference's
// light, and 1.033 drawn by share.
float mesh_light_point(uint first, uint count, vec3 origin, vec3 ng, float share[MESH_LIGHT_MAX_TRIANGLES], vec2 u,
                       out vec3 dir, out float dist) {
    // The triangle whose stretch of the shares holds u.x, and u.x rescaled within it, so that
    // the low-discrepancy points stay well spread.
    uint t = 0u;
    float x = u.x;
    for (; t + 1u < count && x >= share[t]; ++t) x -= share[t];
    dir = vec3(0.0, 0.0, 1.0);
    dist = 0.0;
    // Rounding can leave u.x past the last triangle that sends light.
    if (!(share[t] > 0.0)) return 0.0;
    u.x = clamp(x / share[t], 0.0, 0.99999994);
    Emitter e = emitters[first + t];
    vec2 bary;
    NeeSample s = emitter_point(e, origin, u, bary);
    dir = s.dir;
    dist = s.dist;
    // s.weight is the emitter's cosine over the squared distance times the area, so this is
    // f / (share / area) up to the light's total, which cancels in the ratio.
    return s.weight.x * max(dot(s.dir, ng), 0.0) / share[t];
}

// The mesh light's radiance (one material, no texture: its emissive factor).
vec3 mesh_light_emission(uint first) {
    return materials[instances[emitters[first].instance].material].emissive_factor;
}

#endif
