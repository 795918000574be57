// Shadow volume geometry: homogeneous vertices, w = 0 at infinity (paper 4.1). gl_Position is the
// same expression as world.vert's, and invariant, so front caps land exactly on their casters.
layout(location = 0) in vec4 a_position;

uniform mat4 u_model;     // the caster group's space -> world
uniform mat4 u_view_proj; // world -> camera clip
uniform vec4 u_depth_clip[4]; // clip-space planes the draw is clipped to (zero: none)

invariant gl_Position;

void main() {
    gl_Position = u_view_proj * (u_model * a_position);
    // Without gl_ClipDistance (GLSL ES) the planner's depth clip is off (the clip_distances
    // fallback): every draw's planes are zero and clip nothing.
#ifdef HAS_CLIP_DISTANCE
    gl_ClipDistance[0] = dot(u_depth_clip[0], gl_Position);
    gl_ClipDistance[1] = dot(u_depth_clip[1], gl_Position);
    gl_ClipDistance[2] = dot(u_depth_clip[2], gl_Position);
    gl_ClipDistance[3] = dot(u_depth_clip[3], gl_Position);
#endif
}
