//! How far a caster's shadow can reach receivers: the shadow's bounds, and culling and
//! truncating a piece's volume to the receivers it shadows.

use super::Component;
use crate::geometry::Aabb;
use crate::shadow::edges::Connectivity;
use glam::{DVec3, Vec3};

/// The part of space where a caster inside `caster` can shadow receivers within `radius` of the
/// light: the union of segments from each caster point away from the light to the range's edge
/// lies in the hull of the box and its image scaled about the light by T = radius / (distance to
/// the box); its bounds, clipped to the range's box.
pub fn shadow_bounds(caster: &Aabb, light: Vec3, radius: f32) -> Aabb {
    let range = Aabb {
        min: light - radius,
        max: light + radius,
    };
    let nearest = light.clamp(caster.min, caster.max);
    let d = nearest.distance(light);
    if d <= 1e-3 {
        // The light touches or is inside the box: the shadow can go anywhere in range.
        return range;
    }
    let t = (radius / d).max(1.0);
    let corners = caster.corners();
    let pushed = corners.map(|c| light + (c - light) * t);
    Aabb::from_points(corners.into_iter().chain(pushed)).intersection(&range)
}

/// The receivers a volume has to be right for, in the group's space, and the light's range:
/// a facing triangle whose shadow can reach none of them is treated as not facing. Its shadow
/// would hold no receiver, and the rest of the volume stays closed around the cut (planner).
#[derive(Debug, Clone, Copy)]
pub struct ReceiverCull<'a> {
    pub boxes: &'a [Aabb],
    pub radius: f32,
    /// End the volume just past the receivers instead of at infinity (see [`truncation`]).
    pub truncate: bool,
    /// Keep a culled triangle joined to a kept one through coplanar neighbours
    /// (`shadow_volume.cull_whole_planes`).
    pub whole_planes: bool,
}

/// How far behind a triangle's plane a receiver must reach to be in its shadow: the exact
/// reference lifts its rays 0.01 units off surfaces, so it resolves nothing closer either.
const BEHIND: f64 = 0.01;

/// Beyond the farthest receiver point a truncated volume's far cap keeps this margin (world
/// units, plus 1% of the depth), so that it never meets a receiver in the depth test.
const FAR_CAP_MARGIN: f64 = 1.0;

/// Scale factors above this (a light almost touching a facing triangle) keep the volume
/// infinite: a far cap so far out would buy little and cost precision.
pub(super) const MAX_TRUNCATION: f64 = 1.0e4;

/// Whether facing triangle `t`'s shadow can reach one of `boxes` (those already known to meet
/// its piece's shadow), and if so how far its volume must reach to hold every point of them
/// that it shadows. Its shadow is the part of the pyramid from the light through the triangle
/// that lies behind the triangle's plane, and a box must reach inside all four of those planes
/// (a conservative test: a box near an edge of the pyramid may pass).
///
/// The reach is a scale about the light (the triangle scaled by it is the volume's far cap; the
/// infinite volume has ∞): a point P behind the triangle on the ray from the light through x
/// sits at λ = 1 + h(P) / d, where d is the light's height above the triangle's plane and h(P)
/// the point's depth behind it, largest at a box corner; within the range λ ≤ radius / |x − L|
/// as well. Up to that scale the truncated volume is the infinite one.
fn shadow_reach(
    c: &Connectivity,
    t: usize,
    light: Vec3,
    radius: f32,
    boxes: &[&Aabb],
) -> Option<f64> {
    let l = light.as_dvec3();
    let corners = c.triangles[t].map(|v| c.positions[v as usize]);
    let bounds = Aabb::from_points(corners);
    let in_range = shadow_bounds(&bounds, light, radius);
    let tri = corners.map(|p| p.as_dvec3());
    // The triangle's plane turned toward the light: a triangle cast from behind
    // (`VolumeSettings::two_sided`) shadows its own front side.
    let plane = &c.planes[t];
    let toward = if plane.normal.dot(l) + plane.d < 0.0 {
        -1.0
    } else {
        1.0
    };
    let (normal, d) = (plane.normal * toward, plane.d * toward);
    // Planes (n, d), inside where n·x + d >= 0: behind the triangle, and the pyramid's sides.
    let mut planes = vec![(-normal, -d - BEHIND)];
    for k in 0..3 {
        let (a, b, opposite) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
        let mut n = (b - a).cross(a - l);
        if n.length_squared() < 1e-24 {
            continue;
        }
        n = n.normalize();
        if n.dot(opposite - a) < 0.0 {
            n = -n;
        }
        planes.push((n, -n.dot(a)));
    }
    let nearest = light.clamp(bounds.min, bounds.max).distance(light) as f64;
    let by_range = if nearest > 1e-3 {
        radius as f64 * 1.01 / nearest + 0.01
    } else {
        f64::INFINITY
    };
    let height = normal.dot(l) + d;
    let behind = -normal;
    let mut reach: Option<f64> = None;
    for b in boxes {
        if !b.intersects(&in_range)
            || !planes
                .iter()
                .all(|(n, d)| n.dot(furthest_corner(b, *n)) + d >= 0.0)
        {
            continue;
        }
        let cut = b.intersection(&in_range);
        let deepest = (behind.dot(furthest_corner(&cut, behind)) - d).max(0.0);
        let by_box = if height > 1e-6 {
            1.0 + (deepest * 1.01 + FAR_CAP_MARGIN) / height
        } else {
            f64::INFINITY
        };
        let needed = by_box.min(by_range);
        reach = Some(reach.map_or(needed, |r| r.max(needed)));
    }
    reach
}

/// [`Aabb::furthest_corner`] for an f64 direction, in f64.
fn furthest_corner(b: &Aabb, n: DVec3) -> DVec3 {
    b.furthest_corner(n.cmpge(DVec3::ZERO)).as_dvec3()
}

/// Leaves out of `facing` the facing triangles whose shadow reaches no receiver box near the
/// piece's shadow; returns how many, and one far cap scale for the whole piece (∞ unless
/// `truncate`): the largest any facing triangle needs, so that a light touching one keeps
/// the piece infinite. (A scale per triangle ends each prism sooner but adds a step side on
/// every inner edge: on oa_dm1 it doubled the triangles and cut only a sixth of the
/// fragments, a net loss on llvmpipe.)
pub(super) fn cull_to_receivers(
    c: &Connectivity,
    comp: &Component,
    light: DVec3,
    rc: &ReceiverCull,
    facing: &mut [bool],
) -> (usize, f64) {
    let l = light.as_vec3();
    let piece_shadow = shadow_bounds(&comp.bounds, l, rc.radius);
    let near: Vec<&Aabb> = rc
        .boxes
        .iter()
        .filter(|b| b.intersects(&piece_shadow))
        .collect();
    let mut culled = Vec::new();
    let mut scale = 1.0f64;
    for &t in &comp.triangles {
        if !facing[t as usize] {
            continue;
        }
        match shadow_reach(c, t as usize, l, rc.radius, &near) {
            None => {
                facing[t as usize] = false;
                culled.push(t);
            }
            Some(reach) if rc.truncate => scale = scale.max(reach),
            Some(_) => scale = f64::INFINITY,
        }
    }
    if !rc.truncate {
        scale = f64::INFINITY;
    }
    let restored = match rc.whole_planes {
        true => keep_coplanar_neighbours(c, comp, &culled, facing),
        false => 0,
    };
    (culled.len() - restored, scale)
}

/// Gives back to `facing` the culled triangles joined to a kept one through coplanar
/// neighbours: a cull that splits a flat surface adds a silhouette edge on it, whose side quad
/// rises from the surface itself and ties with it in the depth test along the pixels whose
/// centres lie on that edge (oa_dm3's ceiling at y = 256: 16 pixels shadowed that no cull
/// shadows). A culled triangle's shadow reaches no receiver, so keeping it changes no other
/// pixel. Returns how many came back.
fn keep_coplanar_neighbours(
    c: &Connectivity,
    comp: &Component,
    culled: &[u32],
    facing: &mut [bool],
) -> usize {
    if culled.is_empty() {
        return 0;
    }
    let coplanar = |a: u32, b: u32| {
        let (p, q) = (&c.planes[a as usize], &c.planes[b as usize]);
        p.normal.dot(q.normal) > 1.0 - 1e-9 && (p.d - q.d).abs() < 1e-3
    };
    let is_culled: std::collections::HashSet<u32> = culled.iter().copied().collect();
    // The component's edges by triangle, for the culled ones.
    let mut edges_of: std::collections::HashMap<u32, Vec<u32>> = std::collections::HashMap::new();
    let mut work: Vec<u32> = Vec::new();
    for &e in &comp.edges {
        let on = c.triangles_of(&c.edges[e as usize]);
        for &t in on.iter().filter(|t| is_culled.contains(t)) {
            edges_of.entry(t).or_default().push(e);
        }
        for &kept in on.iter().filter(|t| facing[**t as usize]) {
            work.extend(
                on.iter()
                    .filter(|&&t| is_culled.contains(&t) && coplanar(kept, t)),
            );
        }
    }
    let mut restored = 0;
    while let Some(t) = work.pop() {
        if facing[t as usize] {
            continue;
        }
        facing[t as usize] = true;
        restored += 1;
        for &e in edges_of.get(&t).map_or(&[][..], Vec::as_slice) {
            let on = c.triangles_of(&c.edges[e as usize]);
            work.extend(
                on.iter()
                    .filter(|&&n| !facing[n as usize] && is_culled.contains(&n) && coplanar(t, n)),
            );
        }
    }
    restored
}
