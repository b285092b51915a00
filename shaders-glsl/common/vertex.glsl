// One vertex as the scene's vertex buffer holds it (scalar layout; `Vertex` in
// src/scene/mod.rs): read by every pass through common/scene.glsl, written by skinning.comp.
#ifndef VERTEX_GLSL
#define VERTEX_GLSL

struct Vertex {
    vec3 position;
    vec3 normal;
    vec4 tangent;
    vec2 uv0;
    vec2 uv1;
};

#endif
