// Bestimt and Freitag's shadow fill: blended with (DESTCOLOR, ZERO) it scales what is already in
// the frame by u_shade where the stencil test lets it through.
in vec2 v_uv;
uniform float u_shade;
out vec4 o_color;
void main() {
    o_color = vec4(vec3(u_shade), 1.0);
}
