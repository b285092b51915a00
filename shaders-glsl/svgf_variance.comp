#version 460
// svgf_variance: luminance variance from the temporal moments; where the history is shorter
// than 4 frames the moments are not trustworthy yet, so they are estimated spatially over a
// 7x7 edge-aware neighbourhood instead (and the variance boosted by 4 / history, as Falcor).
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D in_color;
layout(set = 1, binding = 1, rg32f) uniform readonly image2D in_moments;
layout(set = 1, binding = 2, r32f) uniform readonly image2D in_history_length;
layout(set = 1, binding = 3, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 4, rgba16f) uniform readonly image2D g_normal;  // shading normal (gbuffer.normal)
layout(set = 1, binding = 5, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 6, r32f) uniform writeonly image2D out_variance;

#include "common/svgf.glsl"

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    if (imageLoad(g_ids, px).x == NO_INSTANCE) {
        imageStore(out_variance, px, vec4(0.0));
        return;
    }
    float len = imageLoad(in_history_length, px).r;
    vec2 m = imageLoad(in_moments, px).xy;
    if (len >= 4.0) {
        imageStore(out_variance, px, vec4(max(0.0, m.y - m.x * m.x)));
        return;
    }
    vec2 zf = imageLoad(g_depth, px).rg;
    float z = zf.x;
    vec3 n = imageLoad(g_normal, px).xyz;
    float l = luminance(imageLoad(in_color, px).rgb);
    vec2 sum = vec2(0.0);
    float wsum = 0.0;
    for (int dy = -3; dy <= 3; ++dy) {
        for (int dx = -3; dx <= 3; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
            if (imageLoad(g_ids, q).x == NO_INSTANCE) continue;
            float lq = luminance(imageLoad(in_color, q).rgb);
            // The luminance weight uses a fixed scale: there is no variance to scale it yet.
            float w = svgf_weight_depth(z, imageLoad(g_depth, q).r, zf.y, length(vec2(dx, dy))) *
                      svgf_weight_normal(n, imageLoad(g_normal, q).xyz) *
                      exp(-abs(l - lq) / svgf.sigma_l);
            sum += w * imageLoad(in_moments, q).xy;
            wsum += w;
        }
    }
    sum /= max(wsum, 1e-6);
    float var = max(0.0, sum.y - sum.x * sum.x) * 4.0 / max(len, 1.0);
    imageStore(out_variance, px, vec4(var));
}
