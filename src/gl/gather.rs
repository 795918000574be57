//! The G-buffer read at picked pixels only: a point per pixel, drawn into a small target that
//! copies the G-buffer there (`gather.vert`/`gather.frag`), read back in one call. The sampled
//! reference traces a few hundred pixels per light; reading the whole G-buffer back (two
//! RGBA32F images) cost it more than the frame's masks and its rays together.

use super::program::Program;
use super::target::{GBUFFER_OUTPUTS, GBufferTarget, read_pixels_bottom_up};
use super::upload::bytes_of;
use crate::images::GBufferPicks;
use glow::HasContext;

/// Cells per row of the gather target.
const COLUMNS: u32 = 1024;

/// The gather target and the points' buffer, grown to the largest count asked so far.
pub struct Gather {
    target: GBufferTarget,
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    capacity: u32,
}

impl Gather {
    fn new(gl: &glow::Context, capacity: u32) -> Result<Gather, String> {
        let rows = capacity.div_ceil(COLUMNS).max(1);
        let target = GBufferTarget::new(gl, COLUMNS, rows)?;
        // SAFETY: a vertex array and buffer of our own: attribute 0, two floats per point.
        unsafe {
            let vao = gl.create_vertex_array()?;
            let vbo = gl.create_buffer()?;
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 2, glow::FLOAT, false, 8, 0);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            Ok(Gather {
                target,
                vao,
                vbo,
                capacity: rows * COLUMNS,
            })
        }
    }

    /// A gather that holds `n` pixels: `kept` when it does, else a new one (`kept` deleted).
    pub fn holding(gl: &glow::Context, kept: Option<Gather>, n: usize) -> Result<Gather, String> {
        match kept {
            Some(g) if g.capacity as usize >= n => Ok(g),
            other => {
                if let Some(g) = other {
                    g.delete(gl);
                }
                Gather::new(gl, (n as u32).next_power_of_two().max(COLUMNS))
            }
        }
    }

    /// `gbuffer` at `pixels` (row-major, top row first, sorted, each once; fewer than the
    /// capacity), through `program`.
    pub fn read(
        &self,
        gl: &glow::Context,
        program: &Program,
        gbuffer: &GBufferTarget,
        pixels: Vec<u32>,
    ) -> GBufferPicks {
        let n = pixels.len();
        if n == 0 {
            return GBufferPicks::default();
        }
        let (w, h) = (gbuffer.width, gbuffer.height);
        let points: Vec<f32> = pixels
            .iter()
            .flat_map(|&i| [(i % w) as f32, (h - 1 - i / w) as f32])
            .collect();
        let (position, normal) = gbuffer.textures();
        let rows = (n as u32).div_ceil(COLUMNS);
        // SAFETY: our own buffer, target and program; state set for a plain draw of points.
        unsafe {
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(self.vbo));
            gl.buffer_data_u8_slice(glow::ARRAY_BUFFER, bytes_of(&points), glow::STREAM_DRAW);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.target.fbo));
            gl.viewport(0, 0, COLUMNS as i32, rows as i32);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::STENCIL_TEST);
            gl.disable(glow::BLEND);
            gl.color_mask(true, true, true, true);
            program.bind(gl);
            program.set_i32(gl, "u_columns", COLUMNS as i32);
            program.set_vec2(gl, "u_size", glam::Vec2::new(COLUMNS as f32, rows as f32));
            program.set_i32(gl, "u_position", 0);
            program.set_i32(gl, "u_normal", 1);
            gl.active_texture(glow::TEXTURE1);
            gl.bind_texture(glow::TEXTURE_2D, Some(normal));
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(position));
            gl.bind_vertex_array(Some(self.vao));
            gl.draw_arrays(glow::POINTS, 0, n as i32);
            gl.bind_vertex_array(None);
            gl.enable(glow::DEPTH_TEST);
        }
        let read = |attachment: u32| -> Vec<[f32; 4]> {
            read_pixels_bottom_up(
                gl,
                Some(self.target.fbo),
                Some(attachment),
                (COLUMNS, rows),
                (glow::RGBA, glow::FLOAT),
                1,
            )
        };
        let (p, nk) = (read(GBUFFER_OUTPUTS[0]), read(GBUFFER_OUTPUTS[1]));
        let (position, normal, kind) = GBufferTarget::fields(&p[..n], &nk[..n]);
        GBufferPicks {
            pixels,
            position,
            normal,
            kind,
        }
    }

    pub fn delete(&self, gl: &glow::Context) {
        self.target.delete(gl);
        // SAFETY: called once by the owner.
        unsafe {
            gl.delete_vertex_array(self.vao);
            gl.delete_buffer(self.vbo);
        }
    }
}
