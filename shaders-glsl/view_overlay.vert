#version 460
// view_overlay: the viewer's egui overlay. egui gives triangles in points (top-left origin)
// with premultiplied, gamma-encoded colours; the window is UNORM, so colours pass unchanged.

layout(location = 0) in vec2 in_pos;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec4 in_color;

layout(push_constant) uniform Params {
    ivec4 rect;
    ivec2 src_size;
    vec2 screen;  // the window's size in points
} p;

layout(location = 0) out vec2 v_uv;
layout(location = 1) out vec4 v_color;

void main() {
    gl_Position = vec4(in_pos / p.screen * 2.0 - 1.0, 0.0, 1.0);
    v_uv = in_uv;
    v_color = in_color;
}
