// What the camera sees, for the exact reference: world position and shading normal per pixel.
// normal.w: 1 = the surface receives dynamic light, 2 = it does not; 0 (clear) = background.
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in vec2 v_lightmap_uv;
in vec3 v_color;

uniform sampler2D u_texture;
uniform int u_alpha_func;
uniform int u_receives;

// Lights whose lit passes drop shadowed fragments and record (gl/record.rs): bit k of
// o_reach is set where light k reaches the surface, by the lit pass's own test.
uniform int u_reach_lights;
uniform vec4 u_reach_position_radius[32];
uniform vec4 u_reach_direction_cutoff[32];

layout(location = 0) out vec4 o_position;
layout(location = 1) out vec4 o_normal;
layout(location = 2) out uint o_reach;

void main() {
    vec4 albedo = texture(u_texture, v_uv);
    if (!q3_alpha_passes(u_alpha_func, albedo.a)) discard;
    // The same normal the lit pass shades with.
    vec3 n = normalize(gl_FrontFacing ? v_normal : -v_normal);
    o_position = vec4(v_world, 1.0);
    o_normal = vec4(n, u_receives != 0 ? 1.0 : 2.0);
    uint reach = 0u;
    if (u_receives != 0) {
        for (int k = 0; k < u_reach_lights; k++) {
            vec4 pr = u_reach_position_radius[k];
            vec4 dc = u_reach_direction_cutoff[k];
            if (light_reaches(v_world, n, pr.xyz, dc.xyz, dc.w, pr.w)) reach |= 1u << uint(k);
        }
    }
    o_reach = reach;
}
