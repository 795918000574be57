//! The viewer's camera, Quake 3 style: a position, yaw about +Z and pitch, a vertical field of view.

use glam::{Mat4, Vec3};

/// Quake 3's player eye height above the spawn origin.
pub const Q3_VIEW_HEIGHT: f32 = 26.0;
/// Quake 3's `r_znear`.
pub const Q3_ZNEAR: f32 = 4.0;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// Degrees about +Z; 0 looks along +X, 90 along +Y (Quake 3's convention).
    pub yaw_deg: f32,
    /// Degrees; positive looks up (Quake 3's pitch is the opposite sign).
    pub pitch_deg: f32,
    /// Horizontal field of view in degrees (Quake 3's `cg_fov`, 90 by default).
    pub fov_x_deg: f32,
    /// Near plane distance.
    pub near: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            position: Vec3::ZERO,
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            fov_x_deg: 90.0,
            near: Q3_ZNEAR,
        }
    }
}

impl Camera {
    /// A camera at `position` looking at `target`.
    pub fn looking_at(position: Vec3, target: Vec3) -> Camera {
        let d = (target - position).normalize_or(Vec3::X);
        Camera {
            position,
            yaw_deg: d.y.atan2(d.x).to_degrees(),
            pitch_deg: d.z.clamp(-1.0, 1.0).asin().to_degrees(),
            ..Camera::default()
        }
    }

    pub fn forward(&self) -> Vec3 {
        let (y, p) = (self.yaw_deg.to_radians(), self.pitch_deg.to_radians());
        Vec3::new(y.cos() * p.cos(), y.sin() * p.cos(), p.sin())
    }

    /// World to eye space (right-handed, looking down -Z in eye space, +Z world up).
    pub fn view(&self) -> Mat4 {
        let f = self.forward();
        // Straight up or down: any horizontal up vector keeps the matrix finite.
        let up = if f.cross(Vec3::Z).length_squared() < 1e-8 {
            Vec3::new(
                -self.yaw_deg.to_radians().cos(),
                -self.yaw_deg.to_radians().sin(),
                0.0,
            )
        } else {
            Vec3::Z
        };
        Mat4::look_to_rh(self.position, f, up)
    }

    /// Vertical field of view in radians for a frame of this aspect ratio (width / height).
    pub fn fov_y(&self, aspect: f32) -> f32 {
        let half_x = (self.fov_x_deg.to_radians() * 0.5).tan();
        2.0 * (half_x / aspect).atan()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn looking_at_points_forward_at_the_target() {
        let c = Camera::looking_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 6.0, 3.0));
        assert!((c.forward() - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-6);
        let eye = c.view().transform_point3(Vec3::new(4.0, 6.0, 3.0));
        assert!((eye - Vec3::new(0.0, 0.0, -5.0)).length() < 1e-5);
    }

    #[test]
    fn view_is_finite_looking_straight_down() {
        let c = Camera::looking_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO);
        assert!(c.view().is_finite());
        let eye = c.view().transform_point3(Vec3::ZERO);
        assert!((eye - Vec3::new(0.0, 0.0, -10.0)).length() < 1e-5);
    }

    #[test]
    fn q3_default_fov_at_4_3_is_73_74_degrees_vertical() {
        let c = Camera::default();
        assert!((c.fov_y(4.0 / 3.0).to_degrees() - 73.7398).abs() < 1e-3);
    }
}
