//! Per-frame decisions, free of GL: which camera, which surfaces, which lights and which passes.
//!
//! The GL layer executes a [`Plan`] and decides nothing about *what* to draw.

use crate::options::Options;
use crate::scene::Scene;
use crate::shadow::projection;
use glam::{Mat3, Mat4, Vec3};

/// The camera as the passes use it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSetup {
    pub position: Vec3,
    pub view: Mat4,
    pub projection: Mat4,
    pub view_proj: Mat4,
    pub width: u32,
    pub height: u32,
}

impl CameraSetup {
    pub fn new(scene: &Scene, width: u32, height: u32) -> CameraSetup {
        let aspect = width as f32 / height as f32;
        let c = &scene.camera;
        let view = c.view();
        // The paper's camera: far plane at infinity (section 4.1), so nothing is ever far-clipped.
        let projection = projection::perspective_infinite(c.fov_y(aspect), aspect, c.near);
        CameraSetup {
            position: c.position,
            view,
            projection,
            view_proj: projection * view,
            width,
            height,
        }
    }
}

/// One light's work this frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LightPlan {
    /// Index into `Scene::lights`.
    pub light: usize,
}

/// Everything the passes need to know for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub camera: CameraSetup,
    /// Per surface: drawn in camera passes.
    pub visible: Vec<bool>,
    pub lights: Vec<LightPlan>,
}

impl Plan {
    pub fn build(scene: &Scene, options: &Options) -> Plan {
        let camera = CameraSetup::new(scene, options.width, options.height);
        let visible = scene
            .surfaces
            .iter()
            .map(|s| scene.materials[s.material].visible)
            .collect();
        let lights = (0..scene.lights.len())
            .filter(|&i| options.light_enabled(i))
            .map(|light| LightPlan { light })
            .collect();
        Plan {
            camera,
            visible,
            lights,
        }
    }
}

/// Inverse transpose of the upper 3x3: transforms normals of a model with scaling.
pub fn normal_matrix(model: &Mat4) -> Mat3 {
    Mat3::from_mat4(*model).inverse().transpose()
}
