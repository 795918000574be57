// Debug overlay: a light's shadow-volume geometry drawn over the frame (translucent triangles, or
// lines of which only the silhouette edges are kept). Side quads are six vertices (b, a, a', b,
// a', b'), so as GL_LINES the pair (0, 1) of each quad is the silhouette edge a-b.
layout(location = 0) in vec4 a_position;

uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform int u_first; // the part's first vertex, so that quads are counted from it

flat out int v_silhouette;

void main() {
    // Lines take the last vertex's flat value: vertex 1 of a quad ends its silhouette edge.
    v_silhouette = (gl_VertexID - u_first) % 6 == 1 ? 1 : 0;
    gl_Position = u_view_proj * (u_model * a_position);
}
