//! The exact answer to "is this point lit by this light?": a shadow ray from the surface point to
//! the light against every casting triangle of the scene (world, patches, meshes, models), found
//! through a BVH (the `bvh` crate) and intersected in f64. Alpha-tested surfaces let the ray
//! through where their texture's alpha (nearest texel of the full-size image) fails the test.
//!
//! Tolerance: the ray starts at the surface point moved along its normal by
//! [`origin_offset`] — 0.01 units plus 4e-6 of the point's largest coordinate (0.04 units at
//! Quake 3's ±8192), which covers the f32 rounding of G-buffer positions. This offset is the
//! reference's only tolerance; triangles are hit exactly (Möller–Trumbore in f64, edges inclusive).

use crate::images::Rgba;
use crate::scene::{AlphaFunc, Scene};
use bvh::aabb::{Aabb, Bounded};
use bvh::bounding_hierarchy::BHShape;
use bvh::bvh::Bvh;
use bvh::ray::Ray;
use glam::{DVec3, Vec3};
use nalgebra::{Point3, Vector3};

/// Half-size added to each triangle's box, so that rays lying in the plane of an axis-aligned
/// triangle still enter its box (the `bvh` crate treats in-plane rays as misses).
const BOX_PAD: f64 = 1e-3;

/// The shadow ray origin's lift off the surface: a constant and a share of the position's
/// largest coordinate (the float tolerance of positions at that scale).
pub const ORIGIN_LIFT: (f64, f64) = (0.01, 4e-6);

/// How far the shadow ray's origin is lifted off the surface along the normal.
pub fn origin_offset(p: DVec3) -> f64 {
    ORIGIN_LIFT.0 + ORIGIN_LIFT.1 * p.abs().max_element()
}

/// Where the shadow ray from surface point `p` with normal `n` starts.
pub fn shadow_ray_origin(p: Vec3, n: Vec3) -> DVec3 {
    let p = p.as_dvec3();
    p + n.as_dvec3().normalize_or_zero() * origin_offset(p)
}

#[derive(Debug, Clone)]
struct Occluder {
    v: [DVec3; 3],
    uv: [[f32; 2]; 3],
    /// Alpha test and texture index into `Reference::textures`.
    alpha: Option<(AlphaFunc, usize)>,
    /// Index of the scene surface it came from.
    surface: usize,
    node: usize,
}

/// The nearest triangle that blocks a shadow ray (for explaining one pixel's answer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blocker {
    /// Index into `Scene::surfaces`.
    pub surface: usize,
    /// Distance from the ray's origin.
    pub distance: f64,
    /// The triangle's vertices, counter-clockwise seen from its front.
    pub triangle: [DVec3; 3],
    /// Whether its front faces the light (the end of the segment).
    pub faces_light: bool,
}

impl Bounded<f64, 3> for Occluder {
    fn aabb(&self) -> Aabb<f64, 3> {
        let min = self.v[0].min(self.v[1]).min(self.v[2]) - BOX_PAD;
        let max = self.v[0].max(self.v[1]).max(self.v[2]) + BOX_PAD;
        Aabb::with_bounds(
            Point3::new(min.x, min.y, min.z),
            Point3::new(max.x, max.y, max.z),
        )
    }
}

impl BHShape<f64, 3> for Occluder {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// Ray parameter and barycentrics where a segment hits a triangle, in f64, edges inclusive.
fn intersect(origin: DVec3, dir: DVec3, t_max: f64, v: &[DVec3; 3]) -> Option<(f64, f64, f64)> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - v[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let w = dir.dot(q) * inv;
    if w < 0.0 || u + w > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0 && t < t_max).then_some((t, u, w))
}

/// Scene casters in a BVH, ready for shadow rays.
pub struct Reference {
    bvh: Bvh<f64, 3>,
    occluders: Vec<Occluder>,
    textures: Vec<Rgba>,
}

impl Reference {
    /// Every triangle of every visible, casting surface, in world space.
    pub fn build(scene: &Scene) -> Reference {
        Reference::build_with(scene, true)
    }

    /// The same, with alpha-tested casters solid when `alpha` is false: the answer geometric
    /// techniques (shadow volumes) aim at, for telling which errors alpha testing alone causes.
    pub fn build_with(scene: &Scene, alpha: bool) -> Reference {
        let mut occluders = Vec::new();
        let mut textures: Vec<Rgba> = Vec::new();
        let mut texture_slot: Vec<Option<usize>> = vec![None; scene.textures.len()];
        for (surface, s) in scene.surfaces.iter().enumerate() {
            let m = &scene.materials[s.material];
            if !(m.visible && m.casts_shadows) {
                continue;
            }
            let alpha_test = match (alpha, m.alpha_test, m.texture) {
                (true, Some(f), Some(t)) if t < scene.textures.len() => {
                    let slot = *texture_slot[t].get_or_insert_with(|| {
                        textures.push(scene.textures[t].clone());
                        textures.len() - 1
                    });
                    Some((f, slot))
                }
                _ => None,
            };
            let transform = scene.surface_transform(s).as_dmat4();
            let range = s.first_index as usize..(s.first_index + s.index_count) as usize;
            for tri in scene.indices[range].chunks_exact(3) {
                let vert = |k: usize| &scene.vertices[tri[k] as usize];
                let v = [0, 1, 2].map(|k| transform.transform_point3(vert(k).pos().as_dvec3()));
                if !v.iter().all(|p| p.is_finite()) {
                    continue;
                }
                occluders.push(Occluder {
                    v,
                    uv: [0, 1, 2].map(|k| vert(k).uv),
                    alpha: alpha_test,
                    surface,
                    node: 0,
                });
            }
        }
        let bvh = Bvh::build(&mut occluders);
        Reference {
            bvh,
            occluders,
            textures,
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.occluders.len()
    }

    /// Whether occluder `o` blocks the segment: hit before `t_max`, and for alpha-tested
    /// surfaces, the texel at the hit point passes the test.
    fn blocks(&self, o: &Occluder, from: DVec3, dir: DVec3, t_max: f64) -> bool {
        self.block_distance(o, from, dir, t_max).is_some()
    }

    /// Where occluder `o` blocks the segment, if it does.
    fn block_distance(&self, o: &Occluder, from: DVec3, dir: DVec3, t_max: f64) -> Option<f64> {
        let (t, u, w) = intersect(from, dir, t_max, &o.v)?;
        let Some((func, tex)) = o.alpha else {
            return Some(t);
        };
        let b = [(1.0 - u - w) as f32, u as f32, w as f32];
        let s = b[0] * o.uv[0][0] + b[1] * o.uv[1][0] + b[2] * o.uv[2][0];
        let tt = b[0] * o.uv[0][1] + b[1] * o.uv[1][1] + b[2] * o.uv[2][1];
        let texel = self.textures[tex].sample_nearest(s, tt)[3];
        func.passes(texel).then_some(t)
    }

    /// The segment as a unit direction and the parameter where it stops (just short of `to`,
    /// so geometry at the light itself does not count). None for a degenerate segment.
    fn segment(from: DVec3, to: DVec3) -> Option<(DVec3, f64)> {
        let d = to - from;
        let len = d.length();
        (len > 0.0 && len.is_finite()).then(|| (d / len, len * (1.0 - 1e-9)))
    }

    /// Whether anything blocks the open segment from `from` to `to`.
    pub fn occluded(&self, from: DVec3, to: DVec3) -> bool {
        let Some((dir, t_max)) = Self::segment(from, to) else {
            return false;
        };
        let ray = Ray::new(
            Point3::new(from.x, from.y, from.z),
            Vector3::new(dir.x, dir.y, dir.z),
        );
        self.bvh
            .traverse_iterator(&ray, &self.occluders)
            .any(|o| self.blocks(o, from, dir, t_max))
    }

    /// [`Reference::occluded`], and whether the segment, unblocked, passes an alpha-tested
    /// triangle where its texel fails the test: a point lit through such a hole, which a
    /// technique drawing those casters solid (shadow volumes) shadows.
    pub fn occluded_or_through_hole(&self, from: DVec3, to: DVec3) -> (bool, bool) {
        let Some((dir, t_max)) = Self::segment(from, to) else {
            return (false, false);
        };
        let ray = Ray::new(
            Point3::new(from.x, from.y, from.z),
            Vector3::new(dir.x, dir.y, dir.z),
        );
        let mut hole = false;
        for o in self.bvh.traverse_iterator(&ray, &self.occluders) {
            if self.blocks(o, from, dir, t_max) {
                return (true, false);
            }
            hole |= o.alpha.is_some() && intersect(from, dir, t_max, &o.v).is_some();
        }
        (false, hole)
    }

    /// The same answer by testing every triangle, without the BVH (for checking it).
    pub fn occluded_brute_force(&self, from: DVec3, to: DVec3) -> bool {
        let Some((dir, t_max)) = Self::segment(from, to) else {
            return false;
        };
        self.occluders
            .iter()
            .any(|o| self.blocks(o, from, dir, t_max))
    }

    /// Every triangle blocking the segment, nearest first (every triangle is tested: this is
    /// for explaining one pixel).
    pub fn blockers(&self, from: DVec3, to: DVec3) -> Vec<Blocker> {
        let Some((dir, t_max)) = Self::segment(from, to) else {
            return Vec::new();
        };
        let mut hits: Vec<Blocker> = self
            .occluders
            .iter()
            .filter_map(|o| {
                let distance = self.block_distance(o, from, dir, t_max)?;
                let normal = (o.v[1] - o.v[0]).cross(o.v[2] - o.v[0]);
                Some(Blocker {
                    surface: o.surface,
                    distance,
                    triangle: o.v,
                    faces_light: normal.dot(to - o.v[0]) > 0.0,
                })
            })
            .collect();
        hits.sort_by(|a, b| a.distance.total_cmp(&b.distance));
        hits
    }

    /// The nearest triangle along the ray from `from` in unit direction `dir`, within
    /// `max_distance` (through the BVH; alpha-tested texels that fail let the ray through).
    pub fn nearest_hit(&self, from: DVec3, dir: DVec3, max_distance: f64) -> Option<Blocker> {
        let ray = Ray::new(
            Point3::new(from.x, from.y, from.z),
            Vector3::new(dir.x, dir.y, dir.z),
        );
        self.bvh
            .traverse_iterator(&ray, &self.occluders)
            .filter_map(|o| Some((o, self.block_distance(o, from, dir, max_distance)?)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(o, distance)| {
                let normal = (o.v[1] - o.v[0]).cross(o.v[2] - o.v[0]);
                Blocker {
                    surface: o.surface,
                    distance,
                    triangle: o.v,
                    faces_light: normal.dot(from - o.v[0]) > 0.0,
                }
            })
    }

    /// Whether the light at `light` is blocked from surface point `p` with normal `n`.
    pub fn shadowed(&self, p: Vec3, n: Vec3, light: Vec3) -> bool {
        self.occluded(shadow_ray_origin(p, n), light.as_dvec3())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intersection_is_edge_inclusive_and_bounded() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let down = -DVec3::Z;
        // Through the interior, on an edge, and on a vertex.
        assert!(intersect(DVec3::new(0.25, 0.25, 1.0), down, 2.0, &tri).is_some());
        assert!(intersect(DVec3::new(0.5, 0.0, 1.0), down, 2.0, &tri).is_some());
        assert!(intersect(DVec3::new(0.0, 0.0, 1.0), down, 2.0, &tri).is_some());
        // Just outside, and beyond the segment's end.
        assert!(intersect(DVec3::new(0.5, -1e-12, 1.0), down, 2.0, &tri).is_none());
        assert!(intersect(DVec3::new(0.25, 0.25, 1.0), down, 0.999, &tri).is_none());
        // Parallel rays never hit.
        assert!(intersect(DVec3::new(0.25, 0.25, 0.0), DVec3::X, 2.0, &tri).is_none());
    }
}
