// Copies the G-buffer's surface texel at the point's picked pixel (gl/gather.rs).
uniform highp usampler2D u_surface;
flat in ivec2 v_pixel;
// The G-buffer target's surface attachment (gl/target.rs: GBufferTarget).
layout(location = 1) out uvec4 o_surface;
void main() {
    o_surface = texelFetch(u_surface, v_pixel, 0);
}
