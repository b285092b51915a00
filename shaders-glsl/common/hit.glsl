// What a ray hit: the triangle's vertices and the interpolated surface at the hit, for shading,
// and the alpha test that both ray backends call for candidates on alpha-masked instances.
#ifndef HIT_GLSL
#define HIT_GLSL

#include "material.glsl"

// Vertex indices (into `vertices`) of a triangle of an instance's mesh.
uvec3 hit_triangle(uint instance, uint primitive) {
    MeshInfo m = meshes[instances[instance].mesh];
    uint base = m.first_index + 3u * primitive;
    return uvec3(indices[base], indices[base + 1u], indices[base + 2u]) + uint(m.base_vertex);
}

vec3 barycentric_weights(vec2 bary) { return vec3(1.0 - bary.x - bary.y, bary.x, bary.y); }

// Set by the trace functions for the ray being traced: true for shadow and visibility queries
// (any hit ends them), false for closest hits.
bool hit_shadow_query = false;

// True when the candidate hit should count: the material is opaque, or its alpha passes (for
// blended materials, the least alpha drawn; for shadow queries, BLEND_SHADOW_CUTOFF).
bool hit_alpha_accept(uint instance, uint primitive, vec2 bary) {
    uint material = instances[instance].material;
    float cutoff = materials[material].alpha_cutoff;
    if (cutoff < 0.0) return true;
    if (hit_shadow_query && (materials[material].flags & MATERIAL_BLEND) != 0u) cutoff = BLEND_SHADOW_CUTOFF;
    uvec3 tri = hit_triangle(instance, primitive);
    vec3 w = barycentric_weights(bary);
    vec2 uv0 = w.x * vertices[tri.x].uv0 + w.y * vertices[tri.y].uv0 + w.z * vertices[tri.z].uv0;
    vec2 uv1 = w.x * vertices[tri.x].uv1 + w.y * vertices[tri.y].uv1 + w.z * vertices[tri.z].uv1;
    return material_alpha(material, uv0, uv1) >= cutoff;
}

struct HitSurface {
    vec3 position;
    vec3 normal_geo;  // world-space face normal, facing the incoming ray
    vec3 normal;      // world-space shading normal (normal-mapped), same hemisphere as normal_geo
    bool front;       // the ray hit the triangle's front face (outside of a volume)
    uint material;
    SurfaceMaterial mat;
};

// The surface at a hit of `dir` (world space). Normal maps apply as in the G-buffer.
HitSurface hit_surface(uint instance, uint primitive, vec2 bary, vec3 dir) {
    InstanceInfo inst = instances[instance];
    uvec3 tri = hit_triangle(instance, primitive);
    Vertex a = vertices[tri.x];
    Vertex b = vertices[tri.y];
    Vertex c = vertices[tri.z];
    vec3 w = barycentric_weights(bary);
    HitSurface s;
    vec3 pa = (inst.object_to_world * vec4(a.position, 1.0)).xyz;
    vec3 pb = (inst.object_to_world * vec4(b.position, 1.0)).xyz;
    vec3 pc = (inst.object_to_world * vec4(c.position, 1.0)).xyz;
    s.position = w.x * pa + w.y * pb + w.z * pc;
    vec3 ng = normalize(cross(pb - pa, pc - pa));
    bool back = dot(ng, dir) > 0.0;
    if (back) ng = -ng;
    s.normal_geo = ng;
    s.front = !back;
    mat3 nm = mat3(inst.normal_to_world);
    vec3 n = normalize(nm * (w.x * a.normal + w.y * b.normal + w.z * c.normal));
    if (back) n = -n;
    vec2 uv0 = w.x * a.uv0 + w.y * b.uv0 + w.z * c.uv0;
    vec2 uv1 = w.x * a.uv1 + w.y * b.uv1 + w.z * c.uv1;
    s.material = inst.material;
    s.mat = read_material(inst.material, uv0, uv1);
    vec4 t4 = w.x * a.tangent + w.y * b.tangent + w.z * c.tangent;
    vec3 t = mat3(inst.object_to_world) * t4.xyz;
    t = t - n * dot(n, t);
    if (dot(t, t) > 1e-12 && materials[inst.material].tex[TEX_NORMAL] >= 0) {
        t = normalize(t);
        vec3 bt = cross(n, t) * (t4.w < 0.0 ? -1.0 : 1.0);
        n = normalize(t * s.mat.normal_ts.x + bt * s.mat.normal_ts.y + n * s.mat.normal_ts.z);
    }
    // A shading normal bent below the geometric horizon would light the back of the surface.
    if (dot(n, ng) < 0.0) n = normalize(n - ng * dot(n, ng) * 1.01);
    s.normal = n;
    return s;
}

#endif
