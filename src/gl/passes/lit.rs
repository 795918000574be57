//! One light's additive pass (paper 3.1 and 4: "draw lit world with additive blending"), and its
//! mask variant, which writes the same fragments' decision instead of light.

use super::{PassContext, draw_items};
use crate::gl::program::Program;
use crate::scene::{LightKind, light::SPOT_INNER_FRACTION};
use glam::Vec3;
use glow::HasContext;

/// Binds `program` with light `index`'s uniforms.
fn bind_light(ctx: &PassContext, program: &Program, index: usize) {
    let gl = ctx.gl;
    let light = &ctx.scene.lights[index];
    program.bind(gl);
    program.set_mat4(gl, "u_view_proj", &ctx.plan.camera.view_proj);
    program.set_i32(gl, "u_texture", 0);
    program.set_vec3(gl, "u_light_pos", light.position);
    program.set_vec3(
        gl,
        "u_light_color",
        light.color * ctx.options.lighting.intensity,
    );
    let (dir, cos_cutoff, cos_inner) = match light.kind {
        LightKind::Spot {
            direction,
            cutoff_deg,
        } => (
            direction.normalize(),
            cutoff_deg.to_radians().cos(),
            (cutoff_deg * SPOT_INNER_FRACTION).to_radians().cos(),
        ),
        LightKind::Omni => (Vec3::Z, -1.0, -1.0),
    };
    program.set_vec3(gl, "u_spot_dir", dir);
    program.set_f32(gl, "u_cos_cutoff", cos_cutoff);
    program.set_f32(gl, "u_cos_inner", cos_inner);
    program.set_f32(gl, "u_radius", light.radius);
}

/// Receiving surfaces in view.
fn receivers(ctx: &PassContext) -> Vec<crate::gl::upload::DrawItem> {
    let scene = ctx.scene;
    ctx.gpu.draw_list(scene, |s| {
        ctx.plan.visible[s] && scene.materials[scene.surfaces[s].material].receives_light
    })
}

/// Depth state shared by the lit pass and its mask: test against the unlit pass, never write.
fn depth_state(gl: &glow::Context) {
    // SAFETY: fixed-function state.
    unsafe {
        gl.depth_mask(false);
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::LEQUAL);
        gl.disable(glow::STENCIL_TEST);
        gl.disable(glow::POLYGON_OFFSET_FILL);
    }
}

/// Adds light `index`'s contribution where the depth equals the unlit pass's.
pub fn draw(ctx: &PassContext, program: &Program, index: usize) {
    let gl = ctx.gl;
    depth_state(gl);
    // SAFETY: fixed-function state.
    unsafe {
        gl.color_mask(true, true, true, true);
        gl.enable(glow::BLEND);
        gl.blend_func(glow::ONE, glow::ONE);
    }
    bind_light(ctx, program, index);
    draw_items(ctx, program, &receivers(ctx), |_| {});
}

/// Writes light `index`'s decision into the bound mask target (cleared to "not a receiver").
pub fn draw_mask(ctx: &PassContext, program: &Program, index: usize) {
    let gl = ctx.gl;
    depth_state(gl);
    // SAFETY: fixed-function state.
    unsafe {
        gl.color_mask(true, true, true, true);
        gl.disable(glow::BLEND);
    }
    bind_light(ctx, program, index);
    program.set_i32(gl, "u_mask_value", 0);
    draw_items(ctx, program, &receivers(ctx), |_| {});
}
