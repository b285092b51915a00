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

// Both texture coordinate sets at a point of a triangle.
void hit_uvs(uvec3 tri, vec2 bary, out vec2 uv0, out vec2 uv1) {
    vec3 w = barycentric_weights(bary);
    uv0 = w.x * vertices[tri.x].uv0 + w.y * vertices[tri.y].uv0 + w.z * vertices[tri.z].uv0;
    uv1 = w.x * vertices[tri.x].uv1 + w.y * vertices[tri.y].uv1 + w.z * vertices[tri.z].uv1;
}

// Set by the trace functions for the ray being traced (hit_begin_query): its direction, and for
// a shadow query the light that passes the see-through surfaces it has crossed so far.
vec3 hit_query_dir = vec3(0.0, 0.0, 1.0);
vec3 hit_transmittance = vec3(1.0);

void hit_begin_query(vec3 dir) {
    hit_query_dir = dir;
    hit_transmittance = vec3(1.0);
}

// Thin-walled transmissive surfaces (KHR_materials_transmission without a volume) let light
// through without bending it when they are smooth, so a shadow ray may cross them: each passes
// (1 - metallic) T baseColor (1 - F), with F at the angle between the ray and the face normal.
// A rough one spreads the light it lets through; the real-time passes let shadow rays cross it
// all the same (its transmitted energy, not its blur), while the reference, which must be
// exact, stops them there and reaches lights through it by sampling the transmitted lobe
// (pathtrace.comp defines HIT_SHADOWS_CROSS_SMOOTH_GLASS_ONLY).
// The smooth case: GGX's alpha at its floor (brdf.glsl MIN_ALPHA 1e-3), a lobe far narrower
// than a pixel.
#define HIT_SMOOTH_ROUGHNESS 0.0316

// What one see-through surface lets pass straight along a shadow ray: the uncovered share of a
// blended surface, and what thin-walled glass transmits through the rest (0 for other
// materials).
vec3 hit_see_through(uint instance, uint primitive, vec2 bary) {
    uint material = instances[instance].material;
    MaterialInfo m = materials[material];
    uvec3 tri = hit_triangle(instance, primitive);
    vec2 uv0, uv1;
    hit_uvs(tri, bary, uv0, uv1);
    vec4 bc = material_texel(m, TEX_BASE_COLOR, uv0, uv1);
    float alpha = m.base_color_factor.a * bc.a;
    float cover = (m.flags & MATERIAL_BLEND) != 0u ? alpha : (m.alpha_cutoff < 0.0 || alpha >= m.alpha_cutoff ? 1.0 : 0.0);
    vec3 glass = vec3(0.0);
    if (material_thin_glass(m) && cover > 0.0) {
        vec4 mr = material_texel(m, TEX_METAL_ROUGH, uv0, uv1);
        float roughness = clamp(m.roughness * mr.g, 0.0, 1.0);
#ifdef HIT_SHADOWS_CROSS_SMOOTH_GLASS_ONLY
        if (roughness > HIT_SMOOTH_ROUGHNESS) return vec3(1.0 - cover);
#endif
        float metallic = clamp(m.metallic * mr.b, 0.0, 1.0);
        float transmission = m.transmission * material_texel(m, TEX_TRANSMISSION, uv0, uv1).r;
        mat3 to_world = mat3(instances[instance].object_to_world);
        vec3 e1 = to_world * (vertices[tri.y].position - vertices[tri.x].position);
        vec3 e2 = to_world * (vertices[tri.z].position - vertices[tri.x].position);
        float cos_theta = abs(dot(normalize(cross(e1, e2)), normalize(hit_query_dir)));
        float r = (m.ior - 1.0) / (m.ior + 1.0);
        float f = r * r + (1.0 - r * r) * pow(1.0 - cos_theta, 5.0);
        vec3 base = m.base_color_factor.rgb * srgb_to_linear(bc.rgb);
        glass = (1.0 - metallic) * transmission * (1.0 - f) * base;
    }
    return vec3(1.0 - cover) + cover * glass;
}

// True when the candidate hit should count: the material is opaque, or its alpha passes (for
// blended materials, the least alpha drawn). A shadow query (`shadow`: any hit ends the ray)
// counts a see-through surface only once nothing passes any more; until then it multiplies
// what passes into hit_transmittance. The trace functions pass `shadow` as a constant where they
// can, so that closest-hit traversals compile without the see-through code: lavapipe inlines
// this function into every traversal, and each copy lengthens its compile.
bool hit_alpha_accept(uint instance, uint primitive, vec2 bary, bool shadow) {
    uint material = instances[instance].material;
    MaterialInfo m = materials[material];
    if (shadow && ((m.flags & MATERIAL_BLEND) != 0u || material_thin_glass(m))) {
        hit_transmittance *= hit_see_through(instance, primitive, bary);
        return max(hit_transmittance.x, max(hit_transmittance.y, hit_transmittance.z)) <= 0.0;
    }
    float cutoff = m.alpha_cutoff;
    if (cutoff < 0.0) return true;
    uvec3 tri = hit_triangle(instance, primitive);
    vec2 uv0, uv1;
    hit_uvs(tri, bary, uv0, uv1);
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
