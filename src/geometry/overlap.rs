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

/// Triangles of one plane tested against each other at most: a surface with more in one plane
/// is taken to overlap (its lit pass then marks the stencil, which is correct, only slower),
/// so that a hostile file cannot make loading quadratic.
const MOST_TESTED: usize = 4096;

/// Whether two triangles of a surface (any surface: planar, curved or a triangle soup) cover
/// some area twice, tested among the triangles that share a plane. Planes are told apart by
/// their unit normal and distance rounded to 1/256 (a planar Quake 3 surface's vertices lie on
/// its plane to far better than that), so coplanar triangles split across a rounding boundary
/// are not compared: a surface's lit pass then adds a light twice where they overlap, as every
/// surface did without `lighting.light_once`.
pub fn covers_twice(triangles: &[[Vec3; 3]]) -> bool {
    let mut planes: std::collections::HashMap<[i32; 4], Vec<[Vec3; 3]>> =
        std::collections::HashMap::new();
    for t in triangles {
        let n = normal_of(t);
        if n == Vec3::ZERO {
            continue;
        }
        let d = n.dot(t[0]);
        let key = [n.x, n.y, n.z, d].map(|c| (c * 256.0).round() as i32);
        planes.entry(key).or_default().push(*t);
    }
    planes
        .values()
        .filter(|same_plane| same_plane.len() > 1)
        .any(|same_plane| same_plane.len() > MOST_TESTED || overlapping_triangles(same_plane) > 0)
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
    fn a_surface_covers_twice_only_where_triangles_of_one_plane_overlap() {
        let square = [
            [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
            [v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)],
        ];
        assert!(!covers_twice(&square));
        let over = [
            square[0],
            square[1],
            [v(0.5, 0.2), v(0.9, 0.2), v(0.6, 0.9)],
        ];
        assert!(covers_twice(&over));
        // The same triangle one unit above the square: seen from above it covers the same
        // area, but it is not in the square's plane, so nothing is covered twice.
        let lifted = [square[0], square[1], over[2].map(|p| p + Vec3::Z)];
        assert!(!covers_twice(&lifted));
        // A bent surface (a folded card) whose halves do not overlap.
        let folded = [
            [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
            [
                Vec3::new(0.0, 0.0, -144.0),
                Vec3::new(0.0, 1.0, -143.0),
                Vec3::new(1.0, 1.0, -143.0),
            ],
        ];
        assert!(!covers_twice(&folded));
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
