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
void main() {
    if (u_alpha_func != 0 && !q3_alpha_passes(u_alpha_func, texture(u_texture, v_uv).a)) discard;
#ifdef WARP_DEPTH
    float d = 0.5 * v_depth.x / v_depth.y + 0.5;
    float slope = max(abs(dFdx(d)), abs(dFdy(d)));
    gl_FragDepth = clamp(d + u_offset.x * slope + u_offset.y, 0.0, 1.0);
#endif
}
