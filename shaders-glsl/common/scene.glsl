// Set 0: the scene, shared by every pass. Buffers use scalar layout so the Rust structs in
// src/world/scene_gpu.rs match them byte for byte (see the `gpu_layout` test there).
#ifndef SCENE_GLSL
#define SCENE_GLSL

#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_nonuniform_qualifier : require

#include "vertex.glsl"

struct MeshInfo {
    uint first_index;
    uint index_count;
    int base_vertex;
    uint material;
};

#define INSTANCE_ALPHA_MASKED 1u
// The mesh deforms (skinned or morphed): last frame's positions are in `prev_positions`
// (motion vectors).
#define INSTANCE_DEFORMS 2u

struct InstanceInfo {
    mat4 object_to_world;
    mat4 prev_object_to_world;
    mat4 normal_to_world; // inverse transpose of object_to_world (upper 3x3 used)
    uint mesh;
    uint material;
    uint flags;
    uint pad;
};

// Material texture slots.
#define TEX_BASE_COLOR 0
#define TEX_METAL_ROUGH 1
#define TEX_NORMAL 2
#define TEX_OCCLUSION 3
#define TEX_EMISSIVE 4
#define TEX_TRANSMISSION 5  // KHR_materials_transmission: red channel
#define TEX_SLOTS 6

#define MATERIAL_DOUBLE_SIDED 1u
// alphaMode BLEND: the surface covers the share alpha of each point, the rest passes straight
// through (shadow rays included: common/hit.glsl). alpha_cutoff is then the least alpha still
// drawn.
#define MATERIAL_BLEND 2u

struct MaterialInfo {
    vec4 base_color_factor;
    vec3 emissive_factor;
    float alpha_cutoff; // negative: opaque
    float metallic;
    float roughness;
    float normal_scale;
    float occlusion_strength;
    int tex[TEX_SLOTS]; // texture index per slot, -1 when absent
    uint uv_sets;       // bit i set: slot i reads TEXCOORD_1
    uint flags;
    float transmission; // KHR_materials_transmission (0: opaque)
    float ior;          // KHR_materials_ior
    float thickness;    // KHR_materials_volume: 0 thin-walled, else the mesh bounds a volume
    float attenuation_distance;  // +inf: no absorption
    vec3 attenuation_color;
    vec4 uv_xform[2 * TEX_SLOTS];  // per slot two rows of the 2x3 KHR_texture_transform matrix
};

#define LIGHT_DIRECTIONAL 0u
#define LIGHT_POINT 1u
#define LIGHT_SPOT 2u

struct LightInfo {
    vec3 position;
    uint type;
    vec3 direction;  // direction the light travels (spot, directional)
    float range;     // <= 0: infinite
    vec3 intensity;  // colour * intensity
    float radius;
    float cos_inner;
    float cos_outer;
    uint pad0;
    uint pad1;
};

layout(set = 0, binding = 0, scalar) uniform FrameUniforms {
    mat4 view;
    mat4 proj;
    mat4 view_proj;
    mat4 inv_view_proj;
    mat4 inv_view;
    mat4 prev_view_proj;
    mat4 jittered_view_proj;
    vec3 camera_pos;
    float znear;
    vec3 prev_camera_pos;
    float zfar;
    uvec2 size;
    uint frame_index;
    uint light_count;
    vec2 jitter;
    float time;
    float exposure;
    vec3 sky_color;
    uint instance_count;
    uint flags;  // FRAME_*
    vec2 prev_jitter;  // last frame's `jitter` (the G-buffer's texels sat at centre - jitter then)
    // Lights 0..chain_punctual-1 have their own ray-traced visibility (the shadows chain, one
    // channel each, added by composite; at most 4, mesh lights take the channels after them);
    // the rest are resampled in gi (common/light_reservoir.glsl). Rust: FramePlan::chain_punctual.
    uint chain_punctual;
} frame;

// Set on the first frame and after a camera cut: temporal passes start their history anew.
#define FRAME_RESET_HISTORY 1u
// Set when the lights differ from last frame's: the radiance cache starts its light anew.
#define FRAME_LIGHTS_CHANGED 2u

layout(set = 0, binding = 1, scalar) readonly buffer Vertices { Vertex vertices[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Indices { uint indices[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Meshes { MeshInfo meshes[]; };
layout(set = 0, binding = 4, scalar) readonly buffer Instances { InstanceInfo instances[]; };
layout(set = 0, binding = 5, scalar) readonly buffer Materials { MaterialInfo materials[]; };
layout(set = 0, binding = 6, scalar) readonly buffer Lights { LightInfo lights[]; };
layout(set = 0, binding = 7) uniform sampler2D textures[];
// Last frame's position of every skinned vertex (by vertex-buffer index; src/world/skinning.rs).
layout(set = 0, binding = 18, scalar) readonly buffer PrevPositions { vec3 prev_positions[]; };

#endif
