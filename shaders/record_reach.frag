// A recording light's pixels that its lit pass left undrawn though the light reaches them
// (its stencil dropped them: shadowed), added over its layer (gl/record.rs)
// as (0, 1); a pixel the pass lit stays lit. The reach is the lit pass's own test, on the
// G-buffer's position and normal.
uniform sampler2D u_position;
uniform sampler2D u_normal;   // w: 1 = takes dynamic light (gbuffer.frag)
uniform vec3 u_light_pos;
uniform vec3 u_spot_dir;
uniform float u_cos_cutoff;
uniform float u_radius;
out vec4 o_decision;

void main() {
    ivec2 at = ivec2(gl_FragCoord.xy);
    vec4 n = texelFetch(u_normal, at, 0);
    if (n.w != 1.0) discard;
    vec3 p = texelFetch(u_position, at, 0).xyz;
    if (!light_reaches(p, n.xyz, u_light_pos, u_spot_dir, u_cos_cutoff, u_radius)) discard;
    o_decision = vec4(0.0, 1.0, 0.0, 0.0);
}
