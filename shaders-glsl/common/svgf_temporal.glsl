// svgf_temporal_<signal> (svgf_temporal.comp, svgf_temporal_specular.comp): temporal
// accumulation of one demodulated signal (diffuse or specular). The
// previous frame's filtered colour (the first a-trous iteration, copied by `history`), moments
// and history length are reprojected through the motion vectors with bilinear taps that each
// pass the validity test (on screen, same instance, depth, geometric normal); the new frame is blended in
// with max(alpha, 1/history). The input is cleaned first: NaN/Inf samples are dropped (and
// counted) and luminance outliers clamped to mean + k sigma of their 7x7 neighbourhood (5x5
// once the history is established, when the clamp gives back the light it takes out), so
// neither poisons the history.
//
// A pixel with no history at all takes the edge-aware mean of that 7x7 window (on its own
// instance) in place of its sample: the a-trous iterations then start from less noise after a
// disocclusion, a camera cut or a change of the lights, which lets their 3x3 kernel stay
// narrow (common/svgf_atrous.glsl).
//
// The colour's alpha holds its luminance variance (as the deviation, svgf_pack), what the
// a-trous iterations scale their luminance weight by: from the temporal moments, or, while the
// history is shorter than SVGF_MOMENTS_FRAMES, estimated over the same 7x7 neighbourhood of
// this frame's samples with the edge-stopping weights (and boosted by 4 / history, as
// Falcor). Schied et al. estimate it from the neighbours' accumulated moments in a pass of its
// own; one frame's samples are what a young history holds (all of it at a disocclusion), and
// the window is loaded anyway.
//
// With SVGF_REFLECTION_MOTION defined (the specular chain behind the reflections pass) the
// history of a narrow lobe is fetched where the reflected object was, not where the surface
// was: the reflection of a point at hit distance d appears at the virtual point p + d view_dir
// behind a mirror, and a moving camera sees it move with that point's parallax, not the
// surface's. The lobe's width decides between the two (roughness), and caps the history: a
// glossy reflection changes with the view even where the reprojection is right. (The same
// width narrows the a-trous filter's footprint: svgf_footprint.)
#ifndef SVGF_TEMPORAL_GLSL
#define SVGF_TEMPORAL_GLSL

#include "common/scene.glsl"
#include "common/gbuffer.glsl"
#include "common/reflection_motion.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D in_signal;
layout(set = 1, binding = 1, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
// The geometric (face) normal: reprojection asks whether the previous sample lies on the same
// surface, and a crease that smooth vertex normals round off is still a different surface.
layout(set = 1, binding = 2, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 3, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 4, rg32f) uniform readonly image2D g_motion;
layout(set = 1, binding = 5, rg32f) uniform readonly image2D prev_depth;
layout(set = 1, binding = 6, rgba16f) uniform readonly image2D prev_normal_geo;
layout(set = 1, binding = 7, rg32ui) uniform readonly uimage2D prev_ids;
layout(set = 1, binding = 8, rgba16f) uniform readonly image2D prev_color;
layout(set = 1, binding = 9, rg32f) uniform readonly image2D prev_moments;
layout(set = 1, binding = 10, r32f) uniform readonly image2D prev_history_length;
// svgf_guide: shading normal and view depth (w < 0: no surface), for the spatial variance.
layout(set = 1, binding = 11, rgba32f) uniform readonly image2D in_guide;
#ifdef SVGF_REFLECTION_MOTION
// reflections.hit_distance: mean distance to what the reflection rays hit (0: none traced).
layout(set = 1, binding = 12, r32f) uniform readonly image2D in_hit_distance;
layout(set = 1, binding = 13, rgba8) uniform readonly image2D g_metal_rough;
#define SVGF_OUT 14  // outputs follow the inputs
#else
#define SVGF_OUT 12
#endif
layout(set = 1, binding = SVGF_OUT, rgba16f) uniform writeonly image2D out_color;
layout(set = 1, binding = SVGF_OUT + 1, rg32f) uniform writeonly image2D out_moments;
layout(set = 1, binding = SVGF_OUT + 2, r32f) uniform writeonly image2D out_history_length;
// x: input samples that were NaN or Inf, counted since the first frame (only pixel 0,0).
layout(set = 1, binding = SVGF_OUT + 3, r32ui) uniform uimage2D out_rejected;

#include "common/svgf.glsl"

// The input sample with non-finite values removed (false when it was not finite).
bool load_finite(ivec2 q, out vec3 c) {
    c = imageLoad(in_signal, q).rgb;
    if (finite3(c)) return true;
    c = vec3(0.0);
    return false;
}

// What the 7x7 neighbourhood of this frame's samples says about pixel `px`.
struct Neighbourhood {
    float clamp_limit;  // luminance above which the sample is an outlier (infinite: clamp off)
    float variance;     // the spatial variance estimate (computed only when asked for)
    vec3 spread;        // this pixel's share of what the clamp takes out of its neighbours
    vec3 blurred;       // the edge-aware mean of the clamped samples (only with `blur`)
};

// One pass over the 7x7 neighbourhood (surface pixels only) for the outlier clamp's bound,
// mean + k sigma of the luminance, which takes a firefly out of the history before anything
// accumulates it; and, with `spatial`, the luminance variance around `l` (this pixel's
// clamped luminance, which the luminance weight needs, so the clamp's bound is found first
// and the window read twice only then) and, with `blur` (no history at all), the edge-aware
// mean of the clamped samples on this pixel's instance.
//
// With `spread` (an established history) the clamp keeps the firefly's energy: each pixel
// takes an even share of what the clamp takes out of the brightest neighbour on its own
// surface (normal within 25 degrees, depth within 5%). A firefly's own window never holds it,
// so its neighbours' bounds leave the window's brightest sample out too: they then bound it as
// it bounds itself, and what they take back adds up to about what its clamp removed. (Only
// the brightest: two fireflies in one window are rare, and a per-neighbour account needs the
// window's luminances kept, which made the pass half as slow again on lavapipe.) Its window
// is then 5x5: a smaller window clamps more, which cost light when the clamp dropped it, and
// now costs nothing but makes the pass as fast as it was before the give-back.
// An established history's bound is this many times wider: it averages what gets past, and
// one window of one frame's samples is a poor judge of rare bright paths. Measured at 256x256
// on the diffuse box, the frame after 64 frames held 0.956 of the reference's light with the
// bound at 4 sigma and 0.974 at 8 (gi at full rate: 0.857 and 0.891).
#define SVGF_ESTABLISHED_SIGMA_SCALE 2.0

Neighbourhood neighbourhood(ivec2 px, vec4 g, uint id, float fwidth_z, vec3 c, bool spatial, bool spread, bool blur) {
    Neighbourhood nb = Neighbourhood(1.0 / 0.0, 0.0, vec3(0.0), vec3(0.0));
    // clamp_sigma = infinity switches the clamp off (the impulse-response test does).
    bool clamped = !isinf(svgf.clamp_sigma);
    float sum = 0.0, sum2 = 0.0, n = 0.0, brightest = 0.0, n_same = 0.0;
    vec3 brightest_same = vec3(0.0);  // the brightest neighbour on this pixel's surface
    float brightest_same_l = 0.0;
    int radius = spread ? 2 : 3;  // the young history's spatial variance needs the 7x7 one
    for (int dy = -radius; dy <= radius && clamped; ++dy) {
        for (int dx = -radius; dx <= radius; ++dx) {
            // The centre is left out, so a lone firefly cannot widen its own bound.
            if (dx == 0 && dy == 0) continue;
            ivec2 q = clamp(px + ivec2(dx, dy), ivec2(0), ivec2(frame.size) - 1);
            vec4 gq = imageLoad(in_guide, q);
            if (!svgf_guide_surface(gq)) continue;
            vec3 s;
            load_finite(q, s);
            float l = luminance(s);
            sum += l;
            sum2 += l * l;
            n += 1.0;
            brightest = max(brightest, l);
            if (spread && dot(g.xyz, gq.xyz) > 0.9 && abs(gq.w - g.w) < 0.05 * g.w) {
                n_same += 1.0;
                if (l > brightest_same_l) {
                    brightest_same_l = l;
                    brightest_same = s;
                }
            }
        }
    }
    if (clamped) {
        float trim = spread ? brightest : 0.0;
        float m = max(n - (spread ? 1.0 : 0.0), 1.0);
        float mean = (sum - trim) / m;
        float k = spread ? SVGF_ESTABLISHED_SIGMA_SCALE * svgf.clamp_sigma : svgf.clamp_sigma;
        nb.clamp_limit = mean + k * sqrt(max(0.0, (sum2 - trim * trim) / m - mean * mean));
        if (brightest_same_l > nb.clamp_limit) {
            nb.spread = brightest_same * (1.0 - nb.clamp_limit / brightest_same_l) / n_same;
        }
    }
    if (!spatial) return nb;
    float l = min(luminance(c), nb.clamp_limit);
    vec2 m = vec2(0.0);
    vec3 blurred = vec3(0.0);
    float wsum = 0.0, blur_wsum = 0.0;
    for (int dy = -3; dy <= 3; ++dy) {
        for (int dx = -3; dx <= 3; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
            vec4 gq = imageLoad(in_guide, q);
            if (!svgf_guide_surface(gq)) continue;
            vec3 s;
            load_finite(q, s);
            float lq_raw = luminance(s);
            float lq = min(lq_raw, nb.clamp_limit);
            float inv_z_scale = 1.0 / (svgf.sigma_z * fwidth_z * length(vec2(dx, dy)) + 1e-4);
            // The luminance weight uses a fixed scale: there is no variance to scale it yet.
            float w = exp(-svgf_depth_exponent(g.w, gq.w, inv_z_scale) - svgf_normal_exponent(g.xyz, gq.xyz) -
                          abs(l - lq) / svgf.sigma_l);
            m += w * vec2(lq, lq * lq);
            wsum += w;
            if (blur && imageLoad(g_ids, q).x == id) {
                blurred += w * (lq_raw > lq ? s * (lq / lq_raw) : s);
                blur_wsum += w;
            }
        }
    }
    m /= max(wsum, 1e-6);
    nb.blurred = blurred / max(blur_wsum, 1e-6);
    nb.variance = max(0.0, m.y - m.x * m.x);
    return nb;
}

#ifdef SVGF_REFLECTION_MOTION
// A mirror's history is capped at this many frames, rising to svgf.history_cap at roughness
// GLOSSY_CAP_ROUGHNESS.
const float GLOSSY_HISTORY_CAP = 8.0;
const float GLOSSY_CAP_ROUGHNESS = 0.5;
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    uint id = imageLoad(g_ids, px).x;
    if (id == NO_INSTANCE) {
        imageStore(out_color, px, vec4(0.0));
        imageStore(out_moments, px, vec4(0.0));
        imageStore(out_history_length, px, vec4(0.0));
        return;
    }
    vec3 c;
    bool finite = load_finite(px, c);
    if (!finite) imageAtomicAdd(out_rejected, ivec2(0), 1u);

    vec2 zf = imageLoad(g_depth, px).rg;
    float z = zf.x;
    vec3 ng = imageLoad(g_normal_geo, px).xyz;
    float fw = zf.y;
    // Where this pixel's surface was last frame, in continuous pixel coordinates.
    vec2 prev_pos = vec2(px) + 0.5 - imageLoad(g_motion, px).xy;
    float cap = svgf.history_cap;
    float footprint = 1.0;  // how much of the young sample's spatial mean stands for it
    // The depth test's tolerance: fetched away from the surface's own motion (the virtual
    // point's), the previous sample is on the same surface a few pixels off, where depth
    // differs by about fwidth per pixel.
    float fw_tolerance = fw;
#ifdef SVGF_REFLECTION_MOTION
    float roughness = imageLoad(g_metal_rough, px).y;
    float hit = imageLoad(in_hit_distance, px).r;
    float virtual_weight = reflection_motion_weight(roughness);
    if (hit > 0.0 && virtual_weight > 0.0) {
        vec2 surface_pos = prev_pos;
        prev_pos = mix(prev_pos, reflection_prev_pos(px, z, hit), virtual_weight);
        fw_tolerance = fw * (1.0 + distance(prev_pos, surface_pos));
    }
    cap = mix(GLOSSY_HISTORY_CAP, cap, smoothstep(0.0, GLOSSY_CAP_ROUGHNESS, roughness));
    footprint = svgf_footprint(roughness);
#endif
    vec2 base = floor(prev_pos - 0.5);
    vec2 f = prev_pos - 0.5 - base;
    vec3 hist_c = vec3(0.0);
    vec2 hist_m = vec2(0.0);
    float hist_len = 0.0, wsum = 0.0;
    // A camera cut, or lights that changed since last frame: the history holds light that is
    // gone (the lag a lit history would add is the whole accumulation window).
    bool reset = (frame.flags & (FRAME_RESET_HISTORY | FRAME_LIGHTS_CHANGED)) != 0u;
    for (int i = 0; i < 4 && !reset; ++i) {
        ivec2 q = ivec2(base) + ivec2(i & 1, i >> 1);
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
        if (!svgf_consistent(z, imageLoad(prev_depth, q).r, fw_tolerance, ng, imageLoad(prev_normal_geo, q).xyz, id,
                             imageLoad(prev_ids, q).x)) continue;
        float w = ((i & 1) == 1 ? f.x : 1.0 - f.x) * ((i >> 1) == 1 ? f.y : 1.0 - f.y);
        hist_c += w * imageLoad(prev_color, q).rgb;
        hist_m += w * imageLoad(prev_moments, q).xy;
        hist_len += w * imageLoad(prev_history_length, q).r;
        wsum += w;
    }
    bool reprojected = wsum > 1e-3;
    float len = reprojected ? min(hist_len / wsum + 1.0, cap) : 1.0;
    Neighbourhood nb = neighbourhood(px, imageLoad(in_guide, px), id, fw, c, len < SVGF_MOMENTS_FRAMES,
                                     len >= SVGF_MOMENTS_FRAMES, !reprojected);
    float l = luminance(c);
    if (l > nb.clamp_limit && l > 0.0) c *= nb.clamp_limit / l;
    c += nb.spread;
    // No history at all (a disocclusion, a camera cut, changed lights): the sample is replaced
    // by the edge-aware mean of its 7x7 window on the same instance, which the variance
    // estimate has weighed anyway, so the a-trous iterations start from less noise. A narrow
    // lobe's reflection keeps its sharpness (svgf_footprint, as in the a-trous filter).
    if (!reprojected && finite) c = mix(c, nb.blurred, footprint);
    l = luminance(c);
    vec2 moments = vec2(l, l * l);
    if (reprojected) {
        hist_c /= wsum;
        hist_m /= wsum;
        float a = max(svgf.alpha, 1.0 / len);
        float am = max(svgf.moments_alpha, 1.0 / len);
        // A dropped (non-finite) sample leaves the history as it was.
        c = finite ? mix(hist_c, c, a) : hist_c;
        moments = finite ? mix(hist_m, moments, am) : hist_m;
    }
    float variance = len >= SVGF_MOMENTS_FRAMES ? max(0.0, moments.y - moments.x * moments.x)
                                                : nb.variance * 4.0 / len;
    imageStore(out_color, px, svgf_pack(c, variance));
    imageStore(out_moments, px, vec4(moments, 0.0, 0.0));
    imageStore(out_history_length, px, vec4(len));
}

#endif
