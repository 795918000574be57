//! Projection matrices in OpenGL's conventions (eye space looks down -Z, clip depth in [-1, 1]),
//! and the light frusta of shadow mapping.
//!
//! - finite perspective: glFrustum / gluPerspective;
//! - infinite far plane: the limit f → ∞ of the finite matrix (Lengyel, "The Mechanics of Robust
//!   Stencil Shadows"; paper section 4.1), so that vertices at infinity (w = 0) are not clipped;
//! - the same with Lengyel's epsilon, which keeps w = 0 vertices strictly inside the far plane
//!   despite round-off (Doom 3 uses this);
//! - the bias matrix B that maps light clip space [-1, 1] to texture space [0, 1] (thesis 2.1.1).

use glam::{Mat4, Vec3, Vec4};

/// gluPerspective: vertical field of view `fov_y` (radians), `aspect` = width / height.
pub fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    Mat4::perspective_rh_gl(fov_y, aspect, near, far)
}

/// The paper's P_new = lim_{f→∞} P: third row (0, 0, -1, -2n).
pub fn perspective_infinite(fov_y: f32, aspect: f32, near: f32) -> Mat4 {
    perspective_infinite_epsilon(fov_y, aspect, near, 0.0)
}

/// Infinite projection with Lengyel's epsilon: third row (0, 0, ε - 1, n(ε - 2)).
/// With ε = 0.001 the row starts with -0.999, "crunched" so that w = 0 points land at depth
/// 1 - ε instead of exactly on the far plane.
pub fn perspective_infinite_epsilon(fov_y: f32, aspect: f32, near: f32, epsilon: f32) -> Mat4 {
    let f = 1.0 / (fov_y * 0.5).tan();
    Mat4::from_cols(
        Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, f, 0.0, 0.0),
        Vec4::new(0.0, 0.0, epsilon - 1.0, -1.0),
        Vec4::new(0.0, 0.0, near * (epsilon - 2.0), 0.0),
    )
}

/// B: x, y, z from [-1, 1] to [0, 1] (translate 0.5 · scale 0.5).
pub fn bias_matrix() -> Mat4 {
    Mat4::from_translation(Vec3::splat(0.5)) * Mat4::from_scale(Vec3::splat(0.5))
}

/// A view matrix looking from `eye` along `dir`, with an up vector that is never parallel to it
/// (the thesis notes the up vector only has to differ from the light direction).
pub fn look_along(eye: Vec3, dir: Vec3) -> Mat4 {
    let dir = dir.normalize_or(-Vec3::Z);
    let up = if dir.cross(Vec3::Z).length_squared() < 1e-6 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    Mat4::look_to_rh(eye, dir, up)
}

/// Directions and up vectors of the six 90° frusta that cover an omni light (the paper's
/// "six lights with 90 degree FOVs"), in the GL cube-map face order +X, -X, +Y, -Y, +Z, -Z.
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// View matrix of cube face `face` (0..6) of an omni light at `eye`.
pub fn cube_face_view(eye: Vec3, face: usize) -> Mat4 {
    let (dir, up) = CUBE_FACES[face];
    Mat4::look_to_rh(eye, dir, up)
}

/// Near and far distances along a view that just enclose `points` (thesis 2.2.2: a tight range
/// gives the depth texture its precision). Points behind the eye pull the near plane in to
/// `min_near`, which it never goes below; far always lies beyond near, by at least 0.1%.
pub fn fit_near_far(
    view: &Mat4,
    points: impl IntoIterator<Item = Vec3>,
    min_near: f32,
) -> (f32, f32) {
    let mut near = f32::INFINITY;
    let mut far = 0.0f32;
    for p in points {
        let depth = -view.transform_point3(p).z;
        if depth > 0.0 {
            near = near.min(depth);
            far = far.max(depth);
        } else {
            // Something is behind or beside the eye: the near plane has to come all the way in.
            near = min_near;
        }
    }
    let near = if near.is_finite() {
        near.max(min_near)
    } else {
        min_near
    };
    let far = far.max(near * 1.001);
    (near, far)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ndc(m: &Mat4, p: Vec4) -> Vec3 {
        let c = *m * p;
        c.truncate() / c.w
    }

    #[test]
    fn finite_perspective_maps_near_and_far_to_minus_one_and_one() {
        let p = perspective(1.0, 1.5, 2.0, 100.0);
        assert!((ndc(&p, Vec4::new(0.0, 0.0, -2.0, 1.0)).z + 1.0).abs() < 1e-6);
        assert!((ndc(&p, Vec4::new(0.0, 0.0, -100.0, 1.0)).z - 1.0).abs() < 1e-5);
    }

    #[test]
    fn infinite_perspective_is_the_limit_of_the_finite_one() {
        let (fov, aspect, n) = (1.2f32, 4.0 / 3.0, 4.0);
        let inf = perspective_infinite(fov, aspect, n);
        let far = perspective(fov, aspect, n, 1.0e7);
        for (a, b) in inf.to_cols_array().iter().zip(far.to_cols_array()) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        // Near plane at -1; a point at infinity (w = 0) lands exactly on the far plane, not beyond.
        assert!((ndc(&inf, Vec4::new(0.0, 0.0, -n, 1.0)).z + 1.0).abs() < 1e-6);
        let at_inf = inf * Vec4::new(0.3, -0.2, -1.0, 0.0);
        assert!((at_inf.z / at_inf.w - 1.0).abs() < 1e-6);
        assert!(at_inf.w > 0.0);
    }

    #[test]
    fn epsilon_keeps_points_at_infinity_inside_the_far_plane() {
        let p = perspective_infinite_epsilon(1.2, 1.0, 4.0, 0.001);
        assert!((p.col(2).z + 0.999).abs() < 1e-7);
        let c = p * Vec4::new(0.0, 0.0, -1.0, 0.0);
        assert!((c.z / c.w - 0.999).abs() < 1e-6);
        // The near plane moves by less than a part in a thousand.
        assert!((ndc(&p, Vec4::new(0.0, 0.0, -4.0, 1.0)).z + 1.0).abs() < 2e-3);
    }

    #[test]
    fn bias_matrix_maps_clip_cube_to_unit_cube() {
        let b = bias_matrix();
        assert_eq!(b.transform_point3(Vec3::splat(-1.0)), Vec3::ZERO);
        assert_eq!(b.transform_point3(Vec3::splat(1.0)), Vec3::ONE);
        assert_eq!(b.transform_point3(Vec3::ZERO), Vec3::splat(0.5));
    }

    #[test]
    fn six_cube_faces_cover_every_direction_once() {
        let proj = perspective(std::f32::consts::FRAC_PI_2, 1.0, 1.0, 100.0);
        // Sample directions; each must fall inside at least one face's frustum.
        let mut inside_counts = Vec::new();
        for i in 0..40 {
            for j in 0..20 {
                let phi = i as f32 / 40.0 * std::f32::consts::TAU + 0.01;
                let theta = (j as f32 + 0.5) / 20.0 * std::f32::consts::PI;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                let n = (0..6)
                    .filter(|&f| {
                        let c = proj * cube_face_view(Vec3::ZERO, f) * (d * 10.0).extend(1.0);
                        c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w
                    })
                    .count();
                inside_counts.push(n);
            }
        }
        assert!(inside_counts.iter().all(|&n| n >= 1));
    }

    #[test]
    fn spot_frustum_contains_its_cone() {
        let eye = Vec3::new(1.0, 2.0, 3.0);
        let dir = Vec3::new(0.3, -0.4, -0.8).normalize();
        let cutoff = 30f32.to_radians();
        let view = look_along(eye, dir);
        let proj = perspective(2.0 * cutoff, 1.0, 0.5, 100.0);
        // A ray at 29.9° from the axis in any roll stays inside the frustum.
        let side = dir.any_orthonormal_vector();
        for k in 0..16 {
            let roll = glam::Quat::from_axis_angle(dir, k as f32 / 16.0 * std::f32::consts::TAU);
            let axis = roll * side;
            let d = glam::Quat::from_axis_angle(axis, 29.9f32.to_radians()) * dir;
            let c = proj * view * (eye + d * 10.0).extend(1.0);
            assert!(c.x.abs() <= c.w && c.y.abs() <= c.w);
        }
    }

    #[test]
    fn fitted_range_encloses_the_points() {
        let view = look_along(Vec3::ZERO, -Vec3::Z);
        let pts = [Vec3::new(0.0, 0.0, -10.0), Vec3::new(1.0, 1.0, -50.0)];
        assert_eq!(fit_near_far(&view, pts, 1.0), (10.0, 50.0));
        let behind = [Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -20.0)];
        assert_eq!(fit_near_far(&view, behind, 1.0), (1.0, 20.0));
    }
}
