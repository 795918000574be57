//! Coplanar triangles of one surface that cover the same area. Quake 3 never needs a planar
//! surface's triangles to tile it exactly (its light is baked, and the depth test keeps one
//! fragment per pixel), and some compiled maps have surfaces whose triangles overlap; an
//! additive lit pass, which tests LEQUAL, then adds a light twice where they do (oa_dm1's
//! first corridor: bright bands with z-fighting edges). `shadowlab check` counts them.

use glam::{Vec2, Vec3};

/// Two triangles overlap when their interiors share more than this fraction of the smaller
/// one's extent along every separating axis: touching edges and shared vertices do not count.
const TOUCH: f32 = 1e-4;

/// How many triangles of `triangles` (coplanar: one planar surface) overlap an earlier one
/// with some area.
pub fn overlapping_triangles(triangles: &[[Vec3; 3]]) -> usize {
    let Some(normal) = triangles.iter().map(normal_of).find(|n| *n != Vec3::ZERO) else {
        return 0;
    };
    let flat: Vec<[Vec2; 3]> = triangles.iter().map(|t| project(t, normal)).collect();
    (1..flat.len())
        .filter(|&i| {
            flat[..i]
                .iter()
                .any(|earlier| interiors_meet(&flat[i], earlier))
        })
        .count()
}

fn normal_of(t: &[Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
}

/// Drops the coordinate along the normal's largest component.
fn project(t: &[Vec3; 3], normal: Vec3) -> [Vec2; 3] {
    let a = normal.abs();
    t.map(|p| {
        if a.x >= a.y && a.x >= a.z {
            Vec2::new(p.y, p.z)
        } else if a.y >= a.z {
            Vec2::new(p.x, p.z)
        } else {
            Vec2::new(p.x, p.y)
        }
    })
}

/// Separating-axis test on the six edge normals, with touching counted as apart.
fn interiors_meet(a: &[Vec2; 3], b: &[Vec2; 3]) -> bool {
    if area2(a).abs() <= f32::EPSILON || area2(b).abs() <= f32::EPSILON {
        return false;
    }
    let axes = (0..3).flat_map(|k| {
        [
            (a[(k + 1) % 3] - a[k]).perp(),
            (b[(k + 1) % 3] - b[k]).perp(),
        ]
    });
    for axis in axes {
        let (amin, amax) = extent(a, axis);
        let (bmin, bmax) = extent(b, axis);
        let slack = TOUCH * (amax - amin).min(bmax - bmin).max(f32::EPSILON);
        if amax <= bmin + slack || bmax <= amin + slack {
            return false;
        }
    }
    true
}

fn area2(t: &[Vec2; 3]) -> f32 {
    (t[1] - t[0]).perp_dot(t[2] - t[0])
}

fn extent(t: &[Vec2; 3], axis: Vec2) -> (f32, f32) {
    let d = t.map(|p| p.dot(axis));
    (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32) -> Vec3 {
        Vec3::new(x, y, -144.0)
    }

    #[test]
    fn a_square_split_on_its_diagonal_does_not_overlap_and_a_third_triangle_over_it_does() {
        let square = [
            [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
            [v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)],
        ];
        assert_eq!(overlapping_triangles(&square), 0);
        // Sharing only a corner or an edge with the square: apart.
        let beside = [
            square[0],
            square[1],
            [v(1.0, 0.0), v(2.0, 0.0), v(1.0, 1.0)],
        ];
        assert_eq!(overlapping_triangles(&beside), 0);
        // oa_dm1's surface 521 in small: a triangle reaching into the other half.
        let over = [
            square[0],
            square[1],
            [v(0.5, 0.2), v(0.9, 0.2), v(0.6, 0.9)],
        ];
        assert_eq!(overlapping_triangles(&over), 1);
    }

    #[test]
    fn degenerate_triangles_overlap_nothing() {
        let t = [
            [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
            [v(0.0, 0.0), v(0.5, 0.0), v(1.0, 0.0)],
        ];
        assert_eq!(overlapping_triangles(&t), 0);
    }
}
