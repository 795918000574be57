// The G-buffer at picked pixels (gl/gather.rs): point k lands on cell k of a target
// `u_columns` wide, carrying the pixel it reads.
layout(location = 0) in vec2 a_pixel;   // window coordinates of the picked pixel
uniform int u_columns;
uniform vec2 u_size;                     // the target's size in cells
flat out ivec2 v_pixel;
void main() {
    vec2 cell = vec2(float(gl_VertexID % u_columns), float(gl_VertexID / u_columns)) + 0.5;
    gl_Position = vec4(cell / u_size * 2.0 - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
    v_pixel = ivec2(a_pixel);
}
