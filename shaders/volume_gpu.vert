// Shadow volumes extruded here rather than on the CPU (`shadow_volume.gpu_extrusion`; the mesh
// and the rules are `src/shadow/extrusion.rs`, whose `Caster::shade` is this shader's model).
// Each vertex knows the triangle(s) that decide it; vertices go to infinity as P - L, w = 0.
layout(location = 0) in vec3 a_edge_a;
layout(location = 1) in vec3 a_edge_b;
layout(location = 2) in float a_role;
layout(location = 3) in vec3 a_normal_a;
layout(location = 4) in vec3 a_corner_a0;
layout(location = 5) in vec3 a_corner_a1;
layout(location = 6) in vec3 a_corner_a2;
layout(location = 7) in vec3 a_normal_b;
layout(location = 8) in vec3 a_corner_b0;
layout(location = 9) in vec3 a_corner_b1;
layout(location = 10) in vec3 a_corner_b2;

uniform mat4 u_model;     // the caster group's space -> world
uniform mat4 u_view_proj; // world -> camera clip
uniform vec3 u_light;     // the light in the group's space
uniform float u_epsilon;  // Forsyth's facing epsilon (one-sided)
uniform int u_two_sided;  // every triangle casts, turned when it faces away
uniform int u_role;       // 0: sides, 1: front cap, 2: back cap

// The same expression as world.vert's, so that front caps land exactly on their casters.
invariant gl_Position;

// How a triangle casts: +1 as wound, -1 turned, 0 not at all.
int cast_sign(vec3 n, vec3 c0, vec3 c1, vec3 c2) {
    if (n == vec3(0.0) || c0 == u_light || c1 == u_light || c2 == u_light) {
        return 0;
    }
    vec3 d = u_light - (c0 + c1 + c2) / 3.0;
    float o = dot(n, d);
    float dist = length(d);
    if (u_two_sided != 0) {
        // In the plane up to f32's rounding of the coordinates (GPU_IN_PLANE).
        float noise = 1e-6 * (length(u_light) + length(c0));
        return abs(o) > max(noise, 1e-9 * dist) ? (o > 0.0 ? 1 : -1) : 0;
    }
    return o > -u_epsilon * dist ? 1 : 0;
}

vec4 at(vec3 p, bool far) {
    return far ? vec4(p - u_light, 0.0) : vec4(p, 1.0);
}

vec4 position() {
    int sa = cast_sign(a_normal_a, a_corner_a0, a_corner_a1, a_corner_a2);
    int role = int(a_role + 0.5);
    if (u_role == 0) {
        int sb = cast_sign(a_normal_b, a_corner_b0, a_corner_b1, a_corner_b2);
        bool same = role >= 8; // the second triangle runs the edge the same way
        // The edge's count in the first triangle's direction: the signed rule two-sided;
        // one-sided, the paper's rule (both facing: nothing).
        int net;
        if (u_two_sided != 0) {
            net = sa + (same ? sb : -sb);
        } else if (sa == sb) {
            net = 0;
        } else {
            net = (sa != 0 || same) ? 1 : -1;
        }
        int unit = (role - 8 * (role / 8)) >= 4 ? 2 : 1;
        if (abs(net) < unit) {
            return vec4(a_edge_a, 1.0); // collapsed: one point
        }
        vec3 a = net > 0 ? a_edge_a : a_edge_b;
        vec3 b = net > 0 ? a_edge_b : a_edge_a;
        int corner = role - 4 * (role / 4);
        if (corner == 0) return at(b, false);
        if (corner == 1) return at(a, false);
        if (corner == 2) return at(a, true);
        return at(b, true);
    }
    if (sa == 0) {
        return vec4(a_corner_a0, 1.0);
    }
    // A turned triangle casts with corners 1 and 2 swapped.
    int k = (sa < 0 && role != 0) ? 3 - role : role;
    vec3 p = k == 0 ? a_corner_a0 : (k == 1 ? a_corner_a1 : a_corner_a2);
    return at(p, u_role == 2);
}

void main() {
    gl_Position = u_view_proj * (u_model * position());
#ifdef HAS_CLIP_DISTANCE
    // The stencil pass enables the planner's depth clip planes; these volumes have none.
    gl_ClipDistance[0] = 1.0;
    gl_ClipDistance[1] = 1.0;
    gl_ClipDistance[2] = 1.0;
    gl_ClipDistance[3] = 1.0;
#endif
}
