#version 460
// pathtrace: the reference. One path per pixel per frame, progressive and unbiased: camera rays
// through random sub-pixel positions (box filter), at every vertex one light sample (next-event
// estimation) and one BSDF sample, the two combined by multiple importance sampling with the
// power heuristic wherever both can produce the same direction (emissive triangles, the
// environment); lights that are not geometry (punctual, sphere, disk) are reached only by light
// sampling and count with weight 1. Russian roulette from the fourth vertex on. Alpha-masked
// surfaces pass through (the trace interface tests alpha). Transmissive surfaces refract or let
// light through (common/transmission.glsl). Blended surfaces (alphaMode BLEND) cover the share
// alpha of each point: a path passes straight through with probability 1 - alpha, and shadow
// rays let 1 - alpha through. Smooth thin-walled glass lets its transmitted share straight
// through, for paths (a pass, like the uncovered share of a blended surface) and shadow rays
// alike; rough thin-walled glass scatters it, and light samples from the glass itself reach
// lights behind it through its transmitted lobe. Light samples do not cross a volume's surface
// (its refraction would bend them): light reaches through it by BSDF sampling alone. Samples
// are summed into pathtrace.accum; pathtrace.color is the mean so far.
#extension GL_GOOGLE_include_directive : require
// Shadow rays cross only the glass they can cross exactly (common/hit.glsl).
#define HIT_SHADOWS_CROSS_SMOOTH_GLASS_ONLY
#include "common/trace.glsl"
#include "common/brdf.glsl"
#include "common/transmission.glsl"
#include "common/light_sampling.glsl"
#include "common/gbuffer.glsl"
#include "common/ray_offset.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// rgb: sum of all samples so far; a: number of samples.
layout(set = 1, binding = 0, rgba32f) uniform image2D out_accum;
// rgb: accum / samples (linear radiance).
layout(set = 1, binding = 1, rgba32f) uniform writeonly image2D out_color;
// Rays traced for this pixel so far (closest-hit and shadow rays): for rays/s and a map of
// where paths are long.
layout(set = 1, binding = 2, r32ui) uniform uimage2D out_rays;

layout(push_constant) uniform Params {
    // Mixed into every pixel's random stream with the frame index: same seed, same image.
    uint seed;
    // Scattering events per path at most; 1 = direct light only. Russian roulette ends paths
    // long before any sensible cap, which exists so a closed white box cannot run forever.
    uint max_bounces;
} params;

// Sample index = frame index: frame n adds sample n to every pixel.
#define SALT_PATHTRACE 0x70617468u
// Vertices before Russian roulette starts (camera hit = vertex 0).
#define RR_START 3u
// Blended surfaces and smooth thin-walled glass a path passes through at most (then they count
// as covering, and glass ends the path).
#define PASSES 16u
// Longest closest-hit ray (as shadow_ray_tmax for lights at infinity).
#define TRACE_FAR 1e6

float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

vec3 trace_path(vec2 pixel, inout Rng rng, inout uint rays) {
    vec3 origin = frame.camera_pos;
    vec3 dir = camera_ray_dir(pixel);
    vec3 throughput = vec3(1.0);
    vec3 radiance = vec3(0.0);
    // Density of the BSDF sample that made the current ray; 0 for the camera ray, whose hits
    // on emitters are not also reachable by light sampling (no MIS), and for rays that crossed
    // a volume's surface, which light sampling does not cross either.
    float bsdf_pdf = 0.0;
    // Beer-Lambert coefficient of the volume the ray travels in (0 outside every volume).
    vec3 absorption = vec3(0.0);
    // The vertex the current ray left (blended surfaces passed on the way do not count), from
    // which light sampling would have reached what the ray hits.
    vec3 mis_origin = origin;
    bool passed = false;
    uint passes = 0u;
    for (uint vertex = 0u;; ++vertex) {
        if (!passed) mis_origin = origin;
        passed = false;
        Hit h = trace_closest(origin, dir, 0.0, TRACE_FAR, RAY_MASK_ALL);
        ++rays;
        if (h.instance == NO_HIT) {
            float w = bsdf_pdf > 0.0 ? mis_power(bsdf_pdf, light_pdf_environment(dir)) : 1.0;
            radiance += throughput * env_eval(dir) * w;
            break;
        }
        if (any(greaterThan(absorption, vec3(0.0)))) throughput *= exp(-absorption * h.t);
        HitSurface s = hit_surface(h.instance, h.primitive, h.bary, dir);
        // A blended surface covers the share alpha of each point; the rest of the light passes
        // straight through it, which is no scattering event.
        if ((materials[s.material].flags & MATERIAL_BLEND) != 0u && passes < PASSES &&
            rng_next(rng) >= s.mat.base_color.a) {
            ++passes;
            passed = true;
            origin = offset_ray(s.position, -s.normal_geo);
            --vertex;  // wraps for the camera ray; the loop's increment brings it back
            continue;
        }
        if (emitter_visible_side(h.instance, h.primitive, dir)) {
            float w = bsdf_pdf > 0.0 ? mis_power(bsdf_pdf, light_pdf_emitter(h.instance, h.primitive, mis_origin, s.position))
                                     : 1.0;
            radiance += throughput * s.mat.emissive * w;
        }
        BrdfInput m = BrdfInput(s.mat.base_color.rgb, s.mat.metallic, s.mat.roughness, dielectric_f0(s.mat.ior));
        vec3 v = -dir;
        vec3 n = s.normal;
        vec3 ng = s.normal_geo;
        float transmission = s.mat.transmission;
        bool thin_glass = transmission > 0.0 && s.mat.thin_walled;
        bool smooth_glass = thin_glass && s.mat.roughness <= HIT_SMOOTH_ROUGHNESS;
        if (smooth_glass) {
            // Straight through with the chance of the transmitted share: what the shadow rays
            // of the vertex before let through, so no scattering event for multiple importance
            // sampling. Else the surface only reflects, for the rest of this vertex.
            float p_pass = transmitted_share(m, transmission, n, v);
            if (passes >= PASSES || p_pass >= 1.0) break;
            if (rng_next(rng) < p_pass) {
                ++passes;
                float f = fresnel_dielectric(m, abs(dot(dir, ng)));
                throughput *= (1.0 - f) * m.base_color * (transmission * (1.0 - m.metallic) / p_pass);
                passed = true;
                origin = offset_ray(s.position, -ng);
                --vertex;
                continue;
            }
            throughput /= 1.0 - p_pass;
        }
        if (vertex >= params.max_bounces) break;
        // What the reflection is sampled from: the same lobes with the diffuse one shrunk by
        // the transmitted share (exactly so for dielectrics; any such density is unbiased), so
        // clear glass draws its reflections from the specular lobe alone.
        BrdfInput m_reflect = m;
        m_reflect.base_color *= 1.0 - transmission;

        if (transmission > 0.0 && !s.mat.thin_walled && !s.front) {
            // Inside a volume: the bare interface reflects or lets the path out. Lights are
            // outside, behind this very surface: no light sample.
            TransmissionSample ts = interface_sample(s.mat.roughness, s.mat.ior, n, v, rng_next3(rng));
            if (dot(ts.weight, ts.weight) <= 0.0) break;
            throughput *= ts.weight;
            bsdf_pdf = 0.0;
            if (ts.crossed) absorption = vec3(0.0);
            origin = offset_ray(s.position, ts.crossed ? -ng : ng);
            dir = ts.l;
        } else {
            vec3 leave = offset_ray(s.position, ng);
            // The chance that the path continues through the surface (transmissive materials
            // but smooth thin-walled glass, decided above): the transmitted share.
            float p_t = transmission > 0.0 && !smooth_glass ? transmitted_share(m, transmission, n, v) : 0.0;
            // Next-event estimation. A transmissive surface reflects only what it does not let
            // through; rough thin-walled glass also lets light from behind it through its
            // transmitted lobe (drawn from the surface itself, as the shadow ray then leaves
            // from either side). Other directions below the geometric surface would start
            // inside it.
            NeeSample ls = light_sample(thin_glass ? s.position : leave, rng_next3(rng));
            if (dot(ls.weight, ls.weight) > 0.0) {
                bool behind = dot(ls.dir, ng) <= 0.0;
                vec3 f = vec3(0.0);
                float p_bsdf = 0.0;  // density of the path's own sampling drawing ls.dir
                if (!behind) {
                    f = transmission > 0.0 ? reflection_eval_cos(m, transmission, n, v, ls.dir) : brdf_eval_cos(m, n, v, ls.dir);
                    p_bsdf = (1.0 - p_t) * brdf_pdf(m_reflect, n, v, ls.dir);
                } else if (thin_glass && !smooth_glass) {
                    f = transmission * (1.0 - m.metallic) * thin_transmission_eval_cos(m, n, v, ls.dir);
                    p_bsdf = p_t * thin_transmission_pdf(m, n, v, ls.dir);
                }
                if (dot(f, f) > 0.0) {
                    ++rays;
                    vec3 from = offset_ray(s.position, behind ? -ng : ng);
                    vec3 through = trace_transmittance(from, ls.dir, 0.0, shadow_ray_tmax(ls.dist), RAY_MASK_ALL);
                    if (dot(through, through) > 0.0) {
                        float w = ls.pdf > 0.0 ? mis_power(ls.pdf, p_bsdf) : 1.0;
                        radiance += throughput * f * ls.weight * through * w;
                    }
                }
            }

            // Continue the path: through the surface (with the probability p_t), else by
            // sampling the reflecting BSDF.
            if (p_t > 0.0 && rng_next(rng) < p_t) {
                TransmissionSample ts = transmission_sample(m, s.mat.thin_walled, s.mat.ior, n, v, rng_next2(rng));
                if (dot(ts.weight, ts.weight) <= 0.0) break;
                throughput *= ts.weight * (transmission * (1.0 - m.metallic) / p_t);
                // Light samples reach through rough thin-walled glass (above), not into a volume.
                bsdf_pdf = s.mat.thin_walled ? p_t * thin_transmission_pdf(m, n, v, ts.l) : 0.0;
                if (!s.mat.thin_walled) absorption = s.mat.absorption;
                origin = offset_ray(s.position, -ng);
                dir = ts.l;
            } else {
                BrdfSample bs = brdf_sample(m_reflect, n, v, rng_next3(rng));
                if (bs.pdf <= 0.0 || dot(bs.l, ng) <= 0.0) break;
                if (transmission > 0.0) {
                    bsdf_pdf = bs.pdf * (1.0 - p_t);
                    throughput *= reflection_eval_cos(m, transmission, n, v, bs.l) / bsdf_pdf;
                } else {
                    throughput *= bs.weight;
                    bsdf_pdf = bs.pdf;
                }
                origin = leave;
                dir = bs.l;
            }
        }
        if (vertex >= RR_START) {
            // Survival probability follows the throughput (capped so bright paths still end).
            float q = clamp(max3(throughput), 0.05, 0.95);
            if (rng_next(rng) >= q) break;
            throughput /= q;
        }
    }
    return radiance;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    uint sample_index = frame.frame_index;
    Rng rng = rng_init(uvec2(px), sample_index, pcg_hash(params.seed) ^ SALT_PATHTRACE);
    uint rays = 0u;
    vec3 l = trace_path(vec2(px) + rng_next2(rng), rng, rays);
    // A NaN or infinity would poison the pixel for the rest of the run: drop the sample (it
    // still counts as taken, so the image stays an average over the same number of samples).
    if (any(isnan(l)) || any(isinf(l))) l = vec3(0.0);
    vec4 sum = sample_index == 0u ? vec4(0.0) : imageLoad(out_accum, px);
    uint total_rays = sample_index == 0u ? 0u : imageLoad(out_rays, px).x;
    sum += vec4(l, 1.0);
    imageStore(out_accum, px, sum);
    imageStore(out_color, px, vec4(sum.rgb / sum.a, 1.0));
    imageStore(out_rays, px, uvec4(total_rays + rays));
}
