//! The planner's geometric tests: a light's range against boxes and frusta, a six-spot face's
//! pyramid, and the box a caster's shadow can occupy within the light's range. Every test is
//! conservative: it may keep what is not needed, never drop what is.

use crate::geometry::Aabb;
use crate::geometry::Frustum;
use glam::{Vec3, Vec4};

/// Whether the ball (`center`, `radius`) meets the box.
pub fn sphere_meets_aabb(center: Vec3, radius: f32, b: &Aabb) -> bool {
    if b.is_empty() {
        return false;
    }
    let nearest = center.clamp(b.min, b.max);
    nearest.distance_squared(center) <= radius * radius
}

/// Whether the ball meets the frustum (false only when it lies wholly outside one plane).
pub fn sphere_meets_frustum(f: &Frustum, center: Vec3, radius: f32) -> bool {
    f.planes
        .iter()
        .all(|p| p.truncate().dot(center) + p.w >= -radius)
}

/// The box of a light's range.
pub fn range_box(center: Vec3, radius: f32) -> Aabb {
    Aabb {
        min: center - radius,
        max: center + radius,
    }
}

pub use crate::shadow::volume::shadow_bounds;

/// Cube face `f`'s axis and the two axes across it.
pub fn face_axes(f: usize) -> (Vec3, Vec3, Vec3) {
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let (u, v) = match f.min(5) / 2 {
        0 => (Vec3::Y, Vec3::Z),
        1 => (Vec3::X, Vec3::Z),
        _ => (Vec3::X, Vec3::Y),
    };
    (axes[f.min(5)], u, v)
}

/// The four planes through the light bounding the region an omni light's cube face `f` (the
/// [`crate::shadow::views::major_face`] numbering) covers; points on the boundary belong to both
/// faces, as the lit pass's test breaks ties.
pub fn face_pyramid(light: Vec3, f: usize) -> Frustum {
    let (a, u, v) = face_axes(f);
    let plane = |n: Vec3| {
        let n = n.normalize();
        Vec4::new(n.x, n.y, n.z, -n.dot(light))
    };
    Frustum {
        planes: vec![plane(a - u), plane(a + u), plane(a - v), plane(a + v)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadow::views::major_face;

    fn cube(c: Vec3, h: f32) -> Aabb {
        Aabb {
            min: c - h,
            max: c + h,
        }
    }

    #[test]
    fn spheres_meet_boxes_by_their_nearest_point() {
        let b = cube(Vec3::ZERO, 1.0);
        assert!(sphere_meets_aabb(Vec3::new(3.0, 0.0, 0.0), 2.0, &b));
        assert!(!sphere_meets_aabb(Vec3::new(3.0, 3.0, 0.0), 2.5, &b));
        assert!(sphere_meets_aabb(Vec3::new(3.0, 3.0, 0.0), 2.9, &b));
    }

    #[test]
    fn shadow_bounds_hold_every_shadowed_point_in_range() {
        let light = Vec3::new(0.0, 0.0, 100.0);
        let caster = cube(Vec3::new(10.0, 0.0, 50.0), 5.0);
        let radius = 300.0;
        let b = shadow_bounds(&caster, light, radius);
        // Points along rays from the light through the caster, out to the range, are inside.
        let mut checked = 0;
        for i in 0..=4 {
            for j in 0..=4 {
                for k in 0..=4 {
                    let p = caster.min
                        + (caster.max - caster.min) * Vec3::new(i as f32, j as f32, k as f32) / 4.0;
                    let dir = (p - light).normalize();
                    let mut t = (p - light).length();
                    while t <= radius {
                        let q = light + dir * t;
                        assert!(
                            q.cmpge(b.min - 1e-3).all() && q.cmple(b.max + 1e-3).all(),
                            "{q:?} outside {b:?}"
                        );
                        t += 7.0;
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 1000);
        // The shadow falls away from the light: nothing above the caster's top.
        assert!(b.max.z <= caster.max.z + 1e-3);
        // A light inside the caster: the whole range.
        assert_eq!(
            shadow_bounds(&caster, caster.min + 1.0, 50.0),
            range_box(caster.min + 1.0, 50.0)
        );
    }

    #[test]
    fn face_pyramids_agree_with_the_lit_pass_face_test() {
        let light = Vec3::new(5.0, -3.0, 2.0);
        let mut rng = 1u32;
        let mut next = || {
            rng = rng.wrapping_mul(1664525).wrapping_add(1013904223);
            (rng >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let d = Vec3::new(next(), next(), next()) * 100.0;
            let p = light + d;
            let f = major_face(d);
            assert!(face_pyramid(light, f).contains_point(p), "{d:?} face {f}");
            // A point well inside another face's region is outside this pyramid.
            for g in 0..6 {
                if g != f && face_pyramid(light, g).contains_point(p) {
                    let a = d.abs();
                    let mut s = [a.x, a.y, a.z];
                    s.sort_by(|x, y| y.total_cmp(x));
                    assert!(s[0] - s[1] < 1e-3, "{d:?} in faces {f} and {g}");
                }
            }
        }
    }
}
