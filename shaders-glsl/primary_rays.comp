#version 460
// primary_rays: one closest-hit ray through each pixel centre from the camera. Not part of the
// hybrid frame (the G-buffer replaces it); it exists to prove that the ray backends and the
// rasteriser agree, and its output dumps like any other pass.
#extension GL_GOOGLE_include_directive : require
#include "common/trace.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// x = instance id (NO_HIT on a miss), y = primitive, z = float bits of t, w = 1 if front face.
layout(set = 1, binding = 0, rgba32ui) uniform writeonly uimage2D out_hit;
// View-space depth of the hit (as gbuffer.depth), 0 on a miss.
layout(set = 1, binding = 1, r32f) uniform writeonly image2D out_depth;
// Barycentrics of vertices 1 and 2 (a hit on an edge has one of u, v, 1 - u - v at 0).
layout(set = 1, binding = 2, rg32f) uniform writeonly image2D out_bary;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec2 ndc = (vec2(px) + 0.5) / vec2(frame.size) * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 dir = normalize(far.xyz / far.w - frame.camera_pos);
    Hit h = trace_closest(frame.camera_pos, dir, 0.0, 1e6, RAY_MASK_ALL);
    if (h.instance == NO_HIT) {
        imageStore(out_hit, px, uvec4(NO_HIT, 0u, 0u, 0u));
        imageStore(out_depth, px, vec4(0.0));
        imageStore(out_bary, px, vec4(0.0));
        return;
    }
    imageStore(out_hit, px, uvec4(h.instance, h.primitive, floatBitsToUint(h.t), h.front_face ? 1u : 0u));
    imageStore(out_depth, px, vec4(h.t * dot(dir, -frame.inv_view[2].xyz)));
    imageStore(out_bary, px, vec4(h.bary, 0.0, 0.0));
}
