// One light's additive pass (glBlendFunc(GL_ONE, GL_ONE)): diffuse with spot cone and distance
// falloff, and the shadow technique's decision. Fragments the light cannot reach are discarded.
//
// Defines: SHADOW_MAP (shadow.glsl is prepended), RESULT_ALPHA (the compare result goes to alpha
// and glAlphaFunc decides; otherwise it scales the light, INTENSITY), MASK_OUTPUT (write the
// decision instead of light), HYBRID (Chan & Durand: the map decides where its compares agree,
// the stencil elsewhere; u_hybrid_stage 0 is the marking pass of the computation mask).
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

#ifdef SHADOW_MAP
#ifdef TEXGEN_FRAGMENT
// The texgen planes relative to the light (shadow_map.texgen = fragment), applied here to the
// interpolated position: no projective coordinates are interpolated, whose rounding differs
// between rasterisers.
#ifdef SIX_SPOTS
uniform mat4 u_texgens[6];
#else
uniform mat4 u_texgen;
#endif
#ifdef WARP_DEPTH
#ifdef SIX_SPOTS
uniform mat4 u_texgen_depths[6];
#else
uniform mat4 u_texgen_depth;
#endif
#endif
#else
#ifdef SIX_SPOTS
in vec4 v_shadows[6];
#else
in vec4 v_shadow;
#endif
#ifdef WARP_DEPTH
#ifdef SIX_SPOTS
in vec2 v_shadow_refs[6];
#else
in vec2 v_shadow_ref;
#endif
#endif
#endif
#ifdef BUFFER_PRIORITY_DEPTH
uniform float u_priority_bias; // shadow_map.priority_bias
#endif
uniform int u_face;           // six-spot omni light: the cube face this pass lights; -1: all
uniform vec4 u_cell;          // one of several frusta: (min, max) of its cell of the face's image
                              // plane (shadow/frusta.rs); min > max: the whole face
uniform mat3 u_face_rot;      // the face view's rotation: light-relative world to its eye space
// shadow_map.normal_offset: (constant, share of the largest coordinate) of the lift along the
// normal of the point whose depth is compared per fragment; 0: the point itself.
uniform vec2 u_normal_offset;
// That point, relative to the light (set_compared).
vec3 g_compared = vec3(0.0);
uniform int u_sm_alpha_func;  // glAlphaFunc emulation: 0 NEVER .. 7 ALWAYS (options AlphaTestFunc)
uniform float u_sm_alpha_ref;
#ifdef HYBRID
uniform int u_hybrid_stage;   // 0: marking the computation mask; 1: shading
#endif

// The face whose axis is the major axis of d; ties go to x, then y (shadow/views.rs major_face).
int major_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0 ? 0 : 1;
    if (a.y >= a.z) return d.y >= 0.0 ? 2 : 3;
    return d.z >= 0.0 ? 4 : 5;
}

// Whether d (from the light) falls in this pass's cell. Half-open, so a fragment on an edge two
// cells share is lit once; the face's own edges are closed (major_face already decided there).
bool in_cell(vec3 d) {
    if (u_cell.x > u_cell.z) return true;
    vec3 e = u_face_rot * d;
    vec2 q = e.xy / -e.z;
    return (q.x >= u_cell.x || u_cell.x <= -1.0) && (q.y >= u_cell.y || u_cell.y <= -1.0)
        && (q.x < u_cell.z || u_cell.z >= 1.0) && (q.y < u_cell.w || u_cell.w >= 1.0);
}

bool alpha_test(int func, float a, float ref) {
    if (func == 0) return false;
    if (func == 1) return a < ref;
    if (func == 2) return a == ref;
    if (func == 3) return a <= ref;
    if (func == 4) return a > ref;
    if (func == 5) return a != ref;
    if (func == 6) return a >= ref;
    return true;
}
#endif

#if defined(SHADOW_MAP) && !defined(SHADOW_CUBE)
// The fragment's (s, t, r, q) in its spot map (six spots: in face g_face's).
vec4 spot_coords() {
#ifdef TEXGEN_FRAGMENT
#ifdef SIX_SPOTS
    return u_texgens[g_face] * vec4(g_compared, 1.0);
#else
    return u_texgen * vec4(g_compared, 1.0);
#endif
#elif defined(SIX_SPOTS)
    return v_shadows[g_face];
#else
    return v_shadow;
#endif
}

// The fragment's map coordinates (s, t, r, q); an omni light's six spots pick the face first.
// WARP_DEPTH: r from the light's own view, where the map's depth comes from (trapezoidal).
vec4 shadow_coords() {
#ifdef SIX_SPOTS
    g_face = major_face(v_world - u_light_pos);
#endif
    vec4 stq = spot_coords();
#ifdef WARP_DEPTH
#ifdef TEXGEN_FRAGMENT
#ifdef SIX_SPOTS
    vec2 rq = (u_texgen_depths[g_face] * vec4(g_compared, 1.0)).zw;
#else
    vec2 rq = (u_texgen_depth * vec4(g_compared, 1.0)).zw;
#endif
#elif defined(SIX_SPOTS)
    vec2 rq = v_shadow_refs[g_face];
#else
    vec2 rq = v_shadow_ref;
#endif
#endif
#ifdef WARP_DEPTH
    stq.z = rq.y > 0.0 ? rq.x / rq.y * stq.w : -1.0;
#endif
#if defined(BUFFER_PRIORITY) || defined(BUFFER_PRIORITY_DEPTH)
    // Priority buffers compare the fragment's unit, not its depth (shadow_map.buffer).
    vec4 e = table_entry();
#ifdef BUFFER_PRIORITY
    float ref = e.x;
#else
    float ref = e.x + e.y * (clamp((distance(v_world, u_light_pos) - e.z) * e.w, 0.0, 1.0) - u_priority_bias);
#endif
    stq.z = ref * stq.w;
#endif
    return stq;
}
#endif

#ifdef MASK_OUTPUT
// Mask pass: write the decision instead of light (frame::MaskValue / 255): 1 lit, 2 shadowed.
// u_mask_value forces it (stencil-based techniques decide by the stencil test): 0 = from
// the shader's own decision.
uniform int u_mask_value;
#endif

layout(location = 0) out vec4 o_color;
#ifndef MASK_OUTPUT
// The decision, recorded where the frame attaches a layer for this light (gl/record.rs):
// (1, 0) lit, (0, 1) shadowed, added as the light is.
layout(location = 1) out vec4 o_decision;
// While recording, the alpha test's rejected (shadowed) fragments add nothing instead of
// leaving, so their decision is recorded: the frame looks the same.
uniform bool u_keep_shadowed;
#endif

// The surface's normal on the side the camera sees: two-sided surfaces are lit on that side.
vec3 seen_normal() {
    return normalize(gl_FrontFacing ? v_normal : -v_normal);
}

#ifdef SHADOW_MAP
// Sets g_compared: the fragment's point lifted along its normal `n` by u_normal_offset.
void set_compared(vec3 n) {
    vec3 p = abs(v_world);
    float lift = u_normal_offset.x + u_normal_offset.y * max(p.x, max(p.y, p.z));
    g_compared = v_world + n * lift - u_light_pos;
}
#endif

void main() {
#ifdef PRIORITY_MIPMAP
    // The footprint of the pixel on the map, while every fragment of the quad is still here
    // (before any discard: the compared point too).
    set_compared(seen_normal());
    {
        vec4 c = shadow_coords();
        vec2 uv = c.xy / c.w;
        g_map_dx = dFdx(uv);
        g_map_dy = dFdy(uv);
    }
#endif
#ifdef SHADOW_MAP
    // One of an omni light's six spots: fragments of the other faces leave before any work.
    // One of several frusta: fragments of the other cells leave too.
    if (u_face >= 0 && (major_face(v_world - u_light_pos) != u_face || !in_cell(v_world - u_light_pos)))
        discard;
#endif
    vec4 albedo = texture(u_texture, v_uv);
    if (!q3_alpha_passes(u_alpha_func, albedo.a)) discard;
    vec3 n = seen_normal();
#if defined(SHADOW_MAP) && !defined(PRIORITY_MIPMAP)
    // After the discards: fragments of other faces and alpha holes compare nothing.
    set_compared(n);
#endif
    bool reached = light_reaches(v_world, n, u_light_pos, u_spot_dir, u_cos_cutoff, u_radius);
#ifdef HYBRID
    // The marking pass keeps (marks) every pixel no volume needs to count: not reached by the
    // light, or decided by the map.
    float decided;
#ifdef SHADOW_CUBE
    bool agrees = map_agrees_cube(g_compared, decided);
#else
    bool agrees = map_agrees(shadow_coords(), decided);
#endif
    if (u_hybrid_stage == 0) {
        if (reached && !agrees) discard;
        o_color = vec4(0.0);
#ifndef MASK_OUTPUT
        o_decision = vec4(0.0);
#endif
        return;
    }
#endif
    if (!reached) discard;
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
#ifdef BUFFER_ID
    g_my_id = uint(table_entry().x) & u_id_mask;
#endif
#ifdef SHADOW_MAP
#ifdef HYBRID
    // At silhouette pixels the stencil test has decided (count zero): lit.
    visibility = agrees ? decided : 1.0;
#elif defined(SHADOW_CUBE)
    visibility = shadow_visibility_cube(g_compared);
#else
    visibility = shadow_visibility(shadow_coords());
#endif
#endif

#ifdef RESULT_ALPHA
    // DEPTH_TEXTURE_MODE ALPHA: the result lands in alpha and the alpha test keeps or rejects the
    // fragment; the light itself is not scaled.
    bool lit = alpha_test(u_sm_alpha_func, visibility, u_sm_alpha_ref);
    float scale = 1.0;
#else
    // INTENSITY: the result scales the light; the mask calls it lit at one half or more.
    bool lit = visibility >= 0.5;
    float scale = visibility;
#endif

#ifdef MASK_OUTPUT
    int decision = u_mask_value != 0 ? u_mask_value : (lit ? 1 : 2);
    o_color = vec4(float(decision) / 255.0, 0.0, 0.0, 1.0);
#else
    o_decision = lit ? vec4(1.0, 0.0, 0.0, 0.0) : vec4(0.0, 1.0, 0.0, 0.0);
#ifdef RESULT_ALPHA
    if (!lit) {
        if (!u_keep_shadowed) discard;
        o_color = vec4(0.0);
        return;
    }
#endif
    o_color = vec4(albedo.rgb * u_light_color * diffuse * scale, 1.0);
#ifdef TEXEL_GRID
    // Debug view: the shadow map's texels projected onto the receivers, as a checkerboard (one
    // square per texel), which stays readable where a texel covers only a few pixels.
#ifdef SHADOW_CUBE
    vec3 d = v_world - u_light_pos;
    vec3 a = abs(d);
    vec2 face_uv = (a.x >= a.y && a.x >= a.z) ? d.yz / a.x : ((a.y >= a.z) ? d.xz / a.y : d.xy / a.z);
    vec2 texel = (face_uv * 0.5 + 0.5) * u_map_size;
#else
    vec4 stq = spot_coords();
    vec2 texel = stq.xy / stq.w * u_map_size;
#endif
    ivec2 cell = ivec2(floor(texel));
    if (((cell.x + cell.y) & 1) == 1) o_color.rgb *= vec3(0.55, 0.6, 1.0);
#if !defined(SHADOW_CUBE) && !defined(SIX_SPOTS)
    // Multiple frusta: each frustum's squares take a tint of their own, so the frusta and
    // their texel sizes show side by side.
    if (u_cell.x <= u_cell.z) {
        float k = fract(dot(u_cell.xy + 1.0, vec2(0.37, 0.61)) + float(u_face) * 0.13);
        o_color.rgb *= 0.75 + 0.25 * cos(6.2832 * (k + vec3(0.0, 0.33, 0.67)));
    }
#endif
#endif
#endif
}
