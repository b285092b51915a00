// svgf_temporal (svgf_temporal.comp: one signal, svgf_temporal_<signal>;
// svgf_temporal_diffuse_specular.comp: the frame's two, SVGF_PAIR;
// svgf_temporal_let_through.comp: what surfaces let through, SVGF_LET_THROUGH): temporal accumulation of
// demodulated signals. The previous frame's filtered colour (the first a-trous iteration,
// copied by `history`), moments and history length are reprojected through the motion
// vectors with bilinear taps that each pass the validity test (on screen, same instance,
// depth, geometric normal); the new frame is blended in with max(alpha, 1/history). The input
// is cleaned first: NaN/Inf samples are dropped (and counted) and luminance outliers clamped to
// mean + k sigma of their 7x7 neighbourhood (3x3 where there is any history), so neither
// poisons the history; what the clamp takes out is handed to the neighbours on the pixel's
// surface (out_*clamped, which the first a-trous iteration adds), so no light is lost.
//
// A pixel with no history at all takes the edge-aware mean of that 7x7 window (on its own
// instance) in place of its sample: the a-trous iterations then start from less noise after a
// disocclusion, a camera cut or a change of the lights, which lets their 3x3 kernel stay
// narrow (common/svgf_atrous.glsl).
//
// The colour's alpha holds its luminance variance (as the deviation, svgf_pack), what the
// a-trous iterations scale their luminance weight by: from the temporal moments, or, while the
// history is shorter than SVGF_MOMENTS_FRAMES, estimated over the same neighbourhood of this
// frame's samples with the edge-stopping weights (and boosted by 4 / history, as Falcor).
// Schied et al. estimate it from the neighbours' accumulated moments in a pass of its own; one
// frame's samples are what a young history holds (all of it at a disocclusion), and the window
// is loaded anyway. A signal with some history, but less than that, takes it over the 3x3
// window: the 7x7 walk of those pixels (most of them where radiance cache cells restarted one
// to three frames before) cost `svgf_temporal` about 20 of its 330 ms at 1920x1080 on
// lavapipe, at the same error in `bench sweep` and `bench stability` (README, "What a young
// history costs").
//
// The pair accumulates diffuse and specular in one dispatch, because the pass is bound by its
// loads: the G-buffer texels, the window's guide texels and, where the two histories are
// fetched from the same place, the reprojection's validity tests are loaded once for both.
//
// With SVGF_SHARP_SPECULAR set (the pair's specular signal made of reflection rays) the
// history of a narrow lobe is fetched where the reflected object was, not where the surface
// was: the reflection of a point at hit distance d appears at the virtual point p + d view_dir
// behind a mirror, and a moving camera sees it move with that point's parallax, not the
// surface's. The lobe's width decides between the two (roughness), and caps the history: a
// glossy reflection changes with the view even where the reprojection is right. (The same
// width narrows the a-trous filter's footprint: svgf_footprint.)
//
// SVGF_LET_THROUGH: what glass and blended surfaces let through (reflections.let_through), a
// signal of its own, whose history is fetched where what shows through was, on the view ray's
// line at the distance the signal's alpha carries; its sharpness is that of the glass's lobe
// (a blended surface lets it through unaltered, as a mirror reflects).
#ifndef SVGF_TEMPORAL_GLSL
#define SVGF_TEMPORAL_GLSL

#extension GL_EXT_control_flow_attributes : require
#include "common/scene.glsl"
#include "common/gbuffer.glsl"
#include "common/reflection_motion.glsl"
#include "common/light_lost.glsl"

layout(local_size_x = 8, local_size_y = 8) in;  // the tile below assumes 8x8

layout(set = 1, binding = 0, rg32f) uniform readonly image2D g_depth;  // view depth, fwidth of view depth
// The geometric (face) normal: reprojection asks whether the previous sample lies on the same
// surface, and a crease that smooth vertex normals round off is still a different surface.
layout(set = 1, binding = 1, rgba16f) uniform readonly image2D g_normal_geo;
layout(set = 1, binding = 2, rg32ui) uniform readonly uimage2D g_ids;
layout(set = 1, binding = 3, rg32f) uniform readonly image2D g_motion;
layout(set = 1, binding = 4, rg32f) uniform readonly image2D prev_depth;
layout(set = 1, binding = 5, rgba16f) uniform readonly image2D prev_normal_geo;
layout(set = 1, binding = 6, rg32ui) uniform readonly uimage2D prev_ids;
// The shading normal and view depth (w 0: no surface; svgf_guide_surface), for the spatial
// variance.
layout(set = 1, binding = 7, rgba32f) uniform readonly image2D g_normal;
// Per signal: this frame's samples (rgba32f), the previous frame's filtered colour (the first
// a-trous iteration's), moments and history length; then the outputs.
#ifdef SVGF_PAIR
#define SIGNALS 2
layout(set = 1, binding = 8, rgba32f) uniform readonly image2D in_diffuse;
layout(set = 1, binding = 9, rgba32f) uniform readonly image2D in_specular;
layout(set = 1, binding = 10, rgba16f) uniform readonly image2D prev_diffuse;
layout(set = 1, binding = 11, rgba16f) uniform readonly image2D prev_specular;
layout(set = 1, binding = 12, rg32f) uniform readonly image2D prev_diffuse_moments;
layout(set = 1, binding = 13, rg32f) uniform readonly image2D prev_specular_moments;
layout(set = 1, binding = 14, rgba16f) uniform readonly image2D prev_centre;  // svgf_centre: lengths in z, w
// reflections.hit_distance: mean distance to what the reflection rays hit (0: none traced; a
// zero image without SVGF_SHARP_SPECULAR).
layout(set = 1, binding = 15, r32f) uniform readonly image2D in_hit_distance;
layout(set = 1, binding = 16, rgba8) uniform readonly image2D g_metal_rough;
// radiance_cache.changed: 1 where a radiance cache cell around the surface restarted this
// frame on a change of its light that the frame did not announce (an occluder); a zero image
// without a cache.
layout(set = 1, binding = 17, r32f) uniform readonly image2D in_cache_changed;
// gi.light_lost: what a pixel's resampled light brought to each signal last frame where it is
// now in shadow, x diffuse, y specular (an occluder the frame was not told of); a zero image
// without resampled lights.
layout(set = 1, binding = 18, rg32f) uniform readonly image2D in_light_lost;
layout(set = 1, binding = 19, rgba16f) uniform writeonly image2D out_diffuse;
layout(set = 1, binding = 20, rgba16f) uniform writeonly image2D out_specular;
layout(set = 1, binding = 21, rg32f) uniform writeonly image2D out_diffuse_moments;
layout(set = 1, binding = 22, rg32f) uniform writeonly image2D out_specular_moments;
layout(set = 1, binding = 23, rgba16f) uniform writeonly image2D out_diffuse_clamped;
layout(set = 1, binding = 24, rgba16f) uniform writeonly image2D out_specular_clamped;
#define SVGF_OUT_REJECTED 25

vec3 load_input(int s, ivec2 q) { return (s == 0 ? imageLoad(in_diffuse, q) : imageLoad(in_specular, q)).rgb; }
vec3 load_prev_color(int s, ivec2 q) { return (s == 0 ? imageLoad(prev_diffuse, q) : imageLoad(prev_specular, q)).rgb; }
vec2 load_prev_moments(int s, ivec2 q) {
    return (s == 0 ? imageLoad(prev_diffuse_moments, q) : imageLoad(prev_specular_moments, q)).xy;
}
void store(int s, ivec2 q, vec4 color, vec2 moments) {
    if (s == 0) {
        imageStore(out_diffuse, q, color);
        imageStore(out_diffuse_moments, q, vec4(moments, 0.0, 0.0));
    } else {
        imageStore(out_specular, q, color);
        imageStore(out_specular_moments, q, vec4(moments, 0.0, 0.0));
    }
}
void store_clamped(int s, ivec2 q, vec3 share) {
    if (s == 0) imageStore(out_diffuse_clamped, q, vec4(share, 0.0));
    else imageStore(out_specular_clamped, q, vec4(share, 0.0));
}
#else
#define SIGNALS 1
// With SVGF_LET_THROUGH, reflections.let_through: alpha how far along the view ray it was seen.
layout(set = 1, binding = 8, rgba32f) uniform readonly image2D in_signal;
layout(set = 1, binding = 9, rgba16f) uniform readonly image2D prev_color;
layout(set = 1, binding = 10, rg32f) uniform readonly image2D prev_moments;
layout(set = 1, binding = 11, rgba16f) uniform readonly image2D prev_centre;  // svgf_centre: the length in z
#ifdef SVGF_LET_THROUGH
layout(set = 1, binding = 12, rgba8) uniform readonly image2D g_metal_rough;
#define SVGF_OUT_FIRST 13
#else
#define SVGF_OUT_FIRST 12
#endif
layout(set = 1, binding = SVGF_OUT_FIRST, rgba16f) uniform writeonly image2D out_color;
layout(set = 1, binding = SVGF_OUT_FIRST + 1, rg32f) uniform writeonly image2D out_moments;
layout(set = 1, binding = SVGF_OUT_FIRST + 2, rgba16f) uniform writeonly image2D out_clamped;
#define SVGF_OUT_REJECTED (SVGF_OUT_FIRST + 3)

vec3 load_input(int s, ivec2 q) { return imageLoad(in_signal, q).rgb; }
vec3 load_prev_color(int s, ivec2 q) { return imageLoad(prev_color, q).rgb; }
vec2 load_prev_moments(int s, ivec2 q) { return imageLoad(prev_moments, q).xy; }
void store(int s, ivec2 q, vec4 color, vec2 moments) {
    imageStore(out_color, q, color);
    imageStore(out_moments, q, vec4(moments, 0.0, 0.0));
}
void store_clamped(int s, ivec2 q, vec3 share) { imageStore(out_clamped, q, vec4(share, 0.0)); }
#endif
// x: input samples that were NaN or Inf, counted since the first frame (only pixel 0,0).
layout(set = 1, binding = SVGF_OUT_REJECTED, r32ui) uniform uimage2D out_rejected;
// What each a-trous iteration reads of the pixel it filters besides its guide texel (svgf_centre
// in common/svgf.glsl): the view depth's fwidth, the specular footprint, the history lengths,
// which the next frame reprojects (prev_centre).
layout(set = 1, binding = SVGF_OUT_REJECTED + 1, rgba16f) uniform writeonly image2D out_centre;

#include "common/svgf.glsl"

// Signal s's input sample with non-finite values removed (false when it was not finite).
bool load_finite(int s, ivec2 q, out vec3 c) {
    c = load_input(s, q);
    if (finite3(c)) return true;
    c = vec3(0.0);
    return false;
}

// The workgroup's windows, loaded once into shared memory: the 8x8 pixels' 7x7 windows cover a
// 14x14 tile, whose guide texels, finite input samples and their luminances the workgroup loads
// together (about 3 image loads a pixel for both signals) before any pixel walks its window
// from the tile, where each tap had loaded its own texels (72 loads a pixel for a 5x5
// window). On lavapipe at 640x360 the pass went from 62-69 to 56-60 ms in one pair of runs,
// 48 to 45-46 in a later one; the tile alone, with the luminance computed per tap, saved
// nothing: the walk is bound by its arithmetic as much as by its loads. Loading only the
// 10x10 part that 3x3 windows cover where no pixel of the workgroup has a young history
// (decided after the reprojection, between two more barriers) made the pass 2-5 ms slower.
// Texels past the image's edge hold the edge's (the clamp's walk wants that; the young
// history's walk skips them).
#define WINDOW_RADIUS 3
#define TILE_SIDE (8 + 2 * WINDOW_RADIUS)
shared vec4 tile_guide[TILE_SIDE * TILE_SIDE];
shared vec3 tile_sample[SIGNALS][TILE_SIDE * TILE_SIDE];
shared float tile_luminance[SIGNALS][TILE_SIDE * TILE_SIDE];

void load_tile() {
    ivec2 origin = ivec2(gl_WorkGroupID.xy) * 8 - WINDOW_RADIUS;
    for (uint i = gl_LocalInvocationIndex; i < TILE_SIDE * TILE_SIDE; i += 64u) {
        ivec2 q = clamp(origin + ivec2(i % TILE_SIDE, i / TILE_SIDE), ivec2(0), ivec2(frame.size) - 1);
        tile_guide[i] = imageLoad(g_normal, q);
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
            vec3 v;
            load_finite(s, q, v);
            tile_sample[s][i] = v;
            tile_luminance[s][i] = luminance(v);
        }
    }
    barrier();
}

// The tile's index of the pixel at offset d from this invocation's.
int tile_index(ivec2 d) {
    ivec2 t = ivec2(gl_LocalInvocationID.xy) + WINDOW_RADIUS + d;
    return t.y * TILE_SIDE + t.x;
}

// What the neighbourhood of this frame's samples says about pixel `px`, per signal.
struct Neighbourhood {
    float clamp_limit;  // luminance above which the sample is an outlier (infinite: clamp off)
    float variance;     // the spatial variance estimate (only for a young history)
    vec3 blurred;       // the edge-aware mean of the clamped samples (only without history)
};

// One pass over the neighbourhood (surface pixels only; 7x7 for a signal without history, 3x3
// for the others), for each signal, for the outlier clamp's bound, mean + k sigma of the
// luminance, which takes a firefly out of the history before anything accumulates it; and,
// for a young history (`young`), the luminance variance
// around `l` (this pixel's clamped luminance, which the luminance weight needs, so the clamp's
// bound is found first and the window read twice only then) and, with `blur` (no history at
// all), the edge-aware mean of the clamped samples on this pixel's instance.
//
// The clamp keeps the firefly's energy (the give-back, below). With an established history
// its bound leaves the window's brightest sample out, so that a bright sample's neighbours do
// not judge it by a window that holds it. Its window is then 3x3: a smaller window clamps
// more, which cost light while the clamp dropped what it took, and now only saves time (7x7
// until 2026-12-04, 5x5 until 2026-12-05; the 3x3 window took the pass from about 51 to 46 ms
// at 640x360 on lavapipe at the same error in `bench sweep`: README, "The outlier window 3x3").
// An established history's bound is this many times wider: it averages what gets past, and
// one window of one frame's samples is a poor judge of rare bright paths. Measured at 256x256
// on the diffuse box, the frame after 64 frames held 0.956 of the reference's light with the
// bound at 4 sigma, 0.974 at 8 and 0.981 at 12 (gi at full rate: 0.857 and 0.891 at 4 and 8);
// at 16 it held 0.979, the give-back then having less to spread.
#define SVGF_ESTABLISHED_SIGMA_SCALE 3.0

// Adds tap d of the outlier windows to the sums of each signal whose window holds it (`wide`:
// the 7x7 of a signal without history; else the 3x3), if it is on a surface.
void clamp_tap(ivec2 d, bool wide[SIGNALS], inout float sum[SIGNALS], inout float sum2[SIGNALS],
               inout float n[SIGNALS], inout float brightest[SIGNALS]) {
    int t = tile_index(d);
    if (!svgf_guide_surface(tile_guide[t])) return;
    bool inner = max(abs(d.x), abs(d.y)) <= 1;
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        if (wide[s] || inner) {
            float l = tile_luminance[s][t];
            sum[s] += l;
            sum2[s] += l * l;
            n[s] += 1.0;
            brightest[s] = max(brightest[s], l);
        }
    }
}

// The window is walked once for all signals: each tap's guide texel is loaded once. `young[s]`:
// signal s's history is younger than SVGF_MOMENTS_FRAMES (spatial variance); `blur[s]`: it has
// none at all (the 7x7 window, and its mean too).
void neighbourhood(ivec2 px, vec4 g, uint id, float fwidth_z, vec3 c[SIGNALS], bool young[SIGNALS],
                   bool blur[SIGNALS], out Neighbourhood nb[SIGNALS]) {
    // clamp_sigma = infinity switches the clamp off (the impulse-response test does).
    bool clamped = !isinf(svgf.clamp_sigma);
    bool any_young = false, any_blur = false, any_wide = false;
    bool wide[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        nb[s] = Neighbourhood(1.0 / 0.0, 0.0, vec3(0.0));
        wide[s] = young[s] && blur[s];
        any_young = any_young || young[s];
        any_blur = any_blur || blur[s];
        any_wide = any_wide || wide[s];
    }
    float sum[SIGNALS], sum2[SIGNALS], n[SIGNALS], brightest[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) sum[s] = sum2[s] = n[s] = brightest[s] = 0.0;
    // A signal without history takes the 7x7 window (its mean stands for its sample, and a
    // disocclusion's first variance needs the samples), the others the 3x3, whose taps are
    // unrolled (constant tile offsets).
    if (clamped && any_wide) {
        for (int dy = -3; dy <= 3; ++dy) {
            for (int dx = -3; dx <= 3; ++dx) {
                // The centre is left out, so a lone firefly cannot widen its own bound.
                if (dx != 0 || dy != 0) clamp_tap(ivec2(dx, dy), wide, sum, sum2, n, brightest);
            }
        }
    } else if (clamped) {
        [[unroll]] for (int i = 0; i < 8; ++i) {
            int j = i < 4 ? i : i + 1;  // the centre, 4, is left out
            clamp_tap(ivec2(j % 3, j / 3) - 1, wide, sum, sum2, n, brightest);
        }
    }
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        if (clamped) {
            bool established = !young[s];
            float trim = established ? brightest[s] : 0.0;
            float m = max(n[s] - (established ? 1.0 : 0.0), 1.0);
            float mean = (sum[s] - trim) / m;
            float k = established ? SVGF_ESTABLISHED_SIGMA_SCALE * svgf.clamp_sigma : svgf.clamp_sigma;
            nb[s].clamp_limit = mean + k * sqrt(max(0.0, (sum2[s] - trim * trim) / m - mean * mean));
        }
    }
    if (!any_young) return;
    float l[SIGNALS], wsum[SIGNALS], blur_wsum[SIGNALS];
    vec2 m[SIGNALS];
    vec3 blurred[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        l[s] = min(luminance(c[s]), nb[s].clamp_limit);
        m[s] = vec2(0.0);
        blurred[s] = vec3(0.0);
        wsum[s] = blur_wsum[s] = 0.0;
    }
    int r = any_wide ? 3 : 1;
    for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
            int t = tile_index(ivec2(dx, dy));
            vec4 gq = tile_guide[t];
            if (!svgf_guide_surface(gq)) continue;
            float inv_z_scale = 1.0 / (svgf.sigma_z * fwidth_z * length(vec2(dx, dy)) + 1e-4);
            float e_geometry = svgf_depth_exponent(g.w, gq.w, inv_z_scale) + svgf_normal_exponent(g.xyz, gq.xyz);
            bool same_instance = any_blur && imageLoad(g_ids, q).x == id;
            bool inner = max(abs(dx), abs(dy)) <= 1;
            [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
                if (young[s] && (wide[s] || inner)) {
                    float lq_raw = tile_luminance[s][t];
                    float lq = min(lq_raw, nb[s].clamp_limit);
                    // The luminance weight uses a fixed scale: there is no variance to scale it yet.
                    float w = exp(-e_geometry - abs(l[s] - lq) / svgf.sigma_l);
                    m[s] += w * vec2(lq, lq * lq);
                    wsum[s] += w;
                    if (blur[s] && same_instance) {
                        vec3 v = tile_sample[s][t];
                        blurred[s] += w * (lq_raw > lq ? v * (lq / lq_raw) : v);
                        blur_wsum[s] += w;
                    }
                }
            }
        }
    }
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        if (young[s]) {
            vec2 mean = m[s] / max(wsum[s], 1e-6);
            nb[s].blurred = blurred[s] / max(blur_wsum[s], 1e-6);
            nb[s].variance = max(0.0, mean.y - mean.x * mean.x);
        }
    }
}

// The give-back: what the clamp takes out of a sample is handed in even shares to the
// neighbours on its surface (svgf_same_surface) among the 8 around it, which the first a-trous
// iteration adds to its output (the colour the next frame's history is made of). Each share
// is in the history's units, scaled by the weight `a` the sample would have had in it, so the
// light the history lost is the light its neighbours gain, exactly; a pixel without a
// neighbour on its surface (a surface a pixel wide) keeps none of it. Until
// 2026-12-04 each pixel took back a share of the clamped light of the brightest neighbour on
// its surface, estimated against its own bound: where many pixels pass their bounds (gi at
// full rate: 6% of the pixels holding a quarter of the light) that returned about half.
// Spread over the 8 neighbours, not a 7x7 window, because the a-trous
// iteration's step-1 taps are those 8, already loaded. Only a pixel that gives shares writes
// them, and says so by the sign of its colour's alpha (svgf_flag), which the a-trous taps load
// anyway: stored for every pixel and loaded by every tap, the shares made the temporal pass
// 3-6 ms and the first a-trous iteration 2.5 ms slower at 640x360 on lavapipe. main() computes
// the clamp and the excess without branches and gives in one branch after both signals: with
// a branch per signal around the clamp the pass was still about 3 ms slower than without the
// give-back.
// Until 2026-12-05 only an established history gave: a young one (a disocclusion, a restart,
// and always a mirror's, capped at GLOSSY_HISTORY_CAP frames) dropped what its clamp took.
// Giving there too took the Mitsuba glossy box from 0.975 to 0.984 of Mitsuba's light,
// DamagedHelmet from 0.87 to 0.92 of the reference's and a resampled light's first frame
// after it was switched off from 0.061 to 0.042 of the step dark (README, "Stability").
float same_surface_neighbours(ivec2 px) {
    vec4 g = tile_guide[tile_index(ivec2(0))];
    float n = 0.0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if ((dx == 0 && dy == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size)))) continue;
            vec4 gq = tile_guide[tile_index(ivec2(dx, dy))];
            if (svgf_guide_surface(gq) && svgf_same_surface(g, gq)) n += 1.0;
        }
    }
    return n;
}

// A mirror's history is capped at this many frames, rising to svgf.history_cap at roughness
// GLOSSY_CAP_ROUGHNESS. A narrow lobe's sample is nearly free of noise, and its reprojection is
// the least certain (a virtual point from one hit distance), so a long history buys little and
// smears the reflection once the camera moves: the stability suite's mirror pan measured 0.199
// with a cap of 8, 0.145 with 2 and 0.132 with 1, its still frame 0.065, 0.063 and 0.063.
const float GLOSSY_HISTORY_CAP = 2.0;
// SVGF_LET_THROUGH: image motion, pixels a frame, from which what shows through at no
// distance keeps no history (taa.comp's UNANCHORED_MOTION).
const float UNANCHORED_MOTION = 0.5;
const float GLOSSY_CAP_ROUGHNESS = 0.5;

// The bilinear weights of the previous frame's four texels around `prev_pos` (continuous pixel
// coordinates), zero for each that fails the validity test (svgf_consistent) against this
// pixel's depth z, geometric normal ng and instance id. A texel without bilinear weight is not
// tested: where the camera holds still, the reprojection lands on a texel's centre, and that
// texel's three loads are all the test needs, where it took twelve.
vec4 reprojection_weights(vec2 prev_pos, float z, float fw_tolerance, vec3 ng, uint id) {
    vec2 base = floor(prev_pos - 0.5);
    vec2 f = prev_pos - 0.5 - base;
    vec4 w = vec4(0.0);
    [[unroll]] for (int i = 0; i < 4; ++i) {
        ivec2 q = ivec2(base) + ivec2(i & 1, i >> 1);
        float bilinear = ((i & 1) == 1 ? f.x : 1.0 - f.x) * ((i >> 1) == 1 ? f.y : 1.0 - f.y);
        if (bilinear > 0.0 && all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(frame.size))) &&
            svgf_consistent(z, imageLoad(prev_depth, q).r, fw_tolerance, ng, imageLoad(prev_normal_geo, q).xyz, id,
                            imageLoad(prev_ids, q).x)) {
            w[i] = bilinear;
        }
    }
    return w;
}

void main() {
    load_tile();  // before any invocation returns: the whole workgroup reaches its barrier
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size)))) return;
    uint id = imageLoad(g_ids, px).x;
    if (id == NO_INSTANCE) {
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) store(s, px, vec4(0.0), vec2(0.0));
        imageStore(out_centre, px, vec4(0.0));
        return;
    }
    vec3 c[SIGNALS];
    bool finite[SIGNALS];
    uint rejected = 0u;
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        finite[s] = load_finite(s, px, c[s]);
        if (!finite[s]) rejected += 1u;
    }
    if (rejected > 0u) imageAtomicAdd(out_rejected, ivec2(0), rejected);

    vec2 zf = imageLoad(g_depth, px).rg;
    float z = zf.x;
    vec3 ng = imageLoad(g_normal_geo, px).xyz;
    float fw = zf.y;
    // Where this pixel's surface was last frame, in continuous pixel coordinates.
    vec2 surface_pos = vec2(px) + 0.5 - imageLoad(g_motion, px).xy;
    vec2 prev_pos[SIGNALS];
    float cap[SIGNALS], footprint[SIGNALS], fw_tolerance[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        prev_pos[s] = surface_pos;
        cap[s] = svgf.history_cap;
        footprint[s] = 1.0;  // how much of the young sample's spatial mean stands for it
        fw_tolerance[s] = fw;
    }
#ifdef SVGF_PAIR
    if ((svgf.flags & SVGF_SHARP_SPECULAR) != 0u) {
        float hit = imageLoad(in_hit_distance, px).r;
        float roughness = imageLoad(g_metal_rough, px).y;
        float virtual_weight = reflection_motion_weight(roughness);
        if (hit > 0.0 && virtual_weight > 0.0) {
            prev_pos[1] = mix(surface_pos, reflection_prev_pos(px, z, hit), virtual_weight);
            // The depth test's tolerance: fetched away from the surface's own motion (the
            // virtual point's), the previous sample is on the same surface a few pixels off,
            // where depth differs by about fwidth per pixel.
            fw_tolerance[1] = fw * (1.0 + distance(prev_pos[1], surface_pos));
        }
        cap[1] = mix(GLOSSY_HISTORY_CAP, svgf.history_cap, smoothstep(0.0, GLOSSY_CAP_ROUGHNESS, roughness));
        footprint[1] = svgf_footprint(roughness);
    }
#endif
#ifdef SVGF_LET_THROUGH
    {
        // Seen through thin glass (which does not bend the view ray), past a blended surface, or
        // out of a slab the way it went in: on the view ray's line `seen_at` beyond the surface,
        // which moves with that point's parallax, as a mirror's virtual point does.
        float seen_at = imageLoad(in_signal, px).a;
        // What shows through at no distance (a lens's turned image, the sky through glass) has
        // no history that a moving image can follow: none from UNANCHORED_MOTION on. (A path
        // that brought nothing, rough glass's sample below the horizon, says nothing.)
        float unanchored = 0.0;
        if (seen_at > 0.0) {
            prev_pos[0] = reflection_prev_pos(px, z, seen_at);
            fw_tolerance[0] = fw * (1.0 + distance(prev_pos[0], surface_pos));
        } else if (luminance(c[0]) > 0.0) {
            unanchored = clamp(length(vec2(px) + 0.5 - surface_pos) / UNANCHORED_MOTION, 0.0, 1.0);
        }
        // As sharp as the glass's lobe leaves it; a blended surface, however rough, lets it
        // through unaltered. An opaque surface lets nothing through: nothing to filter there,
        // and the a-trous iterations after the first skip it.
        bool blended = (materials[imageLoad(g_ids, px).y].flags & MATERIAL_BLEND) != 0u;
        vec4 mr = imageLoad(g_metal_rough, px);
        float roughness = blended ? 0.0 : mr.y;
        cap[0] = mix(GLOSSY_HISTORY_CAP, svgf.history_cap, smoothstep(0.0, GLOSSY_CAP_ROUGHNESS, roughness));
        cap[0] = mix(cap[0], 1.0, unanchored);
        footprint[0] = blended || mr.w * (1.0 - mr.x) > 0.0 ? svgf_footprint(roughness) : 0.0;
    }
#endif
    // A camera cut, or lights that changed since last frame: the history holds light that is
    // gone (the lag a lit history would add is the whole accumulation window).
    bool reset = (frame.flags & (FRAME_RESET_HISTORY | FRAME_LIGHTS_CHANGED)) != 0u;
#ifdef SVGF_PAIR
    // A radiance cache cell around here let go of light that is gone (radiance_cache.comp):
    // the diffuse history holds it too, and starts anew as at a disocclusion.
    bool diffuse_changed = imageLoad(in_cache_changed, px).r > 0.0;
    // The resampled light this pixel saw last frame is in shadow now: where it brought a
    // share of what a signal's history holds, that history starts anew too.
    vec2 lost = imageLoad(in_light_lost, px).xy;
#else
    bool diffuse_changed = false;
    vec2 lost = vec2(0.0);
#endif
    vec4 tap_w[SIGNALS];
    bool young[SIGNALS], blur[SIGNALS];
    float len[SIGNALS];
    vec3 hist_c[SIGNALS];
    vec2 hist_m[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        // A history fetched from where the other's was shares its validity tests (and the
        // other's fallback below).
        if (reset) {
            tap_w[s] = vec4(0.0);
        } else if (s > 0 && prev_pos[s] == surface_pos && fw_tolerance[s] == fw_tolerance[0]) {
            tap_w[s] = tap_w[0];
            prev_pos[s] = prev_pos[0];
        } else {
            tap_w[s] = reprojection_weights(prev_pos[s], z, fw_tolerance[s], ng, id);
            // No tap holds this surface: look where its sample was among last frame's, whose
            // texels sat at centre - prev_jitter (the motion vectors leave TAA's jitter out).
            // Only then: a still camera's reprojection lands on texel centres, one tap with all
            // the weight, and a history resampled off-centre every frame would be blurred a
            // little more every frame. At an edge the jitter shows one surface in one frame and
            // the other in the next, and without this each edge pixel restarted its history,
            // and walked the 7x7 window (above), every other frame or so.
            if (dot(tap_w[s], vec4(1.0)) <= 1e-3 && frame.prev_jitter != frame.jitter) {
                prev_pos[s] += frame.prev_jitter - frame.jitter;
                tap_w[s] = reprojection_weights(prev_pos[s], z, fw_tolerance[s], ng, id);
            }
        }
        vec2 base = floor(prev_pos[s] - 0.5);
        hist_c[s] = vec3(0.0);
        hist_m[s] = vec2(0.0);
        float hist_len = 0.0;
        [[unroll]] for (int i = 0; i < 4; ++i) {
            if (tap_w[s][i] > 0.0) {
                ivec2 q = ivec2(base) + ivec2(i & 1, i >> 1);
                hist_c[s] += tap_w[s][i] * load_prev_color(s, q);
                hist_m[s] += tap_w[s][i] * load_prev_moments(s, q);
                hist_len += tap_w[s][i] * imageLoad(prev_centre, q)[2 + s];
            }
        }
        float wsum = dot(tap_w[s], vec4(1.0));
        if (wsum > 1e-3) {
            hist_c[s] /= wsum;
            hist_m[s] /= wsum;
        }
        bool gone = (s == 0 && diffuse_changed) || lost_share_of(lost[s], luminance(hist_c[s]));
        blur[s] = wsum <= 1e-3 || gone;  // nothing reprojects, or nothing holds
        len[s] = blur[s] ? 1.0 : min(hist_len / wsum + 1.0, cap[s]);
        // A signal the a-trous iterations leave as it is (a mirror's, footprint 0) is never
        // young: its spatial variance and its window's mean would go unused, and a mirror's
        // history, capped at GLOSSY_HISTORY_CAP frames, would walk its window every frame.
        young[s] = len[s] < SVGF_MOMENTS_FRAMES && footprint[s] > 0.0;
    }
    Neighbourhood nb[SIGNALS];
    neighbourhood(px, tile_guide[tile_index(ivec2(0))], id, fw, c, young, blur, nb);
    vec3 excess[SIGNALS];  // what the clamp takes out, which the pixel gives on
    bool gives = false;
    vec4 texel[SIGNALS];
    vec2 moments[SIGNALS];
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
        vec3 cs = c[s];
        float l = luminance(cs);
        float kept = l > nb[s].clamp_limit && l > 0.0 ? nb[s].clamp_limit / l : 1.0;
        excess[s] = cs * ((1.0 - kept) * max(svgf.alpha, 1.0 / len[s]));
        gives = gives || kept < 1.0;
        cs *= kept;
        // No history at all (a disocclusion, a camera cut, changed lights): the sample is
        // replaced by the edge-aware mean of its 7x7 window on the same instance, which the
        // variance estimate has weighed anyway, so the a-trous iterations start from less
        // noise. A narrow lobe's reflection keeps its sharpness (svgf_footprint, as in the
        // a-trous filter).
        if (blur[s] && finite[s]) cs = mix(cs, nb[s].blurred, footprint[s]);
        l = luminance(cs);
        moments[s] = vec2(l, l * l);
        if (!blur[s]) {
            float a = max(svgf.alpha, 1.0 / len[s]);
            float am = max(svgf.moments_alpha, 1.0 / len[s]);
            // A dropped (non-finite) sample leaves the history as it was.
            cs = finite[s] ? mix(hist_c[s], cs, a) : hist_c[s];
            moments[s] = finite[s] ? mix(hist_m[s], moments[s], am) : hist_m[s];
        }
        float variance = young[s] ? nb[s].variance * 4.0 / len[s] : max(0.0, moments[s].y - moments[s].x * moments[s].x);
        texel[s] = svgf_pack(cs, variance);
    }
    if (gives) {
        float neighbours = same_surface_neighbours(px);
        [[unroll]] for (int s = 0; s < SIGNALS; ++s) {
            vec3 share = svgf_nearest_half(vec4(min(excess[s] / neighbours, vec3(SVGF_HALF_MAX)), 0.0)).rgb;
            if (neighbours > 0.0 && any(greaterThan(share, vec3(0.0)))) {
                store_clamped(s, px, share);
                texel[s] = svgf_flag(texel[s]);
            }
        }
    }
    [[unroll]] for (int s = 0; s < SIGNALS; ++s) store(s, px, texel[s], moments[s]);
    imageStore(out_centre, px, svgf_centre(fw, footprint[SIGNALS - 1], len[0], len[SIGNALS - 1]));
}

#endif
