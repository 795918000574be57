//! Chan & Durand's hybrid (2004; thesis chapter 5): the computation mask, and the counts of
//! what it saves.
//!
//! The mask lives in the stencil's top bit ([`MAP_DECIDES`]): the marking pass draws the
//! light's receivers over the unlit pass's depth with the hybrid lit program at stage 0, which
//! keeps only fragments the map decides (its 2×2 compares agree) or the light does not reach,
//! and sets the bit there. The volumes then count in the low seven bits (`lit::COUNT_BITS`) with
//! the stencil test passing only where the bit is clear, so their fragments elsewhere stop at
//! the stencil test, before any count (on hardware, the early stencil test). Chan & Durand
//! used the depth bounds test over a rewritten depth buffer instead; the stencil bit needs
//! neither the extension (absent on llvmpipe) nor a depth restore.

use super::PassContext;
use super::lit::{LitShadow, MAP_DECIDES, bind_light, finish};
use super::state::DrawState;
use super::{draw_items, stencil};
use crate::gl::program::Program;
use crate::gl::volumes::LightVolumes;
use crate::plan::LightPlan;
use glow::HasContext;

/// Sets [`MAP_DECIDES`] where the map decides or the light does not reach. `overwrite`: the
/// volumes were counted everywhere first (`hybrid.mask = false`), and the pixels the map decides
/// lose their counts to the bit.
pub fn mark(
    ctx: &PassContext,
    program: &Program,
    lp: &LightPlan,
    shadow: &LitShadow,
    receivers: &[u32],
    overwrite: bool,
) {
    let gl = ctx.gl;
    DrawState {
        color_write: false,
        ..DrawState::OVER_DEPTH
    }
    .apply(gl);
    // SAFETY: fixed-function state.
    unsafe {
        gl.enable(glow::STENCIL_TEST);
        gl.stencil_func(glow::ALWAYS, MAP_DECIDES as i32, 0xff);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
        gl.stencil_mask(if overwrite { 0xff } else { MAP_DECIDES });
    }
    bind_light(ctx, program, lp, shadow);
    program.set_i32(gl, "u_hybrid_stage", 0);
    draw_items(
        ctx,
        program,
        &ctx.gpu
            .draw_list_of(ctx.scene, crate::gl::upload::Merge::ByMaterial, receivers),
        |_| {},
    );
    finish(gl);
    // SAFETY: fixed-function state.
    unsafe { gl.color_mask(true, true, true, true) };
}

/// Samples that pass the tests `draw` sets up (GL_SAMPLES_PASSED); None where the GL has no
/// such query (OpenGL ES has only "any samples passed").
pub fn samples_passed(gl: &glow::Context, draw: impl FnOnce()) -> Option<u64> {
    if gl.version().is_embedded {
        return None;
    }
    // SAFETY: a query object of our own, begun and ended around the draws, then deleted.
    unsafe {
        let q = gl.create_query().ok()?;
        gl.begin_query(glow::SAMPLES_PASSED, q);
        draw();
        gl.end_query(glow::SAMPLES_PASSED);
        let n = gl.get_query_parameter_u32(q, glow::QUERY_RESULT);
        crate::gl::syncs::count(crate::gl::syncs::SyncKind::QueryRead);
        gl.delete_query(q);
        Some(n as u64)
    }
}

/// The light's volume fragments that the rasteriser hands to the stencil test and that pass it:
/// with `masked`, only where the computation mask lets them (depth test off, no writes: every
/// fragment counts once, whatever the counting would do with it).
pub fn volume_fragments(
    ctx: &PassContext,
    programs: &stencil::VolumePrograms,
    volumes: &LightVolumes<'_>,
    (masked, light_scissor): (bool, Option<crate::plan::scissor::Scissor>),
) -> Option<u64> {
    let gl = ctx.gl;
    samples_passed(gl, || {
        // SAFETY: fixed-function state; the volume program's own uniforms.
        unsafe {
            gl.color_mask(false, false, false, false);
            gl.depth_mask(false);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::CULL_FACE);
            gl.disable(glow::BLEND);
            gl.enable(glow::STENCIL_TEST);
            if masked {
                gl.stencil_func(glow::EQUAL, 0, MAP_DECIDES);
            } else {
                gl.stencil_func(glow::ALWAYS, 0, 0xff);
            }
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
            gl.stencil_mask(0);
        }
        stencil::draw_all_parts(ctx, programs, volumes, light_scissor);
        // SAFETY: back to the passes' defaults.
        unsafe {
            gl.enable(glow::DEPTH_TEST);
            gl.stencil_mask(0xff);
            gl.disable(glow::STENCIL_TEST);
            gl.color_mask(true, true, true, true);
        }
    })
}
