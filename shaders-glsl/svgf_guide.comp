#version 460
// svgf_guide: packs the G-buffer texels the a-trous iterations weigh their taps by (view depth,
// shading normal, whether there is a surface) into one texel per pixel, once per frame for
// every chain and iteration (common/svgf.glsl, svgf_guide_pack).
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D g_normal;  // shading normal
layout(set = 1, binding = 2, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D out_guide;

#include "common/svgf.glsl"

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    imageStore(out_guide, px, svgf_guide_pack(imageLoad(g_depth, px).r, imageLoad(g_normal, px).xyz,
                                              imageLoad(g_ids, px).x));
}
