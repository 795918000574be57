// One texel of the depth pyramid's level 2 per fragment: the farthest depth of a 4×4 block of the
// frame, and the farthest of those nearer than the far plane (-1: none), so that the CPU reads
// back a sixteenth of the pixels (see plan::occlusion).
uniform sampler2D u_depth; // the frame's depth (compare mode none)
uniform ivec2 u_size;      // the frame's size in pixels; pixels past it repeat the last ones
out vec2 o_max;
void main() {
    ivec2 corner = ivec2(gl_FragCoord.xy) * 4;
    float farthest = 0.0;
    float surface = -1.0;
    for (int j = 0; j < 4; j++) {
        for (int i = 0; i < 4; i++) {
            float d = texelFetch(u_depth, min(corner + ivec2(i, j), u_size - 1), 0).r;
            farthest = max(farthest, d);
            if (d < 1.0) {
                surface = max(surface, d);
            }
        }
    }
    o_max = vec2(farthest, surface);
}
