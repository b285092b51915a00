// Punctual lights (KHR_lights_punctual): incident direction, distance and unshadowed radiance
// arriving at a point. Range culling uses a smooth window that reaches exactly zero at the
// range, so lights switch off without a pop.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL

#include "scene.glsl"

// Which lights have the shadows chain and which are resampled: frame.chain_punctual.

struct LightSample {
    vec3 dir;       // from the surface toward the light
    float dist;     // distance to the light (a large value for directional lights)
    vec3 radiance;  // irradiance scale: intensity * attenuation (no cosine)
};

float range_window(float dist, float range) {
    if (range <= 0.0) return 1.0;
    float r = dist / range;
    float w = clamp(1.0 - r * r * r * r, 0.0, 1.0);
    return w * w;
}

LightSample sample_punctual(LightInfo light, vec3 p) {
    LightSample s;
    if (light.type == LIGHT_DIRECTIONAL) {
        s.dir = -light.direction;
        s.dist = 1e30;
        s.radiance = light.intensity;
        return s;
    }
    vec3 d = light.position - p;
    float dist2 = max(dot(d, d), 1e-8);
    s.dist = sqrt(dist2);
    s.dir = d / s.dist;
    float atten = range_window(s.dist, light.range) / dist2;
    if (light.type == LIGHT_SPOT) {
        float cd = dot(light.direction, -s.dir);
        float t = clamp((cd - light.cos_outer) / max(light.cos_inner - light.cos_outer, 1e-4), 0.0, 1.0);
        atten *= t * t;
    }
    s.radiance = light.intensity * atten;
    return s;
}

#endif
