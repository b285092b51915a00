// Ray origins that leave a surface without re-hitting it.
#ifndef RAY_OFFSET_GLSL
#define RAY_OFFSET_GLSL

// Moves a ray origin off the surface it leaves along the geometric normal on the side the ray
// goes: a few float ulps scaled with the coordinates' magnitude (Waechter and Binder, Ray
// Tracing Gems ch. 6), so it works for scenes of any size without a scene-dependent epsilon.
vec3 offset_ray(vec3 p, vec3 n) {
    const float origin = 1.0 / 32.0;
    const float float_scale = 1.0 / 65536.0;
    const float int_scale = 256.0;
    ivec3 of_i = ivec3(int_scale * n);
    vec3 p_i = intBitsToFloat(floatBitsToInt(p) + ivec3(p.x < 0.0 ? -of_i.x : of_i.x,
                                                           p.y < 0.0 ? -of_i.y : of_i.y,
                                                           p.z < 0.0 ? -of_i.z : of_i.z));
    return vec3(abs(p.x) < origin ? p.x + float_scale * n.x : p_i.x,
                abs(p.y) < origin ? p.y + float_scale * n.y : p_i.y,
                abs(p.z) < origin ? p.z + float_scale * n.z : p_i.z);
}

// Shadow-ray length toward a light sample at `dist`: stops just short of the light so that an
// emitter's own triangle does not occlude it; lights at infinity get a long finite ray.
float shadow_ray_tmax(float dist) { return dist >= 1e29 ? 1e6 : dist * (1.0 - 1e-4); }

#endif
