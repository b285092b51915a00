#version 460
// view_present: copies the shown image (already display-encoded 8-bit: the tonemap output or
// the capture's preview of any other output) into the window, fitted with its aspect kept.
// Nearest texels by integer arithmetic, so at 1:1 the window holds exactly the image's bytes
// (the viewer's screenshots are compared with the headless capture byte for byte).

layout(set = 0, binding = 0) uniform sampler2D shown;

layout(push_constant) uniform Params {
    ivec4 rect;      // where the image goes in the window: x, y, width, height (pixels)
    ivec2 src_size;  // the image's size
    vec2 screen;     // the window's size in egui points (view_overlay.vert)
} p;

layout(location = 0) out vec4 out_color;

void main() {
    ivec2 local = ivec2(gl_FragCoord.xy) - p.rect.xy;
    if (any(lessThan(local, ivec2(0))) || any(greaterThanEqual(local, p.rect.zw))) {
        out_color = vec4(0.08, 0.08, 0.08, 1.0);
        return;
    }
    ivec2 texel = min(local * p.src_size / p.rect.zw, p.src_size - 1);
    out_color = vec4(texelFetch(shown, texel, 0).rgb, 1.0);
}
