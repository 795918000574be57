// Debug overlay colour; as lines, only silhouette edges are drawn.
uniform vec4 u_color;
uniform int u_lines;

flat in int v_silhouette;
out vec4 o_color;

void main() {
    if (u_lines == 1 && v_silhouette == 0) discard;
    o_color = u_color;
}
