// The light's view for a shadow map: depth only (paper 3.1; thesis 2.2.3).
layout(location = 0) in vec3 a_position;
layout(location = 2) in vec2 a_uv;

uniform mat4 u_model;
uniform mat4 u_view_proj; // world -> light clip

out vec2 v_uv;

void main() {
    v_uv = a_uv;
    gl_Position = u_view_proj * (u_model * vec4(a_position, 1.0));
}
