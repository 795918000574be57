//! The frame's depth for the planner (`plan.occlusion`, `plan.depth_clip`), read back after the
//! base pass: whole, or (`plan.reduce_depth`) as level 2 of its max-depth pyramid, reduced by a
//! shader. The shader runs on the GL's own threads and the CPU then converts and copies a
//! sixteenth of the pixels; the planner reads no level finer than 2 for the rectangles and boxes
//! it judges but the smallest, and those get a bound a few pixels wider. Not read at all while
//! the base pass draws what it drew last frame (the planner's `DepthNeed::Reuse`,
//! `plan.reuse_depth`).

use super::program::Program;
use super::target::{Framebuffer, framebuffer_of, read_pixels_bottom_up, texture_2d};
use crate::plan::occlusion::DepthPyramid;
use glow::HasContext;

/// The pyramid level the shader computes: blocks of 2^2×2^2 pixels.
pub const LEVEL: usize = 2;

/// A two-channel float target one texel per block: (farthest depth, farthest surface depth).
pub struct DepthReducer {
    fbo: glow::Framebuffer,
    texture: glow::Texture,
    size: (u32, u32),
}

impl DepthReducer {
    /// A target for a `width`×`height` frame.
    pub fn new(gl: &glow::Context, width: u32, height: u32) -> Result<DepthReducer, String> {
        let size = (width.div_ceil(1 << LEVEL), height.div_ceil(1 << LEVEL));
        let texture = texture_2d(gl, glow::RG32F, glow::RG, glow::FLOAT, size.0, size.1)?;
        match framebuffer_of(gl, texture, None, "depth reduction (RG32F)") {
            Ok(fbo) => Ok(DepthReducer { fbo, texture, size }),
            Err(e) => {
                // SAFETY: the texture made above, attached to nothing now.
                unsafe { gl.delete_texture(texture) };
                Err(e)
            }
        }
    }

    /// Whether this target fits a `width`×`height` frame.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.size == (width.div_ceil(1 << LEVEL), height.div_ceil(1 << LEVEL))
    }

    /// The pyramid of `frame`'s depth from level [`LEVEL`] up. Leaves the reduction target
    /// bound: the caller binds what it draws into next.
    pub fn read(
        &self,
        gl: &glow::Context,
        program: &Program,
        empty_vao: glow::VertexArray,
        frame: &Framebuffer,
    ) -> Option<DepthPyramid> {
        let (w, h) = self.size;
        // SAFETY: state for one full-screen triangle into our own target, sampling the frame's
        // depth texture (not attached to the bound framebuffer, so no feedback); what is
        // switched off here the passes after this set for themselves.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            gl.viewport(0, 0, w as i32, h as i32);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::STENCIL_TEST);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::CULL_FACE);
            gl.color_mask(true, true, true, true);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(frame.depth_stencil));
            program.bind(gl);
            program.set_i32(gl, "u_depth", 0);
            program.set_ivec2(gl, "u_size", [frame.width as i32, frame.height as i32]);
            gl.bind_vertex_array(Some(empty_vao));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_vertex_array(None);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.enable(glow::DEPTH_TEST);
        }
        let texels: Vec<f32> = read_pixels_bottom_up(
            gl,
            Some(self.fbo),
            None,
            self.size,
            (glow::RG, glow::FLOAT),
            2,
        );
        let (max, surface) = texels.chunks_exact(2).map(|t| (t[0], t[1])).unzip();
        DepthPyramid::from_level(
            LEVEL,
            max,
            surface,
            frame.width as usize,
            frame.height as usize,
        )
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: our own objects, deleted once by the owner.
        unsafe {
            gl.delete_framebuffer(self.fbo);
            gl.delete_texture(self.texture);
        }
    }
}
