// Reading the G-buffer back: world position from view depth, camera rays through pixels.
#ifndef GBUFFER_GLSL
#define GBUFFER_GLSL

#include "scene.glsl"

#define NO_INSTANCE 0xffffffffu

// Unit world-space direction from the camera through a pixel position (centres at +0.5).
vec3 camera_ray_dir(vec2 pixel) {
    vec2 ndc = pixel / vec2(frame.size) * 2.0 - 1.0;
    vec4 p = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    return normalize(p.xyz / p.w - frame.camera_pos);
}

vec3 camera_forward() { return -frame.inv_view[2].xyz; }

// World position of the surface at pixel `px` whose view depth is `depth`. The G-buffer was
// rasterised with the frame's sub-pixel jitter, so its sample sits at centre - jitter.
vec3 world_position(ivec2 px, float depth) {
    vec3 dir = camera_ray_dir(vec2(px) + 0.5 - frame.jitter);
    // depth is measured along the view axis, the ray along dir: divide by their cosine.
    return frame.camera_pos + dir * (depth / dot(dir, camera_forward()));
}

// Origin for a secondary ray leaving a G-buffer surface: pushed off along the geometric
// normal by a distance that grows with the depth (the reconstruction error of the position
// grows with it too), so rays neither re-hit their own surface (acne) nor start visibly
// detached from it (peter-panning).
vec3 offset_ray_origin(vec3 p, vec3 normal_geo, float depth) {
    return p + normal_geo * (2e-4 * depth + 1e-5);
}

#endif
