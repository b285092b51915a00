#version 460
// composite: the hybrid frame in linear HDR radiance. Per G-buffer pixel:
//   emission
// + the first SHADOWED_LIGHTS punctual lights (Lambert + GGX) times their ray-traced
//   visibility (the shadows chain, one channel each; coloured by shadows.tint where tinted
//   glass is on the way)
// + the diffuse signal (gi: emitters, environment, the other punctual lights resampled, every
//   bounce; demodulated) times the diffuse albedo
// + the specular signal (reflections, with gi's specular lobe of the resampled lights, and
//   what glass lets through).
// Pixels that hit nothing show the environment.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/brdf.glsl"
#include "common/transmission.glsl"
#include "common/lights.glsl"
#include "common/gbuffer.glsl"
#include "common/light_sampling.glsl"
#include "common/shadow_tint.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform CompositeParams {
    uint tinted;  // 1: shadows.tint colours the visibility (some thin glass is tinted)
} cp;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D g_normal;
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D g_base_color;
layout(set = 1, binding = 3, rgba8) uniform readonly image2D g_metal_rough;
layout(set = 1, binding = 4, rgba16f) uniform readonly image2D g_emissive;
layout(set = 1, binding = 5, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 6, rgba16f) uniform readonly image2D in_visibility;
// The diffuse and specular signals, raw (rgba32f) or denoised (rgba16f): sampled, which reads
// either format.
layout(set = 1, binding = 7, rgba32ui) uniform readonly uimage2D in_tint;  // 1x1 unless cp.tinted
layout(set = 1, binding = 8) uniform sampler2D in_diffuse;
layout(set = 1, binding = 9) uniform sampler2D in_specular;
layout(set = 1, binding = 10, rgba32f) uniform writeonly image2D out_color;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    uvec2 ids = imageLoad(g_ids, px).xy;
    if (ids.x == NO_INSTANCE) {
        imageStore(out_color, px, vec4(env_eval(camera_ray_dir(vec2(px) + 0.5 - frame.jitter)), 1.0));
        return;
    }
    float depth = imageLoad(g_depth, px).r;
    vec3 p = world_position(px, depth);
    vec3 n = imageLoad(g_normal, px).xyz;
    vec3 v = normalize(frame.camera_pos - p);
    vec4 mr = imageLoad(g_metal_rough, px);
    MaterialInfo mi = materials[ids.y];
    BrdfInput m = BrdfInput(imageLoad(g_base_color, px).rgb, mr.x, mr.y, dielectric_f0(mi.ior));

    // Glass lets the share `transmission` of its diffuse light through instead (reflections
    // adds what comes through).
    float transmission = mr.w;
    // A blended surface covers the share alpha of the pixel; reflections adds what shows
    // through the rest.
    float cover = (mi.flags & MATERIAL_BLEND) != 0u ? imageLoad(g_base_color, px).a : 1.0;

    vec4 vis = imageLoad(in_visibility, px);
    uvec4 tint = cp.tinted != 0u ? imageLoad(in_tint, px) : uvec4(0u);
    vec3 radiance = imageLoad(g_emissive, px).rgb;
    for (uint i = 0u; i < min(frame.light_count, SHADOWED_LIGHTS); ++i) {
        LightSample ls = sample_punctual(lights[i], p);
        vec3 through = vis[i] * shadow_tint_decode(tint[i]);
        radiance += reflection_eval_cos(m, transmission, n, v, ls.dir) * ls.radiance * through;
    }
    // The diffuse signal is the lobe without its albedo (gi.comp).
    radiance += (1.0 - transmission) * brdf_diffuse_albedo(m) * texelFetch(in_diffuse, px, 0).rgb;
    radiance = cover * radiance + texelFetch(in_specular, px, 0).rgb;
    imageStore(out_color, px, vec4(radiance, 1.0));
}
