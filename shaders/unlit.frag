// The paper's "unlit world": surface texture times lightmap in one pass (two texture units,
// ARB_multitexture in the paper). Vertex-lit Quake 3 surfaces use their vertex colours; models and
// the built-in scene use a constant level instead (paper 2.5).
//
// With GBUFFER, the same pass also writes what the exact reference needs of the visible surface
// (gl/passes/gbuffer.rs): the frame's own surfaces, from the same fragments, at no second pass.
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in vec2 v_lightmap_uv;
in vec3 v_color;

uniform sampler2D u_texture;
uniform sampler2D u_lightmap;
uniform int u_alpha_func;
uniform int u_baked;          // 0 constant, 1 lightmap, 2 vertex colours (scene BakedLight)
uniform float u_lightmap_scale; // 2^r_overBrightBits, Quake 3's overbright
uniform vec3 u_ambient;

layout(location = 0) out vec4 o_color;

#ifdef GBUFFER
uniform int u_receives;
// Lights whose lit passes drop shadowed fragments and record (gl/record.rs): bit k of
// o_reach is set where light k reaches the surface, by the lit pass's own test.
uniform int u_reach_lights;
uniform vec4 u_reach_position_radius[32];
uniform vec4 u_reach_direction_cutoff[32];

// Location 1 is free here (the lit pass's record uses it later, on another program).
layout(location = 1) out vec4 o_position;
// normal.w: 1 = the surface receives dynamic light, 2 = it does not; 0 (clear) = background.
layout(location = 2) out vec4 o_normal;
layout(location = 3) out uint o_reach;

void write_gbuffer() {
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
#endif

void main() {
    vec4 albedo = texture(u_texture, v_uv);
    if (!q3_alpha_passes(u_alpha_func, albedo.a)) discard;
    vec3 light = u_ambient;
    if (u_baked == 1) light = texture(u_lightmap, v_lightmap_uv).rgb * u_lightmap_scale;
    if (u_baked == 2) light = v_color * u_lightmap_scale;
    o_color = vec4(albedo.rgb * light, 1.0);
#ifdef GBUFFER
    write_gbuffer();
#endif
}
