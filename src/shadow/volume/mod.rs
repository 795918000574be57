//! Stenciled shadow volumes on the CPU (paper section 4; thesis chapter 3), GL-free.
//!
//! Casters are grouped by owner (the world; each model, in its own model space so its caps reuse
//! the exact vertex arithmetic of its lit pass) and split into connected components, which are the
//! unit of the depth-pass / depth-fail choice. Per light:
//! 1. triangles are classified as facing the light (`n·(L - c) > -ε |L - c|`, Forsyth's ε);
//! 2. edges are extruded by a rule: the paper's world rule (skip an edge only when it is shared by
//!    exactly two facing triangles; otherwise every facing triangle on it extrudes it), extrude
//!    every edge of every facing triangle (the paper's first fix), or the naive 2-manifold rule;
//! 3. side quads run from the edge to infinity, P' = (P.xyz·L.w − L.xyz·P.w, 0) (or a finite
//!    distance); depth-fail adds the facing triangles as the front cap and their flipped
//!    extrusions as the back cap.

mod facing;
mod groups;
mod mesh;
mod near_plane;
mod reach;

pub use facing::*;
pub use groups::*;
pub use mesh::*;
pub use near_plane::*;
pub use reach::*;

use super::edges::Connectivity;
use crate::geometry::Aabb;
pub use crate::options::{EdgeRule, Extrusion};
use crate::scene::{Scene, SurfaceOwner};
use glam::Mat4;
use serde::Serialize;

/// Whether a component's volume is counted in front of (depth-pass) or behind (depth-fail) the
/// visible surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Counting {
    ZPass,
    ZFail,
}

/// A connected set of caster triangles.
#[derive(Debug, Clone)]
pub struct Component {
    /// Triangles of the group's connectivity.
    pub triangles: Vec<u32>,
    /// Edges of the group's connectivity whose triangles belong to this component.
    pub edges: Vec<u32>,
    /// Bounds in the group's space.
    pub bounds: Aabb,
    /// Whether it holds triangles of an alpha-tested material (rays pass through their holes
    /// into the volume through its front cap, so it must count depth-fail).
    pub alpha_tested: bool,
    /// Whether its connected surface has an open edge (one triangle). Depth-pass on such a
    /// piece changed masks on open Quake 3 worlds (ctf_compromise: 20 179 pixels beyond the
    /// edge band against the paper's depth-fail), so the planner keeps it at depth-fail
    /// (`plan.open_depth_fail`). Chunks take their component's.
    pub open: bool,
}

/// Which piece of a caster group a volume is extruded from: a whole connected component (the
/// paper's frame) or one chunk of one (the planner's unit, `plan.cull_casters`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PieceRef {
    Component(usize),
    Chunk(usize),
}

/// The casters of one owner, welded, with their connectivity and components.
#[derive(Debug, Clone)]
pub struct CasterGroup {
    pub owner: SurfaceOwner,
    pub connectivity: Connectivity,
    pub components: Vec<Component>,
    /// The same triangles in pieces of at most [`CHUNK_TRIANGLES`]: each component split in
    /// space. A piece's volume is closed on its own (its cut edges are extruded like open
    /// edges), so the planner can cull pieces of a large connected world one by one.
    pub chunks: Vec<Component>,
    /// How the components were cut into `chunks`, children before parents: a component of
    /// more than one chunk has a node for each cut.
    pub chunk_tree: Vec<ChunkNode>,
    /// The owner's pose it was built from (`ModelInstance::pose`; 0 for the world).
    pub pose: u64,
}

/// One cut of [`split_chunks`]: the chunks `first..end` (consecutive: each half's chunks follow
/// one another) are the halves `first..mid` and `mid..end` of one piece of a component. Two
/// neighbouring halves share the edges along the cut, where each half's volume has a side the
/// other's cancels; drawn as one piece, those sides go away.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkNode {
    pub first: usize,
    pub mid: usize,
    pub end: usize,
}

/// Every caster group of a scene, built once per scene. Shared, so that reposing a model
/// builds its own group and copies no other (the world's is the scene's largest).
#[derive(Debug, Clone, Default)]
pub struct CasterGroups {
    pub groups: Vec<std::sync::Arc<CasterGroup>>,
}

/// A group's transform to world space.
pub fn group_transform(scene: &Scene, owner: SurfaceOwner) -> Mat4 {
    match owner {
        SurfaceOwner::World => Mat4::IDENTITY,
        SurfaceOwner::Model(m) => scene.models[m].transform,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes::{MeshData, cuboid, sphere, torus};
    use glam::{DVec3, Vec3};

    fn tris(m: &MeshData) -> Vec<[Vec3; 3]> {
        m.indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| m.vertices[t[k] as usize].pos()))
            .collect()
    }

    fn settings(rule: EdgeRule) -> VolumeSettings {
        VolumeSettings {
            rule,
            extrusion: Extrusion::Infinite,
            finite_distance: 1000.0,
            facing_epsilon: 0.0,
            two_sided: false,
        }
    }

    /// Every vertex of the extruded edges has even degree: the silhouette is closed loops.
    fn silhouette_is_closed(mesh: &VolumeMesh) -> bool {
        let mut degree = std::collections::HashMap::new();
        for q in mesh.vertices[..mesh.side_vertices].chunks_exact(6) {
            // Quad (b, a, a', b', ...): its edge is a-b.
            for v in [q[0], q[1]] {
                *degree.entry(v.map(f32::to_bits)).or_insert(0) += 1;
            }
        }
        degree.values().all(|d| d % 2 == 0)
    }

    #[test]
    fn closed_meshes_give_closed_silhouettes_and_finite_geometry() {
        let light = DVec3::new(3.0, 4.0, 12.0);
        for m in [
            cuboid(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 2.0, 3.0), 1.0),
            sphere(Vec3::new(0.5, 0.0, 2.0), 2.0, 24, 12),
            torus(Vec3::ZERO, 3.0, 1.0, 32, 16, 50.0),
        ] {
            let g = CasterGroup::build(SurfaceOwner::World, tris(&m));
            assert_eq!(g.components.len(), 1);
            let v = build_volume(&g, 0, light, &settings(EdgeRule::Paper), true);
            assert!(v.quads > 0 && v.facing > 0);
            assert!(silhouette_is_closed(&v), "open silhouette");
            assert!(v.vertices.iter().all(|p| p.iter().all(|x| x.is_finite())));
            assert_eq!(v.cap_vertices, 6 * v.facing);
            // On a closed 2-manifold the paper's rule and the manifold rule agree.
            let m2 = build_volume(&g, 0, light, &settings(EdgeRule::Manifold), true);
            assert_eq!(m2.quads, v.quads);
        }
    }

    /// The receiver cull leaves out the half of a floor whose shadow reaches no receiver,
    /// and a wall beside it; the half comes back (a silhouette edge across the floor would
    /// close the kept half with a side quad rising from the floor itself, which ties with it
    /// in the depth test), the wall, on another plane, stays out. Made to fail by keeping
    /// nothing back: 4 culled, 4 quads (the floor's kept half closed along x = 100).
    #[test]
    fn the_receiver_cull_splits_no_flat_surface() {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| [[a, b, c], [a, c, d]];
        let mut triangles = Vec::new();
        // Two floor halves facing up (x 0..100 and 100..200), and a wall at x = 200 facing -x.
        triangles.extend(quad(
            p(0., 0., 0.),
            p(100., 0., 0.),
            p(100., 100., 0.),
            p(0., 100., 0.),
        ));
        triangles.extend(quad(
            p(100., 0., 0.),
            p(200., 0., 0.),
            p(200., 100., 0.),
            p(100., 100., 0.),
        ));
        triangles.extend(quad(
            p(200., 0., 0.),
            p(200., 0., 50.),
            p(200., 100., 50.),
            p(200., 100., 0.),
        ));
        let g = CasterGroup::build(SurfaceOwner::World, triangles);
        assert_eq!(g.components.len(), 1);
        // Receivers under the first half only: the second half's shadow falls past x = 105.
        let boxes = [crate::geometry::Aabb {
            min: p(0., 0., -50.),
            max: p(100., 100., -10.),
        }];
        let cull = |whole_planes| ReceiverCull {
            boxes: &boxes,
            radius: 1000.0,
            truncate: false,
            whole_planes,
        };
        let light = DVec3::new(50.0, 50.0, 100.0);
        let s = settings(EdgeRule::Paper);
        let v = build_volume_of(&g, &g.components[0], light, &s, false, Some(cull(true)));
        assert_eq!((v.culled, v.facing), (2, 4), "the wall alone left out");
        // The floor's outline: two edges along y = 0, two along y = 100, x = 0 and x = 200.
        assert_eq!(v.quads, 6);
        // `shadow_volume.cull_whole_planes = false`: the kept half closed along x = 100.
        let split = build_volume_of(&g, &g.components[0], light, &s, false, Some(cull(false)));
        assert_eq!((split.culled, split.facing, split.quads), (4, 2, 4));
    }

    #[test]
    fn a_cube_under_a_light_above_has_a_four_edge_silhouette() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let v = build_volume(
            &g,
            0,
            DVec3::new(0.0, 0.0, 10.0),
            &settings(EdgeRule::Paper),
            false,
        );
        // Only the top face (2 triangles) faces the light; its 4 outer edges extrude.
        assert_eq!((v.facing, v.quads), (2, 4));
        assert_eq!(v.cap_vertices, 0);
        let all = build_volume(
            &g,
            0,
            DVec3::new(0.0, 0.0, 10.0),
            &settings(EdgeRule::All),
            false,
        );
        assert_eq!(all.quads, 6, "extrude-all adds the diagonal twice");
    }

    #[test]
    fn open_and_non_manifold_edges_follow_each_rule() {
        // A quad (two triangles) facing up, plus a third triangle on its diagonal (a fin).
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        let fin = [a, c, Vec3::new(0.5, 0.5, 1.0)];
        let g = CasterGroup::build(SurfaceOwner::World, vec![[a, b, c], [a, c, d], fin]);
        let light = DVec3::new(0.3, 0.2, 10.0);
        let paper = build_volume(&g, 0, light, &settings(EdgeRule::Paper), false);
        let manifold = build_volume(&g, 0, light, &settings(EdgeRule::Manifold), false);
        // Paper: the 4 open outer edges, the diagonal once per facing triangle on it (3 triangles
        // there), and the fin's own open edges if it faces the light.
        assert!(paper.quads >= 4 + 2);
        // The naive rule never extrudes open edges: the outer boundary is missing.
        assert!(
            manifold.quads < 4,
            "manifold rule extruded {}",
            manifold.quads
        );
    }

    #[test]
    fn components_split_disconnected_casters_and_bound_them() {
        let mut t = tris(&cuboid(Vec3::ZERO, Vec3::ONE, 1.0));
        t.extend(tris(&cuboid(Vec3::splat(5.0), Vec3::splat(6.0), 1.0)));
        let g = CasterGroup::build(SurfaceOwner::World, t);
        assert_eq!(g.components.len(), 2);
        assert_eq!(g.components[1].bounds.min, Vec3::splat(5.0));
        let light = DVec3::new(3.0, 3.0, 20.0);
        let v0 = build_volume(&g, 0, light, &settings(EdgeRule::Paper), true);
        let v1 = build_volume(&g, 1, light, &settings(EdgeRule::Paper), true);
        assert!(v0.quads >= 4 && v1.quads >= 4);
    }

    #[test]
    fn the_near_plane_test_spots_views_inside_a_shadow() {
        let caster = Aabb {
            min: Vec3::new(-1.0, -1.0, 4.0),
            max: Vec3::new(1.0, 1.0, 5.0),
        };
        let light = Vec3::new(0.0, 0.0, 10.0);
        // Straight below the caster: inside its infinite shadow.
        assert!(potentially_inside_shadow(&caster, Vec3::ZERO, light, 0.1));
        // Off to the side: safe for depth-pass.
        assert!(!potentially_inside_shadow(
            &caster,
            Vec3::new(20.0, 0.0, 0.0),
            light,
            0.1
        ));
        // Near the caster, within the near-plane stretch.
        assert!(potentially_inside_shadow(
            &caster,
            Vec3::new(1.5, 0.0, 4.5),
            light,
            1.0
        ));
    }

    #[test]
    fn the_triangle_near_plane_test_is_conservative_and_finer_than_the_box() {
        // A 20x20 floor facing up at z = 5 and a cube on it; the light just above the floor.
        let mut t = vec![
            [
                Vec3::new(-10.0, -10.0, 5.0),
                Vec3::new(10.0, -10.0, 5.0),
                Vec3::new(10.0, 10.0, 5.0),
            ],
            [
                Vec3::new(-10.0, -10.0, 5.0),
                Vec3::new(10.0, 10.0, 5.0),
                Vec3::new(-10.0, 10.0, 5.0),
            ],
        ];
        t.extend(tris(&cuboid(
            Vec3::new(2.0, 2.0, 5.0),
            Vec3::new(3.0, 3.0, 6.0),
            1.0,
        )));
        let g = CasterGroup::build(SurfaceOwner::World, t);
        let piece = Component {
            triangles: (0..g.connectivity.triangles.len() as u32).collect(),
            edges: Vec::new(),
            bounds: g
                .components
                .iter()
                .fold(Aabb::EMPTY, |b, c| b.union(&c.bounds)),
            alpha_tested: false,
            open: false,
        };
        let light = DVec3::new(0.0, 0.0, 5.5);
        let near_test =
            |quad: &[DVec3; 4]| near_plane_shadowed(&g, &piece, light, quad, 0.0, false);
        let quad_at = |c: DVec3, half: f64| {
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, y)| c + DVec3::new(x * half, y * half, 0.0))
        };
        // Above the floor, beside the cube: the box test says depth-fail, the triangles say no
        // segment from the light to the near plane crosses a facing triangle.
        let open = quad_at(DVec3::new(-6.0, 0.0, 7.0), 0.1);
        assert!(potentially_inside_shadow(
            &piece.bounds,
            open[0].as_vec3(),
            light.as_vec3(),
            0.1
        ));
        assert!(!near_test(&open));
        // Below the floor, and behind the cube: in shadow.
        assert!(near_test(&quad_at(DVec3::new(0.0, 0.0, 2.0), 0.1)));
        assert!(near_test(&quad_at(DVec3::new(5.0, 5.0, 6.5), 0.1)));
        // A point (the eye, under depth clamping): the segment to the light alone.
        assert!(near_test(&[DVec3::new(0.0, 0.0, 2.0); 4]));
        assert!(!near_test(&[DVec3::new(-6.0, 0.0, 7.0); 4]));
        // Never false where a point of the rectangle is in shadow (random rectangles, points
        // on a grid over each, segments against every facing triangle).
        let facing = facing_flags_of(&g, &piece, light, 0.0);
        let crosses = |q: DVec3| {
            piece
                .triangles
                .iter()
                .filter(|&&t| facing[t as usize])
                .any(|&t| {
                    let [a, b, c] = g.connectivity.triangles[t as usize]
                        .map(|v| g.connectivity.positions[v as usize].as_dvec3());
                    segment_hits_triangle(light, q, a, b, c)
                })
        };
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut shadowed, mut refined) = (0, 0);
        for _ in 0..400 {
            let c = DVec3::new(rnd() * 24.0 - 12.0, rnd() * 24.0 - 12.0, rnd() * 6.0 + 2.0);
            let quad = quad_at(c, 0.05 + rnd() * 0.5);
            let any = (0..=4).any(|i| {
                (0..=4).any(|j| {
                    let (u, v) = (i as f64 / 4.0, j as f64 / 4.0);
                    crosses(quad[0].lerp(quad[1], u).lerp(quad[3].lerp(quad[2], u), v))
                })
            });
            let test = near_test(&quad);
            assert!(
                test || !any,
                "rectangle at {c} is in shadow but the test says not"
            );
            shadowed += any as usize;
            refined += (!test) as usize;
        }
        assert!(
            shadowed > 20 && refined > 100,
            "{shadowed} shadowed, {refined} refined"
        );
    }

    /// Whether the segment p→q crosses triangle abc (Möller–Trumbore, edges included).
    fn segment_hits_triangle(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
        let d = q - p;
        let (e1, e2) = (b - a, c - a);
        let h = d.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-12 {
            return false;
        }
        let s = (p - a) / det;
        let u = s.dot(h);
        let qv = s.cross(e1);
        let v = d.dot(qv);
        let t = e2.dot(qv);
        (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&t)
    }

    /// Generalised winding number of the closed triangle soup `vertices` (w = 1) at `p`: the
    /// signed solid angles of its triangles over 4π (Van Oosterom and Strackee).
    fn winding(vertices: &[[f32; 4]], p: DVec3) -> f64 {
        let mut total = 0.0;
        for t in vertices.chunks_exact(3) {
            let [a, b, c] =
                [t[0], t[1], t[2]].map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) - p);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let num = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            total += 2.0 * num.atan2(den);
        }
        total / (4.0 * std::f64::consts::PI)
    }

    #[test]
    fn a_truncated_volume_holds_exactly_the_shadowed_receiver_points() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let light = DVec3::new(0.3, 0.2, 10.0);
        let floor = Aabb {
            min: Vec3::new(-20.0, -20.0, -3.0),
            max: Vec3::new(20.0, 20.0, -2.0),
        };
        let cull = |truncate| {
            Some(ReceiverCull {
                boxes: std::slice::from_ref(&floor),
                radius: 100.0,
                truncate,
                whole_planes: true,
            })
        };
        let s = settings(EdgeRule::Paper);
        for with_caps in [false, true] {
            let v = build_volume_of(&g, &g.components[0], light, &s, with_caps, cull(true));
            assert!(v.truncated);
            let infinite = build_volume_of(&g, &g.components[0], light, &s, with_caps, cull(false));
            assert!(!infinite.truncated && infinite.quads == v.quads);
            // Finite everywhere, closed by a far cap even without the depth-fail caps, and the
            // far cap just below the floor box.
            assert!(v.vertices.iter().all(|p| p[3] == 1.0));
            let far = &v.vertices[v.side_vertices..v.side_vertices + v.back_cap_vertices];
            assert_eq!(far.len(), 3 * v.facing);
            assert!(far.iter().all(|p| p[2] < -3.0 && p[2] > -6.0), "{far:?}");
            if !with_caps {
                assert_eq!(v.cap_vertices, 3 * v.facing);
                continue;
            }
            // A point of the floor box is inside the volume exactly when the cube hides the
            // light from it.
            let (mut inside, mut outside) = (0, 0);
            for i in 0..21 {
                for j in 0..21 {
                    let p = DVec3::new(-5.05 + 0.5 * i as f64, -5.05 + 0.5 * j as f64, -2.5);
                    let shadowed = (0..=1000).any(|k| {
                        let q = p + (light - p) * (k as f64 / 1000.0);
                        q.abs().max_element() <= 1.0
                    });
                    let w = winding(&v.vertices, p);
                    assert!(
                        (w.abs() - if shadowed { 1.0 } else { 0.0 }).abs() < 1e-6,
                        "{p} {w}"
                    );
                    if shadowed {
                        inside += 1;
                    } else {
                        outside += 1;
                    }
                }
            }
            assert!(inside > 20 && outside > 20, "{inside} {outside}");
        }
    }

    #[test]
    fn a_piece_split_in_two_holds_what_the_whole_holds() {
        // A slab of sixteen boxes welded into one component under a light.
        let mut t = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = (i as f32 - 2.0, j as f32 - 2.0);
                t.extend(tris(&cuboid(
                    Vec3::new(x, y, 0.0),
                    Vec3::new(x + 1.0, y + 1.0, 0.5),
                    1.0,
                )));
            }
        }
        let g = CasterGroup::build(SurfaceOwner::World, t);
        let light = DVec3::new(0.2, 0.1, 6.0);
        // Finite and capped: every part is a closed mesh of finite points.
        let mut s = settings(EdgeRule::Signed);
        s.extrusion = Extrusion::Finite;
        s.finite_distance = 20.0;
        let (mut inside, mut checked) = (0, 0);
        for c in &g.components {
            // Every other triangle on one side of the cut.
            let a = g.subset(c, |tri| tri % 2 == 0);
            let b = g.subset(c, |tri| tri % 2 == 1);
            assert_eq!(a.triangles.len() + b.triangles.len(), c.triangles.len());
            assert!(a.edges.len() < c.edges.len() && b.edges.len() < c.edges.len());
            let mesh = |piece: &Component| build_volume_of(&g, piece, light, &s, true, None);
            let (whole, ma, mb) = (mesh(c), mesh(&a), mesh(&b));
            assert!(ma.facing > 0 && mb.facing > 0);
            // The parts' winding numbers add up to the whole's everywhere (points off the
            // slab's faces, in and out of its shadow).
            for i in 0..9 {
                for j in 0..9 {
                    let p = DVec3::new(-3.93 + i as f64, -3.87 + j as f64, -1.3 - 0.1 * j as f64);
                    let w = winding(&whole.vertices, p);
                    let sum = winding(&ma.vertices, p) + winding(&mb.vertices, p);
                    assert!((w - sum).abs() < 1e-6, "{p}: {w} against {sum}");
                    inside += (w.abs() > 0.5) as usize;
                    checked += 1;
                }
            }
        }
        assert!(inside > 10 && inside < checked, "{inside} of {checked}");
    }

    #[test]
    fn finite_extrusion_ends_at_its_distance() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let mut s = settings(EdgeRule::Paper);
        s.extrusion = Extrusion::Finite;
        s.finite_distance = 50.0;
        let light = DVec3::new(0.0, 0.0, 10.0);
        let v = build_volume(&g, 0, light, &s, true);
        for p in &v.vertices {
            assert_eq!(p[3], 1.0);
            let d = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64).distance(light);
            assert!(d < 62.0, "{d}");
        }
    }

    /// Two quads side by side in one plane, one facing the light and one (one-sided) facing
    /// away: an open surface seen from behind in part.
    fn half_turned_floor() -> CasterGroup {
        let (a, b, c, d) = (
            Vec3::new(-2.0, -1.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-2.0, 1.0, 0.0),
        );
        let (e, f) = (Vec3::new(2.0, -1.0, 0.0), Vec3::new(2.0, 1.0, 0.0));
        let up = [[a, b, c], [a, c, d]];
        let down = [[b, f, e], [b, c, f]];
        CasterGroup::build(SurfaceOwner::World, up.into_iter().chain(down).collect())
    }

    #[test]
    fn two_sided_casting_shadows_what_any_face_hides_and_one_sided_loses_the_turned_half() {
        let g = half_turned_floor();
        let light = DVec3::new(0.3, 0.2, 10.0);
        let s = VolumeSettings {
            extrusion: Extrusion::Finite,
            finite_distance: 100.0,
            ..settings(EdgeRule::Paper)
        };
        let grid = || {
            (0..25).flat_map(|i| {
                (0..13)
                    .map(move |j| DVec3::new(-6.05 + 0.5 * i as f64, -3.05 + 0.5 * j as f64, -3.0))
            })
        };
        // Hidden from the light by either quad (the reference counts every face as solid).
        let hidden = |p: DVec3| {
            let t = p.z / (p.z - light.z);
            let q = p + (light - p) * t;
            q.x.abs() <= 2.0 && q.y.abs() <= 1.0
        };
        let count = |two_sided: bool| {
            let s = VolumeSettings { two_sided, ..s };
            let v = build_volume_of(&g, &g.components[0], light, &s, true, None);
            let windings: Vec<(DVec3, f64)> =
                grid().map(|p| (p, winding(&v.vertices, p))).collect();
            // Closed and wound one way: every count 0 or the same ±1 (a count of the other
            // sign would cancel in the stencil, or saturate at 0 and light the point).
            let sign = windings
                .iter()
                .map(|w| w.1)
                .find(|w| w.abs() > 0.5)
                .unwrap_or(1.0);
            for &(p, w) in &windings {
                assert!(
                    w.abs() < 1e-6 || (w - sign.signum()).abs() < 1e-6,
                    "{p} {w}"
                );
            }
            windings
                .iter()
                .filter(|(p, w)| (w.abs() > 0.5) != hidden(*p))
                .count()
        };
        let hidden_points = grid().filter(|&p| hidden(p)).count();
        assert!(hidden_points > 40, "{hidden_points}");
        assert_eq!(count(true), 0);
        // One-sided (the paper): the turned half casts nothing.
        assert!(count(false) * 3 > hidden_points, "{}", count(false));
    }

    #[test]
    fn a_light_on_a_cubes_vertex_or_edge_keeps_the_cubes_whole_shadow_when_casting_two_sided() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let s = VolumeSettings {
            two_sided: true,
            // The winding test reads positions, not points at infinity.
            extrusion: Extrusion::Finite,
            finite_distance: 100.0,
            ..settings(EdgeRule::Signed)
        };
        // Hidden: the segment to the light passes through the cube's inside.
        let hidden = |p: DVec3, light: DVec3| {
            (1..200).any(|k| {
                let q = p + (light - p) * (k as f64 / 200.0);
                q.abs().max_element() < 1.0 - 1e-6
            })
        };
        for light in [DVec3::new(1.0, 1.0, 1.0), DVec3::new(0.0, 1.0, 1.0)] {
            let sides = light_sides_of(&g, &g.components[0], light);
            let in_plane = sides.iter().filter(|&&x| x == LightSide::InPlane).count();
            assert_eq!(in_plane, if light.x == 0.0 { 4 } else { 6 }, "{light}");
            assert!(sides.iter().all(|&x| x != LightSide::Front));
            let v = build_volume_of(&g, &g.components[0], light, &s, true, None);
            let mut wrong = 0;
            let mut shadowed = 0;
            for i in 0..21 {
                for j in 0..21 {
                    // A floor under the cube, off its planes and the light's.
                    let p = DVec3::new(-5.03 + 0.5 * i as f64, -5.07 + 0.5 * j as f64, -4.0);
                    let inside = winding(&v.vertices, p).abs() > 0.5;
                    shadowed += inside as usize;
                    wrong += (inside != hidden(p, light)) as usize;
                }
            }
            assert!(shadowed > 50, "{light}: {shadowed}");
            assert_eq!(wrong, 0, "{light}");
        }
    }
}
