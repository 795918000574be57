//! One light's additive pass (paper 3.1 and 4: "draw lit world with additive blending").

use super::{PassContext, draw_items};
use crate::gl::program::Program;
use crate::scene::{LightKind, light::SPOT_INNER_FRACTION};
use glam::Vec3;
use glow::HasContext;

/// Adds light `index`'s contribution where the depth equals the unlit pass's.
pub fn draw(ctx: &PassContext, program: &Program, index: usize) {
    let gl = ctx.gl;
    let light = &ctx.scene.lights[index];
    // SAFETY: fixed-function state on the bound framebuffer.
    unsafe {
        gl.color_mask(true, true, true, true);
        gl.depth_mask(false);
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::LEQUAL);
        gl.enable(glow::BLEND);
        gl.blend_func(glow::ONE, glow::ONE);
        gl.disable(glow::STENCIL_TEST);
        gl.disable(glow::POLYGON_OFFSET_FILL);
    }
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
    let scene = ctx.scene;
    let items = ctx.gpu.draw_list(scene, |s| {
        ctx.plan.visible[s] && scene.materials[scene.surfaces[s].material].receives_light
    });
    draw_items(ctx, program, &items, |_| {});
}
