// Helpers shared by every stage. Prepended after #version and the variant's #defines.

// glAlphaFunc emulation for Quake 3's alphaFunc (scene/mod.rs AlphaFunc::code):
// 0 = no test, 1 = GT0, 2 = LT128, 3 = GE128. Returns whether the fragment is kept.
bool q3_alpha_passes(int func, float alpha) {
    if (func == 1) return alpha > 0.0;
    if (func == 2) return alpha < 0.5;
    if (func == 3) return alpha >= 0.5;
    return true;
}

// scene::light::GRAZING_COSINE: a surface grazed closer than this receives nothing visible.
const float GRAZING_COSINE = 1.0 / 512.0;

// The receiver rule of scene/light.rs Light::reaches: within the radius, in the spot cone and on
// the lit side of the surface by more than GRAZING_COSINE. `cos_cutoff` is -1 for omni lights.

bool light_reaches(vec3 p, vec3 n, vec3 light_pos, vec3 spot_dir, float cos_cutoff, float radius) {
    vec3 to_light = light_pos - p;
    float dist = length(to_light);
    if (!(dist > 0.0 && dist < radius)) return false;
    if (dot(n, to_light) <= GRAZING_COSINE * dist) return false;
    if (cos_cutoff > -1.0 && dot(-to_light / dist, spot_dir) <= cos_cutoff) return false;
    return true;
}

// The G-buffer's surface texel (gl/target.rs GBufferTarget): the position's float bits in xyz,
// and in w a unit normal in octahedral coordinates, 15 bits each, over the kind in the low two
// bits (0 background, 1 receives dynamic light, 2 does not). One attachment, not two: on a
// CPU rasteriser each colour output costs the base pass about a millisecond a frame.
uvec4 pack_surface(vec3 p, vec3 n, uint kind) {
    vec2 o = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0) {
        vec2 s = vec2(o.x >= 0.0 ? 1.0 : -1.0, o.y >= 0.0 ? 1.0 : -1.0);
        o = (1.0 - abs(o.yx)) * s;
    }
    uvec2 q = uvec2(round(clamp(o * 0.5 + 0.5, 0.0, 1.0) * 32767.0));
    return uvec4(floatBitsToUint(p), (q.x << 17) | (q.y << 2) | kind);
}
vec3 surface_position(uvec4 t) {
    return uintBitsToFloat(t.xyz);
}
uint surface_kind(uvec4 t) {
    return t.w & 3u;
}
vec3 surface_normal(uvec4 t) {
    vec2 o = vec2(uvec2(t.w >> 17, t.w >> 2) & 32767u) / 32767.0 * 2.0 - 1.0;
    vec3 n = vec3(o, 1.0 - abs(o.x) - abs(o.y));
    if (n.z < 0.0) {
        vec2 s = vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
        n.xy = (1.0 - abs(n.yx)) * s;
    }
    return normalize(n);
}

#if defined(ID_TABLE) && defined(FRAGMENT_STAGE)
// Per-triangle table of ID and priority buffers (gl/id_tables.rs): row-major, 1024 texels a
// row, at the triangle's place in the GPU index buffer.
uniform sampler2D u_table;
uniform int u_tri_base;
vec4 table_entry() {
    int t = u_tri_base + gl_PrimitiveID;
    return texelFetch(u_table, ivec2(t % 1024, t / 1024), 0);
}
// An ID as RGBA8 bytes, low byte in red.
vec4 id_colour(uint id) {
    return vec4(float(id & 255u), float((id >> 8) & 255u), float((id >> 16) & 255u), float(id >> 24)) / 255.0;
}
uint colour_id(vec4 c) {
    uvec4 b = uvec4(round(c * 255.0));
    return b.r | (b.g << 8) | (b.b << 16) | (b.a << 24);
}
#endif
