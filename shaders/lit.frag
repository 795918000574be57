// One light's additive pass (glBlendFunc(GL_ONE, GL_ONE)): diffuse with spot cone and distance
// falloff. Fragments the light cannot reach are discarded, so they add nothing.
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in vec2 v_lightmap_uv;
in vec3 v_color;

uniform sampler2D u_texture;
uniform int u_alpha_func;
uniform vec3 u_light_pos;
uniform vec3 u_light_color;
uniform vec3 u_spot_dir;
uniform float u_cos_cutoff;   // -1 for omni lights
uniform float u_cos_inner;    // where the cone edge starts to soften
uniform float u_radius;

#ifdef MASK_OUTPUT
// Mask pass: write the decision instead of light (frame::MaskValue / 255): 1 lit, 2 shadowed.
// u_mask_value forces it (stencil-based techniques decide by the stencil test): 0 = from
// the shader's own visibility.
uniform int u_mask_value;
#endif

out vec4 o_color;

void main() {
    vec4 albedo = texture(u_texture, v_uv);
    if (!q3_alpha_passes(u_alpha_func, albedo.a)) discard;
    // Two-sided surfaces are lit on the side the camera sees.
    vec3 n = normalize(gl_FrontFacing ? v_normal : -v_normal);
    if (!light_reaches(v_world, n, u_light_pos, u_spot_dir, u_cos_cutoff, u_radius)) discard;
    vec3 to_light = u_light_pos - v_world;
    float dist = length(to_light);
    vec3 l = to_light / dist;
    float x = clamp(dist / u_radius, 0.0, 1.0);
    float falloff = (1.0 - x * x) * (1.0 - x * x);
    float cone = u_cos_cutoff > -1.0
        ? smoothstep(u_cos_cutoff, u_cos_inner, dot(-l, u_spot_dir))
        : 1.0;
    float diffuse = max(dot(n, l), 0.0) * falloff * cone;
    // Fraction of the light that reaches the fragment (1 without a shadow technique).
    float visibility = 1.0;
#ifdef MASK_OUTPUT
    int decision = u_mask_value != 0 ? u_mask_value : (visibility >= 0.5 ? 1 : 2);
    o_color = vec4(float(decision) / 255.0, 0.0, 0.0, 1.0);
#else
    o_color = vec4(albedo.rgb * u_light_color * diffuse * visibility, 1.0);
#endif
}
