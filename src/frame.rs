//! What rendering one frame produces: the image, and how long each pass took.

use glam::{Mat4, Vec3};
use serde::Serialize;
use std::path::Path;

/// Time spent in one pass of a frame.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PassTime {
    /// e.g. `base`, `light0.lit`.
    pub name: String,
    pub ms: f64,
    /// `gpu` (GL_TIME_ELAPSED) or `cpu` (wall time around glFinish, or CPU-only work).
    pub clock: &'static str,
}

#[derive(Debug, Clone)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA8, top row first.
    pub rgba: Vec<u8>,
    /// World to clip space of the camera that rendered the frame.
    pub view_proj: Mat4,
    pub passes: Vec<PassTime>,
    /// Wall time of the whole frame including glFinish.
    pub frame_ms: f64,
}

impl Frame {
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// Rec. 709 luma of a pixel, 0..=255.
    pub fn luma(&self, x: u32, y: u32) -> f32 {
        let p = self.pixel(x, y);
        0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32
    }

    /// The pixel (column, row from the top) a world point lands on, if it is in front of the
    /// camera and on screen.
    pub fn project(&self, world: Vec3) -> Option<(u32, u32)> {
        let c = self.view_proj * world.extend(1.0);
        if c.w <= 0.0 {
            return None;
        }
        let ndc = c.truncate() / c.w;
        let x = (ndc.x * 0.5 + 0.5) * self.width as f32;
        let y = (0.5 - ndc.y * 0.5) * self.height as f32;
        if x < 0.0 || y < 0.0 || x >= self.width as f32 || y >= self.height as f32 {
            return None;
        }
        Some((x as u32, y as u32))
    }

    pub fn save_png(&self, path: &Path) -> Result<(), image::ImageError> {
        image::save_buffer(
            path,
            &self.rgba,
            self.width,
            self.height,
            image::ExtendedColorType::Rgba8,
        )
    }

    /// Milliseconds of the named pass, if it ran.
    pub fn pass_ms(&self, name: &str) -> Option<f64> {
        self.passes.iter().find(|p| p.name == name).map(|p| p.ms)
    }
}
