// Alpha-tested casters discard where their surface does (shadow_map.alpha_casters = test);
// otherwise u_alpha_func is 0 and everything is written. Only depth is kept.
in vec2 v_uv;
uniform sampler2D u_texture;
uniform int u_alpha_func;
#ifdef WARP_DEPTH
in vec2 v_depth;
// glPolygonOffset does not reach a depth the shader writes: (factor, units × the depth
// format's resolution), added here as the GL would.
uniform vec2 u_offset;
#endif
#ifdef ID_TABLE
// ID and priority buffers (shadow_map.buffer): the triangle's entry of the table
// (gl/id_tables.rs). No polygon offset: the written value is the unit's, not a depth.
in vec3 v_world;
uniform vec3 u_light_pos;
#ifdef BUFFER_ID
// The ID as four bytes of colour, modulo 2^u_id_bits (as a narrower channel would keep it).
out vec4 o_id;
uniform uint u_id_mask;
#endif
#endif
void main() {
    if (u_alpha_func != 0 && !q3_alpha_passes(u_alpha_func, texture(u_texture, v_uv).a)) discard;
#ifdef ID_TABLE
    vec4 e = table_entry();
#ifdef BUFFER_ID
    o_id = id_colour(uint(e.x) & u_id_mask);
#elif defined(BUFFER_PRIORITY)
    gl_FragDepth = e.x + 0.5 * e.y;
#else
    gl_FragDepth = e.x + e.y * clamp((distance(v_world, u_light_pos) - e.z) * e.w, 0.0, 1.0);
#endif
#endif
#ifdef WARP_DEPTH
    float d = 0.5 * v_depth.x / v_depth.y + 0.5;
    float slope = max(abs(dFdx(d)), abs(dFdy(d)));
    gl_FragDepth = clamp(d + u_offset.x * slope + u_offset.y, 0.0, 1.0);
#endif
}
