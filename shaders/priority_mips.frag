// One level of a priority buffer's mip chain (shadow_map.priority_mipmap): each texel holds a
// median of the four texels below it. A mean of ranks is no rank: it falls between two units'
// slots and shadows wherever any texel below held a nearer unit. A median is a rank that is
// there, and a fragment whose own slot starts at or below it is lit by half of the texels below.
// Four values have two medians: always taking the upper one would call a 2-2 tie lit at every
// level, and the ties compound (a footprint 60% shadowed reads 48% one level up, 28% two levels
// up); texels take the upper and the lower one in a checkerboard, so ties fall either way.
uniform sampler2D u_below;   // the level below (its only level while this one is drawn)
uniform ivec2 u_below_size;
uniform int u_level;          // the level drawn
void main() {
    ivec2 c = ivec2(gl_FragCoord.xy) * 2;
    ivec2 last = u_below_size - 1;
    float a = texelFetch(u_below, min(c, last), 0).r;
    float b = texelFetch(u_below, min(c + ivec2(1, 0), last), 0).r;
    float d = texelFetch(u_below, min(c + ivec2(0, 1), last), 0).r;
    float e = texelFetch(u_below, min(c + ivec2(1, 1), last), 0).r;
    // The middle two of four are the larger of the two pairs' minima and the smaller of their
    // maxima.
    float m1 = max(min(a, b), min(d, e));
    float m2 = min(max(a, b), max(d, e));
    ivec2 t = ivec2(gl_FragCoord.xy);
    bool upper = ((t.x + t.y + u_level) & 1) == 0;
    gl_FragDepth = upper ? max(m1, m2) : min(m1, m2);
}
