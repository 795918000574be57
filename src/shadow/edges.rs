//! Connectivity for shadow volumes (paper 4.1), built once at load and GL-free.
//!
//! Vertices are welded by exact position, unique edges are found with every triangle on each, and
//! triangle planes are stored in f64. Quake 3 worlds are not 2-manifold: edges with one triangle
//! (open) and with more than two (non-manifold) are normal there and kept as they are.
//! Triangles whose welded corners repeat are not triangles and are left out (counted).

use glam::{DVec3, Vec3};
use serde::Serialize;
use std::collections::HashMap;

/// One unique edge: its welded endpoints (`v[0] < v[1]`) and the triangles on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    pub v: [u32; 2],
    /// Range in [`Connectivity::edge_triangles`].
    pub first: u32,
    pub count: u32,
}

/// A triangle plane `n·p + d = 0`, `n` of unit length (zero for zero-area triangles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrianglePlane {
    pub normal: DVec3,
    pub d: f64,
}

#[derive(Debug, Clone, Default)]
pub struct Connectivity {
    /// Welded positions.
    pub positions: Vec<Vec3>,
    /// Triangles over welded positions, in input order (degenerate ones left out).
    pub triangles: Vec<[u32; 3]>,
    /// For each kept triangle, its index in the input sequence.
    pub source_triangle: Vec<u32>,
    pub planes: Vec<TrianglePlane>,
    pub edges: Vec<Edge>,
    /// Triangle indices of each edge, grouped by edge.
    pub edge_triangles: Vec<u32>,
    /// Input triangles left out because two welded corners coincide.
    pub degenerate: usize,
}

/// Edges by number of triangles: 1 (open), 2 (manifold), more (non-manifold).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct EdgeCounts {
    pub open: usize,
    pub manifold: usize,
    pub non_manifold: usize,
}

/// The key of an exact position; -0.0 and 0.0 weld together.
fn key(p: Vec3) -> [u32; 3] {
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

impl Connectivity {
    /// Builds connectivity from world-space triangles.
    pub fn build(triangles: impl IntoIterator<Item = [Vec3; 3]>) -> Connectivity {
        let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
        let mut c = Connectivity::default();
        for (i, tri) in triangles.into_iter().enumerate() {
            let mut w = [0u32; 3];
            for (k, p) in tri.iter().enumerate() {
                let next = c.positions.len() as u32;
                w[k] = *weld.entry(key(*p)).or_insert_with(|| {
                    c.positions.push(*p + Vec3::ZERO);
                    next
                });
            }
            if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
                c.degenerate += 1;
                continue;
            }
            c.triangles.push(w);
            c.source_triangle.push(i as u32);
        }
        c.planes = c
            .triangles
            .iter()
            .map(|t| {
                let p = |i: u32| c.positions[i as usize].as_dvec3();
                let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
                let len = n.length();
                let normal = if len > 0.0 { n / len } else { DVec3::ZERO };
                TrianglePlane {
                    normal,
                    d: -normal.dot(p(t[0])),
                }
            })
            .collect();
        // Sort (edge, triangle) pairs so each edge's triangles are contiguous.
        let mut pairs: Vec<([u32; 2], u32)> = Vec::with_capacity(c.triangles.len() * 3);
        for (ti, t) in c.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                pairs.push(([a.min(b), a.max(b)], ti as u32));
            }
        }
        pairs.sort_unstable();
        let mut i = 0;
        while i < pairs.len() {
            let v = pairs[i].0;
            let first = c.edge_triangles.len() as u32;
            while i < pairs.len() && pairs[i].0 == v {
                c.edge_triangles.push(pairs[i].1);
                i += 1;
            }
            c.edges.push(Edge {
                v,
                first,
                count: c.edge_triangles.len() as u32 - first,
            });
        }
        c
    }

    pub fn triangles_of(&self, e: &Edge) -> &[u32] {
        &self.edge_triangles[e.first as usize..(e.first + e.count) as usize]
    }

    pub fn counts(&self) -> EdgeCounts {
        let mut c = EdgeCounts::default();
        for e in &self.edges {
            match e.count {
                1 => c.open += 1,
                2 => c.manifold += 1,
                _ => c.non_manifold += 1,
            }
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes::cuboid;

    fn tris(m: &crate::scene::shapes::MeshData) -> Vec<[Vec3; 3]> {
        m.indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| m.vertices[t[k] as usize].pos()))
            .collect()
    }

    #[test]
    fn a_closed_box_welds_to_8_vertices_and_18_manifold_edges() {
        let c = Connectivity::build(tris(&cuboid(Vec3::ZERO, Vec3::ONE, 1.0)));
        assert_eq!(c.positions.len(), 8);
        assert_eq!(c.triangles.len(), 12);
        assert_eq!(
            c.counts(),
            EdgeCounts {
                open: 0,
                manifold: 18,
                non_manifold: 0
            }
        );
        // Planes point outward: the box centre is behind every face.
        for p in &c.planes {
            assert!(p.normal.dot(DVec3::splat(0.5)) + p.d < 0.0);
            assert!((p.normal.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn open_and_non_manifold_edges_are_counted() {
        let (a, b) = (Vec3::ZERO, Vec3::X);
        // Three triangles on edge a-b (a fin), and nothing else shared.
        let fan = vec![[a, b, Vec3::Y], [b, a, Vec3::Z], [a, b, -Vec3::Y]];
        let c = Connectivity::build(fan);
        let counts = c.counts();
        assert_eq!(counts.non_manifold, 1);
        assert_eq!(counts.open, 6);
        assert_eq!(counts.manifold, 0);
        let e = c.edges.iter().find(|e| e.count == 3).unwrap();
        assert_eq!(c.triangles_of(e), &[0, 1, 2]);
    }

    #[test]
    fn degenerate_triangles_are_left_out_and_signed_zero_welds() {
        let c = Connectivity::build(vec![
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::new(-0.0, 0.0, 0.0), Vec3::X, Vec3::X],
        ]);
        assert_eq!(c.degenerate, 1);
        assert_eq!(c.triangles.len(), 1);
        assert_eq!(c.positions.len(), 3, "-0.0 welds with 0.0");
        assert_eq!(c.source_triangle, vec![0]);
    }
}
