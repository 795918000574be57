// Volumes write only the stencil buffer (colour and depth writes are off).
out vec4 o_color;
void main() {
    o_color = vec4(0.0);
}
