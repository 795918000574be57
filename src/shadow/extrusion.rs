//! Shadow volumes extruded on the GPU (`shadow_volume.gpu_extrusion`), GL-free: the mesh the
//! vertex shader (`shaders/volume_gpu.vert`) turns into a light's volume, built once per caster
//! group and pose whatever the light.
//!
//! Every edge becomes a degenerate quad (two where two-sided casting may count it twice),
//! whose four vertices each know the two triangles on the edge. The shader finds how each
//! triangle casts (+1 facing the light, −1 casting turned, two-sided only; 0 not at all) and
//! the edge's net count in the first triangle's winding, `s_A − s_B`, as the CPU build's signed
//! rule does (one-sided, the paper's rule on a manifold edge): where it is 0 the quad collapses
//! to a point, where it is ±1 the quad opens into the edge's side (wound by the sign), where it
//! is ±2 the second quad opens too. An edge with one triangle (open) has a partner that never
//! casts; an edge with more than two gets one quad per triangle with such a partner, which
//! sums to the same count. Caps: each triangle, kept in the winding it casts with (front cap)
//! or sent to infinity reversed (back cap), collapsed where it casts nothing.
//!
//! The tests are the CPU build's (`n·(L − c) > −ε |L − c|` with the centroid, one-sided;
//! the side of the plane beyond `IN_PLANE`, or f32's rounding noise (`GPU_IN_PLANE`),
//! two-sided; never for a triangle without area or with a corner at the light), in f32.

use super::volume::{CasterGroup, IN_PLANE};
use glam::{Vec3, Vec4};

/// Two-sided casting: a light whose offset from a triangle's plane is under this share of the
/// coordinates' size lies in the plane. The CPU's `IN_PLANE` is relative to the distance and
/// works in f64; in f32 the offset of a light meant to lie in the plane is rounding noise of
/// about 2⁻²⁴ of the coordinates, and a triangle read as casting there draws a sliver of
/// shadow along its plane (seen on oa_dm1's ceiling grate before this bound).
pub const GPU_IN_PLANE: f32 = 1e-6;

/// A triangle as the shader sees it: its unit normal (zero: it never casts) and its corners.
pub type Face = [[f32; 3]; 4];

const NEVER: Face = [[0.0; 3]; 4];

/// One vertex of the mesh.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ExtrusionVertex {
    /// Sides: the edge (a, b) in the first triangle's winding. Caps: unused.
    pub edge: [[f32; 3]; 2],
    /// Sides: the corner of the quad (0: b, 1: a, 2: a at infinity, 3: b at infinity), plus 4
    /// for the second quad of a double count, plus 8 where the second triangle runs the edge
    /// the same way as the first (inconsistently wound neighbours). Caps: the triangle's
    /// corner (0, 1, 2).
    pub role: f32,
    /// The first triangle (caps: the triangle itself).
    pub face_a: Face,
    /// The second triangle on the edge (never casting for an open edge; unused by caps).
    pub face_b: Face,
}

/// What one draw of the mesh produces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Sides,
    FrontCap,
    BackCap,
}

impl Role {
    /// The shader's `u_role`.
    pub fn code(self) -> i32 {
        match self {
            Role::Sides => 0,
            Role::FrontCap => 1,
            Role::BackCap => 2,
        }
    }
}

/// A caster group's extrusion mesh: the vertices, and index lists for the sides (two triangles
/// per quad), the front cap and the back cap (the cap triangles reversed).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExtrusionMesh {
    pub vertices: Vec<ExtrusionVertex>,
    pub sides: Vec<u32>,
    pub front_cap: Vec<u32>,
    pub back_cap: Vec<u32>,
}

impl ExtrusionMesh {
    /// The mesh of `group`; `double` adds each edge's second quad (two-sided casting).
    pub fn build(group: &CasterGroup, double: bool) -> ExtrusionMesh {
        let c = &group.connectivity;
        let face = |t: u32| -> Face {
            let [a, b, cc] = c.triangles[t as usize].map(|i| c.positions[i as usize].to_array());
            [c.planes[t as usize].normal.as_vec3().to_array(), a, b, cc]
        };
        let mut mesh = ExtrusionMesh::default();
        for e in &c.edges {
            let tris = c.triangles_of(e);
            let pairs: Vec<(u32, Option<u32>)> = if tris.len() == 2 {
                vec![(tris[0], Some(tris[1]))]
            } else {
                tris.iter().map(|&t| (t, None)).collect()
            };
            for (a_tri, b_tri) in pairs {
                let (a, b) = oriented(c.triangles[a_tri as usize], e.v);
                let same = b_tri.is_some_and(|t| oriented(c.triangles[t as usize], e.v) == (a, b));
                let edge = [c.positions[a as usize], c.positions[b as usize]].map(|p| p.to_array());
                let (face_a, face_b) = (face(a_tri), b_tri.map_or(NEVER, face));
                for unit in 0..if double { 2 } else { 1 } {
                    let first = mesh.vertices.len() as u32;
                    for corner in 0..4 {
                        mesh.vertices.push(ExtrusionVertex {
                            edge,
                            role: (corner + 4 * unit + 8 * usize::from(same)) as f32,
                            face_a,
                            face_b,
                        });
                    }
                    mesh.sides.extend([0, 1, 2, 0, 2, 3].map(|k| first + k));
                }
            }
        }
        for t in 0..c.triangles.len() as u32 {
            let first = mesh.vertices.len() as u32;
            for corner in 0..3 {
                mesh.vertices.push(ExtrusionVertex {
                    edge: [[0.0; 3]; 2],
                    role: corner as f32,
                    face_a: face(t),
                    face_b: NEVER,
                });
            }
            mesh.front_cap.extend([first, first + 1, first + 2]);
            mesh.back_cap.extend([first + 2, first + 1, first]);
        }
        mesh
    }

    /// The indices of `role`.
    pub fn indices(&self, role: Role) -> &[u32] {
        match role {
            Role::Sides => &self.sides,
            Role::FrontCap => &self.front_cap,
            Role::BackCap => &self.back_cap,
        }
    }
}

/// Edge `v` in the winding of triangle `tri`.
fn oriented(tri: [u32; 3], v: [u32; 2]) -> (u32, u32) {
    for k in 0..3 {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        if (a, b) == (v[0], v[1]) || (a, b) == (v[1], v[0]) {
            return (a, b);
        }
    }
    (v[0], v[1])
}

/// How the shader's light casts: where it is, Forsyth's ε, and whether every triangle casts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Caster {
    pub light: Vec3,
    pub epsilon: f32,
    pub two_sided: bool,
}

impl Caster {
    /// How `face` casts: +1 as wound, −1 turned (two-sided only), 0 not at all.
    pub fn sign(&self, face: &Face) -> i32 {
        let n = Vec3::from_array(face[0]);
        let corners = [face[1], face[2], face[3]].map(Vec3::from_array);
        if n == Vec3::ZERO || corners.contains(&self.light) {
            return 0;
        }
        let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
        let d = self.light - centroid;
        let (o, dist) = (n.dot(d), d.length());
        if self.two_sided {
            let noise = GPU_IN_PLANE * (self.light.length() + corners[0].length());
            if o.abs() > noise.max(IN_PLANE as f32 * dist) {
                if o > 0.0 { 1 } else { -1 }
            } else {
                0
            }
        } else {
            i32::from(o > -self.epsilon * dist)
        }
    }

    /// What the shader computes for one vertex (the model of `volume_gpu.vert` the tests
    /// check).
    pub fn shade(&self, v: &ExtrusionVertex, role: Role) -> Vec4 {
        let l = self.light;
        let at = |p: Vec3, far: bool| {
            if far {
                (p - l).extend(0.0)
            } else {
                p.extend(1.0)
            }
        };
        let corner = |k: usize| Vec3::from_array(v.face_a[1 + k]);
        match role {
            Role::Sides => {
                let role = v.role as i32;
                let same = role >= 8;
                let (sa, sb) = (self.sign(&v.face_a), self.sign(&v.face_b));
                // The edge's count in the first triangle's direction: the signed rule
                // two-sided; one-sided, the paper's rule (both facing: nothing).
                let net = if self.two_sided {
                    sa + if same { sb } else { -sb }
                } else if sa == sb {
                    0
                } else if sa != 0 || same {
                    1
                } else {
                    -1
                };
                let unit = if role % 8 >= 4 { 2 } else { 1 };
                let [a, b] = v.edge.map(Vec3::from_array);
                if net.abs() < unit {
                    return a.extend(1.0);
                }
                // Turned: the quad (a, b, b', a'), the other way round.
                let (a, b) = if net > 0 { (a, b) } else { (b, a) };
                match role % 4 {
                    0 => at(b, false),
                    1 => at(a, false),
                    2 => at(a, true),
                    _ => at(b, true),
                }
            }
            Role::FrontCap | Role::BackCap => {
                let s = self.sign(&v.face_a);
                if s == 0 {
                    return corner(0).extend(1.0);
                }
                // A turned triangle casts with corners 1 and 2 swapped.
                let k = v.role as usize;
                let k = if s < 0 { [0, 2, 1][k] } else { k };
                at(corner(k), role == Role::BackCap)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SurfaceOwner;
    use crate::scene::shapes::cuboid;
    use crate::shadow::volume::{EdgeRule, Extrusion, VolumeSettings, build_volume};

    /// The triangles of a cube from -1 to 1.
    fn cube_triangles() -> Vec<[Vec3; 3]> {
        let m = cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0);
        m.indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| m.vertices[t[k] as usize].pos()))
            .collect()
    }

    fn cube_group() -> CasterGroup {
        CasterGroup::build(SurfaceOwner::World, cube_triangles())
    }

    /// The triangles a role draws, without those that collapsed (zero area in every view).
    fn drawn(mesh: &ExtrusionMesh, caster: &Caster, role: Role) -> Vec<[Vec4; 3]> {
        mesh.indices(role)
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| caster.shade(&mesh.vertices[t[k] as usize], role)))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect()
    }

    /// A quad as the cycle of its corners' bits, started at its least corner.
    fn cycle(q: &[Vec4; 4]) -> [[u32; 4]; 4] {
        let bits = q.map(|v| v.to_array().map(f32::to_bits));
        let start = (0..4).min_by_key(|&k| bits[k]).unwrap_or(0);
        [0, 1, 2, 3].map(|k| bits[(start + k) % 4])
    }

    /// The quads left when each quad and one wound the other way round on the same corners
    /// cancel, sorted.
    fn net_quads(quads: &[[Vec4; 4]]) -> Vec<[[u32; 4]; 4]> {
        let mut left: Vec<[[u32; 4]; 4]> = Vec::new();
        for q in quads {
            let reversed = cycle(&[q[0], q[3], q[2], q[1]]);
            match left.iter().position(|c| *c == reversed) {
                Some(i) => {
                    left.swap_remove(i);
                }
                None => left.push(cycle(q)),
            }
        }
        left.sort_unstable();
        left
    }

    /// An open box (a cube less its top face): a caster with open edges.
    fn open_box_group() -> CasterGroup {
        let mut tris = cube_triangles();
        tris.retain(|t| !t.iter().all(|p| p.z == 1.0));
        CasterGroup::build(SurfaceOwner::World, tris)
    }

    /// Two triangles on one edge, both running it the same way (a fold wound inconsistently,
    /// as some Quake 3 brush faces meet), and a third making the edge non-manifold.
    fn folded_group(third: bool) -> CasterGroup {
        let (a, b) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0));
        let mut tris = vec![
            [a, b, Vec3::new(2.0, 1.0, 0.0)],
            [a, b, Vec3::new(-1.0, 1.0, 1.5)],
        ];
        if third {
            tris.push([b, a, Vec3::new(0.5, 1.0, -2.0)]);
        }
        CasterGroup::build(SurfaceOwner::World, tris)
    }

    #[test]
    fn the_mesh_has_a_quad_per_edge_and_a_cap_per_triangle() {
        let mesh = ExtrusionMesh::build(&cube_group(), false);
        // 18 welded edges of 12 triangles: one quad each, and 12 cap triangles.
        assert_eq!(mesh.sides.len(), 18 * 6);
        assert_eq!(mesh.front_cap.len(), 12 * 3);
        assert_eq!(
            ExtrusionMesh::build(&cube_group(), true).sides.len(),
            2 * 18 * 6
        );
    }

    #[test]
    fn casters_extrude_their_silhouettes_and_caps_like_the_cpu_build() {
        let lights = [
            Vec3::new(0.3, 0.2, 5.0),
            Vec3::new(4.0, 3.0, 2.0),
            // Inside the open box: its inner faces cast, turned, when two-sided.
            Vec3::new(0.1, 0.2, 0.3),
        ];
        for (group, two_sided) in [
            (cube_group(), false),
            (cube_group(), true),
            (open_box_group(), false),
            (open_box_group(), true),
            (folded_group(false), false),
            (folded_group(false), true),
            (folded_group(true), false),
            (folded_group(true), true),
        ] {
            let mesh = ExtrusionMesh::build(&group, two_sided);
            for light in lights {
                let s = VolumeSettings {
                    rule: EdgeRule::Paper,
                    extrusion: Extrusion::Infinite,
                    finite_distance: 0.0,
                    facing_epsilon: 1e-4,
                    two_sided,
                };
                let caster = Caster {
                    light,
                    epsilon: 1e-4,
                    two_sided,
                };
                let cpu = build_volume(&group, 0, light.as_dvec3(), &s, true);
                // The same sides, wound the same way, once opposite quads on one edge (which
                // the GPU draws where a non-manifold edge's triangles cancel) are taken out.
                let gpu_quads: Vec<[Vec4; 4]> = mesh
                    .sides
                    .chunks_exact(6)
                    .map(|q| {
                        [q[0], q[1], q[2], q[5]]
                            .map(|i| caster.shade(&mesh.vertices[i as usize], Role::Sides))
                    })
                    .filter(|q| q[0] != q[1])
                    .collect();
                let cpu_quads: Vec<[Vec4; 4]> = cpu.vertices[..cpu.side_vertices]
                    .chunks_exact(6)
                    .map(|t| {
                        let t = t.iter().map(|v| Vec4::from_array(*v)).collect::<Vec<_>>();
                        // Either diagonal: (b, a, b', a, a', b') or (b, a, a', b, a', b').
                        let far_a = if t[3] == t[1] { t[4] } else { t[2] };
                        [t[0], t[1], far_a, t[5]]
                    })
                    .collect();
                assert_eq!(
                    net_quads(&gpu_quads),
                    net_quads(&cpu_quads),
                    "light {light}, two-sided {two_sided}"
                );
                let front = drawn(&mesh, &caster, Role::FrontCap);
                let back = drawn(&mesh, &caster, Role::BackCap);
                assert_eq!(
                    front.len() + back.len(),
                    (cpu.vertices.len() - cpu.side_vertices) / 3
                );
                // The CPU's caps, corner for corner and in the same winding (rotations allowed).
                let cpu_caps: Vec<[Vec4; 3]> = cpu.vertices[cpu.side_vertices..]
                    .chunks_exact(3)
                    .map(|t| [0, 1, 2].map(|k| Vec4::from_array(t[k])))
                    .collect();
                let rotations = |t: &[Vec4; 3]| [*t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]];
                for t in front.iter().chain(&back) {
                    assert!(
                        cpu_caps.iter().any(|c| rotations(c).contains(t)),
                        "cap {t:?} is the CPU's (light {light}, two-sided {two_sided})"
                    );
                }
            }
        }
    }

    #[test]
    fn sides_are_wound_out_of_the_volume() {
        let group = cube_group();
        let mesh = ExtrusionMesh::build(&group, false);
        let light = Vec3::new(0.0, 0.0, 6.0);
        let caster = Caster {
            light,
            epsilon: 0.0,
            two_sided: false,
        };
        // Seen from far below the cube's shadow axis, every side quad's far end is at
        // infinity; each drawn side's normal points away from the shadow's axis.
        for t in drawn(&mesh, &caster, Role::Sides) {
            let finite: Vec<Vec3> = t
                .iter()
                .filter(|v| v.w == 1.0)
                .map(|v| v.truncate())
                .collect();
            let far: Vec<Vec3> = t
                .iter()
                .filter(|v| v.w == 0.0)
                .map(|v| v.truncate())
                .collect();
            assert!(!finite.is_empty() && !far.is_empty());
            // The side's plane passes through the light: its normal from the edge and the
            // direction to infinity.
            let edge_mid = finite.iter().sum::<Vec3>() / finite.len() as f32;
            let pts: Vec<Vec3> = t
                .iter()
                .map(|v| {
                    if v.w == 1.0 {
                        v.truncate()
                    } else {
                        light + v.truncate() * 2.0
                    }
                })
                .collect();
            let n = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
            let outward = Vec3::new(edge_mid.x, edge_mid.y, 0.0);
            assert!(n.dot(outward) > 0.0, "side {t:?} faces in");
        }
    }
}
