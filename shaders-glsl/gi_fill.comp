#version 460
// gi_fill: completes gi's signals at half or quarter rate. gi traced one pixel of each pair
// or 2x2 block and marked the others (common/gi_fill.glsl) with the traced neighbours that
// show their surface; such a pixel takes their mean. Every other pixel is copied. A pass of its own, not gi's second
// step through shared memory: the workgroup barrier that needed made a CPU driver compile gi
// as a coroutine, minutes longer, and kept neighbours across workgroup edges out of reach.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gi_fill.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D in_radiance;
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D in_specular;
layout(set = 1, binding = 2, rgba32f) uniform writeonly image2D out_radiance;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D out_specular;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 radiance = imageLoad(in_radiance, px);
    if (radiance.a >= 0.0) {
        imageStore(out_radiance, px, radiance);
        imageStore(out_specular, px, imageLoad(in_specular, px));
        return;
    }
    uint bits = uint(-radiance.a + 0.5);
    vec3 d_sum = vec3(0.0), s_sum = vec3(0.0);
    float count = 0.0;
    for (int i = 0; i < GI_FILL_NEIGHBOURS; ++i) {
        if ((bits & (1u << i)) == 0u) continue;
        ivec2 q = px + GI_FILL_OFFSETS[i];
        d_sum += imageLoad(in_radiance, q).rgb;
        s_sum += imageLoad(in_specular, q).rgb;
        count += 1.0;
    }
    bool diffuse = (bits & GI_FILL_DIFFUSE) != 0u, specular = (bits & GI_FILL_SPECULAR) != 0u;
    imageStore(out_radiance, px, vec4(diffuse ? d_sum / count : vec3(0.0), 1.0));
    imageStore(out_specular, px, vec4(specular ? s_sum / count : vec3(0.0), 1.0));
}
