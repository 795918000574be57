//! The G-buffer pass: world position and normal of the visible surface at every pixel, for the
//! exact reference. Run only when masks are requested, so it never counts in frame timings.

use super::state::DrawState;
use super::{PassContext, draw_items};
use crate::gl::program::Program;
use glow::HasContext;

/// The most lights whose reach one G-buffer pass records (a bit each of a 32-bit target).
pub const REACH_LIGHTS: usize = 32;

/// Draws the G-buffer, with bit k of its reach target set where light `reach_lights[k]` (at
/// most [`REACH_LIGHTS`]) reaches the pixel's surface.
pub fn draw(ctx: &PassContext, program: &Program, reach_lights: &[usize]) {
    let gl = ctx.gl;
    DrawState::OPAQUE.apply(gl);
    // SAFETY: clears of the bound G-buffer framebuffer's attachments (the reach target is an
    // integer one, which glClear leaves undefined).
    unsafe {
        gl.clear_buffer_f32_slice(glow::COLOR, 0, &[0.0; 4]);
        gl.clear_buffer_f32_slice(glow::COLOR, 1, &[0.0; 4]);
        gl.clear_buffer_u32_slice(glow::COLOR, 2, &[0; 4]);
        gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[1.0]);
    }
    program.bind(gl);
    program.set_mat4(gl, "u_view_proj", &ctx.plan.camera.view_proj);
    program.set_i32(gl, "u_texture", 0);
    let reach_lights = &reach_lights[..reach_lights.len().min(REACH_LIGHTS)];
    program.set_i32(gl, "u_reach_lights", reach_lights.len() as i32);
    for (k, &l) in reach_lights.iter().enumerate() {
        let light = &ctx.scene.lights[l];
        let (dir, cos_cutoff, _) = super::lit::cone_of(light);
        program.set_vec4(
            gl,
            &format!("u_reach_position_radius[{k}]"),
            light.position.extend(light.radius),
        );
        program.set_vec4(
            gl,
            &format!("u_reach_direction_cutoff[{k}]"),
            dir.extend(cos_cutoff),
        );
    }
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
