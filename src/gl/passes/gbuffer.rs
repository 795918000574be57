//! The G-buffer, for the exact reference: world position and normal of the visible surface at
//! every pixel, and which stenciled lights reach it. Written by the base pass itself in frames
//! asked for masks (`unlit.frag` with `GBUFFER`, its outputs 1–3 attached to the frame), so the
//! surfaces are the frame's own and no second pass draws the world again.

use super::PassContext;
use crate::gl::program::Program;
use crate::gl::target::GBUFFER_OUTPUTS;
use glow::HasContext;

/// The most lights whose reach one G-buffer records (a bit each of a 32-bit target).
pub const REACH_LIGHTS: usize = 32;

/// Clears the G-buffer's outputs of the bound framebuffer: no surface. Draw buffer k is
/// attachment k there ([`GBUFFER_OUTPUTS`]).
pub fn clear(gl: &glow::Context) {
    let [position, normal, reach] = GBUFFER_OUTPUTS.map(|a| a - glow::COLOR_ATTACHMENT0);
    // SAFETY: clears of the bound framebuffer's G-buffer draw buffers (the reach target is an
    // integer one, which glClear leaves undefined).
    unsafe {
        gl.clear_buffer_f32_slice(glow::COLOR, position, &[0.0; 4]);
        gl.clear_buffer_f32_slice(glow::COLOR, normal, &[0.0; 4]);
        gl.clear_buffer_u32_slice(glow::COLOR, reach, &[0; 4]);
    }
}

/// Sets `program`'s reach lights: bit k of the reach target is set where light
/// `reach_lights[k]` (at most [`REACH_LIGHTS`]) reaches the pixel's surface.
pub fn set_reach(ctx: &PassContext, program: &Program, reach_lights: &[usize]) {
    let gl = ctx.gl;
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
}
