//! View frusta as planes, for culling boxes (BSP nodes and leaves, surfaces, light bounds).

use crate::geometry::Aabb;
use glam::{Mat4, Vec3, Vec4};

/// The four side planes and the near plane `(n, d)`, `n·p + d ≥ 0` inside, of a world-to-clip
/// matrix (Gribb and Hartmann's row sums, not normalised; no far plane).
pub fn sides_and_near(m: &Mat4) -> [Vec4; 5] {
    let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
    [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 + r2]
}

/// Planes `(n, d)` with `n·p + d ≥ 0` inside. An infinite projection has no far plane, so only
/// the near and four side planes are kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Frustum {
    pub planes: Vec<Vec4>,
}

impl Frustum {
    /// From a world-to-clip matrix (Gribb and Hartmann's row sums). Planes whose normal vanishes
    /// (the far plane of an infinite projection) are dropped.
    pub fn from_view_proj(m: &Mat4) -> Frustum {
        let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
        let planes = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 + r2, r3 - r2]
            .into_iter()
            .filter_map(|p| {
                let len = p.truncate().length();
                (len > 1e-6 && len.is_finite()).then(|| p / len)
            })
            .collect();
        Frustum { planes }
    }

    /// False only when the box is entirely outside one plane (conservative).
    pub fn intersects_aabb(&self, b: &Aabb) -> bool {
        if b.is_empty() {
            return false;
        }
        self.planes.iter().all(|p| {
            let n = p.truncate();
            n.dot(b.furthest_corner(n.cmpge(Vec3::ZERO))) + p.w >= 0.0
        })
    }

    pub fn contains_point(&self, p: Vec3) -> bool {
        self.planes.iter().all(|q| q.truncate().dot(p) + q.w >= 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::projection::{perspective, perspective_infinite};

    #[test]
    fn boxes_in_front_pass_and_behind_or_beside_fail() {
        let view = Mat4::look_to_rh(Vec3::ZERO, -Vec3::Z, Vec3::Y);
        for proj in [
            perspective(1.0, 1.0, 1.0, 100.0),
            perspective_infinite(1.0, 1.0, 1.0),
        ] {
            let f = Frustum::from_view_proj(&(proj * view));
            let cube = |c: Vec3| Aabb {
                min: c - 0.5,
                max: c + 0.5,
            };
            assert!(f.intersects_aabb(&cube(Vec3::new(0.0, 0.0, -10.0))));
            assert!(!f.intersects_aabb(&cube(Vec3::new(0.0, 0.0, 10.0))));
            assert!(!f.intersects_aabb(&cube(Vec3::new(50.0, 0.0, -10.0))));
            // Straddling the left plane still counts as visible.
            assert!(f.intersects_aabb(&cube(Vec3::new(-5.3, 0.0, -10.0))));
            assert!(f.contains_point(Vec3::new(0.0, 0.0, -2.0)));
        }
        let inf = Frustum::from_view_proj(&(perspective_infinite(1.0, 1.0, 1.0) * view));
        assert_eq!(inf.planes.len(), 5, "no far plane at infinity");
        assert!(inf.contains_point(Vec3::new(0.0, 0.0, -1.0e9)));
    }
}
