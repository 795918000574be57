//! One light's shadow volumes into the stencil with legacy state (paper 4.1): the camera's
//! (infinite) projection and the caster group's modelview on the matrix stacks, four-component
//! vertices through glVertexPointer (w = 0 at infinity), two passes with face culling; and the
//! fill variant's darkening through glRectf.

use super::FixedFunction;
use crate::gl::fragments::LightFragmentDraw;
use crate::gl::legacy;
use crate::gl::passes::PassContext;
use crate::gl::passes::state::DrawState;
use crate::gl::passes::stencil;
use crate::gl::volumes::LightVolumes;
use crate::plan::scissor::Scissor;
use crate::shadow::volume::Counting;
use glow::HasContext;

fn draw_parts(ctx: &PassContext, ff: &FixedFunction, v: &LightVolumes<'_>, counting: Counting) {
    let gl = ctx.gl;
    let view = ctx.plan.camera.view;
    ff.bind_volumes(gl, v.vbo, v.ebo);
    // SAFETY: the light's own buffers; ranges lie inside them.
    unsafe {
        for d in v.draws.iter().filter(|d| d.counting == counting) {
            if d.scissor.is_some() {
                crate::gl::passes::set_scissor(gl, d.scissor);
            }
            ff.legacy.load_matrix(legacy::MODELVIEW, &(view * d.model));
            if d.indexed {
                gl.draw_elements(glow::TRIANGLES, d.count, glow::UNSIGNED_INT, d.first * 4);
            } else {
                gl.draw_arrays(glow::TRIANGLES, d.first, d.count);
            }
        }
    }
    ff.unbind(gl);
}

/// Clears the stencil and counts the light's volumes into it, two passes per counting mode
/// (the legacy path has no glStencilOpSeparate: `plan::fixed_function`).
pub fn draw(
    ctx: &PassContext,
    ff: &FixedFunction,
    volumes: &LightVolumes<'_>,
    light_scissor: Option<Scissor>,
) {
    let gl = ctx.gl;
    let o = &ctx.settings.shadow_volume;
    stencil::begin(gl, o, true);
    // SAFETY: fixed-function state of the current compatibility context.
    unsafe {
        gl.use_program(None);
        ff.legacy
            .load_matrix(legacy::PROJECTION, &ctx.plan.camera.projection);
    }
    // The same transform as the unlit pass: front caps land on their casters' depths.
    ff.clip_planes(gl, None);
    stencil::count(gl, volumes, ctx.plan.stencil, o.wrap, |counting| {
        draw_parts(ctx, ff, volumes, counting)
    });
    crate::gl::passes::set_scissor(gl, light_scissor);
    ff.reset(gl);
    stencil::end(gl, o);
}

/// The fill variant: where the stencil is not zero, scale the frame by `shade` and zero the
/// stencil, with one glRectf over the viewport (identity matrices).
pub fn fill(gl: &glow::Context, ff: &FixedFunction, shade: f32) {
    DrawState {
        color_write: true,
        depth_write: false,
        depth_test: None,
        blend: Some((glow::DST_COLOR, glow::ZERO)),
        stencil_test: true,
        polygon_offset: None,
    }
    .apply(gl);
    ff.reset(gl);
    // SAFETY: fixed-function state; glRectf draws in the identity's clip space.
    unsafe {
        gl.use_program(None);
        gl.disable(glow::CULL_FACE);
        gl.stencil_func(glow::NOTEQUAL, 0, 0xff);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::ZERO);
        (ff.legacy.color_4f)(shade, shade, shade, 1.0);
        (ff.legacy.rect_f)(-1.0, -1.0, 1.0, 1.0);
        (ff.legacy.color_4f)(1.0, 1.0, 1.0, 1.0);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
        gl.disable(glow::BLEND);
        gl.enable(glow::DEPTH_TEST);
    }
}

/// The subdivision's shadowed fragments marked into the stencil with legacy state (as
/// [`stencil::mark_fragments`]): the camera's matrices on the stacks, vec4 corners through
/// glVertexPointer. `clear`: the stencil first (else it holds the models' volume counts).
pub fn mark_fragments(
    ctx: &PassContext,
    ff: &FixedFunction,
    fragments: &LightFragmentDraw,
    clear: bool,
) {
    let gl = ctx.gl;
    stencil::mark_state(gl, clear);
    // SAFETY: fixed-function state of the current compatibility context.
    unsafe {
        gl.use_program(None);
        ff.legacy
            .load_matrix(legacy::PROJECTION, &ctx.plan.camera.projection);
        let pull = stencil::towards_camera(ctx.plan.camera.position, stencil::FIXED_FRAGMENT_PULL);
        ff.legacy
            .load_matrix(legacy::MODELVIEW, &(ctx.plan.camera.view * pull));
    }
    ff.clip_planes(gl, None);
    ff.bind_volumes(gl, fragments.vbo, fragments.ebo);
    for m in fragments.marks.iter().filter(|m| m.count > 0) {
        crate::gl::passes::apply_cull(gl, m.cull);
        // SAFETY: the light's own buffer; the range lies inside it.
        unsafe { gl.draw_arrays(glow::TRIANGLES, m.first, m.count) };
    }
    ff.unbind(gl);
    ff.reset(gl);
    stencil::end_marks(gl);
}
