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
