//! Warped shadow maps: perspective shadow maps (Stamminger & Drettakis 2002, the thesis's
//! chapter 4) and trapezoidal shadow maps (Martin & Tan 2004), each a 4×4 matrix that replaces
//! one standard view's, so that the map pass, the texgen of the lit pass and every debug view
//! take it unchanged.
//!
//! Both warp one view at a time (a spot's frustum, or one of an omni light's six faces, whose
//! directions the lit pass still picks by the world-space major axis), fitted to the *focus*:
//! the receivers in view clipped to the camera's frustum and the view's own (the thesis's
//! cube clipping). A degenerate case returns why, and the planner falls back to the standard
//! view (`psm.fallback`).
//!
//! Depth along each light ray keeps its order under both warps (the map pass and the lit pass
//! share the matrix, and a compare only ever meets depths of one ray), which is all a depth
//! compare needs: a trapezoidal map scales each ray's depths by its own positive constant.

use crate::geometry::Aabb;
use crate::geometry::clip::clip_box;
use crate::geometry::frustum::sides_and_near;
use crate::options::{PsmOptions, Warp};
use crate::scene::Camera;
use glam::{Mat4, Vec2, Vec3, Vec4, Vec4Swizzles};

/// Why a view keeps its standard map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Degenerate {
    /// No receiver of this view lies in the camera's frustum: nothing to warp toward.
    NothingInView,
    /// Forsyth's duelling frusta: the light shines toward the camera, and the warp would give
    /// the near field no more texels than the far one.
    DuellingFrusta,
    /// The light lies in the virtual camera's plane: a directional light in post-perspective
    /// space (no single frustum from a point there).
    LightInCameraPlane,
    /// The light is behind the virtual camera and `psm.invert` is off.
    LightBehind,
    /// In post-perspective space the light sees the view from within (wider than
    /// `psm.max_fov`): one map cannot cover it.
    TooWide,
    /// Trapezoidal: the camera looks along the light's rays, so its frustum has no direction
    /// on the map to spend texels along.
    ViewAlongLight,
}

impl Degenerate {
    pub fn describe(self) -> &'static str {
        match self {
            Degenerate::NothingInView => "no receiver of the view in the camera's frustum",
            Degenerate::DuellingFrusta => "duelling frusta (the light shines toward the camera)",
            Degenerate::LightInCameraPlane => {
                "the light lies in the camera's plane (directional after the projection)"
            }
            Degenerate::LightBehind => "the light is behind the camera (psm.invert is off)",
            Degenerate::TooWide => "the light sees the view from inside (wider than psm.max_fov)",
            Degenerate::ViewAlongLight => "the camera looks along the light's rays",
        }
    }
}

/// A warped view: world → map clip space is `projection * view`.
#[derive(Debug, Clone, PartialEq)]
pub struct Warped {
    pub view: Mat4,
    pub projection: Mat4,
    /// Per caster box given, whether it can shadow the focus (only those are drawn: a
    /// caster behind the virtual camera would be projected through infinity).
    pub casters: Vec<bool>,
    /// How far the virtual camera slid back, in world units (perspective maps).
    pub slide: f32,
    /// The light was behind the virtual camera and is drawn with its depth range reversed.
    pub inverted: bool,
    /// The matrix whose depth the map keeps, when not `projection * view` (trapezoidal).
    pub depth: Option<Mat4>,
}

/// What a warp is fitted to.
pub struct WarpInput<'a> {
    pub camera: &'a Camera,
    /// Width / height of the frame.
    pub aspect: f32,
    pub light: Vec3,
    /// The standard view's world → clip matrix (its frustum bounds the focus).
    pub standard: Mat4,
    /// Boxes of the receivers this view lights.
    pub receivers: &'a [Aabb],
    /// Boxes of the casters this view draws.
    pub casters: &'a [Aabb],
    /// The light's range: with `psm.fit` off, the focus is the view frustum within it.
    pub reach: Aabb,
}

/// The warp `kind` of one view, or why it degenerates.
pub fn warp(kind: Warp, input: &WarpInput, o: &PsmOptions) -> Result<Warped, Degenerate> {
    let focus = focus_points(input, o.fit, None);
    if focus.is_empty() {
        return Err(Degenerate::NothingInView);
    }
    let parts = relevant_casters(input, &focus);
    match kind {
        Warp::Perspective => perspective(input, o, &focus, parts),
        Warp::Trapezoid => trapezoid(
            input,
            o,
            &focus,
            parts.iter().map(Option::is_some).collect(),
        ),
    }
}

/// The camera's world → clip matrix with a finite far plane (the focus is finite anyway).
fn camera_matrix(c: &Camera, aspect: f32) -> Mat4 {
    Mat4::perspective_infinite_rh(c.fov_y(aspect), aspect, c.near) * c.view()
}

/// The focus: each receiver box (or, without fitting, the light's range) clipped to the camera's
/// frustum and the standard view's (and to `extra`), as the vertices of the clipped polyhedra.
fn focus_points(input: &WarpInput, fit: bool, extra: Option<Vec4>) -> Vec<Vec3> {
    // No far planes: the camera's is at infinity, and receivers beyond the light's fitted far
    // plane are still looked up.
    let mut planes: Vec<Vec4> = sides_and_near(&camera_matrix(input.camera, input.aspect)).to_vec();
    planes.extend(sides_and_near(&input.standard));
    planes.extend(extra);
    let boxes: &[Aabb] = if fit {
        input.receivers
    } else {
        std::slice::from_ref(&input.reach)
    };
    let mut points = Vec::new();
    for b in boxes.iter().filter(|b| !b.is_empty()) {
        clip_box(b, &planes, &mut points);
    }
    points
}

/// Per caster box, its part that may shadow a focus point (None: none): the box clipped to the
/// frustum from the light around the focus's rectangle in the standard view, up to the focus's
/// farthest depth (a superset of the hull of the light and the focus, cheap to test). Only
/// these parts need the virtual camera in front of them.
fn relevant_casters(input: &WarpInput, focus: &[Vec3]) -> Vec<Option<Vec<Vec3>>> {
    let m = input.standard;
    let mut lo = Vec2::splat(f32::INFINITY);
    let mut hi = Vec2::splat(f32::NEG_INFINITY);
    let mut far = 0.0f32;
    for &p in focus {
        let c = m * p.extend(1.0);
        if c.w > 1e-6 {
            lo = lo.min(c.xy() / c.w);
            hi = hi.max(c.xy() / c.w);
            far = far.max(c.w);
        }
    }
    let (r0, r1, r3) = (m.row(0), m.row(1), m.row(3));
    let planes = [
        r0 - r3 * lo.x,
        r3 * hi.x - r0,
        r1 - r3 * lo.y,
        r3 * hi.y - r1,
        // In front of the light, and no farther than the focus.
        r3,
        Vec4::new(0.0, 0.0, 0.0, far) - r3,
    ];
    input
        .casters
        .iter()
        .map(|b| {
            let mut part = Vec::new();
            clip_box(b, &planes, &mut part);
            (!part.is_empty()).then_some(part)
        })
        .collect()
}

/// A perspective matrix from a half-angle tangent and a depth range; `reversed` maps `near` to
/// +1 and `far` to -1 (the order of depths inverted).
fn frustum(tan_half: f32, near: f32, far: f32, reversed: bool) -> Mat4 {
    let (n, f) = if reversed { (far, near) } else { (near, far) };
    let s = 1.0 / tan_half;
    Mat4::from_cols(
        Vec4::new(s, 0.0, 0.0, 0.0),
        Vec4::new(0.0, s, 0.0, 0.0),
        Vec4::new(0.0, 0.0, (f + n) / (n - f), -1.0),
        Vec4::new(0.0, 0.0, 2.0 * f * n / (n - f), 0.0),
    )
}

/// A look-at from `eye` toward `target` with any up vector not parallel to the view.
fn look_at(eye: Vec3, target: Vec3) -> Mat4 {
    let dir = (target - eye).normalize_or(Vec3::Z);
    let up = if dir.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    Mat4::look_to_rh(eye, dir, up)
}

/// Perspective shadow map: the virtual camera (slid back behind the casters), its
/// post-perspective space, and there a frustum from the light fitted to the focus.
fn perspective(
    input: &WarpInput,
    o: &PsmOptions,
    focus: &[Vec3],
    mut parts: Vec<Option<Vec<Vec3>>>,
) -> Result<Warped, Degenerate> {
    let cam = input.camera;
    let forward = cam.forward().normalize();
    let centre = focus.iter().copied().sum::<Vec3>() / focus.len() as f32;
    let to_focus = (centre - input.light).normalize_or(forward);
    let duel = to_focus.dot(forward).clamp(-1.0, 1.0).acos().to_degrees();
    if duel > o.duel_angle {
        return Err(Degenerate::DuellingFrusta);
    }
    // Slide back until every caster that may shadow the focus lies a near distance in front.
    let depth = |p: Vec3| (p - cam.position).dot(forward);
    let mut slide = 0.0f32;
    for part in parts.iter_mut() {
        let Some(points) = part else { continue };
        let nearest = points
            .iter()
            .map(|&c| depth(c))
            .fold(f32::INFINITY, f32::min);
        if nearest < cam.near {
            if o.slide_back {
                slide = slide.max(cam.near - nearest);
            } else {
                *part = None;
            }
        }
    }
    let eye = cam.position - forward * slide;
    let d_focus: Vec<f32> = focus.iter().map(|&p| depth(p) + slide).collect();
    let far = d_focus
        .iter()
        .copied()
        .fold(0.0f32, f32::max)
        .max(cam.near * 2.0);
    let near = d_focus
        .iter()
        .copied()
        .fold(f32::INFINITY, f32::min)
        .max(o.min_near * far)
        .max(1e-3)
        .min(far * 0.999);
    let up = cam.view().inverse().transform_vector3(Vec3::Y);
    let virtual_camera = Mat4::perspective_rh_gl(cam.fov_y(input.aspect), input.aspect, near, far)
        * Mat4::look_to_rh(eye, forward, up);
    let light_h = virtual_camera * input.light.extend(1.0);
    // w is the light's distance in front of the virtual eye.
    if light_h.w.abs() < 1e-4 * far {
        return Err(Degenerate::LightInCameraPlane);
    }
    let inverted = light_h.w < 0.0;
    if inverted && !o.invert {
        return Err(Degenerate::LightBehind);
    }
    let light = light_h.xyz() / light_h.w;
    let pps = |p: Vec3| {
        let c = virtual_camera * p.extend(1.0);
        c.xyz() / c.w
    };
    let focus_pps: Vec<Vec3> = focus.iter().map(|&p| pps(p)).collect();
    let (lo, hi) = focus_pps.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    // The axis: the mean of the directions to the focus points (inside their cone, and nearer
    // its middle than the direction to the centre of their box when the cone is wide).
    let axis = focus_pps
        .iter()
        .map(|&p| (p - light).normalize_or_zero())
        .sum::<Vec3>()
        .normalize_or(Vec3::Z);
    let light_view = look_at(light, light + axis);
    let scale = (hi - lo).length().max(1e-6);
    let mut tan_half = 0.0f32;
    let (mut d_min, mut d_max) = (f32::INFINITY, 0.0f32);
    for &p in &focus_pps {
        let v = light_view.transform_point3(p);
        let d = -v.z;
        if d <= 1e-4 * scale {
            return Err(Degenerate::TooWide);
        }
        tan_half = tan_half.max(v.x.abs() / d).max(v.y.abs() / d);
        d_min = d_min.min(d);
        d_max = d_max.max(d);
    }
    if 2.0 * tan_half.atan().to_degrees() > o.max_fov {
        return Err(Degenerate::TooWide);
    }
    // Casters extend the range toward the light: nearer it, or (inverted) farther from it.
    for points in parts.iter().flatten() {
        for &c in points {
            let d = -light_view.transform_point3(pps(c)).z;
            if d > 0.0 {
                if inverted {
                    d_max = d_max.max(d);
                } else {
                    d_min = d_min.min(d);
                }
            }
        }
    }
    let d_min = (d_min / 1.02).max(d_max * 1e-4);
    let d_max = d_max * 1.02;
    let projection = frustum(tan_half * 1.01, d_min, d_max, inverted) * light_view;
    Ok(Warped {
        view: virtual_camera,
        projection,
        casters: parts.iter().map(Option::is_some).collect(),
        slide,
        inverted,
        depth: None,
    })
}

/// Trapezoidal shadow map: in the standard view's map plane, the trapezoid around the focus
/// whose top edge lies at the camera's end, with Martin & Tan's 80% rule placing its apex, mapped
/// onto the square.
fn trapezoid(
    input: &WarpInput,
    o: &PsmOptions,
    focus: &[Vec3],
    casters: Vec<bool>,
) -> Result<Warped, Degenerate> {
    let m = input.standard;
    let cam = input.camera;
    let forward = cam.forward().normalize();
    let ndc = |p: Vec3| {
        let c = m * p.extend(1.0);
        c.xy() / c.w.max(1e-6)
    };
    let depths: Vec<f32> = focus
        .iter()
        .map(|&p| (p - cam.position).dot(forward))
        .collect();
    let d_near = depths.iter().copied().fold(f32::INFINITY, f32::min);
    let d_far = depths.iter().copied().fold(0.0f32, f32::max);
    let span = (d_far - d_near).max(1e-6);
    // The centre line runs from the focus's near end to its far end on the map (Martin & Tan
    // take the centres of the camera's near and far planes, which may lie behind the light:
    // the focus points all lie in front of it).
    let centroid = |keep: &dyn Fn(f32) -> bool| {
        let (sum, n) = focus
            .iter()
            .zip(&depths)
            .filter(|(_, d)| keep(**d))
            .fold((Vec2::ZERO, 0.0f32), |(s, n), (&p, _)| {
                (s + ndc(p), n + 1.0)
            });
        sum / n.max(1.0)
    };
    let top = centroid(&|d| d <= d_near + 0.1 * span);
    let base = centroid(&|d| d >= d_far - 0.1 * span);
    let axis = base - top;
    if axis.length() < 1e-3 {
        return Err(Degenerate::ViewAlongLight);
    }
    let u = axis.normalize();
    let v = Vec2::new(-u.y, u.x);
    let coords: Vec<Vec2> = focus
        .iter()
        .map(|&p| {
            let q = ndc(p) - top;
            Vec2::new(q.dot(u), q.dot(v))
        })
        .collect();
    let a_top = coords.iter().map(|c| c.x).fold(f32::INFINITY, f32::min);
    let a_base = coords.iter().map(|c| c.x).fold(f32::NEG_INFINITY, f32::max);
    let height = (a_base - a_top).max(1e-6);
    // The 80% rule: the part of the focus within the first `tsm_focus` of its depth range maps
    // onto the first 80% of the height.
    let focus_depth = d_near + o.tsm_focus * span;
    let near_part = Vec4::from((-forward, forward.dot(cam.position) + focus_depth));
    let delta = focus_points(input, o.fit, Some(near_part))
        .iter()
        .map(|&p| (ndc(p) - top).dot(u) - a_top)
        .fold(0.0f32, f32::max)
        .clamp(0.0, height);
    let xi = 0.6f32;
    let denominator = height * (1.0 + xi) - 2.0 * delta;
    let eta = if denominator > 1e-6 * height {
        (height * delta * (1.0 - xi) / denominator).clamp(1e-3 * height, 1e3 * height)
    } else {
        1e3 * height
    };
    let apex = a_top - eta;
    let slope = coords
        .iter()
        .map(|c| c.y.abs() / (c.x - apex))
        .fold(1e-6f32, f32::max)
        * 1.01;
    // Along the centre line, y' = A - B / a1 takes the top (a1 = eta) to -1 and the base to +1.
    let b = 2.0 * eta * (height + eta) / height;
    let a = 1.0 + 2.0 * eta / height;
    // Rows acting on the standard view's clip coordinates (x, y, z, w).
    let t_u = top.dot(u);
    let t_v = top.dot(v);
    let w_row = Vec4::new(u.x, u.y, 0.0, -(t_u + apex));
    let x_row = Vec4::new(v.x, v.y, 0.0, -t_v) / slope;
    let y_row = w_row * a - Vec4::new(0.0, 0.0, 0.0, b);
    // Each ray's depth divides by its a1 >= eta: scaled by eta it stays within [-1, 1] and in
    // order along the ray; the map stores the standard view's depth instead (`depth`), but
    // clipping uses this one.
    let z_row = Vec4::new(0.0, 0.0, eta, 0.0);
    let n = Mat4::from_cols(x_row, y_row, z_row, w_row).transpose();
    Ok(Warped {
        view: Mat4::IDENTITY,
        projection: n * m,
        casters,
        slide: 0.0,
        inverted: false,
        depth: Some(m),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::projection::perspective;

    fn spot_down(at: Vec3) -> Mat4 {
        perspective(100f32.to_radians(), 1.0, 1.0, 400.0)
            * crate::geometry::projection::look_along(at, -Vec3::Z)
    }

    fn floor() -> Aabb {
        Aabb {
            min: Vec3::new(-300.0, -300.0, -1.0),
            max: Vec3::new(300.0, 300.0, 0.0),
        }
    }

    fn grazing_camera() -> Camera {
        let mut c = Camera::looking_at(Vec3::new(0.0, -200.0, 20.0), Vec3::new(0.0, 200.0, 0.0));
        c.near = 1.0;
        c
    }

    fn input<'a>(camera: &'a Camera, receivers: &'a [Aabb], casters: &'a [Aabb]) -> WarpInput<'a> {
        let light = Vec3::new(0.0, 0.0, 200.0);
        WarpInput {
            camera,
            aspect: 4.0 / 3.0,
            light,
            standard: spot_down(light),
            receivers,
            casters,
            reach: Aabb {
                min: light - 400.0,
                max: light + 400.0,
            },
        }
    }

    /// Map area per world area at floor point `p` (the square root: texels per world unit)
    /// under a world → clip matrix.
    fn density(m: &Mat4, p: Vec3) -> f32 {
        let at = |q: Vec3| {
            let c = *m * q.extend(1.0);
            c.xy() / c.w
        };
        let (dx, dy) = (at(p + Vec3::X) - at(p), at(p + Vec3::Y) - at(p));
        (dx.x * dy.y - dx.y * dy.x).abs().sqrt()
    }

    #[test]
    fn both_warps_give_the_near_field_more_texels_than_the_standard_map() {
        let camera = grazing_camera();
        let receivers = [floor()];
        let caster = [Aabb {
            min: Vec3::new(-10.0, -150.0, 0.0),
            max: Vec3::new(10.0, -130.0, 30.0),
        }];
        let i = input(&camera, &receivers, &caster);
        let near = Vec3::new(0.0, -170.0, 0.0);
        let far = Vec3::new(0.0, 250.0, 0.0);
        for kind in [Warp::Perspective, Warp::Trapezoid] {
            let w = warp(kind, &i, &PsmOptions::default()).expect("warps");
            let m = w.projection * w.view;
            let gain_near = density(&m, near) / density(&i.standard, near);
            let gain_far = density(&m, far) / density(&i.standard, far);
            assert!(gain_near > 1.5, "{kind:?}: near gain {gain_near}");
            assert!(gain_near > 2.0 * gain_far, "{kind:?}: far gain {gain_far}");
            assert!(w.casters[0], "the caster in front is kept");
            // Every focus point lands in the map with its depth in range.
            for p in focus_points(&i, true, None) {
                let c = m * p.extend(1.0);
                let n = c.xyz() / c.w;
                assert!(
                    c.w > 0.0 && n.abs().max_element() <= 1.0001,
                    "{kind:?} {p} -> {n}"
                );
            }
        }
    }

    #[test]
    fn depth_order_along_a_light_ray_is_kept() {
        let camera = grazing_camera();
        let receivers = [floor()];
        let i = input(&camera, &receivers, &[]);
        for kind in [Warp::Perspective, Warp::Trapezoid] {
            let w = warp(kind, &i, &PsmOptions::default()).unwrap();
            let m = w.projection * w.view;
            let ray = |t: f32| i.light + (Vec3::new(0.0, -150.0, 0.0) - i.light) * t;
            let depth = |t: f32| {
                let c = m * ray(t).extend(1.0);
                c.z / c.w
            };
            let xy = |t: f32| {
                let c = m * ray(t).extend(1.0);
                c.xy() / c.w
            };
            assert!(
                depth(0.5) < depth(0.9) && depth(0.9) < depth(1.0),
                "{kind:?}"
            );
            assert!(
                (xy(0.5) - xy(1.0)).length() < 1e-3,
                "{kind:?}: one ray, one texel"
            );
        }
    }

    #[test]
    fn a_light_behind_the_camera_is_inverted_or_falls_back() {
        let mut camera = grazing_camera();
        // Looking away from the light, which stands behind and above.
        camera.position = Vec3::new(0.0, 150.0, 20.0);
        let camera = {
            let mut c = Camera::looking_at(camera.position, Vec3::new(0.0, 400.0, 0.0));
            c.near = 1.0;
            c
        };
        let receivers = [floor()];
        let caster = [Aabb {
            min: Vec3::new(-10.0, 180.0, 0.0),
            max: Vec3::new(10.0, 200.0, 30.0),
        }];
        let mut i = input(&camera, &receivers, &caster);
        i.light = Vec3::new(0.0, 0.0, 60.0);
        i.standard = perspective(160f32.to_radians(), 1.0, 1.0, 600.0)
            * crate::geometry::projection::look_along(i.light, Vec3::new(0.0, 1.0, -0.3));
        let w = warp(Warp::Perspective, &i, &PsmOptions::default()).expect("inverted");
        assert!(w.inverted);
        let m = w.projection * w.view;
        // The caster is nearer the light on the ray to the floor behind it: smaller depth.
        let floor_point = Vec3::new(0.0, 300.0, 0.0);
        let on_ray = i.light + (floor_point - i.light) * 0.7;
        let d = |p: Vec3| {
            let c = m * p.extend(1.0);
            assert!(c.w > 0.0);
            c.z / c.w
        };
        assert!(d(on_ray) < d(floor_point));
        let no_invert = PsmOptions {
            invert: false,
            ..PsmOptions::default()
        };
        assert_eq!(
            warp(Warp::Perspective, &i, &no_invert),
            Err(Degenerate::LightBehind)
        );
    }

    #[test]
    fn duelling_frusta_are_detected() {
        // The camera looks straight at a light that shines back at it.
        let camera = {
            let mut c = Camera::looking_at(Vec3::new(0.0, -200.0, 40.0), Vec3::new(0.0, 0.0, 40.0));
            c.near = 1.0;
            c
        };
        let receivers = [floor()];
        let mut i = input(&camera, &receivers, &[]);
        i.light = Vec3::new(0.0, 100.0, 40.0);
        i.standard = perspective(120f32.to_radians(), 1.0, 1.0, 600.0)
            * crate::geometry::projection::look_along(i.light, Vec3::new(0.0, -1.0, -0.2));
        assert_eq!(
            warp(Warp::Perspective, &i, &PsmOptions::default()),
            Err(Degenerate::DuellingFrusta)
        );
    }

    #[test]
    fn casters_behind_the_camera_slide_it_back_or_are_dropped() {
        let camera = grazing_camera();
        let receivers = [floor()];
        // Between the light and the floor in view, behind the camera's eye: its shadow falls
        // about 150 units ahead of the camera.
        let caster = [Aabb {
            min: Vec3::new(-10.0, -225.0, 120.0),
            max: Vec3::new(10.0, -215.0, 130.0),
        }];
        let mut i = input(&camera, &receivers, &caster);
        i.light = Vec3::new(0.0, -260.0, 200.0);
        i.standard = spot_down(i.light);
        let w = warp(Warp::Perspective, &i, &PsmOptions::default()).unwrap();
        assert!(w.casters[0] && w.slide > 10.0, "slide {}", w.slide);
        let fixed = PsmOptions {
            slide_back: false,
            ..PsmOptions::default()
        };
        let w = warp(Warp::Perspective, &i, &fixed).unwrap();
        assert!(!w.casters[0] && w.slide == 0.0);
    }
}
