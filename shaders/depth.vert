// The light's view for a shadow map: depth only (paper 3.1; thesis 2.2.3).
layout(location = 0) in vec3 a_position;
layout(location = 2) in vec2 a_uv;

uniform mat4 u_model;
uniform mat4 u_view_proj; // (world - u_origin) -> light clip
// The light's position, or 0 for world positions: subtracted before the matrix, which then
// holds no large translation to cancel (shadow_map.caster_space).
uniform vec3 u_origin;

out vec2 v_uv;
#ifdef ID_TABLE
out vec3 v_world;
#endif

#ifdef WARP_DEPTH
// Trapezoidal maps: the depth written is this matrix's (the light's own view), not the warp's.
uniform mat4 u_depth_view_proj;
out vec2 v_depth;
#endif

void main() {
    v_uv = a_uv;
    vec4 world = u_model * vec4(a_position, 1.0);
    vec4 relative = vec4(world.xyz - u_origin, 1.0);
#ifdef ID_TABLE
    v_world = world.xyz;
#endif
#ifdef WARP_DEPTH
    v_depth = (u_depth_view_proj * relative).zw;
#endif
    gl_Position = u_view_proj * relative;
}
