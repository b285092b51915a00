#version 460
// taa: temporal anti-aliasing of the composited HDR frame. The G-buffer was rasterised with a
// sub-pixel jitter (Halton 2,3); the previous result is reprojected through the motion vectors
// (Catmull-Rom), clamped to the YCoCg bounding box of this frame's 3x3 neighbourhood, and
// blended with the new frame, which weighs more the faster the image moves. Disocclusion is told by motion, not by instance id: where the surface
// seen last frame at the reprojected spot moved differently from the one seen now, something
// uncovered this pixel and the history is dropped. (An id test would also drop the history at
// every silhouette, where the jitter alternates between two surfaces, and nothing would be
// anti-aliased.) On a metal with a narrow lobe, whose colour is all reflection, the history is
// fetched where the reflected object was (common/reflection_motion.glsl), as the specular
// chain's SVGF history is, and on glass or a blended surface where what they let through
// carries most of the colour (reflections.let_through, seen along the view ray), where that
// was; the disocclusion test still asks about the surface. What glass shows at no distance
// along the view ray (a lens's turned image) no reprojection follows: while the image moves,
// its share of the colour is taken from this frame. Where the light changed, the history is dropped: where the
// frame says its lights changed and the neighbourhood's mean moved away from the history, and
// where a radiance cache cell restarted or the pixel's resampled light went into shadow (an
// occluder the frame was not told of); else the clamp box of a noisy neighbourhood lets the old
// light through for TAA's whole window.
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"
#include "common/color.glsl"
#include "common/reflection_motion.glsl"
#include "common/light_lost.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D in_color;
layout(set = 1, binding = 1, rg32f) uniform readonly image2D g_motion;
layout(set = 1, binding = 2, rg32f) uniform readonly image2D prev_motion;
layout(set = 1, binding = 3) uniform sampler2D prev_color;
layout(set = 1, binding = 4, rg32f) uniform readonly image2D g_depth;
layout(set = 1, binding = 5, rgba8) uniform readonly image2D g_metal_rough;
// reflections.hit_distance (a zero image when the frame traces no reflection rays).
layout(set = 1, binding = 6, r32f) uniform readonly image2D in_hit_distance;
// radiance_cache.changed and gi.light_lost (zero images where the frame has no cache or no
// resampled light).
layout(set = 1, binding = 7, rgba16f) uniform readonly image2D g_base_color;
layout(set = 1, binding = 8, r32f) uniform readonly image2D in_cache_changed;
layout(set = 1, binding = 9, rg32f) uniform readonly image2D in_light_lost;
// reflections.let_through: rgb the light, alpha where along the view ray it was seen (1x1
// unless taa.let_through).
layout(set = 1, binding = 10, rgba32f) uniform readonly image2D in_let_through;
layout(set = 1, binding = 11, rgba32f) uniform writeonly image2D out_color;

// Motion vectors differing by more than this many pixels belong to different surfaces.
#define DISOCCLUSION_MOTION 0.5
// The new frame's weight rises linearly with the motion from `taa.blend` (still) to FAST_BLEND
// at `taa.fast_motion` pixels a frame and above (no history: at that speed what the clamp lets
// through is smear, not detail). Tuned on the stability suite's fast pan (2.5 px a frame). The
// renderer shrinks the jitter by as much as the camera's motion raises the blend
// (src/passes/taa.rs `jitter_scale`).
#define FAST_BLEND 1.0
// What no reprojection can follow (a lens's image) is taken from this frame alone from this
// much image motion, pixels a frame, on.
#define UNANCHORED_MOTION 0.5
// On a change of the lights the history is dropped where this frame's 3x3 mean differs from it
// by more than this share of the larger of the two.
#define LIGHTS_CHANGED_SHARE 0.1

layout(push_constant) uniform TaaParams {
    float blend;        // weight of the new frame where the image holds still
    float fast_motion;  // pixels a frame from which the new frame is taken whole
    uint let_through;   // 1: some surface lets light through (in_let_through is full size)
} taa;

vec3 to_ycocg(vec3 c) {
    return vec3(dot(c, vec3(0.25, 0.5, 0.25)), dot(c, vec3(0.5, 0.0, -0.5)), dot(c, vec3(-0.25, 0.5, -0.25)));
}

vec3 from_ycocg(vec3 c) { return vec3(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z); }

// Catmull-Rom filtered history at continuous pixel position `pos` from five bilinear fetches
// (the corner taps of the 4x4 footprint, whose weights are tiny, are left out and the rest
// renormalised). A bilinear fetch blurs by up to half a pixel, and the history is resampled
// every frame it moves: during a pan that blur compounds into a smear; Catmull-Rom keeps it
// sharp.
vec3 history_catmull_rom(vec2 pos) {
    vec2 size = vec2(frame.size);
    vec2 centre = floor(pos - 0.5) + 0.5;
    vec2 f = pos - centre;
    vec2 w0 = f * (-0.5 + f * (1.0 - 0.5 * f));
    vec2 w1 = 1.0 + f * f * (-2.5 + 1.5 * f);
    vec2 w2 = f * (0.5 + f * (2.0 - 1.5 * f));
    vec2 w3 = f * f * (-0.5 + 0.5 * f);
    vec2 w12 = w1 + w2;
    vec2 t0 = (centre - 1.0) / size, t3 = (centre + 2.0) / size, t12 = (centre + w2 / w12) / size;
    vec3 sum = textureLod(prev_color, vec2(t12.x, t0.y), 0.0).rgb * (w12.x * w0.y) +
               textureLod(prev_color, vec2(t0.x, t12.y), 0.0).rgb * (w0.x * w12.y) +
               textureLod(prev_color, t12, 0.0).rgb * (w12.x * w12.y) +
               textureLod(prev_color, vec2(t3.x, t12.y), 0.0).rgb * (w3.x * w12.y) +
               textureLod(prev_color, vec2(t12.x, t3.y), 0.0).rgb * (w12.x * w3.y);
    float wsum = w12.x * w0.y + w0.x * w12.y + w12.x * w12.y + w3.x * w12.y + w12.x * w3.y;
    return max(sum / wsum, vec3(0.0));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    vec3 cur = imageLoad(in_color, px).rgb;
    if ((frame.flags & FRAME_RESET_HISTORY) != 0u) {
        imageStore(out_color, px, vec4(cur, 1.0));
        return;
    }
    // Clamp box of the current neighbourhood, in YCoCg where it hugs colour better.
    vec3 lo = vec3(1e30), hi = vec3(-1e30), sum = vec3(0.0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = clamp(px + ivec2(dx, dy), ivec2(0), ivec2(frame.size) - 1);
            vec3 y = to_ycocg(imageLoad(in_color, q).rgb);
            lo = min(lo, y);
            hi = max(hi, y);
            sum += y;
        }
    }
    float neighbourhood_luma = sum.x / 9.0;
    vec2 motion = imageLoad(g_motion, px).xy;
    vec2 prev_pos = vec2(px) + 0.5 - motion;
    bool valid = all(greaterThanEqual(prev_pos, vec2(0.0))) && all(lessThan(prev_pos, vec2(frame.size)));
    if (valid) {
        vec2 prev_surface_motion = imageLoad(prev_motion, ivec2(floor(prev_pos))).xy;
        valid = length(prev_surface_motion - motion) <= DISOCCLUSION_MOTION;
    }
    vec4 metal_rough = imageLoad(g_metal_rough, px);
    // The share of the colour that the history follows away from the surface, and how far
    // beyond it along the view ray: what the surface lets through where that is most of the
    // colour (whatever the roughness), else what a narrow lobe reflects (the metal's, the
    // glass's).
    float hit = imageLoad(in_hit_distance, px).r;
    float mirror = max(metal_rough.x, metal_rough.w * (1.0 - metal_rough.x)) * reflection_motion_weight(metal_rough.y);
    // The share of the colour that nothing can reproject: what a lens shows, turned, or the
    // sky through glass; where the image moves it is taken from this frame.
    float unanchored = 0.0;
    if (taa.let_through != 0u) {
        vec4 through = imageLoad(in_let_through, px);
        float share = clamp(luminance(through.rgb) / max(luminance(cur), 1e-6), 0.0, 1.0);
        if (through.a == 0.0) {
            unanchored = share;
        } else if (share >= 0.5) {
            hit = through.a;
            mirror = 1.0;
        }
    }
    if (valid && hit > 0.0 && mirror > 0.0) {
        vec2 reflected = mix(prev_pos, reflection_prev_pos(px, imageLoad(g_depth, px).r, hit), mirror);
        if (all(greaterThanEqual(reflected, vec2(0.0))) && all(lessThan(reflected, vec2(frame.size)))) prev_pos = reflected;
    }
    vec3 result = cur;
    vec3 hist_rgb = vec3(0.0);
    if (valid) {
        hist_rgb = history_catmull_rom(prev_pos);
        // What the pixel's resampled light no longer brings, modulated as the colour is.
        vec2 lost = imageLoad(in_light_lost, px).xy;
        vec3 albedo = imageLoad(g_base_color, px).rgb * (1.0 - metal_rough.x);
        float lost_here = lost.x * luminance(albedo) + lost.y;
        valid = imageLoad(in_cache_changed, px).r == 0.0 && !lost_share_of(lost_here, luminance(hist_rgb));
        // The lights changed: the history goes where this frame's neighbourhood (denoised, so
        // its mean is steady) is far from it, and stays, anti-aliased, where the change left
        // the pixel as it was (a light animated every frame would otherwise leave none).
        float hist_luma = to_ycocg(hist_rgb).x;
        if ((frame.flags & FRAME_LIGHTS_CHANGED) != 0u &&
            abs(neighbourhood_luma - hist_luma) > LIGHTS_CHANGED_SHARE * max(hist_luma, neighbourhood_luma)) {
            valid = false;
        }
    }
    if (valid) {
        vec3 hist = to_ycocg(hist_rgb);
        vec2 moved = vec2(px) + 0.5 - prev_pos;
        float blend = mix(taa.blend, FAST_BLEND, clamp(length(moved) / taa.fast_motion, 0.0, 1.0));
        blend = mix(blend, FAST_BLEND, unanchored * clamp(length(moved) / UNANCHORED_MOTION, 0.0, 1.0));
        result = mix(from_ycocg(clamp(hist, lo, hi)), cur, blend);
    }
    imageStore(out_color, px, vec4(result, 1.0));
}
