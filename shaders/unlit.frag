// The paper's "unlit world": surface texture times lightmap in one pass (two texture units,
// ARB_multitexture in the paper). Vertex-lit Quake 3 surfaces use their vertex colours; models and
// the built-in scene use a constant level instead (paper 2.5).
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

out vec4 o_color;

void main() {
    vec4 albedo = texture(u_texture, v_uv);
    if (!q3_alpha_passes(u_alpha_func, albedo.a)) discard;
    vec3 light = u_ambient;
    if (u_baked == 1) light = texture(u_lightmap, v_lightmap_uv).rgb * u_lightmap_scale;
    if (u_baked == 2) light = v_color * u_lightmap_scale;
    o_color = vec4(albedo.rgb * light, 1.0);
}
