#version 460
// shadows: visibility of the first four punctual lights from every G-buffer surface, one
// shadow ray per light (hard shadows), through the trace interface.
#extension GL_GOOGLE_include_directive : require
#include "common/trace.glsl"
#include "common/gbuffer.glsl"
#include "common/lights.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 2, rg32ui) uniform readonly uimage2D g_ids;
// Channel i: visibility (0 or 1) of light i; 1 for lights that do not exist.
layout(set = 1, binding = 3, rgba16f) uniform writeonly image2D out_visibility;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 vis = vec4(1.0);
    if (imageLoad(g_ids, px).x != NO_INSTANCE) {
        float depth = imageLoad(g_depth, px).r;
        vec3 ng = imageLoad(g_normal_geo, px).xyz;
        vec3 p = world_position(px, depth);
        vec3 origin = offset_ray_origin(p, ng, depth);
        uint n = min(frame.light_count, 4u);
        for (uint i = 0u; i < n; ++i) {
            LightSample ls = sample_punctual(lights[i], p);
            // Surfaces facing away from the light are dark anyway: no ray needed.
            if (dot(ls.dir, ng) <= 0.0 || dot(ls.radiance, ls.radiance) == 0.0) {
                vis[i] = 0.0;
                continue;
            }
            float tmax = ls.dist >= 1e29 ? 1e6 : ls.dist * (1.0 - 1e-4);
            vis[i] = trace_any(origin, ls.dir, 0.0, tmax, RAY_MASK_ALL) ? 0.0 : 1.0;
        }
    }
    imageStore(out_visibility, px, vis);
}
