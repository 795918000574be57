//! Which triangles face a light (and on which side of each triangle's plane it stands).

use super::{CasterGroup, Component};
use crate::shadow::edges::Connectivity;
use glam::{DVec3, Vec3};

/// Which triangles of `component` face a point light at `light` (indexed by the group's
/// triangles; others are false): `n·(L − c) > −ε |L − c|` in f64, with the centroid `c`. A
/// triangle with zero area, or with a corner at the light, never faces it.
pub fn facing_flags(
    group: &CasterGroup,
    component: usize,
    light: DVec3,
    epsilon: f32,
) -> Vec<bool> {
    facing_flags_of(group, &group.components[component], light, epsilon)
}

/// [`facing_flags`] for any piece of the group (a component or a chunk).
pub fn facing_flags_of(
    group: &CasterGroup,
    piece: &Component,
    light: DVec3,
    epsilon: f32,
) -> Vec<bool> {
    let c = &group.connectivity;
    let mut facing = vec![false; c.triangles.len()];
    for &t in &piece.triangles {
        if let Some((d, distance)) = light_offset(c, t, light) {
            facing[t as usize] = d > -(epsilon as f64) * distance;
        }
    }
    facing
}

/// The light's signed distance from triangle `t`'s plane and its distance from the centroid,
/// in f64; None for a triangle without area or with a corner at the light, which never faces
/// it and casts nothing.
fn light_offset(c: &Connectivity, t: u32, light: DVec3) -> Option<(f64, f64)> {
    let pos = |i: u32| c.positions[i as usize].as_dvec3();
    let tri = c.triangles[t as usize];
    let plane = &c.planes[t as usize];
    if plane.normal == DVec3::ZERO || tri.iter().any(|&v| pos(v) == light) {
        return None;
    }
    let centroid = (pos(tri[0]) + pos(tri[1]) + pos(tri[2])) / 3.0;
    let to_light = light - centroid;
    Some((plane.normal.dot(to_light), to_light.length()))
}

/// Where a point light stands to a triangle's plane, for two-sided casting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightSide {
    /// On the side the triangle's normal points to.
    Front,
    /// On the other side: the triangle casts with the opposite winding.
    Behind,
    /// In its plane (within [`IN_PLANE`]), at a corner, or the triangle has no area: its
    /// volume has no thickness and it casts none. Its edges to casting neighbours become
    /// silhouettes, which keeps the shadow of a closed caster whose faces all hold the light
    /// or face away from it (a light on its vertex or edge).
    InPlane,
}

/// A light closer to a triangle's plane than this fraction of its distance to the centroid
/// lies in the plane: f32 positions put a light meant to be on a tilted plane about 1e-7 of
/// the coordinates off it, and either side's thin volume would then be right anyway; what
/// must not happen is an exact zero read as one side, which turns a face that casts nothing
/// into a neighbour that hides the silhouette.
pub const IN_PLANE: f64 = 1e-9;

/// [`LightSide`] of every triangle of `piece` (indexed by the group's triangles; others are
/// `InPlane`), in f64.
pub fn light_sides_of(group: &CasterGroup, piece: &Component, light: DVec3) -> Vec<LightSide> {
    let c = &group.connectivity;
    let mut sides = vec![LightSide::InPlane; c.triangles.len()];
    for &t in &piece.triangles {
        match light_offset(c, t, light) {
            Some((d, distance)) if d.abs() > IN_PLANE * distance => {
                sides[t as usize] = if d > 0.0 {
                    LightSide::Front
                } else {
                    LightSide::Behind
                };
            }
            _ => {}
        }
    }
    sides
}

/// The same classification computed in f32 throughout, to find where single precision decides
/// differently (lights on or near a triangle's plane, far from the origin).
pub fn facing_flags_f32(
    group: &CasterGroup,
    component: usize,
    light: Vec3,
    epsilon: f32,
) -> Vec<bool> {
    let c = &group.connectivity;
    let pos = |i: u32| c.positions[i as usize];
    let mut facing = vec![false; c.triangles.len()];
    for &t in &group.components[component].triangles {
        let tri = c.triangles[t as usize];
        let n = (pos(tri[1]) - pos(tri[0])).cross(pos(tri[2]) - pos(tri[0]));
        if n == Vec3::ZERO || tri.iter().any(|&v| pos(v) == light) {
            continue;
        }
        let n = n.normalize();
        let centroid = (pos(tri[0]) + pos(tri[1]) + pos(tri[2])) / 3.0;
        let to_light = light - centroid;
        facing[t as usize] = n.dot(to_light) > -epsilon * to_light.length();
    }
    facing
}
