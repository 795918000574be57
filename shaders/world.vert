// Every camera pass draws the world with this vertex stage, so depth is bit-identical across the
// unlit and lit passes (`invariant`): the lit pass's LEQUAL test then passes exactly where the
// unlit pass wrote, which is what the paper's passes rely on. Clip planes (CLIP_PLANES) change
// which polygons are rasterized, not this computation: that is paper Fig. 1's anomaly.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in vec2 a_lightmap_uv;
layout(location = 4) in vec4 a_color;

uniform mat4 u_model;        // owner space -> world
uniform mat3 u_normal_model; // inverse transpose of u_model's upper 3x3
uniform mat4 u_view_proj;    // world -> camera clip

out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out vec2 v_lightmap_uv;
out vec3 v_color;

#if defined(SHADOW_MAP) && !defined(TEXGEN_FRAGMENT)
// glTexGen(EYE_LINEAR) with planes T = B * P_light * V_light * inverse(V_camera), specified while
// the camera's modelview is loaded: applied to eye coordinates it gives (s, t, r, q).
uniform mat4 u_view;    // world -> camera eye
#ifdef SIX_SPOTS
// An omni light's six spot views at once, each computed exactly as its own pass would.
uniform mat4 u_texgens[6];
out vec4 v_shadows[6];
#else
uniform mat4 u_texgen;
out vec4 v_shadow;
#endif
#ifdef WARP_DEPTH
// Trapezoidal maps: the compared depth's (r, q) from the light's own view.
#ifdef SIX_SPOTS
uniform mat4 u_texgen_depths[6];
out vec2 v_shadow_refs[6];
#else
uniform mat4 u_texgen_depth;
out vec2 v_shadow_ref;
#endif
#endif
#endif

// Only where gl_ClipDistance exists (HAS_CLIP_DISTANCE, see gl/program.rs); elsewhere the
// planner never asks for clip planes (the clip_distances fallback).
#if defined(CLIP_PLANES) && defined(HAS_CLIP_DISTANCE)
uniform vec4 u_clip_planes[4]; // the light frustum's sides, world space, inside >= 0
out float gl_ClipDistance[4];  // sized, so a loop may index it (GLSL 3.30)
#endif

invariant gl_Position;

void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world = world.xyz;
    v_normal = u_normal_model * a_normal;
    v_uv = a_uv;
    v_lightmap_uv = a_lightmap_uv;
    v_color = a_color.rgb;
#if defined(SHADOW_MAP) && !defined(TEXGEN_FRAGMENT)
#ifdef SIX_SPOTS
    for (int f = 0; f < 6; f++) v_shadows[f] = u_texgens[f] * (u_view * world);
#else
    v_shadow = u_texgen * (u_view * world);
#endif
#ifdef WARP_DEPTH
#ifdef SIX_SPOTS
    for (int f = 0; f < 6; f++) v_shadow_refs[f] = (u_texgen_depths[f] * (u_view * world)).zw;
#else
    v_shadow_ref = (u_texgen_depth * (u_view * world)).zw;
#endif
#endif
#endif
#if defined(CLIP_PLANES) && defined(HAS_CLIP_DISTANCE)
    for (int i = 0; i < 4; i++) gl_ClipDistance[i] = dot(u_clip_planes[i], world);
#endif
    gl_Position = u_view_proj * world;
}
