//! Procedural meshes for built-in and test scenes, in local space, counter-clockwise front faces.
//!
//! Seam and pole vertices are computed from wrapped indices so that vertices meant to coincide
//! are bit-identical: welding by exact position then yields closed 2-manifolds, which shadow
//! volumes rely on.

use super::Vertex;
use glam::Vec3;
use std::f32::consts::TAU;

/// Vertices and triangle indices of one shape.
#[derive(Debug, Clone, Default)]
pub struct MeshData {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
}

impl MeshData {
    fn push(&mut self, p: Vec3, n: Vec3, uv: [f32; 2]) -> u32 {
        self.vertices.push(Vertex::new(p, n, uv));
        self.vertices.len() as u32 - 1
    }

    /// A planar quad a, b, c, d (counter-clockwise seen from the front) with the given uv scale.
    pub fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3, uv_scale: [f32; 2]) {
        let n = (b - a).cross(d - a).normalize();
        let [su, sv] = uv_scale;
        let i0 = self.push(a, n, [0.0, sv]);
        let i1 = self.push(b, n, [su, sv]);
        let i2 = self.push(c, n, [su, 0.0]);
        let i3 = self.push(d, n, [0.0, 0.0]);
        self.indices.extend_from_slice(&[i0, i1, i2, i0, i2, i3]);
    }

    pub fn translated(mut self, by: Vec3) -> MeshData {
        for v in &mut self.vertices {
            v.position = (Vec3::from_array(v.position) + by).to_array();
        }
        self
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// An axis-aligned box with outward faces; texture repeats every `uv_period` units.
pub fn cuboid(min: Vec3, max: Vec3, uv_period: f32) -> MeshData {
    let mut m = MeshData::default();
    let c = |x: usize, y: usize, z: usize| {
        Vec3::new(
            if x == 0 { min.x } else { max.x },
            if y == 0 { min.y } else { max.y },
            if z == 0 { min.z } else { max.z },
        )
    };
    let s = max - min;
    let p = uv_period;
    // Each face listed counter-clockwise seen from outside.
    m.quad(
        c(0, 0, 0),
        c(0, 1, 0),
        c(1, 1, 0),
        c(1, 0, 0),
        [s.y / p, s.x / p],
    ); // -Z
    m.quad(
        c(0, 0, 1),
        c(1, 0, 1),
        c(1, 1, 1),
        c(0, 1, 1),
        [s.x / p, s.y / p],
    ); // +Z
    m.quad(
        c(0, 0, 0),
        c(1, 0, 0),
        c(1, 0, 1),
        c(0, 0, 1),
        [s.x / p, s.z / p],
    ); // -Y
    m.quad(
        c(1, 1, 0),
        c(0, 1, 0),
        c(0, 1, 1),
        c(1, 1, 1),
        [s.x / p, s.z / p],
    ); // +Y
    m.quad(
        c(0, 1, 0),
        c(0, 0, 0),
        c(0, 0, 1),
        c(0, 1, 1),
        [s.y / p, s.z / p],
    ); // -X
    m.quad(
        c(1, 0, 0),
        c(1, 1, 0),
        c(1, 1, 1),
        c(1, 0, 1),
        [s.y / p, s.z / p],
    ); // +X
    m
}

/// A UV sphere; poles are single positions, the seam is welded.
pub fn sphere(center: Vec3, radius: f32, segments: u32, rings: u32) -> MeshData {
    let segments = segments.max(3);
    let rings = rings.max(2);
    let mut m = MeshData::default();
    let dir = |seg: u32, ring: u32| -> Vec3 {
        if ring == 0 {
            return Vec3::Z;
        }
        if ring == rings {
            return -Vec3::Z;
        }
        let theta = ring as f32 / rings as f32 * std::f32::consts::PI;
        let phi = (seg % segments) as f32 / segments as f32 * TAU;
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    };
    for ring in 0..=rings {
        for seg in 0..=segments {
            let d = dir(seg, ring);
            m.push(
                center + d * radius,
                d,
                [seg as f32 / segments as f32, ring as f32 / rings as f32],
            );
        }
    }
    let idx = |seg: u32, ring: u32| ring * (segments + 1) + seg;
    for ring in 0..rings {
        for seg in 0..segments {
            let (a, b) = (idx(seg, ring), idx(seg + 1, ring));
            let (c, d) = (idx(seg + 1, ring + 1), idx(seg, ring + 1));
            if ring != 0 {
                m.indices.extend_from_slice(&[a, d, b]);
            }
            if ring != rings - 1 {
                m.indices.extend_from_slice(&[b, d, c]);
            }
        }
    }
    m
}

/// A torus around `axis` = +Z before `tilt_deg` about +X; major radius `big`, tube radius `small`.
pub fn torus(
    center: Vec3,
    big: f32,
    small: f32,
    segments: u32,
    sides: u32,
    tilt_deg: f32,
) -> MeshData {
    let segments = segments.max(3);
    let sides = sides.max(3);
    let rot = glam::Mat3::from_rotation_x(tilt_deg.to_radians());
    let mut m = MeshData::default();
    for i in 0..=segments {
        let u = (i % segments) as f32 / segments as f32 * TAU;
        for j in 0..=sides {
            let v = (j % sides) as f32 / sides as f32 * TAU;
            let ring_center = Vec3::new(u.cos(), u.sin(), 0.0) * big;
            let n = Vec3::new(u.cos() * v.cos(), u.sin() * v.cos(), v.sin());
            let p = ring_center + n * small;
            m.push(
                center + rot * p,
                rot * n,
                [i as f32 / segments as f32 * 4.0, j as f32 / sides as f32],
            );
        }
    }
    let idx = |i: u32, j: u32| i * (sides + 1) + j;
    for i in 0..segments {
        for j in 0..sides {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            m.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    m
}

/// A closed vertical cylinder standing on `base` (flat caps).
pub fn cylinder(base: Vec3, radius: f32, height: f32, segments: u32) -> MeshData {
    let segments = segments.max(3);
    let mut m = MeshData::default();
    let ring = |i: u32| {
        let a = (i % segments) as f32 / segments as f32 * TAU;
        Vec3::new(a.cos(), a.sin(), 0.0)
    };
    let top = Vec3::Z * height;
    for i in 0..segments {
        let (d0, d1) = (ring(i), ring(i + 1));
        let (p0, p1) = (base + d0 * radius, base + d1 * radius);
        let u0 = i as f32 / segments as f32;
        let u1 = (i + 1) as f32 / segments as f32;
        let a = m.push(p0, d0, [u0, 1.0]);
        let b = m.push(p1, d1, [u1, 1.0]);
        let c = m.push(p1 + top, d1, [u1, 0.0]);
        let d = m.push(p0 + top, d0, [u0, 0.0]);
        m.indices.extend_from_slice(&[a, b, c, a, c, d]);
        // Caps as fans around the centre points.
        let tc = m.push(base + top, Vec3::Z, [0.5, 0.5]);
        let t0 = m.push(p0 + top, Vec3::Z, [0.5, 0.5]);
        let t1 = m.push(p1 + top, Vec3::Z, [0.5, 0.5]);
        m.indices.extend_from_slice(&[tc, t0, t1]);
        let bc = m.push(base, -Vec3::Z, [0.5, 0.5]);
        let b0 = m.push(p0, -Vec3::Z, [0.5, 0.5]);
        let b1 = m.push(p1, -Vec3::Z, [0.5, 0.5]);
        m.indices.extend_from_slice(&[bc, b1, b0]);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Counts, after welding by exact position, how many triangles use each undirected edge.
    fn edge_uses(m: &MeshData) -> HashMap<([u32; 3], [u32; 3]), usize> {
        let key = |i: u32| m.vertices[i as usize].position.map(f32::to_bits);
        let mut uses = HashMap::new();
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                let e = if a < b { (a, b) } else { (b, a) };
                *uses.entry(e).or_insert(0) += 1;
            }
        }
        uses
    }

    fn assert_closed_manifold(m: &MeshData) {
        for (e, n) in edge_uses(m) {
            assert_eq!(n, 2, "edge {e:?} used by {n} triangles");
        }
    }

    #[test]
    fn closed_shapes_are_two_manifold_after_welding() {
        assert_closed_manifold(&cuboid(Vec3::ZERO, Vec3::ONE, 1.0));
        assert_closed_manifold(&sphere(Vec3::ZERO, 1.0, 16, 8));
        assert_closed_manifold(&torus(Vec3::ZERO, 3.0, 1.0, 24, 12, 30.0));
        assert_closed_manifold(&cylinder(Vec3::ZERO, 1.0, 5.0, 12));
    }

    #[test]
    fn outward_winding_gives_positive_volume() {
        // Signed volume by the divergence theorem: positive iff faces wind outward.
        for (m, expect) in [
            (cuboid(Vec3::ZERO, Vec3::new(2.0, 3.0, 4.0), 1.0), 24.0),
            (cylinder(Vec3::ZERO, 1.0, 1.0, 256), std::f32::consts::PI),
            (
                sphere(Vec3::ZERO, 1.0, 128, 64),
                4.0 / 3.0 * std::f32::consts::PI,
            ),
        ] {
            let mut vol = 0.0;
            for t in m.indices.chunks_exact(3) {
                let p = |i: u32| m.vertices[i as usize].pos();
                vol += p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0;
            }
            assert!((vol - expect).abs() / expect < 0.01, "{vol} vs {expect}");
        }
    }
}
