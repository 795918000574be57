//! The light's "virtual cameras" of shadow mapping (thesis 2.2.2): one frustum per spot light, six
//! 90° frusta or one cube for an omni light, with near and far fitted to the casters.

use crate::geometry::Aabb;
use crate::geometry::projection::{
    bias_matrix, cube_face_view, fit_near_far, look_along, perspective,
};
use crate::options::{OmniMode, ShadowMapOptions};
use crate::scene::{Light, LightKind};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// Smallest near plane a fitted frustum gets, in world units.
pub const MIN_NEAR: f32 = 1.0;
/// Relative margin of fitted near and far planes around the casters.
pub const FIT_MARGIN: f32 = 1.02;

/// What a view covers of its light.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewKind {
    /// The spot light's cone.
    Spot,
    /// The directions of an omni light whose major axis is cube face `0..6` (+X, -X, +Y, -Y, +Z,
    /// -Z): six such views partition the sphere.
    Face(usize),
    /// All six faces in one cube map.
    Cube,
}

/// A rectangle of a face's image plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub min: Vec2,
    pub max: Vec2,
}

impl Rect {
    /// The whole face.
    pub const FACE: Rect = Rect {
        min: Vec2::NEG_ONE,
        max: Vec2::ONE,
    };

    pub fn union(&self, o: &Rect) -> Rect {
        Rect {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// The common part, edges included (a receiver seen edge-on is a line and still counts).
    pub fn intersection(&self, o: &Rect) -> Option<Rect> {
        let (min, max) = (self.min.max(o.min), self.max.min(o.max));
        (min.x <= max.x && min.y <= max.y).then_some(Rect { min, max })
    }

    /// The longer side: a square map over the rectangle has `size / side` texels per plane unit
    /// in its coarser direction.
    pub fn side(&self) -> f32 {
        (self.max - self.min).max_element()
    }

    pub fn contains(&self, p: Vec2) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Whether the two share more than an edge.
    pub fn overlaps(&self, o: &Rect) -> bool {
        let (min, max) = (self.min.max(o.min), self.max.min(o.max));
        min.x < max.x && min.y < max.y
    }

    /// The four quarters, split at the centre (a quadtree's children).
    pub fn quadrants(&self) -> [Rect; 4] {
        let c = (self.min + self.max) * 0.5;
        [
            Rect {
                min: self.min,
                max: c,
            },
            Rect {
                min: Vec2::new(c.x, self.min.y),
                max: Vec2::new(self.max.x, c.y),
            },
            Rect {
                min: Vec2::new(self.min.x, c.y),
                max: Vec2::new(c.x, self.max.y),
            },
            Rect {
                min: c,
                max: self.max,
            },
        ]
    }
}

/// Where one of several frusta of an omni light lies (`shadow_map.omni = frusta`,
/// [`crate::shadow::frusta`]): its map's own size and the cell of its face's image plane whose
/// fragments it lights (a face's cells never overlap, so each fragment has one frustum).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacePart {
    pub size: u32,
    pub cell: Rect,
}

/// One shadow map's camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowView {
    pub kind: ViewKind,
    /// World to light eye space (for cubes: unused, faces come from [`cube_face_view`]).
    pub view: Mat4,
    pub projection: Mat4,
    pub near: f32,
    pub far: f32,
    /// The world → clip matrix whose depth the map stores and the lit pass compares, when it
    /// is not `view_proj` (trapezoidal maps: Martin & Tan keep the light's own depth, since the
    /// trapezoid's projective map would scale each ray's depth by its own factor and make
    /// the map's depth slope, and so the slope-scaled offset, huge).
    pub depth_view_proj: Option<Mat4>,
    /// One of several frusta over part of face `Face(f)`; None: a whole view.
    pub part: Option<FacePart>,
    /// Its map's side in texels: `shadow_map.size`, the light's own size (`auto`'s
    /// `shadow_map@N`), or its frustum's.
    pub size: u32,
}

impl ShadowView {
    pub fn view_proj(&self) -> Mat4 {
        self.projection * self.view
    }

    /// What drawing this view's map draws: a cube's six faces seen from the light at `eye`
    /// (by face), or the one view; for world positions, or with `origin` for positions
    /// relative to it (composed in double precision, see [`Self::texgen_relative`]).
    pub fn face_view_projs(&self, eye: Vec3, origin: Option<Vec3>) -> Vec<(Option<usize>, Mat4)> {
        let from = |m: glam::DMat4, world: Mat4| origin.map_or(world, |o| relative(m, o));
        match self.kind {
            ViewKind::Cube => (0..6)
                .map(|f| {
                    let view = cube_face_view(eye, f);
                    let m = self.projection.as_dmat4() * view.as_dmat4();
                    (Some(f), from(m, self.projection * view))
                })
                .collect(),
            _ => {
                let m = self.projection.as_dmat4() * self.view.as_dmat4();
                vec![(None, from(m, self.view_proj()))]
            }
        }
    }

    /// The matrix whose depth a warped map stores (`depth_view_proj`), for world positions or,
    /// with `origin`, for positions relative to it.
    pub fn depth_matrix_from(&self, origin: Option<Vec3>) -> Option<Mat4> {
        let m = self.depth_view_proj?;
        Some(origin.map_or(m, |o| relative(m.as_dmat4(), o)))
    }

    /// The side of this view's map in texels.
    pub fn map_size(&self) -> u32 {
        self.size
    }

    /// The paper's eye-linear texgen planes: T = B · P_light · V_light · V_camera⁻¹, taking camera
    /// eye coordinates to shadow-map coordinates (s, t, r, q).
    pub fn texgen(&self, camera_view: &Mat4) -> Mat4 {
        bias_matrix() * self.projection * self.view * camera_view.inverse()
    }

    /// [`Self::texgen`] for positions relative to `origin` (`shadow_map.texgen = light`): the
    /// same planes composed in double precision, so the shader applies them to small numbers.
    pub fn texgen_relative(&self, origin: Vec3) -> Mat4 {
        relative(
            bias_matrix().as_dmat4() * self.projection.as_dmat4() * self.view.as_dmat4(),
            origin,
        )
    }

    /// [`Self::depth_texgen`] for positions relative to `origin`.
    pub fn depth_texgen_relative(&self, origin: Vec3) -> Mat4 {
        let depth = match self.depth_view_proj {
            Some(m) => m.as_dmat4(),
            None => self.projection.as_dmat4() * self.view.as_dmat4(),
        };
        relative(bias_matrix().as_dmat4() * depth, origin)
    }

    /// The world → clip matrix whose depth the map holds.
    pub fn depth_matrix(&self) -> Mat4 {
        self.depth_view_proj.unwrap_or_else(|| self.view_proj())
    }

    /// The texgen of the compared depth (its r and q): [`Self::texgen`] unless the map's depth
    /// comes from another matrix.
    pub fn depth_texgen(&self, camera_view: &Mat4) -> Mat4 {
        bias_matrix() * self.depth_matrix() * camera_view.inverse()
    }

    /// World-space planes `(n, d)` (n·p + d ≥ 0 inside) of the frustum's four sides and its near
    /// plane, for clipping the lit pass (gl_ClipDistance).
    pub fn clip_planes(&self) -> [Vec4; 5] {
        crate::geometry::frustum::sides_and_near(&self.view_proj())
    }
}

/// `m` (world → clip, double precision) taking positions relative to `origin` instead.
fn relative(m: glam::DMat4, origin: Vec3) -> Mat4 {
    (m * glam::DMat4::from_translation(origin.as_dvec3())).as_mat4()
}

/// The cube face whose axis is the major axis of `d` (ties go to x, then y): the face partition
/// the shaders use too.
pub fn major_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 { 0 } else { 1 }
    } else if a.y >= a.z {
        if d.y >= 0.0 { 2 } else { 3 }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

/// Near and far for a view: fitted to the boxes of casters within the light's radius
/// (thesis 2.2.2), or near 1 and far = radius when fitting is off.
pub(crate) fn near_far(view: &Mat4, light: &Light, casters: &[Aabb], fit: bool) -> (f32, f32) {
    if !fit {
        return (MIN_NEAR, light.radius.max(MIN_NEAR * 2.0));
    }
    let reach = Aabb {
        min: light.position - light.radius,
        max: light.position + light.radius,
    };
    let corners = casters
        .iter()
        .filter(|b| {
            !b.is_empty()
                && b.min.x <= reach.max.x
                && b.max.x >= reach.min.x
                && b.min.y <= reach.max.y
                && b.max.y >= reach.min.y
                && b.min.z <= reach.max.z
                && b.max.z >= reach.min.z
        })
        .flat_map(|b| b.corners());
    let (near, far) = fit_near_far(view, corners, MIN_NEAR);
    // Nothing is lit beyond the radius, so no depth beyond it matters. A 2% margin keeps the
    // nearest and farthest casters off the planes themselves, where the polygon offset would push
    // them out (fixed-point maps hide that by clamping the compared depth; 32F maps do not).
    let near = (near / FIT_MARGIN).max(MIN_NEAR);
    let far = (far.min(light.radius) * FIT_MARGIN).max(near * FIT_MARGIN * FIT_MARGIN);
    (near, far)
}

/// The shadow views of `light`; `casters` are the world bounds of casting surfaces.
pub fn shadow_views(
    light: &Light,
    casters: &[Aabb],
    options: &ShadowMapOptions,
) -> Vec<ShadowView> {
    match light.kind {
        LightKind::Spot {
            direction,
            cutoff_deg,
        } => {
            let view = look_along(light.position, direction);
            let (near, far) = near_far(&view, light, casters, options.fit_near_far);
            // Thesis 2.2.2: the viewing angle is twice the cutoff angle.
            let fov = (2.0 * cutoff_deg * options.fov_scale)
                .clamp(1.0, 179.0)
                .to_radians();
            vec![ShadowView {
                kind: ViewKind::Spot,
                view,
                projection: perspective(fov, 1.0, near, far),
                near,
                far,
                depth_view_proj: None,
                part: None,
                size: options.size,
            }]
        }
        LightKind::Omni => {
            let fov = (90.0 * options.fov_scale).clamp(1.0, 179.0).to_radians();
            let faces: Vec<ShadowView> = (0..6)
                .map(|f| {
                    let view = cube_face_view(light.position, f);
                    let (near, far) = near_far(&view, light, casters, options.fit_near_far);
                    ShadowView {
                        kind: ViewKind::Face(f),
                        view,
                        projection: perspective(fov, 1.0, near, far),
                        near,
                        far,
                        depth_view_proj: None,
                        part: None,
                        size: options.size,
                    }
                })
                .collect();
            // ID and priority buffers read their maps as 2D textures: six spots always.
            let cube = options.omni == OmniMode::Cube
                && options.buffer == crate::options::MapBuffer::Depth;
            match cube {
                false => faces,
                true => {
                    // One range for all faces: a cube map is compared with one projection.
                    let near = faces.iter().map(|f| f.near).fold(f32::INFINITY, f32::min);
                    let far = faces.iter().map(|f| f.far).fold(0.0, f32::max);
                    vec![ShadowView {
                        kind: ViewKind::Cube,
                        view: Mat4::from_translation(-light.position),
                        projection: perspective(std::f32::consts::FRAC_PI_2, 1.0, near, far),
                        near,
                        far,
                        depth_view_proj: None,
                        part: None,
                        size: options.size,
                    }]
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spot_gets_one_view_of_twice_its_cutoff() {
        let light = Light::spot("s", Vec3::new(0.0, 0.0, 100.0), Vec3::ZERO, 30.0, 500.0);
        let boxes = [Aabb {
            min: Vec3::new(-100.0, -100.0, -1.0),
            max: Vec3::new(100.0, 100.0, 0.0),
        }];
        let v = shadow_views(&light, &boxes, &ShadowMapOptions::default());
        assert_eq!(v.len(), 1);
        // The floor lies 100 to 101 units below: the fitted range encloses it with its margin.
        assert!(
            (v[0].near - 100.0 / FIT_MARGIN).abs() < 1e-3,
            "near {}",
            v[0].near
        );
        assert!(
            (v[0].far - 101.0 * FIT_MARGIN).abs() < 1e-3,
            "far {}",
            v[0].far
        );
        // A point at 29.9° off the axis projects inside the map; the edge of the FOV is at 30°.
        let p = Vec3::new(100.0 * 29.9f32.to_radians().tan(), 0.0, 0.0);
        let c = v[0].view_proj() * p.extend(1.0);
        assert!(c.x.abs() < c.w && c.x.abs() > 0.99 * c.w);
    }

    #[test]
    fn fitting_off_uses_the_radius() {
        let light = Light::omni("o", Vec3::ZERO, 300.0);
        let o = ShadowMapOptions {
            fit_near_far: false,
            ..ShadowMapOptions::default()
        };
        let v = shadow_views(&light, &[], &o);
        assert_eq!(v.len(), 6);
        assert!(v.iter().all(|f| f.near == MIN_NEAR && f.far == 300.0));
    }

    #[test]
    fn the_six_faces_partition_directions_and_each_contains_its_share() {
        let light = Light::omni("o", Vec3::new(5.0, 6.0, 7.0), 1000.0);
        let v = shadow_views(&light, &[], &ShadowMapOptions::default());
        for i in 0..500 {
            let t = i as f32 * 0.618;
            let d =
                Vec3::new(t.sin() * 3.0, (t * 1.7).cos() * 2.0, (t * 0.3).sin() - 0.2).normalize();
            let f = major_face(d);
            let c = v[f].view_proj() * (light.position + d * 50.0).extend(1.0);
            assert!(
                c.w > 0.0 && c.x.abs() <= c.w * 1.0001 && c.y.abs() <= c.w * 1.0001,
                "{d} face {f}"
            );
        }
        assert_eq!(major_face(Vec3::new(1.0, 1.0, 0.0)), 0, "ties go to x");
        assert_eq!(major_face(Vec3::new(0.0, -1.0, 1.0)), 3, "then to y");
    }

    #[test]
    fn texgen_maps_eye_space_to_the_unit_cube() {
        let light = Light::spot("s", Vec3::new(0.0, 0.0, 100.0), Vec3::ZERO, 30.0, 500.0);
        let unfitted = ShadowMapOptions {
            fit_near_far: false,
            ..ShadowMapOptions::default()
        };
        let v = shadow_views(&light, &[], &unfitted)[0];
        let camera_view = Mat4::look_at_rh(Vec3::new(50.0, -80.0, 60.0), Vec3::ZERO, Vec3::Z);
        let eye = camera_view.transform_point3(Vec3::ZERO);
        let t = v.texgen(&camera_view) * eye.extend(1.0);
        // The spot's target is the centre of its map.
        assert!((t.x / t.w - 0.5).abs() < 1e-5 && (t.y / t.w - 0.5).abs() < 1e-5);
        assert!(t.z / t.w > 0.0 && t.z / t.w < 1.0);
    }

    #[test]
    fn clip_planes_keep_the_inside() {
        let light = Light::spot("s", Vec3::new(0.0, 0.0, 100.0), Vec3::ZERO, 30.0, 500.0);
        let v = shadow_views(&light, &[], &ShadowMapOptions::default())[0];
        let inside = Vec3::new(10.0, 10.0, 0.0).extend(1.0);
        let outside = Vec3::new(80.0, 0.0, 0.0).extend(1.0);
        assert!(v.clip_planes().iter().all(|p| p.dot(inside) >= 0.0));
        assert!(v.clip_planes().iter().any(|p| p.dot(outside) < 0.0));
    }
}
