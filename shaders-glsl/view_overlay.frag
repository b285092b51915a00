#version 460
// view_overlay: egui's texture (font atlas or image) times the vertex colour, both
// premultiplied and gamma-encoded, blended "one, one minus source alpha" as egui expects.

layout(set = 0, binding = 0) uniform sampler2D tex;

layout(location = 0) in vec2 v_uv;
layout(location = 1) in vec4 v_color;
layout(location = 0) out vec4 out_color;

void main() {
    out_color = v_color * texture(tex, v_uv);
}
