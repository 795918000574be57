//! What rendering one frame produces: the image, and how long each pass took.

use glam::{Mat4, Vec3};
use serde::Serialize;
use std::path::Path;

/// An RGBA8 image, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgba {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

impl Rgba {
    pub fn save(&self, path: &Path) -> Result<(), image::ImageError> {
        image::save_buffer(
            path,
            &self.data,
            self.width,
            self.height,
            image::ExtendedColorType::Rgba8,
        )
    }
}

/// What a step of a frame does (the walkthrough steps through them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StepKind {
    /// Draw the casters' depth from a light (one view or cube face).
    LightView,
    /// Copy the depth buffer into the shadow map texture.
    DepthCopy,
    /// The unlit world: depth and baked light.
    Base,
    /// Count a light's shadow volumes into the stencil buffer.
    Stencil,
    /// A light's additive pass.
    Lit,
    /// The fill quad that darkens where the stencil is set.
    Fill,
}

/// One executed step of a frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    pub kind: StepKind,
    pub light: Option<usize>,
    /// The shadow-map view (spot, six-spot face) or cube face, for light views and copies.
    pub face: Option<usize>,
    /// The technique the light's step runs under (resolved: never `auto`).
    pub technique: Option<crate::options::Technique>,
}

/// What the frame reused from earlier frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct CacheStats {
    pub maps_rendered: usize,
    pub maps_reused: usize,
    /// The planner's depth taken from the last frame, not read back: the base pass drew the
    /// same thing (`plan.reuse_depth`).
    pub depth_reused: bool,
    pub volume_parts_built: usize,
    pub volume_parts_reused: usize,
}

/// A light's stencil counts after its volume pass (row-major, top row first).
#[derive(Debug, Clone, PartialEq)]
pub struct StencilImage {
    pub light: usize,
    pub width: u32,
    pub height: u32,
    pub values: Vec<u8>,
    /// Whether the counts wrap modulo 256 (255 is then -1), rather than saturating.
    pub wraps: bool,
}

/// Time spent in one pass of a frame.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PassTime {
    /// e.g. `base`, `light0.lit`.
    pub name: String,
    pub ms: f64,
    /// `gpu` (GL_TIME_ELAPSED) or `cpu` (wall time around glFinish, or CPU-only work).
    pub clock: &'static str,
}

/// One light's decision at one pixel. Stored as `u8` in masks and mask PNGs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[repr(u8)]
pub enum MaskValue {
    /// Background, outside the light's cone or range, facing away, or a surface that takes no
    /// dynamic light.
    NotReceiver = 0,
    Lit = 1,
    Shadowed = 2,
}

impl MaskValue {
    pub fn from_u8(v: u8) -> MaskValue {
        match v {
            1 => MaskValue::Lit,
            2 => MaskValue::Shadowed,
            _ => MaskValue::NotReceiver,
        }
    }
}

/// One light's decision for every pixel (row-major, top row first; values of [`MaskValue`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Mask {
    pub light: usize,
    pub width: u32,
    pub height: u32,
    pub values: Vec<u8>,
}

impl Mask {
    pub fn get(&self, x: u32, y: u32) -> MaskValue {
        MaskValue::from_u8(self.values[(y * self.width + x) as usize])
    }

    pub fn count(&self, v: MaskValue) -> usize {
        self.values.iter().filter(|&&x| x == v as u8).count()
    }

    /// Black = not a receiver, white = lit, mid grey = shadowed.
    pub fn save_png(&self, path: &Path) -> Result<(), image::ImageError> {
        let grey: Vec<u8> = self
            .values
            .iter()
            .map(|&v| match MaskValue::from_u8(v) {
                MaskValue::NotReceiver => 0,
                MaskValue::Lit => 255,
                MaskValue::Shadowed => 96,
            })
            .collect();
        image::save_buffer(
            path,
            &grey,
            self.width,
            self.height,
            image::ExtendedColorType::L8,
        )
    }
}

/// What the camera sees at each pixel, read back from a G-buffer pass (row-major, top row first).
#[derive(Debug, Clone, PartialEq)]
pub struct GBuffer {
    pub width: u32,
    pub height: u32,
    /// World position of the visible surface.
    pub position: Vec<[f32; 3]>,
    /// Shading normal, facing the camera on two-sided surfaces.
    pub normal: Vec<[f32; 3]>,
    /// Per pixel: 0 background, 1 a surface that receives dynamic light, 2 one that does not.
    pub kind: Vec<u8>,
}

impl GBuffer {
    pub fn is_receiver_surface(&self, i: usize) -> bool {
        self.kind[i] == 1
    }
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
    /// What the camera sees per pixel (when masks were requested).
    pub gbuffer: Option<GBuffer>,
    /// Each planned light's decision per pixel (when masks were requested).
    pub masks: Vec<Mask>,
    /// Shadow-volume work per light (shadow volumes only).
    pub volumes: Vec<crate::gl::volumes::VolumeStats>,
    /// The steps executed, in order (all of them unless the request stopped early).
    pub steps: Vec<Step>,
    /// The buffer the last step wrote, as an image, when the request stopped after a step.
    pub step_image: Option<Rgba>,
    /// A light's stencil counts, when the request asked for them.
    pub stencil: Option<StencilImage>,
    /// What the plan decided (visible surfaces, triangles, BSP culling, lights and casters
    /// culled, scissor, counting, auto choices).
    pub plan_stats: crate::plan::PlanStats,
    /// Shadow maps and volume parts drawn afresh or reused.
    pub cache: CacheStats,
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
