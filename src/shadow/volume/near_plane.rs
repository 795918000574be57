//! Whether the view may be inside a shadow volume (when depth-pass counting is safe): Doom 3's
//! box test per caster and the near-plane rectangle tests per piece and triangle.

use super::{CasterGroup, Component, facing_flags_of};
use crate::geometry::Aabb;
use glam::{DVec3, Vec3};

/// Doom 3's test of whether the view may be inside a caster's infinite shadow: the caster's bounds
/// stretched by twice the near distance contain the eye or the light, or the segment from the
/// light to the eye crosses them. When it may not, depth-pass is safe for that caster.
pub fn potentially_inside_shadow(bounds: &Aabb, eye: Vec3, light: Vec3, near: f32) -> bool {
    if bounds.is_empty() {
        return false;
    }
    let stretch = 2.0 * near;
    let (min, max) = (bounds.min - stretch, bounds.max + stretch);
    let inside = |p: Vec3| p.cmpge(min).all() && p.cmple(max).all();
    if inside(eye) || inside(light) {
        return true;
    }
    // Slab test of the segment light → eye against the stretched box.
    let d = eye - light;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for a in 0..3 {
        if d[a].abs() < 1e-12 {
            if light[a] < min[a] || light[a] > max[a] {
                return false;
            }
        } else {
            let (mut ta, mut tb) = ((min[a] - light[a]) / d[a], (max[a] - light[a]) / d[a]);
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// Whether the camera's near-plane rectangle `quad` (corners in order, in the group's space)
/// may lie in the shadow volume of `piece` for a light at `light`: whether some facing
/// triangle meets the hull of the light and the rectangle (every segment from the light to a
/// near-plane point lies in it). A separating-axis test per facing triangle, exact for the
/// convex hull; touching counts as meeting. When false, depth-pass counts start at zero on the
/// near plane for this piece.
pub fn near_plane_shadowed(
    group: &CasterGroup,
    piece: &Component,
    light: DVec3,
    quad: &[DVec3; 4],
    epsilon: f32,
    two_sided: bool,
) -> bool {
    near_plane_triangles(group, piece, light, quad, epsilon, two_sided)
        .next()
        .is_some()
}

/// The facing triangles of `piece` whose shadow may hold part of the near-plane rectangle (the
/// test of [`near_plane_shadowed`], triangle by triangle), in the piece's order. The volume of
/// the other triangles, closed along the cut, holds none of the rectangle: depth-pass counts
/// it correctly.
pub fn near_plane_triangles<'a>(
    group: &'a CasterGroup,
    piece: &'a Component,
    light: DVec3,
    quad: &[DVec3; 4],
    epsilon: f32,
    two_sided: bool,
) -> impl Iterator<Item = u32> + 'a {
    let hull = [light, quad[0], quad[1], quad[2], quad[3]];
    let hull_edges: [DVec3; 8] = [
        quad[0] - light,
        quad[1] - light,
        quad[2] - light,
        quad[3] - light,
        quad[1] - quad[0],
        quad[2] - quad[1],
        quad[3] - quad[2],
        quad[0] - quad[3],
    ];
    let mut hull_faces = [(quad[1] - quad[0]).cross(quad[3] - quad[0]); 5];
    for i in 0..4 {
        hull_faces[i + 1] = hull_edges[i].cross(hull_edges[(i + 1) % 4]);
    }
    let c = &group.connectivity;
    // Two-sided casting: every triangle's shadow counts (the test is blind to winding).
    let facing = if two_sided {
        vec![true; c.triangles.len()]
    } else {
        facing_flags_of(group, piece, light, epsilon)
    };
    let separated = move |axis: DVec3, tri: &[DVec3; 3]| -> bool {
        if axis.length_squared() == 0.0 {
            return false;
        }
        let (mut hmin, mut hmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &hull {
            let d = axis.dot(*p);
            hmin = hmin.min(d);
            hmax = hmax.max(d);
        }
        let (mut tmin, mut tmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in tri {
            let d = axis.dot(*p);
            tmin = tmin.min(d);
            tmax = tmax.max(d);
        }
        hmax < tmin || tmax < hmin
    };
    piece.triangles.iter().copied().filter(move |&t| {
        if !facing[t as usize] {
            return false;
        }
        let tri = c.triangles[t as usize].map(|v| c.positions[v as usize].as_dvec3());
        let tri_edges = [tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]];
        let normal = tri_edges[0].cross(tri_edges[1]);
        if separated(normal, &tri) || hull_faces.iter().any(|&n| separated(n, &tri)) {
            return false;
        }
        !hull_edges
            .iter()
            .any(|h| tri_edges.iter().any(|e| separated(h.cross(*e), &tri)))
    })
}
