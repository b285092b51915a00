#version 460
// view_present: the viewer shows one named output full screen. A triangle covering the whole
// window; the fragment shader picks the texel (see view_present.frag).

void main() {
    vec2 uv = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(uv * 2.0 - 1.0, 0.0, 1.0);
}
