//! The fly-through camera: WASD to move along the view, Space and C up and down, mouse to look,
//! in Quake 3 units (320 units/s is Quake 3's run speed).

use crate::scene::Camera;
use glam::Vec3;

/// Quake 3's run speed, units per second.
pub const RUN_SPEED: f32 = 320.0;
/// Shift's speed factor.
pub const FAST: f32 = 3.0;
/// Degrees of turn per pixel of mouse motion.
pub const LOOK_DEG_PER_PIXEL: f32 = 0.2;

/// What the keys and the mouse ask for this frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FlyInput {
    pub forward: bool,
    pub back: bool,
    pub left: bool,
    pub right: bool,
    pub up: bool,
    pub down: bool,
    pub fast: bool,
    /// Mouse motion in pixels (right, down).
    pub look: [f32; 2],
}

impl FlyInput {
    pub fn moves(&self) -> bool {
        self.forward
            || self.back
            || self.left
            || self.right
            || self.up
            || self.down
            || self.look != [0.0, 0.0]
    }
}

/// Moves and turns `camera` for `dt` seconds of `input`.
pub fn fly(camera: &mut Camera, input: &FlyInput, dt: f32) {
    camera.yaw_deg = (camera.yaw_deg - input.look[0] * LOOK_DEG_PER_PIXEL).rem_euclid(360.0);
    camera.pitch_deg = (camera.pitch_deg - input.look[1] * LOOK_DEG_PER_PIXEL).clamp(-89.0, 89.0);
    let forward = camera.forward();
    let right = forward.cross(Vec3::Z).normalize_or(Vec3::Y);
    let axis = |pos: bool, neg: bool| pos as i32 as f32 - neg as i32 as f32;
    let dir = forward * axis(input.forward, input.back)
        + right * axis(input.right, input.left)
        + Vec3::Z * axis(input.up, input.down);
    let speed = RUN_SPEED * if input.fast { FAST } else { 1.0 };
    camera.position += dir.normalize_or_zero() * speed * dt.clamp(0.0, 0.25);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_at_run_speed_along_the_view_and_turns_with_the_mouse() {
        let mut c = Camera::default();
        fly(
            &mut c,
            &FlyInput {
                forward: true,
                ..FlyInput::default()
            },
            0.25,
        );
        assert!((c.position - Vec3::new(80.0, 0.0, 0.0)).length() < 1e-3);
        fly(
            &mut c,
            &FlyInput {
                right: true,
                fast: true,
                ..FlyInput::default()
            },
            0.1,
        );
        // Right of +X with +Z up is -Y.
        assert!((c.position - Vec3::new(80.0, -96.0, 0.0)).length() < 1e-3);
        // A stalled frame does not throw the camera across the map.
        let before = c.position;
        fly(
            &mut c,
            &FlyInput {
                forward: true,
                ..FlyInput::default()
            },
            5.0,
        );
        assert!((c.position - before).length() <= 0.25 * RUN_SPEED + 1e-3);
        fly(
            &mut c,
            &FlyInput {
                look: [-450.0, 1000.0],
                ..FlyInput::default()
            },
            0.0,
        );
        assert!((c.yaw_deg - 90.0).abs() < 1e-4);
        assert_eq!(c.pitch_deg, -89.0);
    }
}
