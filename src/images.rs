//! Images on the CPU, free of GL: RGBA8 pictures (frames, textures, lightmaps), each light's
//! decision mask, the G-buffer the reference reads and the stencil counts.

use serde::Serialize;
use std::path::Path;

/// An RGBA8 image, top row first: frames, textures and lightmaps (v = 0 is the top row).
#[derive(Debug, Clone, PartialEq)]
pub struct Rgba {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

impl Rgba {
    pub fn solid(rgba: [u8; 4]) -> Rgba {
        Rgba {
            width: 1,
            height: 1,
            data: rgba.to_vec(),
        }
    }
    /// The texel at texture coordinates (u, v), wrapped, nearest: what the exact reference reads
    /// for alpha-tested surfaces.
    pub fn sample_nearest(&self, u: f32, v: f32) -> [u8; 4] {
        let fx = u - u.floor();
        let fy = v - v.floor();
        let x = ((fx * self.width as f32) as u32).min(self.width - 1);
        let y = ((fy * self.height as f32) as u32).min(self.height - 1);
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.data[i],
            self.data[i + 1],
            self.data[i + 2],
            self.data[i + 3],
        ]
    }

    /// The pixel at column `x`, row `y` from the top.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.data[i],
            self.data[i + 1],
            self.data[i + 2],
            self.data[i + 3],
        ]
    }

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

/// What the camera sees at each pixel, read back from the G-buffer (row-major, top row first).
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

/// The G-buffer at some of its pixels (`Renderer::gbuffer_at`): what the sampled reference
/// reads where it picked, without the whole G-buffer read back.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GBufferPicks {
    /// Row-major pixel indices (top row first), sorted, each once.
    pub pixels: Vec<u32>,
    pub position: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
    /// As [`GBuffer::kind`].
    pub kind: Vec<u8>,
}

/// A G-buffer, whole or at picked pixels: the surface a pixel shows.
pub trait Surfaces: Sync {
    /// The point and normal of the surface pixel `i` shows, when it receives dynamic light
    /// (None: background, a surface that does not, or a pixel not read).
    fn receiver_at(&self, i: usize) -> Option<([f32; 3], [f32; 3])>;
}

impl Surfaces for GBuffer {
    fn receiver_at(&self, i: usize) -> Option<([f32; 3], [f32; 3])> {
        self.is_receiver_surface(i)
            .then(|| (self.position[i], self.normal[i]))
    }
}

impl Surfaces for GBufferPicks {
    fn receiver_at(&self, i: usize) -> Option<([f32; 3], [f32; 3])> {
        let k = self.pixels.binary_search(&(i as u32)).ok()?;
        (self.kind[k] == 1).then(|| (self.position[k], self.normal[k]))
    }
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
