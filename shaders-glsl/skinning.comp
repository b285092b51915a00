#version 460
// Skinning: one skinned mesh's bind-pose vertices, each moved by the weighted blend of up to
// four joint matrices, written over the mesh's range of the scene's vertex buffer; last
// frame's joint matrices give last frame's positions, which the G-buffer's motion vectors
// read. The same formula runs on the CPU in src/scene/skin.rs (the tests compare them).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_scalar_block_layout : require
#include "common/vertex.glsl"

layout(local_size_x = 64) in;

struct Influence {
    uvec4 joints;  // indices into the mesh's run of joint matrices
    vec4 weights;  // sum to 1, or all 0: the vertex keeps its bind-pose place
};

layout(set = 0, binding = 0, scalar) readonly buffer BindVertices { Vertex bind_vertices[]; };
layout(set = 0, binding = 1, scalar) readonly buffer Influences { Influence influences[]; };
// Per skinned mesh: its joints' matrices this frame, then last frame's.
layout(set = 0, binding = 2, scalar) readonly buffer Joints { mat4 joints[]; };
layout(set = 0, binding = 3, scalar) writeonly buffer Vertices { Vertex vertices[]; };
layout(set = 0, binding = 4, scalar) writeonly buffer PrevPositions { vec3 prev_positions[]; };

layout(push_constant, scalar) uniform Push {
    uint first_source;  // the mesh's first vertex in bind_vertices and influences
    uint first_target;  // ... in the scene's vertex buffer (and prev_positions)
    uint count;
    uint first_joint;   // this frame's matrices; last frame's follow `joint_count` later
    uint joint_count;
} pc;

mat4 blend(Influence inf, uint base) {
    if (inf.weights == vec4(0.0)) return mat4(1.0);
    return joints[base + inf.joints.x] * inf.weights.x + joints[base + inf.joints.y] * inf.weights.y +
           joints[base + inf.joints.z] * inf.weights.z + joints[base + inf.joints.w] * inf.weights.w;
}

// Normals move by the inverse transpose; the cofactor matrix has its direction without a
// division (skin.rs `cofactor`), its sign kept for mirroring joints.
mat3 cofactor(mat3 m) {
    mat3 c = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    return determinant(m) < 0.0 ? -c : c;
}

vec3 normalize_or(vec3 v, vec3 fallback) {
    float len = length(v);
    return len > 0.0 ? v / len : fallback;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Vertex v = bind_vertices[pc.first_source + i];
    Influence inf = influences[pc.first_source + i];
    mat4 m = blend(inf, pc.first_joint);
    mat4 prev = blend(inf, pc.first_joint + pc.joint_count);
    mat3 linear = mat3(m);
    Vertex o = v;
    o.position = (m * vec4(v.position, 1.0)).xyz;
    o.normal = normalize_or(cofactor(linear) * v.normal, v.normal);
    o.tangent = vec4(normalize_or(linear * v.tangent.xyz, v.tangent.xyz), v.tangent.w);
    vertices[pc.first_target + i] = o;
    prev_positions[pc.first_target + i] = (prev * vec4(v.position, 1.0)).xyz;
}
