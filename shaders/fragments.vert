// The light-volume subdivision's shadowed fragments, marked into the stencil over the frame's
// depth. Their corners were cut in f64 and rounded to f32, so each lies off its surface's plane
// by up to half the f32 spacing of its coordinates: near the camera far more depth than
// glPolygonOffset's units cover. Each corner is pulled towards the camera by `u_pull_ulps` of
// that spacing (a fixed distance per corner: a pull in proportion to the distance would pull
// far walls past the floors they meet).
layout(location = 0) in vec4 a_position;

uniform mat4 u_view_proj; // world -> camera clip
uniform vec3 u_camera;    // the camera's position
uniform float u_pull_ulps;

void main() {
    vec3 p = a_position.xyz;
    vec3 to_camera = u_camera - p;
    float d = length(to_camera);
    float spacing = max(max(abs(p.x), abs(p.y)), abs(p.z)) * 1.1920929e-7;
    float pull = min(u_pull_ulps * spacing, 0.5 * d);
    gl_Position = u_view_proj * vec4(p + to_camera * (pull / max(d, 1e-6)), 1.0);
}
