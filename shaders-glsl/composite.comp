#version 460
// composite: the hybrid frame in linear HDR radiance. Per G-buffer pixel:
//   emission
// + the lights of the shadows chain's four channels: the first frame.chain_punctual punctual
//   lights (Lambert + GGX), then the mesh lights (common/mesh_lights.glsl), times their
//   ray-traced visibility (coloured by shadows.tint where tinted glass is on the way)
// + the diffuse signal (gi: the other emitters, environment, the other punctual lights
//   resampled, every bounce; demodulated) times the diffuse albedo
// + the specular signal (reflections, with gi's specular lobe of the resampled lights)
// + what glass and blended surfaces let through (reflections.let_through, its own signal).
// Pixels that hit nothing show the environment.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/brdf.glsl"
#include "common/transmission.glsl"
#include "common/lights.glsl"
#include "common/gbuffer.glsl"
#include "common/light_sampling.glsl"
#include "common/shadow_tint.glsl"
#include "common/mesh_lights.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform CompositeParams {
    uint tinted;             // 1: shadows.tint colours the visibility (some thin glass is tinted)
    float roughness_cutoff;  // the reflections pass's (see mesh_light_radiance)
    uint let_through;        // 1: some surface lets light through (in_let_through is full size)
    uvec4 mesh_first_emitter;  // per channel of the shadows chain, a mesh light's first emitter
    uvec4 mesh_triangles;      // and its triangles (0: not a mesh light)
} cp;

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D g_normal;
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
layout(set = 1, binding = 10) uniform sampler2D in_let_through;  // 1x1 unless cp.let_through
layout(set = 1, binding = 11, rgba32f) uniform writeonly image2D out_color;

// Specular anti-aliasing of the punctual lights (after Kaplanyan et al. 2016 and Tokuyoshi and
// Kaplanyan 2019): a point light's highlight on a curved glossy surface can be smaller than a
// pixel. The jittered frame then sees it in some frames and misses it in others, and TAA's
// neighbourhood clamp throws the history that holds it away: over LightsPunctualLamp's brass
// body (128x96) the frame kept 0.36 of the reference's light, 0.74 with the clamp off. The lobe
// is widened by the spread of the shading normal over the pixel (its differences to the next
// pixels on the same instance), GGX alpha^2 + min(2 sigma^2, SPECULAR_AA_MAX): the pixel's
// share of the highlight, spread over the pixels that average it. The body now keeps 0.54 at
// 128x96 and 0.72 at 512x384 (0.60 before; without TAA 0.71 before and 0.74 after). A wider
// cap did worse (alpha^2 up to 0.18: 0.48 and 0.69): a rough lobe masks and shadows more of
// its own light at the grazing angles of a curved surface. Only here: the lights sampled by
// rays are averaged by the denoiser, and a curved mirror would turn glossy.
#define SPECULAR_AA_VARIANCE 0.25  // the footprint's variance (pixel^2) that scales the squared differences
#define SPECULAR_AA_MAX 0.02       // the most alpha^2 it adds
float antialiased_roughness(ivec2 px, uint instance, vec3 n, float roughness) {
    float spread = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
        // The next pixel along the axis on the same surface, else the previous one.
        for (int side = 1; side >= -1; side -= 2) {
            ivec2 q = px + (axis == 0 ? ivec2(side, 0) : ivec2(0, side));
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
            if (imageLoad(g_ids, q).x != instance) continue;
            vec3 d = imageLoad(g_normal, q).xyz - n;
            spread += dot(d, d);
            break;
        }
    }
    float alpha = roughness * roughness;
    return sqrt(sqrt(alpha * alpha + min(2.0 * SPECULAR_AA_VARIANCE * spread, SPECULAR_AA_MAX)));
}

// The unshadowed light of the mesh light on channel i toward the viewer: its irradiance in
// closed form times the material's f at the direction it arrives from on average (exact for
// the Lambert lobe; glTF's diffuse weight and the specular lobe are taken at that one
// direction). On surfaces at or under the reflections' roughness cut-off the reflection rays
// find the emitter, so only the diffuse lobe is composite's, as gi's reservoirs did.
vec3 mesh_light_radiance(uint i, vec3 p, vec3 n, vec3 v, BrdfInput m, float transmission) {
    vec3 f = mesh_light_form_factor(cp.mesh_first_emitter[i], cp.mesh_triangles[i], p, n);
    float irradiance = dot(n, f);
    if (!(irradiance > 0.0)) return vec3(0.0);
    vec3 l = normalize(f);
    float cos_l = dot(n, l);
    if (cos_l <= 1e-4) return vec3(0.0);
    vec3 lobe = m.roughness > cp.roughness_cutoff ? reflection_eval_cos(m, transmission, n, v, l)
                                                  : (1.0 - transmission) * brdf_diffuse_cos(m, n, v, l);
    return mesh_light_emission(cp.mesh_first_emitter[i]) * irradiance * lobe / cos_l;
}

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

    // Glass lets the share `transmission` of its diffuse light through instead (in_let_through
    // is what comes through).
    float transmission = mr.w;
    // A blended surface covers the share alpha of the pixel; in_let_through is what shows
    // through the rest.
    float cover = (mi.flags & MATERIAL_BLEND) != 0u ? imageLoad(g_base_color, px).a : 1.0;

    BrdfInput lit = m;
    lit.roughness = antialiased_roughness(px, ids.x, n, m.roughness);
    vec4 vis = imageLoad(in_visibility, px);
    uvec4 tint = cp.tinted != 0u ? imageLoad(in_tint, px) : uvec4(0u);
    vec3 radiance = imageLoad(g_emissive, px).rgb;
    for (uint i = 0u; i < 4u; ++i) {  // the chain's channels (shadows_common.glsl's SHADOW_LIGHTS)
        vec3 through = vis[i] * shadow_tint_decode(tint[i]);
        if (i < frame.chain_punctual) {
            LightSample ls = sample_punctual(lights[i], p);
            radiance += reflection_eval_cos(lit, transmission, n, v, ls.dir) * ls.radiance * through;
        } else if (cp.mesh_triangles[i] > 0u) {
            radiance += mesh_light_radiance(i, p, n, v, m, transmission) * through;
        }
    }
    // The diffuse signal is the lobe without its albedo (gi.comp).
    radiance += (1.0 - transmission) * brdf_diffuse_albedo(m) * texelFetch(in_diffuse, px, 0).rgb;
    radiance = cover * radiance + texelFetch(in_specular, px, 0).rgb;
    if (cp.let_through != 0u) radiance += texelFetch(in_let_through, px, 0).rgb;
    imageStore(out_color, px, vec4(radiance, 1.0));
}
