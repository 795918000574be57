// A recording light's pixels that its lit pass left undrawn though the light reaches them
// (its stencil dropped them: shadowed), added over its layer (gl/record.rs)
// as (0, 1); a pixel the pass lit stays lit. The reach is the lit pass's own test, on the
// G-buffer's position and normal.
uniform highp usampler2D u_surface;   // common.glsl pack_surface
uniform vec3 u_light_pos;
uniform vec3 u_spot_dir;
uniform float u_cos_cutoff;
uniform float u_radius;
out vec4 o_decision;

void main() {
    ivec2 at = ivec2(gl_FragCoord.xy);
    uvec4 s = texelFetch(u_surface, at, 0);
    if (surface_kind(s) != 1u) discard;
    vec3 p = surface_position(s);
    vec3 n = surface_normal(s);
    if (!light_reaches(p, n, u_light_pos, u_spot_dir, u_cos_cutoff, u_radius)) discard;
    o_decision = vec4(0.0, 1.0, 0.0, 0.0);
}
