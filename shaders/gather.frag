// Copies the G-buffer's position and normal at the point's picked pixel (gl/gather.rs).
uniform sampler2D u_position;
uniform sampler2D u_normal;
flat in ivec2 v_pixel;
// The G-buffer target's attachments (gl/target.rs: GBufferTarget).
layout(location = 1) out vec4 o_position;
layout(location = 2) out vec4 o_normal;
void main() {
    o_position = texelFetch(u_position, v_pixel, 0);
    o_normal = texelFetch(u_normal, v_pixel, 0);
}
