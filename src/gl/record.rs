//! Each light's shadow decision recorded by its own lit pass, as it shades: a layer per light
//! of an RG8 array texture, attached beside the frame's colour while that light's lit passes
//! draw. A frame asked for masks then reads them from what it drew instead of drawing every
//! light's mask again (and waiting for each one's read-back) after it.
//!
//! The lit shader's second output adds (1, 0) where it calls the light lit and (0, 1) where
//! it calls it shadowed, under the lit pass's own additive blending: a pixel a light reaches
//! twice (coplanar triangles without `lighting.light_once`) stays what it was, since only
//! which channel is non-zero is read. A fragment the lit pass never runs (shadowed by the
//! stencil, unreached) leaves (0, 0); the alpha test of `result = alpha` keeps its rejected
//! fragments while recording (`u_keep_shadowed`), so they record.

use super::target::{check_complete, read_pixels};
use glow::HasContext;

/// The most bytes the layers may take: lights beyond are drawn again after the frame.
pub const RECORD_BUDGET_BYTES: u64 = 128 << 20;

/// The layers, frame-sized, and a framebuffer to read them back through.
pub struct DecisionRecord {
    texture: glow::Texture,
    read_fbo: glow::Framebuffer,
    pub width: u32,
    pub height: u32,
    pub layers: u32,
}

impl DecisionRecord {
    /// The layers a frame of `width`×`height` may record `wanted` lights into: as many as
    /// the budget and the GL allow (at least one).
    pub fn layers_for(gl: &glow::Context, (width, height): (u32, u32), wanted: usize) -> u32 {
        let per_layer = (width as u64 * height as u64 * 2).max(1);
        // SAFETY: a state query.
        let max = unsafe { gl.get_parameter_i32(glow::MAX_ARRAY_TEXTURE_LAYERS) }.max(1) as u64;
        (wanted as u64)
            .min(max)
            .min((RECORD_BUDGET_BYTES / per_layer).max(1))
            .max(1) as u32
    }

    pub fn new(
        gl: &glow::Context,
        width: u32,
        height: u32,
        layers: u32,
    ) -> Result<DecisionRecord, String> {
        // SAFETY: a texture and framebuffer of our own; bindings reset to 0.
        unsafe {
            let texture = gl.create_texture()?;
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, Some(texture));
            gl.tex_image_3d(
                glow::TEXTURE_2D_ARRAY,
                0,
                glow::RG8 as i32,
                width as i32,
                height as i32,
                layers as i32,
                0,
                glow::RG,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            for (key, value) in [
                (glow::TEXTURE_MIN_FILTER, glow::NEAREST),
                (glow::TEXTURE_MAG_FILTER, glow::NEAREST),
            ] {
                gl.tex_parameter_i32(glow::TEXTURE_2D_ARRAY, key, value as i32);
            }
            gl.bind_texture(glow::TEXTURE_2D_ARRAY, None);
            let read_fbo = match gl.create_framebuffer() {
                Ok(f) => f,
                Err(e) => {
                    gl.delete_texture(texture);
                    return Err(e);
                }
            };
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(read_fbo));
            gl.framebuffer_texture_layer(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                Some(texture),
                0,
                0,
            );
            let complete = check_complete(gl, "decision record");
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            let record = DecisionRecord {
                texture,
                read_fbo,
                width,
                height,
                layers,
            };
            match complete {
                Ok(()) => Ok(record),
                Err(e) => {
                    record.delete(gl);
                    Err(e)
                }
            }
        }
    }

    /// Attaches `layer` as the bound frame framebuffer's second colour output, cleared within
    /// the scissor as it stands (the light's), so the lit passes that follow record into it.
    pub fn attach(&self, gl: &glow::Context, layer: u32) {
        // SAFETY: the frame's framebuffer is bound; the layer is within the texture.
        unsafe {
            gl.framebuffer_texture_layer(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT1,
                Some(self.texture),
                0,
                layer as i32,
            );
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0, glow::COLOR_ATTACHMENT1]);
            gl.color_mask(true, true, true, true);
            gl.clear_buffer_f32_slice(glow::COLOR, 1, &[0.0; 4]);
        }
    }

    /// The bound frame framebuffer back to its one colour output.
    pub fn detach(gl: &glow::Context) {
        // SAFETY: the frame's framebuffer is bound.
        unsafe {
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0]);
            gl.framebuffer_texture_layer(glow::FRAMEBUFFER, glow::COLOR_ATTACHMENT1, None, 0, 0);
        }
    }

    /// Binds `layer` as the colour of the record's own framebuffer, to draw into it.
    pub fn bind_layer(&self, gl: &glow::Context, layer: u32) {
        // SAFETY: our own framebuffer and texture.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.read_fbo));
            gl.framebuffer_texture_layer(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                Some(self.texture),
                0,
                layer as i32,
            );
            gl.viewport(0, 0, self.width as i32, self.height as i32);
        }
    }

    /// Layer `layer`, top row first, a (lit, shadowed) pair of bytes per pixel.
    pub fn read(&self, gl: &glow::Context, layer: u32) -> Vec<u8> {
        self.bind_layer(gl, layer);
        read_pixels(
            gl,
            Some(self.read_fbo),
            Some(glow::COLOR_ATTACHMENT0),
            (self.width, self.height),
            (glow::RG, glow::UNSIGNED_BYTE),
            2,
        )
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: called once by the owner.
        unsafe {
            gl.delete_framebuffer(self.read_fbo);
            gl.delete_texture(self.texture);
        }
    }
}
