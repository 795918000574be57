// Alpha-tested casters discard where their surface does (shadow_map.alpha_casters = test);
// otherwise u_alpha_func is 0 and everything is written. Only depth is kept.
in vec2 v_uv;
uniform sampler2D u_texture;
uniform int u_alpha_func;
void main() {
    if (u_alpha_func != 0 && !q3_alpha_passes(u_alpha_func, texture(u_texture, v_uv).a)) discard;
}
