#version 460
// G-buffer, vertex stage: pulls vertices from the scene buffers (no vertex input state), and
// passes this frame's and last frame's clip positions for motion vectors.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec4 out_tangent;
layout(location = 3) out vec2 out_uv0;
layout(location = 4) out vec2 out_uv1;
layout(location = 5) out vec4 out_clip;
layout(location = 6) out vec4 out_prev_clip;
layout(location = 7) flat out uint out_instance;

void main() {
    InstanceInfo inst = instances[gl_InstanceIndex];
    Vertex v = vertices[gl_VertexIndex];
    vec4 world = inst.object_to_world * vec4(v.position, 1.0);
    // A deforming vertex also moved within its mesh: skinning.comp or the morph deformer kept
    // where it was.
    vec3 prev_position = (inst.flags & INSTANCE_DEFORMS) != 0u ? prev_positions[gl_VertexIndex] : v.position;
    vec4 prev_world = inst.prev_object_to_world * vec4(prev_position, 1.0);
    mat3 nm = mat3(inst.normal_to_world);
    out_world = world.xyz;
    out_normal = nm * v.normal;
    out_tangent = vec4(mat3(inst.object_to_world) * v.tangent.xyz, v.tangent.w);
    out_uv0 = v.uv0;
    out_uv1 = v.uv1;
    out_clip = frame.view_proj * world;
    out_prev_clip = frame.prev_view_proj * prev_world;
    out_instance = gl_InstanceIndex;
    gl_Position = frame.jittered_view_proj * world;
}
