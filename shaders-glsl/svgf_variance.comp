#version 460
// svgf_variance_<signal>: luminance variance from the temporal moments; where the history is
// shorter than 4 frames the moments are not trustworthy yet, so they are estimated spatially
// over a 7x7 edge-aware neighbourhood instead (and the variance boosted by 4 / history, as
// Falcor). Written as the alpha of the temporal colour, so each a-trous tap loads one texel
// for both.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D in_color;
layout(set = 1, binding = 1, rg32f) uniform readonly image2D in_moments;
layout(set = 1, binding = 2, r32f) uniform readonly image2D in_history_length;
layout(set = 1, binding = 3, rgba32f) uniform readonly image2D in_guide;
layout(set = 1, binding = 4, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 5, rgba32f) uniform writeonly image2D out_color;  // rgb: in_color, a: variance

#include "common/svgf.glsl"

// The spatial estimate of the variance at px from its 7x7 neighbours' moments.
float spatial_variance(ivec2 px, vec4 g, float fwidth_z, float len) {
    float l = luminance(imageLoad(in_color, px).rgb);
    vec2 sum = vec2(0.0);
    float wsum = 0.0;
    for (int dy = -3; dy <= 3; ++dy) {
        for (int dx = -3; dx <= 3; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
            vec4 gq = imageLoad(in_guide, q);
            if (!svgf_guide_surface(gq)) continue;
            float inv_z_scale = 1.0 / (svgf.sigma_z * fwidth_z * length(vec2(dx, dy)) + 1e-4);
            // The luminance weight uses a fixed scale: there is no variance to scale it yet.
            float w = exp(-svgf_depth_exponent(g.w, gq.w, inv_z_scale) - svgf_normal_exponent(g.xyz, gq.xyz) -
                          abs(l - luminance(imageLoad(in_color, q).rgb)) / svgf.sigma_l);
            sum += w * imageLoad(in_moments, q).xy;
            wsum += w;
        }
    }
    sum /= max(wsum, 1e-6);
    return max(0.0, sum.y - sum.x * sum.x) * 4.0 / max(len, 1.0);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec4 g = imageLoad(in_guide, px);
    vec3 c = imageLoad(in_color, px).rgb;
    float var = 0.0;
    if (svgf_guide_surface(g)) {
        float len = imageLoad(in_history_length, px).r;
        vec2 m = imageLoad(in_moments, px).xy;
        var = len >= SVGF_MOMENTS_FRAMES ? max(0.0, m.y - m.x * m.x) : spatial_variance(px, g, imageLoad(g_depth, px).g, len);
    }
    imageStore(out_color, px, vec4(c, var));
}
