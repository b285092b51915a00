// Where a reflection was last frame. A mirror shows the point it reflects at hit distance d
// (reflections.hit_distance) as if it stood at the virtual point p + d view_dir behind the
// surface, and a moving camera sees it move with that point's parallax, not the surface's.
// Shared by the specular chain's temporal stage (common/svgf_temporal.glsl) and taa.comp.
// The includer includes scene.glsl and gbuffer.glsl first.
#ifndef REFLECTION_MOTION_GLSL
#define REFLECTION_MOTION_GLSL

// Below roughness x the reflection follows the virtual point only, above y the surface only:
// a wide lobe averages many directions, whose virtual points are spread over the hit
// distances, and what stays put is the surface.
const vec2 REFLECTION_MOTION_ROUGHNESS = vec2(0.15, 0.4);

float reflection_motion_weight(float roughness) {
    return 1.0 - smoothstep(REFLECTION_MOTION_ROUGHNESS.x, REFLECTION_MOTION_ROUGHNESS.y, roughness);
}

vec2 ndc_of(mat4 view_proj, vec3 p) {
    vec4 c = view_proj * vec4(p, 1.0);
    return c.xy / c.w;
}

// Where the reflection seen at px (view depth z, hit distance `hit`) was last frame, in
// continuous pixel coordinates, in the motion vectors' convention (gbuffer.frag).
vec2 reflection_prev_pos(ivec2 px, float z, float hit) {
    vec3 p = world_position(px, z);
    vec3 v = p + normalize(p - frame.camera_pos) * hit;
    vec2 motion = (ndc_of(frame.view_proj, v) - ndc_of(frame.prev_view_proj, v)) * 0.5 * vec2(frame.size);
    return vec2(px) + 0.5 - motion;
}

#endif
