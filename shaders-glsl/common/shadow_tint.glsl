// The colour of the light that reaches a surface through tinted see-through surfaces
// (shadows.tint), kept beside the grey visibility that the shadows chain filters: one uint per
// light, the transmitted colour scaled to its largest channel and packed as RGBA8 (alpha 1).
// 0 means no tint: nothing coloured on the way, or no ray got through (then the visibility is
// 0 and the colour never shows). Shared by shadows.comp (writes) and composite.comp (reads).
#ifndef SHADOW_TINT_GLSL
#define SHADOW_TINT_GLSL

uint shadow_tint_encode(vec3 through) {
    float m = max(through.r, max(through.g, through.b));
    // Grey within 8-bit precision: stored as no tint, so untinted scenes write only zeros.
    if (m <= 0.0 || min(through.r, min(through.g, through.b)) >= m * (1.0 - 1.0 / 512.0)) return 0u;
    return packUnorm4x8(vec4(through / m, 1.0));
}

// The factor on the grey visibility (the mean of the channels) that gives back the colour.
vec3 shadow_tint_decode(uint packed) {
    if (packed == 0u) return vec3(1.0);
    vec3 t = unpackUnorm4x8(packed).rgb;
    return t * (3.0 / max(t.r + t.g + t.b, 1e-6));
}

#endif
