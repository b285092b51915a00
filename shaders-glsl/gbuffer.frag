#version 460
// G-buffer, fragment stage: material lookup, alpha test (masked texels are discarded), normal
// mapping, and the channels every later pass reads.
#extension GL_GOOGLE_include_directive : require
#define MATERIAL_IMPLICIT_LOD
#include "common/material.glsl"

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv0;
layout(location = 4) in vec2 in_uv1;
layout(location = 5) in vec4 in_clip;
layout(location = 6) in vec4 in_prev_clip;
layout(location = 7) flat in uint in_instance;

layout(location = 0) out vec2 out_depth;        // gbuffer.depth: view depth (along the view axis), its fwidth
layout(location = 1) out vec4 out_normal_geo;   // gbuffer.normal_geo: world geometric normal, facing the viewer
layout(location = 2) out vec4 out_normal;       // gbuffer.normal: world shading normal (normal-mapped), view depth
layout(location = 3) out vec4 out_base_color;   // gbuffer.base_color: linear RGB, alpha
layout(location = 4) out vec4 out_metal_rough;  // gbuffer.metal_rough: metallic, roughness, occlusion, transmission
layout(location = 5) out vec4 out_emissive;     // gbuffer.emissive: emitted radiance
layout(location = 6) out vec2 out_motion;       // gbuffer.motion: pixels moved since the previous frame
layout(location = 7) out uvec2 out_ids;         // gbuffer.ids: instance id, material id

void main() {
    InstanceInfo inst = instances[in_instance];
    MaterialInfo mat = materials[inst.material];
    bool double_sided = (mat.flags & MATERIAL_DOUBLE_SIDED) != 0u;
    if (!gl_FrontFacing && !double_sided) discard;

    SurfaceMaterial s = read_material(inst.material, in_uv0, in_uv1);
    if (mat.alpha_cutoff >= 0.0 && s.base_color.a < mat.alpha_cutoff) discard;

    // The derivatives of the interpolated world position span the triangle's plane exactly,
    // also in helper lanes, so their cross product is the true face normal.
    vec3 to_eye = frame.camera_pos - in_world;
    vec3 ng = normalize(cross(dFdx(in_world), dFdy(in_world)));
    if (dot(ng, to_eye) < 0.0) ng = -ng;

    vec3 n = normalize(in_normal);
    if (!gl_FrontFacing) n = -n;
    vec3 t = in_tangent.xyz - n * dot(n, in_tangent.xyz);
    if (dot(t, t) > 1e-12 && mat.tex[TEX_NORMAL] >= 0) {
        t = normalize(t);
        vec3 b = cross(n, t) * (in_tangent.w < 0.0 ? -1.0 : 1.0);
        n = normalize(t * s.normal_ts.x + b * s.normal_ts.y + n * s.normal_ts.z);
    }

    vec2 ndc = in_clip.xy / in_clip.w;
    vec2 prev_ndc = in_prev_clip.xy / in_prev_clip.w;

    float depth = dot(in_world - frame.camera_pos, -frame.inv_view[2].xyz);
    // The rasteriser's derivative is the slope of this triangle's plane, even in a one-pixel
    // sliver between two other surfaces, where neighbouring pixels would give the jump.
    out_depth = vec2(depth, fwidth(depth));
    out_normal_geo = vec4(ng, 0.0);
    out_normal = vec4(n, depth);
    out_base_color = s.base_color;
    out_metal_rough = vec4(s.metallic, s.roughness, s.occlusion, s.transmission);
    out_emissive = vec4(s.emissive, 0.0);
    out_motion = (ndc - prev_ndc) * 0.5 * vec2(frame.size);
    out_ids = uvec2(in_instance, inst.material);
}
