//! Clipping of boxes and convex polygons by planes `(n, d)` (inside: n·p + d ≥ 0).

use crate::geometry::Aabb;
use glam::{Vec3, Vec4, Vec4Swizzles};

/// Appends the vertices of box `b` clipped by `planes`.
pub fn clip_box(b: &Aabb, planes: &[Vec4], out: &mut Vec<Vec3>) {
    let corners = b.corners();
    let inside = |p: &Vec3, pl: &Vec4| pl.xyz().dot(*p) + pl.w >= 0.0;
    if planes
        .iter()
        .any(|pl| corners.iter().all(|c| !inside(c, pl)))
    {
        return;
    }
    if planes
        .iter()
        .all(|pl| corners.iter().all(|c| inside(c, pl)))
    {
        out.extend_from_slice(&corners);
        return;
    }
    let (lo, hi) = (b.min, b.max);
    let faces: [[Vec3; 4]; 6] = [
        [
            lo,
            lo.with_y(hi.y),
            lo.with_y(hi.y).with_z(hi.z),
            lo.with_z(hi.z),
        ],
        [
            hi.with_y(lo.y).with_z(lo.z),
            hi.with_z(lo.z),
            hi,
            hi.with_y(lo.y),
        ],
        [
            lo,
            lo.with_x(hi.x),
            lo.with_x(hi.x).with_z(hi.z),
            lo.with_z(hi.z),
        ],
        [
            lo.with_y(hi.y),
            hi.with_z(lo.z),
            hi,
            lo.with_y(hi.y).with_z(hi.z),
        ],
        [lo, lo.with_x(hi.x), hi.with_z(lo.z), lo.with_y(hi.y)],
        [
            lo.with_z(hi.z),
            hi.with_y(lo.y),
            hi,
            lo.with_y(hi.y).with_z(hi.z),
        ],
    ];
    for face in faces {
        let mut poly = face.to_vec();
        for pl in planes {
            poly = clip_polygon(&poly, *pl);
            if poly.is_empty() {
                break;
            }
        }
        out.extend(poly);
    }
}

/// Sutherland–Hodgman: the part of convex polygon `poly` inside `plane`.
pub fn clip_polygon(poly: &[Vec3], plane: Vec4) -> Vec<Vec3> {
    let dist = |p: Vec3| plane.xyz().dot(p) + plane.w;
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (da, db) = (dist(a), dist(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygons_clip_to_the_inside() {
        let square = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let half = clip_polygon(&square, Vec4::new(1.0, 0.0, 0.0, 0.0));
        assert_eq!(half.len(), 4);
        assert!(half.iter().all(|p| p.x >= 0.0));
        assert!(clip_polygon(&square, Vec4::new(1.0, 0.0, 0.0, -2.0)).is_empty());
    }
}
