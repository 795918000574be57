//! The unlit world (paper 2.4): texture × lightmap, writing the depth the later passes test against.

use super::state::DrawState;
use super::{PassContext, draw_items};
use crate::gl::program::Program;
use crate::scene::{BakedLight, SurfaceOwner};
use glam::Vec3;
use glow::HasContext;

/// Draws the unlit world; with `gbuffer` (the reach lights), `program` is the G-buffer
/// variant and the bound framebuffer's draw buffers 1–3 take the G-buffer (`gbuffer.rs`).
pub fn draw(ctx: &PassContext, program: &Program, gbuffer: Option<&[usize]>) {
    let gl = ctx.gl;
    // SAFETY: fixed-function state on the bound framebuffer.
    DrawState::OPAQUE.apply(gl);
    unsafe {
        gl.stencil_mask(0xff);
        gl.clear_depth(1.0);
        gl.clear_stencil(0);
        gl.clear(glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
        // Draw buffer 0 alone: glClear would clear the G-buffer's too, its integer one
        // undefined.
        gl.clear_buffer_f32_slice(glow::COLOR, 0, &[0.0, 0.0, 0.0, 1.0]);
    }
    program.bind(gl);
    if let Some(reach_lights) = gbuffer {
        super::gbuffer::clear(gl);
        super::gbuffer::set_reach(ctx, program, reach_lights);
    }
    program.set_mat4(gl, "u_view_proj", &ctx.plan.camera.view_proj);
    program.set_i32(gl, "u_texture", 0);
    program.set_i32(gl, "u_lightmap", 1);
    program.set_f32(
        gl,
        "u_lightmap_scale",
        (1u32 << ctx.settings.overbright_bits) as f32,
    );
    let items = ctx
        .gpu
        .draw_list(ctx.scene, crate::gl::upload::Merge::ByLightmap, |s| {
            ctx.plan.visible[s]
        });
    let lighting = &ctx.settings.lighting;
    draw_items(ctx, program, &items, |item| {
        let level = match item.owner {
            SurfaceOwner::World => lighting.ambient,
            SurfaceOwner::Model(_) => lighting.model_ambient,
        };
        program.set_vec3(gl, "u_ambient", Vec3::splat(level));
        if gbuffer.is_some() {
            let receives = ctx.scene.materials[item.material].receives_light;
            program.set_i32(gl, "u_receives", receives as i32);
        }
        let lightmap = item
            .lightmap
            .and_then(|l| ctx.gpu.images().lightmaps.get(l).copied());
        let baked = match (item.baked, lightmap) {
            _ if !lighting.baked => 0,
            (BakedLight::Lightmap, Some(_)) => 1,
            (BakedLight::Vertex, _) => 2,
            _ => 0,
        };
        program.set_i32(gl, "u_baked", baked);
        if let (1, Some(lm)) = (baked, lightmap) {
            // SAFETY: binding a valid texture to unit 1.
            unsafe {
                gl.active_texture(glow::TEXTURE1);
                gl.bind_texture(glow::TEXTURE_2D, Some(lm));
                gl.active_texture(glow::TEXTURE0);
            }
        }
    });
}
