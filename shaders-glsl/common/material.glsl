// Reads a material at a surface point: base colour, metallic/roughness, occlusion, emission and
// the tangent-space normal, with KHR_texture_transform and the alpha cutoff. One file for every
// pass, raster or ray-traced. Fragment shaders sample with derivatives; compute shaders at an
// explicit LOD (MATERIAL_LOD, 0 unless the including shader defines it).
#ifndef MATERIAL_GLSL
#define MATERIAL_GLSL

#include "scene.glsl"
#include "color.glsl"

struct SurfaceMaterial {
    vec4 base_color;  // linear RGB, alpha
    float metallic;
    float roughness;
    float occlusion;
    vec3 emissive;
    vec3 normal_ts;   // tangent-space normal (0,0,1 when there is no normal map)
    float transmission;  // share of the dielectric's diffuse light that passes through
    float ior;
    bool thin_walled;    // light passes straight through (no volume behind the surface)
    vec3 absorption;     // Beer-Lambert coefficient per unit length inside the volume
};

// Thin-walled glass: transmissive with no volume behind the surface (KHR_materials_volume's
// thickness 0), so light passes it without bending; a shadow ray may cross it.
bool material_thin_glass(MaterialInfo m) { return m.transmission > 0.0 && m.thickness <= 0.0; }

vec2 material_uv(MaterialInfo m, int slot, vec2 uv0, vec2 uv1) {
    vec2 uv = ((m.uv_sets >> slot) & 1u) != 0u ? uv1 : uv0;
    vec3 h = vec3(uv, 1.0);
    return vec2(dot(m.uv_xform[slot * 2].xyz, h), dot(m.uv_xform[slot * 2 + 1].xyz, h));
}

#ifndef MATERIAL_LOD
#define MATERIAL_LOD 0.0
#endif

vec4 material_texel(MaterialInfo m, int slot, vec2 uv0, vec2 uv1) {
    int t = m.tex[slot];
    if (t < 0) return vec4(1.0);
    vec2 uv = material_uv(m, slot, uv0, uv1);
#ifdef MATERIAL_IMPLICIT_LOD
    return texture(textures[nonuniformEXT(t)], uv);
#else
    return textureLod(textures[nonuniformEXT(t)], uv, MATERIAL_LOD);
#endif
}

// Alpha only: the cheap path for alpha tests in shadow and visibility rays.
float material_alpha(uint material_id, vec2 uv0, vec2 uv1) {
    MaterialInfo m = materials[material_id];
    return m.base_color_factor.a * material_texel(m, TEX_BASE_COLOR, uv0, uv1).a;
}

bool material_alpha_passes(uint material_id, vec2 uv0, vec2 uv1) {
    float cutoff = materials[material_id].alpha_cutoff;
    return cutoff < 0.0 || material_alpha(material_id, uv0, uv1) >= cutoff;
}

// Beer-Lambert coefficient per unit length inside a material's volume (KHR_materials_volume):
// -ln(colour) / distance; a black colour absorbs everything within any finite length.
vec3 volume_absorption(MaterialInfo m) {
    return -log(max(m.attenuation_color, vec3(1e-6))) / m.attenuation_distance;
}

SurfaceMaterial read_material(uint material_id, vec2 uv0, vec2 uv1) {
    MaterialInfo m = materials[material_id];
    SurfaceMaterial s;
    vec4 bc = material_texel(m, TEX_BASE_COLOR, uv0, uv1);
    s.base_color = m.base_color_factor * vec4(srgb_to_linear(bc.rgb), bc.a);
    vec4 mr = material_texel(m, TEX_METAL_ROUGH, uv0, uv1);
    s.roughness = clamp(m.roughness * mr.g, 0.0, 1.0);
    s.metallic = clamp(m.metallic * mr.b, 0.0, 1.0);
    s.occlusion = 1.0 + m.occlusion_strength * (material_texel(m, TEX_OCCLUSION, uv0, uv1).r - 1.0);
    s.emissive = m.emissive_factor * srgb_to_linear(material_texel(m, TEX_EMISSIVE, uv0, uv1).rgb);
    if (m.tex[TEX_NORMAL] >= 0) {
        vec3 n = material_texel(m, TEX_NORMAL, uv0, uv1).xyz * 2.0 - 1.0;
        s.normal_ts = normalize(vec3(n.xy * m.normal_scale, n.z));
    } else {
        s.normal_ts = vec3(0.0, 0.0, 1.0);
    }
    s.transmission = m.transmission * material_texel(m, TEX_TRANSMISSION, uv0, uv1).r;
    s.ior = m.ior;
    s.thin_walled = m.thickness <= 0.0;
    s.absorption = volume_absorption(m);
    return s;
}

#endif
