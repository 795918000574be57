//! Debug drawing over a finished frame: a light's shadow volumes as translucent geometry
//! (depth-fail parts red, depth-pass parts green, after Doom 3's `r_showShadows`) and the
//! silhouette edges they were extruded from (yellow lines). Depth-tested against the frame,
//! never written; the stencil is left alone.

use super::PassContext;
use super::state::DrawState;
use crate::gl::program::Program;
use crate::gl::volumes::LightVolumes;
use crate::shadow::volume::Counting;
use glow::HasContext;

const ZFAIL: [f32; 4] = [0.9, 0.15, 0.1, 0.12];
const ZPASS: [f32; 4] = [0.1, 0.85, 0.2, 0.12];
const SILHOUETTE: [f32; 4] = [1.0, 0.9, 0.1, 1.0];

pub fn volumes(
    ctx: &PassContext,
    program: &Program,
    v: &LightVolumes<'_>,
    geometry: bool,
    silhouettes: bool,
) {
    let gl = ctx.gl;
    program.bind(gl);
    program.set_mat4(gl, "u_view_proj", &ctx.plan.camera.view_proj);
    DrawState {
        blend: Some((glow::SRC_ALPHA, glow::ONE_MINUS_SRC_ALPHA)),
        ..DrawState::OVER_DEPTH
    }
    .apply(gl);
    // SAFETY: fixed-function state; draws the light's own volume buffer.
    unsafe {
        gl.disable(glow::CULL_FACE);
        gl.bind_vertex_array(Some(v.vao));
        for p in v.parts.iter().filter(|p| p.drawn()) {
            program.set_mat4(gl, "u_model", &p.model);
            program.set_i32(gl, "u_first", p.first);
            if geometry {
                let (colour, count) = match p.counting {
                    Counting::ZFail => (ZFAIL, p.sides + p.caps),
                    Counting::ZPass => (ZPASS, p.sides),
                };
                program.set_vec4(gl, "u_color", glam::Vec4::from_array(colour));
                program.set_i32(gl, "u_lines", 0);
                gl.draw_arrays(glow::TRIANGLES, p.first, count);
            }
            if silhouettes {
                program.set_vec4(gl, "u_color", glam::Vec4::from_array(SILHOUETTE));
                program.set_i32(gl, "u_lines", 1);
                gl.draw_arrays(glow::LINES, p.first, p.sides);
            }
        }
        gl.bind_vertex_array(None);
        gl.disable(glow::BLEND);
        gl.depth_mask(true);
    }
}
