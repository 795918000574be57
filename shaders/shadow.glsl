// Shadow-map lookups for the lit pass (included only with SHADOW_MAP).
//
// Defines: SHADOW_CUBE (one cube map), SIX_SPOTS (an omni light's six spot maps in one pass: the
// fragment's face picks its map, as the six passes' face test would), COMPARE_SHADER (fetch and
// compare here instead of sampler2DShadow), FILTER_HW2X2 / FILTER_PCF3 / FILTER_PCFN (default:
// nearest),
// OUTSIDE_RANGE (no compare outside [0,1]), REF_CLAMP (fixed-point depth: the reference is
// clamped to [0,1] before the compare, as GL does), HYBRID (Chan & Durand's classification).

uniform float u_map_size;
uniform int u_pcf_size;

#ifdef SHADOW_CUBE
#ifdef COMPARE_SHADER
uniform samplerCube u_shadow_cube;
#else
uniform samplerCubeShadow u_shadow_cube;
#endif
uniform vec2 u_cube_near_far;
#else
#if defined(COMPARE_SHADER) || defined(BUFFER_ID)
#define MAP_SAMPLER sampler2D
#else
#define MAP_SAMPLER sampler2DShadow
#endif
#ifdef SIX_SPOTS
// GLSL 3.30 indexes sampler arrays with constants only: the face is chosen by branches.
uniform MAP_SAMPLER u_face_maps[6];
int g_face = 0;
#define MAP_PICK(E0, E1, E2, E3, E4, E5) (g_face == 0 ? E0 : g_face == 1 ? E1 : g_face == 2 ? E2 : g_face == 3 ? E3 : g_face == 4 ? E4 : E5)
#define MAP_CALL1(F, A) MAP_PICK(F(u_face_maps[0], A), F(u_face_maps[1], A), F(u_face_maps[2], A), F(u_face_maps[3], A), F(u_face_maps[4], A), F(u_face_maps[5], A))
#define MAP_CALL2(F, A, B) MAP_PICK(F(u_face_maps[0], A, B), F(u_face_maps[1], A, B), F(u_face_maps[2], A, B), F(u_face_maps[3], A, B), F(u_face_maps[4], A, B), F(u_face_maps[5], A, B))
#define MAP_CALL3(F, A, B, C) MAP_PICK(F(u_face_maps[0], A, B, C), F(u_face_maps[1], A, B, C), F(u_face_maps[2], A, B, C), F(u_face_maps[3], A, B, C), F(u_face_maps[4], A, B, C), F(u_face_maps[5], A, B, C))
#else
uniform MAP_SAMPLER u_shadow_map;
#define MAP_CALL1(F, A) F(u_shadow_map, A)
#define MAP_CALL2(F, A, B) F(u_shadow_map, A, B)
#define MAP_CALL3(F, A, B, C) F(u_shadow_map, A, B, C)
#endif
#ifdef PRIORITY_MIPMAP
// A priority buffer's mip chain: the level is chosen from the map coordinates' derivatives,
// taken at the top of lit.frag's main (lookups sit in branches, where implicit ones are
// undefined).
vec2 g_map_dx = vec2(0.0);
vec2 g_map_dy = vec2(0.0);
// The level one step finer than the texel with the pixel's footprint's area. The area, not the
// longer side (GL's own choice): a receiver seen at a grazing angle would read a level far
// coarser than it covers. One step finer: a level's texels are aligned to the map's grid, not
// to the pixel, and a texel of the footprint's size misplaces an edge by up to a texel
// (measured: docs/id-buffers.md).
float map_lod() {
    vec2 a = g_map_dx * u_map_size;
    vec2 b = g_map_dy * u_map_size;
    float area = abs(a.x * b.y - a.y * b.x);
    return max(0.5 * log2(max(area, 1e-12)) - 1.0, 0.0);
}
#define MAP_LOOKUP(A) MAP_CALL2(textureLod, A, map_lod())
#else
#define MAP_LOOKUP(A) MAP_CALL1(texture, A)
#endif
#if defined(COMPARE_SHADER) || defined(BUFFER_ID)
float map_depth(vec2 uv) { return MAP_LOOKUP(uv).r; }
float map_texel(ivec2 t) { return MAP_CALL2(texelFetch, t, 0).r; }
#else
float map_compare(vec3 c) { return MAP_LOOKUP(c); }
#endif
#ifdef BUFFER_ID
// ID buffers: the fragment's own ID (lit.frag sets it from the table) against the IDs stored.
uint g_my_id = 0u;
uniform uint u_id_mask;
vec4 id_texel(ivec2 t) {
    ivec2 last = ivec2(int(u_map_size) - 1);
    return MAP_CALL2(texelFetch, clamp(t, ivec2(0), last), 0);
}
#endif
#endif

float reference_depth(float r) {
#ifdef REF_CLAMP
    return clamp(r, 0.0, 1.0);
#else
    return r;
#endif
}

#ifndef SHADOW_CUBE
// One compare at uv: 1 if the fragment is no farther than the stored depth (LEQUAL).
float compare_at(vec2 uv, float ref) {
#ifdef BUFFER_ID
    // Lit where the texel holds the fragment's own ID; with the edge filter, where any of
    // the nine texels around it does (Forsyth's cure for edge acne).
    ivec2 t = ivec2(floor(uv * u_map_size));
#ifdef ID_EDGE_FILTER
    for (int j = -1; j <= 1; j++) {
        for (int i = -1; i <= 1; i++) {
            if (colour_id(id_texel(t + ivec2(i, j))) == g_my_id) return 1.0;
        }
    }
    return 0.0;
#else
    return colour_id(id_texel(t)) == g_my_id ? 1.0 : 0.0;
#endif
#elif defined(COMPARE_SHADER)
    return reference_depth(ref) <= map_depth(uv) ? 1.0 : 0.0;
#else
    return map_compare(vec3(uv, ref));
#endif
}

#if defined(COMPARE_SHADER) && defined(FILTER_HW2X2)
// LINEAR filtering of compares, as the hardware does it: four texel compares, bilinear weights.
float compare_bilinear(vec2 uv, float ref) {
    vec2 t = uv * u_map_size - 0.5;
    vec2 f = fract(t);
    ivec2 i0 = ivec2(floor(t));
    ivec2 last = ivec2(int(u_map_size) - 1);
    float r = reference_depth(ref);
    float c00 = r <= map_texel(clamp(i0, ivec2(0), last)) ? 1.0 : 0.0;
    float c10 = r <= map_texel(clamp(i0 + ivec2(1, 0), ivec2(0), last)) ? 1.0 : 0.0;
    float c01 = r <= map_texel(clamp(i0 + ivec2(0, 1), ivec2(0), last)) ? 1.0 : 0.0;
    float c11 = r <= map_texel(clamp(i0 + ivec2(1, 1), ivec2(0), last)) ? 1.0 : 0.0;
    return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}
#endif

#ifdef HYBRID
// Chan & Durand's classification: the compares of the texels around the fragment's map
// position (2r x 2r, r = u_hybrid_radius: the bilinear footprint at r = 1), each at its texel's
// centre. True when they all agree (`decided` is then their result); false at a silhouette
// pixel, behind the light or outside the map, where the volumes decide.
uniform int u_hybrid_radius;
bool map_agrees(vec4 stq, out float decided) {
    decided = 1.0;
    if (stq.w <= 0.0) return false;
    vec3 p = stq.xyz / stq.w;
    if (p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 || p.z < 0.0) return false;
    vec2 first = floor(p.xy * u_map_size - 0.5) - float(u_hybrid_radius - 1);
    int n = 2 * u_hybrid_radius;
    float sum = 0.0;
    for (int j = 0; j < n; j++) {
        for (int i = 0; i < n; i++) {
            vec2 uv = (first + vec2(float(i), float(j)) + 0.5) / u_map_size;
            sum += compare_at(uv, p.z) >= 0.5 ? 1.0 : 0.0;
        }
    }
    decided = sum > 0.0 ? 1.0 : 0.0;
    return sum == 0.0 || sum == float(n * n);
}
#endif

// Fraction of the light reaching the fragment, from texgen coordinates (s, t, r, q).
float shadow_visibility(vec4 stq) {
    // ARB_shadow: points behind the light (q <= 0) and with negative r read as shadowed.
    if (stq.w <= 0.0 || stq.z < 0.0) return 0.0;
    vec3 p = stq.xyz / stq.w;
#ifdef OUTSIDE_RANGE
    // The texgen range test: outside the map no compare is made.
    if (p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0) return 1.0;
#endif
    float texel = 1.0 / u_map_size;
#if defined(FILTER_PCF3) || defined(FILTER_PCFN)
#ifdef FILTER_PCF3
    int n = 3;
#else
    int n = u_pcf_size;
#endif
    float sum = 0.0;
    float lo = -0.5 * float(n - 1);
    for (int j = 0; j < n; j++) {
        for (int i = 0; i < n; i++) {
            sum += compare_at(p.xy + vec2(lo + float(i), lo + float(j)) * texel, p.z);
        }
    }
    return sum / float(n * n);
#elif defined(COMPARE_SHADER) && defined(FILTER_HW2X2)
    return compare_bilinear(p.xy, p.z);
#else
    return compare_at(p.xy, p.z);
#endif
}
#else
// Cube map: the compared depth is the major axis distance through the faces' projection.
float cube_compare(vec3 d, float ref) {
#ifdef COMPARE_SHADER
    return reference_depth(ref) <= texture(u_shadow_cube, d).r ? 1.0 : 0.0;
#else
    return texture(u_shadow_cube, vec4(d, ref));
#endif
}

#ifdef HYBRID
// The classification on a cube map: 2r x 2r compares one texel apart across the face around
// direction d (the bilinear footprint at r = 1).
uniform int u_hybrid_radius;
bool map_agrees_cube(vec3 d, out float decided) {
    decided = 1.0;
    vec3 a = abs(d);
    float major = max(a.x, max(a.y, a.z));
    float n = u_cube_near_far.x;
    float f = u_cube_near_far.y;
    float ref = 0.5 * ((f + n) / (f - n) - 2.0 * f * n / ((f - n) * major)) + 0.5;
    if (ref < 0.0) return false;
    vec3 axis = a.x >= a.y && a.x >= a.z ? vec3(1, 0, 0) : (a.y >= a.z ? vec3(0, 1, 0) : vec3(0, 0, 1));
    vec3 u = normalize(cross(axis, abs(axis.y) > 0.5 ? vec3(0, 0, 1) : vec3(0, 1, 0)));
    vec3 v = cross(axis, u);
    float step = 2.0 * major / u_map_size;
    int k = 2 * u_hybrid_radius;
    float lo = -0.5 * float(k - 1);
    float sum = 0.0;
    for (int j = 0; j < k; j++) {
        for (int i = 0; i < k; i++) {
            vec3 at = d + (u * (lo + float(i)) + v * (lo + float(j))) * step;
            sum += cube_compare(at, ref) >= 0.5 ? 1.0 : 0.0;
        }
    }
    decided = sum > 0.0 ? 1.0 : 0.0;
    return sum == 0.0 || sum == float(k * k);
}
#endif

float shadow_visibility_cube(vec3 d) {
    vec3 a = abs(d);
    float major = max(a.x, max(a.y, a.z));
    float n = u_cube_near_far.x;
    float f = u_cube_near_far.y;
    float ndc = (f + n) / (f - n) - 2.0 * f * n / ((f - n) * major);
    float ref = 0.5 * ndc + 0.5;
    if (ref < 0.0) return 0.0;
#if defined(FILTER_PCF3) || defined(FILTER_PCFN)
#ifdef FILTER_PCF3
    int k = 3;
#else
    int k = u_pcf_size;
#endif
    // Taps across the face, one texel apart at this distance.
    vec3 axis = a.x >= a.y && a.x >= a.z ? vec3(1, 0, 0) : (a.y >= a.z ? vec3(0, 1, 0) : vec3(0, 0, 1));
    vec3 u = normalize(cross(axis, abs(axis.y) > 0.5 ? vec3(0, 0, 1) : vec3(0, 1, 0)));
    vec3 v = cross(axis, u);
    float step = 2.0 * major / u_map_size;
    float sum = 0.0;
    float lo = -0.5 * float(k - 1);
    for (int j = 0; j < k; j++) {
        for (int i = 0; i < k; i++) {
            sum += cube_compare(d + (u * (lo + float(i)) + v * (lo + float(j))) * step, ref);
        }
    }
    return sum / float(k * k);
#else
    return cube_compare(d, ref);
#endif
}
#endif
