//! The passes a plan executes. Each pass sets every piece of GL state it relies on and leaves
//! nothing for the next pass to assume.

pub mod base;
pub mod debug;
pub mod gbuffer;
pub mod hybrid;
pub mod lit;
pub mod shadow_map;
pub mod state;
pub mod stencil;

use super::program::Program;
use super::upload::{DrawItem, GpuScene};
use crate::plan::settings::PassSettings;
use crate::plan::{Plan, normal_matrix};
use crate::scene::{Cull, Scene};
use glow::HasContext;

thread_local! {
    /// Surface draw calls made on this thread (`surface_draws`).
    static SURFACE_DRAWS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Surface draw calls made on this thread so far (the map, base, lit and measuring passes'):
/// take one before and one after a frame. Counted per thread, as a context is current on one.
pub fn surface_draws() -> usize {
    SURFACE_DRAWS.with(std::cell::Cell::get)
}

/// Counts one surface draw call.
pub fn count_surface_draw() {
    SURFACE_DRAWS.with(|c| c.set(c.get().wrapping_add(1)));
}

/// What every pass reads.
pub struct PassContext<'a> {
    pub gl: &'a glow::Context,
    pub scene: &'a Scene,
    pub gpu: &'a GpuScene,
    pub plan: &'a Plan,
    /// What the passes draw with (the options resolved for this frame).
    pub settings: &'a PassSettings,
}

/// The state every frame starts from: whoever drew last (a UI painter in the viewer) may have
/// left state the passes do not set themselves.
pub fn reset_state(gl: &glow::Context) {
    // SAFETY: fixed-function state only.
    unsafe {
        gl.disable(glow::SCISSOR_TEST);
        gl.disable(glow::BLEND);
        gl.disable(glow::STENCIL_TEST);
        gl.disable(glow::FRAMEBUFFER_SRGB);
        gl.color_mask(true, true, true, true);
        gl.depth_mask(true);
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 4);
    }
}

/// Face culling for a material's `cull`.
pub fn apply_cull(gl: &glow::Context, cull: Cull) {
    // SAFETY: fixed-function state only.
    unsafe {
        match cull {
            Cull::None => gl.disable(glow::CULL_FACE),
            Cull::Back => {
                gl.enable(glow::CULL_FACE);
                gl.cull_face(glow::BACK);
            }
            Cull::Front => {
                gl.enable(glow::CULL_FACE);
                gl.cull_face(glow::FRONT);
            }
        }
    }
}

/// Draws `items` with `program` bound: per item the owner's transform, the material's texture on
/// unit 0, its alpha function and culling. `extra` sets anything else per item.
pub fn draw_items(
    ctx: &PassContext,
    program: &Program,
    items: &[DrawItem],
    extra: impl FnMut(&DrawItem),
) {
    draw_items_with(ctx, program, items, |c| c, true, extra);
}

/// [`draw_items`] with the material's culling mapped through `cull` and its alpha test applied
/// only when `alpha_test` is set.
pub fn draw_items_with(
    ctx: &PassContext,
    program: &Program,
    items: &[DrawItem],
    cull: impl Fn(Cull) -> Cull,
    alpha_test: bool,
    mut extra: impl FnMut(&DrawItem),
) {
    let gl = ctx.gl;
    // ID and priority buffers find each triangle's table entry from its place in the index
    // buffer: the item's first triangle plus gl_PrimitiveID.
    let tri_base = program.uniform("u_tri_base").cloned();
    let alpha_func = program.uniform("u_alpha_func").cloned();
    // What the last item set: consecutive items share owners, textures and state more often
    // than not, so each is set only where it changes (the first item sets all of them).
    let (mut owner, mut texture, mut alpha_code, mut culling) = (None, None, None, None);
    // SAFETY: the scene's VAO and buffers are valid; index ranges come from the GPU index buffer.
    unsafe {
        gl.bind_vertex_array(Some(ctx.gpu.vao));
        gl.active_texture(glow::TEXTURE0);
        for item in items {
            if owner != Some(item.owner) {
                let model = crate::shadow::volume::group_transform(ctx.scene, item.owner);
                program.set_mat4(gl, "u_model", &model);
                program.set_mat3(gl, "u_normal_model", &normal_matrix(&model));
                owner = Some(item.owner);
            }
            let material = &ctx.scene.materials[item.material];
            let t = ctx.gpu.texture_for(ctx.scene, item.material);
            if texture != Some(t) {
                // `extra` may have left another unit active.
                gl.active_texture(glow::TEXTURE0);
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                texture = Some(t);
            }
            let alpha = if alpha_test {
                material.alpha_test
            } else {
                None
            };
            let code = alpha.map_or(0, |a| a.code());
            if alpha_code != Some(code) {
                gl.uniform_1_i32(alpha_func.as_ref(), code);
                alpha_code = Some(code);
            }
            let c = cull(material.cull);
            if culling != Some(c) {
                apply_cull(gl, c);
                culling = Some(c);
            }
            extra(item);
            if let Some(l) = &tri_base {
                gl.uniform_1_i32(Some(l), (item.first_index / 3) as i32);
            }
            gl.draw_elements(
                glow::TRIANGLES,
                item.index_count as i32,
                glow::UNSIGNED_INT,
                (item.first_index as usize * 4) as i32,
            );
            count_surface_draw();
        }
        gl.bind_vertex_array(None);
    }
}

/// Scissors to `s`, or switches the scissor test off.
pub fn set_scissor(gl: &glow::Context, s: Option<crate::plan::scissor::Scissor>) {
    // SAFETY: fixed-function state only.
    unsafe {
        match s {
            Some(s) => {
                gl.enable(glow::SCISSOR_TEST);
                gl.scissor(s.x, s.y, s.width, s.height);
            }
            None => gl.disable(glow::SCISSOR_TEST),
        }
    }
}
