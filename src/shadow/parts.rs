//! Convex parts: the triangles of each caster group (the world, each model copy) grouped
//! greedily into pieces of convex surface, for the ID and priority buffers (Forsyth's slides:
//! "IDs per convex sub-object need pre-processing"). A convex part cannot shadow itself from
//! any light outside it, so giving it one ID loses no shadow the ID buffer could show.
//!
//! The decomposition is an approximation, not the fewest parts: triangles are joined across
//! shared edges (positions welded) while every triangle of the part keeps every vertex of the
//! part on or behind its plane. Parts are capped at [`MAX_PART_TRIANGLES`], which bounds the
//! cost (each join checks the part's distinct planes) and splits large convex pieces (a long
//! flat floor becomes several parts; it still cannot shadow itself, only the ID changes).

pub use crate::options::IdUnit;
use crate::scene::Scene;
use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// Largest part, in triangles.
pub const MAX_PART_TRIANGLES: usize = 512;

/// Distance within which a vertex counts as on a plane: welded Quake 3 brushes are exact to
/// about 1e-3 units; curved patches are tessellated from smooth control nets.
const CONVEX_EPSILON: f64 = 0.05;

/// The ID of every triangle of the scene, surface by surface in `Scene::surfaces` order and in
/// index order within a surface (so `ids[first_index / 3 + k]` in scene index space), with
/// the number of distinct IDs.
pub fn triangle_ids(scene: &Scene, unit: IdUnit) -> (Vec<u32>, u32) {
    let triangles = scene.indices.len() / 3;
    match unit {
        IdUnit::Triangle => ((0..triangles as u32).collect(), triangles as u32),
        IdUnit::Surface => {
            let mut ids = vec![0u32; triangles];
            for (i, s) in scene.surfaces.iter().enumerate() {
                let first = s.first_index as usize / 3;
                let n = s.index_count as usize / 3;
                ids[first..first + n].fill(i as u32);
            }
            (ids, scene.surfaces.len() as u32)
        }
        IdUnit::Part => convex_parts(scene),
    }
}

/// What the depth and lit passes read per triangle for a priority buffer lit from `at`:
/// `[lo, width, nearest, 1 / (farthest - nearest)]`, the unit's slot of depth (`lo` to
/// `lo + width`) and its range of distances from the light. Units are ranked by the distance
/// of their vertices' mean (by the nearest vertex, a floor reaching under the light would come
/// before every post standing on it: the grazing hard case loses all its shadow); slot k is `[(k + 1/4) / n, (k + 3/4) / n)`, so any two units' slots are
/// a quarter slot apart (far above a 24-bit depth's step for any count below a million).
///
/// Units wholly beyond `radius` rank after every unit within it, so that what moves out of the
/// light's range changes no rank within it (the light's maps stay valid).
pub fn priority_entries(
    scene: &Scene,
    ids: &[u32],
    units: u32,
    at: Vec3,
    radius: f32,
) -> Vec<[f32; 4]> {
    let at = at.as_dvec3();
    let mut range = vec![(f64::INFINITY, f64::NEG_INFINITY); units as usize];
    let mut centre = vec![(DVec3::ZERO, 0u32); units as usize];
    for s in &scene.surfaces {
        let transform = scene.surface_transform(s).as_dmat4();
        let first = s.first_index as usize;
        for (k, tri) in scene.indices[first..first + s.index_count as usize]
            .chunks_exact(3)
            .enumerate()
        {
            let unit = ids[first / 3 + k] as usize;
            let (Some(r), Some(c)) = (range.get_mut(unit), centre.get_mut(unit)) else {
                continue;
            };
            for &i in tri {
                let p = transform.transform_point3(scene.vertices[i as usize].pos().as_dvec3());
                let d = p.distance(at);
                if d.is_finite() {
                    *r = (r.0.min(d), r.1.max(d));
                    *c = (c.0 + p, c.1 + 1);
                }
            }
        }
    }
    let mut order: Vec<u32> = (0..units).collect();
    let key: Vec<(bool, f64)> = centre
        .iter()
        .zip(&range)
        .map(|((sum, n), (near, _))| {
            let beyond = near.is_nan() || *near >= radius as f64;
            let d = if *n == 0 {
                f64::INFINITY
            } else {
                (*sum / *n as f64).distance(at)
            };
            (beyond, d)
        })
        .collect();
    order.sort_by(|a, b| {
        let (ka, kb) = (key[*a as usize], key[*b as usize]);
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    let mut rank = vec![0u32; units as usize];
    for (r, u) in order.iter().enumerate() {
        rank[*u as usize] = r as u32;
    }
    let slot = 1.0 / units.max(1) as f64;
    ids.iter()
        .map(|&id| {
            let Some(&(near, far)) = range.get(id as usize) else {
                return [0.0; 4];
            };
            let lo = (rank[id as usize] as f64 + 0.25) * slot;
            let spread = if far > near { 1.0 / (far - near) } else { 0.0 };
            [lo as f32, (0.5 * slot) as f32, near as f32, spread as f32]
        })
        .collect()
}

/// World-space triangles of one caster group, with their index in scene index space.
fn group_triangles(scene: &Scene) -> HashMap<usize, Vec<(usize, [DVec3; 3])>> {
    let mut groups: HashMap<_, Vec<_>> = HashMap::new();
    for s in &scene.surfaces {
        let transform = scene.surface_transform(s).as_dmat4();
        let first = s.first_index as usize;
        let range = first..first + s.index_count as usize;
        for (k, tri) in scene.indices[range].chunks_exact(3).enumerate() {
            let v = [0, 1, 2].map(|j| {
                transform.transform_point3(scene.vertices[tri[j] as usize].pos().as_dvec3())
            });
            let group = match s.owner {
                crate::scene::SurfaceOwner::World => 0,
                crate::scene::SurfaceOwner::Model(m) => m + 1,
            };
            groups.entry(group).or_default().push((first / 3 + k, v));
        }
    }
    groups
}

/// Unit normal and offset of a triangle's plane, None when degenerate.
fn plane(v: &[DVec3; 3]) -> Option<(DVec3, f64)> {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let len = n.length();
    (len > 1e-12 && len.is_finite()).then(|| {
        let n = n / len;
        (n, n.dot(v[0]))
    })
}

/// Convex parts of every caster group: the part ID of each triangle (scene index space) and
/// the number of parts. Degenerate triangles get a part of their own.
pub fn convex_parts(scene: &Scene) -> (Vec<u32>, u32) {
    let mut ids = vec![u32::MAX; scene.indices.len() / 3];
    let mut next = 0u32;
    let mut groups: Vec<_> = group_triangles(scene).into_iter().collect();
    // Deterministic IDs: groups in a fixed order.
    groups.sort_by_key(|(_, tris)| tris.first().map_or(0, |t| t.0));
    for (_, tris) in groups {
        for part in parts_of(&tris) {
            for local in part {
                ids[tris[local].0] = next;
            }
            next += 1;
        }
    }
    (ids, next)
}

/// Welded edge → triangles (local indices) sharing it.
fn edge_map(tris: &[(usize, [DVec3; 3])]) -> HashMap<([u64; 3], [u64; 3]), Vec<usize>> {
    let key = |p: DVec3| p.to_array().map(|c| (c * 1024.0).round().to_bits());
    let mut edges: HashMap<_, Vec<usize>> = HashMap::new();
    for (i, (_, v)) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (key(v[k]), key(v[(k + 1) % 3]));
            let e = if a < b { (a, b) } else { (b, a) };
            edges.entry(e).or_default().push(i);
        }
    }
    edges
}

/// Greedy growth over shared edges; each part a list of local triangle indices.
fn parts_of(tris: &[(usize, [DVec3; 3])]) -> Vec<Vec<usize>> {
    let edges = edge_map(tris);
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); tris.len()];
    for sharing in edges.values() {
        for &a in sharing {
            for &b in sharing {
                if a != b {
                    neighbours[a].push(b);
                }
            }
        }
    }
    // The map's order changes from run to run, and the greedy growth follows the neighbours'
    // order: sorted, the parts are the same every run.
    for n in &mut neighbours {
        n.sort_unstable();
        n.dedup();
    }
    let planes: Vec<Option<(DVec3, f64)>> = tris.iter().map(|(_, v)| plane(v)).collect();
    let mut taken = vec![false; tris.len()];
    let mut parts = Vec::new();
    for seed in 0..tris.len() {
        if taken[seed] {
            continue;
        }
        taken[seed] = true;
        let mut part = vec![seed];
        let Some(p0) = planes[seed] else {
            parts.push(part);
            continue;
        };
        let mut part_planes = vec![p0];
        let mut points: Vec<DVec3> = tris[seed].1.to_vec();
        let mut frontier = vec![seed];
        while let Some(t) = frontier.pop() {
            for &c in &neighbours[t] {
                if taken[c] || part.len() >= MAX_PART_TRIANGLES {
                    continue;
                }
                let Some(pc) = planes[c] else { continue };
                let v = &tris[c].1;
                let behind_all = v.iter().all(|x| {
                    part_planes
                        .iter()
                        .all(|(n, d)| n.dot(*x) - d <= CONVEX_EPSILON)
                });
                let all_behind_it = points.iter().all(|x| pc.0.dot(*x) - pc.1 <= CONVEX_EPSILON);
                if !(behind_all && all_behind_it) {
                    continue;
                }
                taken[c] = true;
                part.push(c);
                frontier.push(c);
                points.extend_from_slice(v);
                if !part_planes
                    .iter()
                    .any(|(n, d)| n.dot(pc.0) > 1.0 - 1e-9 && (d - pc.1).abs() < 1e-6)
                {
                    part_planes.push(pc);
                }
            }
        }
        parts.push(part);
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> (usize, [DVec3; 3]) {
        (0, [a, b, c].map(DVec3::from_array))
    }

    /// The 12 triangles of a unit cube, outward facing.
    fn cube() -> Vec<(usize, [DVec3; 3])> {
        let p = |x: f64, y: f64, z: f64| [x, y, z];
        let quads = [
            [p(0., 0., 0.), p(0., 1., 0.), p(1., 1., 0.), p(1., 0., 0.)],
            [p(0., 0., 1.), p(1., 0., 1.), p(1., 1., 1.), p(0., 1., 1.)],
            [p(0., 0., 0.), p(1., 0., 0.), p(1., 0., 1.), p(0., 0., 1.)],
            [p(0., 1., 0.), p(0., 1., 1.), p(1., 1., 1.), p(1., 1., 0.)],
            [p(0., 0., 0.), p(0., 0., 1.), p(0., 1., 1.), p(0., 1., 0.)],
            [p(1., 0., 0.), p(1., 1., 0.), p(1., 1., 1.), p(1., 0., 1.)],
        ];
        quads
            .iter()
            .flat_map(|q| [tri(q[0], q[1], q[2]), tri(q[0], q[2], q[3])])
            .collect()
    }

    /// The greedy growth follows the neighbours' order, which came from a hash map's (random
    /// per map): the same scene must give the same parts every time.
    #[test]
    fn parts_are_the_same_every_run() {
        let scene = crate::scene::builtin::default_scene();
        let first = convex_parts(&scene);
        for _ in 0..8 {
            assert_eq!(convex_parts(&scene), first);
        }
    }

    #[test]
    fn a_cube_is_one_part() {
        assert_eq!(parts_of(&cube()).len(), 1);
    }

    #[test]
    fn an_l_shaped_fold_splits_where_it_is_concave() {
        // Two quads meeting at a concave edge (a floor and a wall rising from it, facing
        // each other): each quad is convex, the pair is not.
        let floor = [
            tri([0., 0., 0.], [1., 0., 0.], [1., 1., 0.]),
            tri([0., 0., 0.], [1., 1., 0.], [0., 1., 0.]),
        ];
        // Wall at x = 0 facing +x (toward the floor).
        let wall = [
            tri([0., 0., 0.], [0., 1., 0.], [0., 1., 1.]),
            tri([0., 0., 0.], [0., 1., 1.], [0., 0., 1.]),
        ];
        let tris: Vec<_> = floor.into_iter().chain(wall).collect();
        let parts = parts_of(&tris);
        assert_eq!(parts.len(), 2, "{parts:?}");
        // The convex fold (the wall facing away, -x) joins.
        let wall_out = [
            tri([0., 0., 0.], [0., 1., 1.], [0., 1., 0.]),
            tri([0., 0., 0.], [0., 0., 1.], [0., 1., 1.]),
        ];
        let floor_down = [
            tri([0., 0., 0.], [1., 1., 0.], [1., 0., 0.]),
            tri([0., 0., 0.], [0., 1., 0.], [1., 1., 0.]),
        ];
        let tris: Vec<_> = floor_down.into_iter().chain(wall_out).collect();
        assert_eq!(parts_of(&tris).len(), 1);
    }

    #[test]
    fn every_part_is_convex() {
        // A staircase: convex and concave folds in turn.
        let mut tris = Vec::new();
        for s in 0..4 {
            let (x, z) = (s as f64, s as f64);
            tris.push(tri([x, 0., z], [x + 1., 0., z], [x + 1., 1., z]));
            tris.push(tri([x, 0., z], [x + 1., 1., z], [x, 1., z]));
            tris.push(tri(
                [x + 1., 0., z],
                [x + 1., 0., z + 1.],
                [x + 1., 1., z + 1.],
            ));
            tris.push(tri([x + 1., 0., z], [x + 1., 1., z + 1.], [x + 1., 1., z]));
        }
        let parts = parts_of(&tris);
        assert!(parts.len() > 1);
        for part in &parts {
            let points: Vec<DVec3> = part.iter().flat_map(|&t| tris[t].1).collect();
            for &t in part {
                let (n, d) = plane(&tris[t].1).unwrap();
                assert!(points.iter().all(|x| n.dot(*x) - d <= CONVEX_EPSILON));
            }
        }
    }
}
