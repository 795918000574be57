//! The G-buffer pass: world position and normal of the visible surface at every pixel, for the
//! exact reference. Run only when masks are requested, so it never counts in frame timings.

use super::state::DrawState;
use super::{PassContext, draw_items};
use crate::gl::program::Program;
use glow::HasContext;

pub fn draw(ctx: &PassContext, program: &Program) {
    let gl = ctx.gl;
    // SAFETY: fixed-function state on the bound G-buffer framebuffer.
    DrawState::OPAQUE.apply(gl);
    unsafe {
        gl.clear_color(0.0, 0.0, 0.0, 0.0);
        gl.clear_depth(1.0);
        gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
    }
    program.bind(gl);
    program.set_mat4(gl, "u_view_proj", &ctx.plan.camera.view_proj);
    program.set_i32(gl, "u_texture", 0);
    let items = ctx
        .gpu
        .draw_list(ctx.scene, crate::gl::upload::Merge::ByMaterial, |s| {
            ctx.plan.visible[s]
        });
    draw_items(ctx, program, &items, |item| {
        let receives = ctx.scene.materials[item.material].receives_light;
        program.set_i32(gl, "u_receives", receives as i32);
    });
}
