//! One light's additive pass with legacy state (paper 3.1, 4): glLight per-vertex lighting
//! times the texture; for a shadow-mapped light the map on unit 1 with eye-linear glTexGen
//! planes, the hardware compare, DEPTH_TEXTURE_MODE ALPHA (glAlphaFunc keeps the lit
//! fragments) or INTENSITY (the result scales the light), glClipPlane for the light frustum's
//! sides; for a shadow-volume light the stencil test. Its mask variant writes the decision.
//!
//! Two things the legacy state cannot say are done differently from the shader path, both
//! documented in docs/gl-paths.md: the light's reach (range, cone, facing) is per vertex, so the
//! mask marks every receiver fragment and the renderer removes the unreached ones on the CPU
//! from the G-buffer; and the one alpha test belongs to the shadow compare, so alpha-tested
//! materials are kept to their own fragments by an EQUAL depth test against the unlit pass.

use super::FixedFunction;
use crate::gl::legacy::{self, Legacy};
use crate::gl::passes::PassContext;
use crate::gl::passes::lit::{LitShadow, ShadowBinding, finish, lit_stencil, stencil_gate};
use crate::gl::passes::state::DrawState;
use crate::options::{AlphaTestFunc, CompareResult, OffsetPass, Outside};
use crate::plan::LightPlan;
use crate::scene::LightKind;
use crate::shadow::views::ViewKind;
use glam::Mat4;
use glow::HasContext;

/// glAlphaFunc's comparison for the options' function.
fn alpha_func(f: AlphaTestFunc) -> u32 {
    match f {
        AlphaTestFunc::Never => glow::NEVER,
        AlphaTestFunc::Less => glow::LESS,
        AlphaTestFunc::Equal => glow::EQUAL,
        AlphaTestFunc::Lequal => glow::LEQUAL,
        AlphaTestFunc::Greater => glow::GREATER,
        AlphaTestFunc::Notequal => glow::NOTEQUAL,
        AlphaTestFunc::Gequal => glow::GEQUAL,
        AlphaTestFunc::Always => glow::ALWAYS,
    }
}

/// GL_LIGHT0 as the scene's light, with the camera's view on the modelview stack (positions
/// and directions are given in world space and GL takes them to eye space). The shader path's
/// window falloff reaching 0 at the radius has no fixed-function form: quadratic attenuation
/// down to 1/25 at the radius stands in for it.
///
/// SAFETY (caller): the legacy context is current.
unsafe fn set_light(ctx: &PassContext, l: &Legacy, lp: &LightPlan) {
    let light = &ctx.scene.lights[lp.light];
    let color = light.color * ctx.settings.lighting.intensity;
    let p = light.position;
    let black = [0.0f32, 0.0, 0.0, 1.0];
    // SAFETY: see the caller's contract; every array holds what its parameter reads.
    unsafe {
        l.load_matrix(legacy::MODELVIEW, &ctx.plan.camera.view);
        (l.light_fv)(
            legacy::LIGHT0,
            legacy::POSITION,
            [p.x, p.y, p.z, 1.0].as_ptr(),
        );
        (l.light_fv)(
            legacy::LIGHT0,
            legacy::DIFFUSE,
            [color.x, color.y, color.z, 1.0].as_ptr(),
        );
        (l.light_fv)(legacy::LIGHT0, legacy::AMBIENT, black.as_ptr());
        (l.light_fv)(legacy::LIGHT0, legacy::SPECULAR, black.as_ptr());
        let (direction, cutoff) = match light.kind {
            LightKind::Spot {
                direction,
                cutoff_deg,
            } => (direction.normalize(), cutoff_deg.min(90.0)),
            // 180: GL's "not a spot light".
            LightKind::Omni => (glam::Vec3::Z, 180.0),
        };
        let d = direction;
        (l.light_fv)(
            legacy::LIGHT0,
            legacy::SPOT_DIRECTION,
            [d.x, d.y, d.z].as_ptr(),
        );
        (l.light_f)(legacy::LIGHT0, legacy::SPOT_CUTOFF, cutoff);
        (l.light_f)(legacy::LIGHT0, legacy::SPOT_EXPONENT, 1.0);
        (l.light_f)(legacy::LIGHT0, legacy::CONSTANT_ATTENUATION, 1.0);
        (l.light_f)(legacy::LIGHT0, legacy::LINEAR_ATTENUATION, 0.0);
        let r = light.radius.max(1e-3);
        (l.light_f)(
            legacy::LIGHT0,
            legacy::QUADRATIC_ATTENUATION,
            24.0 / (r * r),
        );
        (l.light_model_fv)(legacy::LIGHT_MODEL_AMBIENT, black.as_ptr());
        // Two-sided surfaces are lit on the side the camera sees, as in the shader path.
        (l.light_model_i)(legacy::LIGHT_MODEL_TWO_SIDE, 1);
        (l.material_fv)(
            legacy::FRONT_AND_BACK,
            legacy::DIFFUSE,
            [1.0f32; 4].as_ptr(),
        );
        (l.material_fv)(legacy::FRONT_AND_BACK, legacy::AMBIENT, black.as_ptr());
        (l.material_fv)(legacy::FRONT_AND_BACK, legacy::SPECULAR, black.as_ptr());
    }
}

/// The shadow map on unit 1: texgen, compare result mode, wrap, the combiner that takes the
/// result to alpha (and to colour under INTENSITY when `scale_light`), and the frustum's
/// clip planes when the view is an omni light's face or the options clip to it.
///
/// SAFETY (caller): the legacy context is current; unit 0 is active afterwards.
unsafe fn bind_map(ctx: &PassContext, ff: &FixedFunction, s: &ShadowBinding, scale_light: bool) {
    let gl = ctx.gl;
    let l = &ff.legacy;
    let o = &ctx.settings.shadow_map;
    // World-space planes: T = B · P_light · V_light, loaded under the camera's view.
    let planes = s.view.texgen(&Mat4::IDENTITY);
    // SAFETY: see the caller's contract; our own depth texture.
    unsafe {
        l.load_matrix(legacy::MODELVIEW, &ctx.plan.camera.view);
        gl.active_texture(glow::TEXTURE1);
        gl.enable(glow::TEXTURE_2D);
        gl.bind_texture(glow::TEXTURE_2D, Some(s.texture));
        let mode = match o.result {
            CompareResult::Alpha => legacy::ALPHA,
            CompareResult::Intensity => legacy::INTENSITY,
        };
        gl.tex_parameter_i32(glow::TEXTURE_2D, legacy::DEPTH_TEXTURE_MODE, mode as i32);
        // The range test: outside the map the border's depth 1 compares as lit.
        let wrap = match o.outside {
            Outside::Range => {
                gl.tex_parameter_f32_slice(glow::TEXTURE_2D, glow::TEXTURE_BORDER_COLOR, &[1.0; 4]);
                glow::CLAMP_TO_BORDER
            }
            _ => glow::CLAMP_TO_EDGE,
        };
        gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_WRAP_S, wrap as i32);
        gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_WRAP_T, wrap as i32);
        let coords = [
            (legacy::S, legacy::TEXTURE_GEN_S),
            (legacy::T, legacy::TEXTURE_GEN_T),
            (legacy::R, legacy::TEXTURE_GEN_R),
            (legacy::Q, legacy::TEXTURE_GEN_Q),
        ];
        for (i, (coord, generate)) in coords.into_iter().enumerate() {
            (l.tex_gen_i)(coord, legacy::TEXTURE_GEN_MODE, legacy::EYE_LINEAR as i32);
            (l.tex_gen_fv)(coord, legacy::EYE_PLANE, planes.row(i).to_array().as_ptr());
            gl.enable(generate);
        }
        l.env(legacy::TEXTURE_ENV_MODE, legacy::COMBINE);
        if scale_light && o.result == CompareResult::Intensity {
            l.env(legacy::COMBINE_RGB, legacy::MODULATE);
            l.env(legacy::SOURCE1_RGB, legacy::TEXTURE);
            l.env(legacy::OPERAND1_RGB, legacy::SRC_COLOR);
        } else {
            l.env(legacy::COMBINE_RGB, legacy::REPLACE);
        }
        l.env(legacy::SOURCE0_RGB, legacy::PREVIOUS);
        l.env(legacy::OPERAND0_RGB, legacy::SRC_COLOR);
        l.env(legacy::COMBINE_ALPHA, legacy::REPLACE);
        l.env(legacy::SOURCE0_ALPHA, legacy::TEXTURE);
        l.env(legacy::OPERAND0_ALPHA, legacy::SRC_ALPHA);
        gl.active_texture(glow::TEXTURE0);
        // An omni light's face lights only its own directions (the shader path's face test);
        // a spot is clipped to its frustum when the options say so.
        let face = matches!(s.view.kind, ViewKind::Face(_));
        if face || o.outside == Outside::ClipPlanes {
            ff.clip_planes(gl, Some(&s.view.clip_planes()[..4]));
        }
    }
}

/// Restores unit 1's wrap (the shader path reads the maps clamped to the edge).
fn unbind_map(gl: &glow::Context, s: &ShadowBinding) {
    // SAFETY: parameters of our own texture.
    unsafe {
        gl.active_texture(glow::TEXTURE1);
        gl.bind_texture(glow::TEXTURE_2D, Some(s.texture));
        for p in [glow::TEXTURE_WRAP_S, glow::TEXTURE_WRAP_T] {
            gl.tex_parameter_i32(glow::TEXTURE_2D, p, glow::CLAMP_TO_EDGE as i32);
        }
        gl.active_texture(glow::TEXTURE0);
    }
}

/// The shadow compare's alpha test: the options' function under ALPHA; under INTENSITY "lit
/// at one half or more", which is how the shader path's mask reads it.
fn compare_alpha_test(ctx: &PassContext, l: &Legacy, for_mask: bool) {
    let o = &ctx.settings.shadow_map;
    // SAFETY: fixed-function state.
    unsafe {
        match o.result {
            CompareResult::Alpha => {
                ctx.gl.enable(legacy::ALPHA_TEST);
                (l.alpha_func)(alpha_func(o.alpha_func), o.alpha_ref);
            }
            CompareResult::Intensity if for_mask => {
                ctx.gl.enable(legacy::ALPHA_TEST);
                (l.alpha_func)(glow::GEQUAL, 0.5);
            }
            CompareResult::Intensity => ctx.gl.disable(legacy::ALPHA_TEST),
        }
    }
}

/// Depth units the lit pass is pulled toward the camera by where user clip planes cut its
/// triangles: a clipped triangle's new vertices are interpolated, so its fragments' depths
/// differ from the unlit pass's by a few units in the last place, and LEQUAL then fails on
/// about every other row (stripes: the paper's Fig. 1 speaks of clip-plane anomalies). The
/// shader path's gl_ClipDistance does not move depths on Mesa; 4 units were the least that
/// left no stripe on the built-in scene and oa_dm1 (`tests/fixed_function.rs`).
const CLIPPED_UNITS: f32 = 4.0;

/// Whether the light's lit pass clips by user planes (an omni light's faces, or a spot under
/// `outside = clip_planes`).
fn clips(ctx: &PassContext, maps: &[&ShadowBinding]) -> bool {
    maps.iter().any(|s| {
        matches!(s.view.kind, ViewKind::Face(_))
            || ctx.settings.shadow_map.outside == Outside::ClipPlanes
    })
}

/// The lit pass's polygon offset (the paper's, pulling the lit world toward the camera), and
/// the few units that keep clipped triangles from losing against their own depth.
fn lit_offset(ctx: &PassContext, lp: &LightPlan, maps: &[&ShadowBinding]) -> bool {
    let o = &ctx.settings.shadow_map;
    let paper = lp.map_offset.filter(|_| {
        !maps.is_empty() && matches!(o.offset_pass, OffsetPass::Lit | OffsetPass::Both)
    });
    let clipped = clips(ctx, maps).then_some((0.0, CLIPPED_UNITS));
    let offset = match (paper, clipped) {
        (Some((f, u)), Some((_, c))) => Some((f, u + c)),
        (p, c) => p.or(c),
    };
    // SAFETY: fixed-function state.
    unsafe {
        match offset {
            Some((factor, units)) => {
                ctx.gl.enable(glow::POLYGON_OFFSET_FILL);
                ctx.gl.polygon_offset(-factor, -units);
            }
            None => ctx.gl.disable(glow::POLYGON_OFFSET_FILL),
        }
    }
    offset.is_some()
}

/// Draws the receivers with the bound state; alpha-tested materials keep to their own
/// fragments through an EQUAL depth test (unless a lit-pass offset moved the depth).
fn draw_receivers(ctx: &PassContext, ff: &FixedFunction, receivers: &[u32], offset: bool) {
    let gl = ctx.gl;
    // SAFETY: fixed-function state: planes of the pass's own, or ones that keep everything.
    if !unsafe { gl.is_enabled(legacy::CLIP_PLANE0) } {
        ff.clip_planes(gl, None);
    }
    let items = ctx
        .gpu
        .draw_list_of(ctx.scene, crate::gl::upload::Merge::ByMaterial, receivers);
    ff.bind_scene(ctx);
    // SAFETY: client state of our own vertex array.
    unsafe { (ff.legacy.disable_client_state)(legacy::COLOR_ARRAY) };
    let view = ctx.plan.camera.view;
    ff.draw_items(
        ctx,
        &view,
        &items,
        |c| c,
        |item| {
            let tested = ctx.scene.materials[item.material].alpha_test.is_some() && !offset;
            // SAFETY: fixed-function state.
            unsafe { gl.depth_func(if tested { glow::EQUAL } else { glow::LEQUAL }) };
        },
    );
    ff.unbind(gl);
}

/// The maps a pass tests against, one at a time (the legacy path has no six-map pass).
fn maps_of<'s>(shadow: &'s LitShadow<'s>) -> Vec<&'s ShadowBinding<'s>> {
    match shadow {
        LitShadow::Map(m) => vec![*m],
        LitShadow::Faces(maps) => maps.to_vec(),
        _ => Vec::new(),
    }
}

/// Adds the light's contribution to `receivers` where the depth equals the unlit pass's.
pub fn draw(
    ctx: &PassContext,
    ff: &FixedFunction,
    lp: &LightPlan,
    shadow: &LitShadow,
    receivers: &[u32],
) {
    let gl = ctx.gl;
    let l = &ff.legacy;
    DrawState {
        blend: Some((glow::ONE, glow::ONE)),
        ..DrawState::OVER_DEPTH
    }
    .apply(gl);
    lit_stencil(gl, shadow, ctx.settings.lighting.light_once);
    // SAFETY: fixed-function state of the current compatibility context.
    unsafe {
        gl.use_program(None);
        l.load_matrix(legacy::PROJECTION, &ctx.plan.camera.projection);
        set_light(ctx, l, lp);
        gl.enable(legacy::LIGHTING);
        gl.enable(legacy::LIGHT0);
        gl.enable(legacy::NORMALIZE);
        gl.active_texture(glow::TEXTURE0);
        gl.enable(glow::TEXTURE_2D);
        l.env(legacy::TEXTURE_ENV_MODE, legacy::MODULATE);
    }
    let maps = maps_of(shadow);
    let offset = lit_offset(ctx, lp, &maps);
    if maps.is_empty() {
        draw_receivers(ctx, ff, receivers, offset);
    }
    for s in maps {
        // SAFETY: the legacy context is current.
        unsafe { bind_map(ctx, ff, s, true) };
        compare_alpha_test(ctx, l, false);
        draw_receivers(ctx, ff, receivers, offset);
        unbind_map(gl, s);
        ff.reset(gl);
        // The light and unit 0 again for the next map.
        // SAFETY: as above.
        unsafe {
            l.load_matrix(legacy::PROJECTION, &ctx.plan.camera.projection);
            gl.enable(legacy::LIGHTING);
            gl.enable(legacy::NORMALIZE);
            gl.active_texture(glow::TEXTURE0);
            gl.enable(glow::TEXTURE_2D);
        }
    }
    ff.reset(gl);
    // SAFETY: fixed-function state.
    unsafe {
        gl.disable(legacy::LIGHT0);
        gl.depth_func(glow::LEQUAL);
    }
    finish(gl);
}

/// Writes the light's decision into the bound mask target for every receiver fragment (the
/// caller removes the fragments the light does not reach): 2 everywhere, then 1 where the
/// stencil count is 0 or the shadow compare passes the alpha test.
pub fn draw_mask(
    ctx: &PassContext,
    ff: &FixedFunction,
    lp: &LightPlan,
    shadow: &LitShadow,
    receivers: &[u32],
) {
    let gl = ctx.gl;
    let l = &ff.legacy;
    // Surfaces out of the light's range would only be removed again.
    let receivers = &lp.masked(receivers)[..];
    DrawState::OVER_DEPTH.apply(gl);
    let value = |v: u8| {
        // SAFETY: the current colour, written as the mask's byte.
        unsafe { (l.color_4f)(f32::from(v) / 255.0, 0.0, 0.0, 1.0) }
    };
    let projection = || {
        // SAFETY: the camera's projection on its stack.
        unsafe {
            gl.use_program(None);
            l.load_matrix(legacy::PROJECTION, &ctx.plan.camera.projection);
        }
    };
    projection();
    let maps = maps_of(shadow);
    let offset = lit_offset(ctx, lp, &maps);
    match shadow {
        LitShadow::Stencil { .. } => {
            for (func, decision) in [(glow::EQUAL, 1), (glow::NOTEQUAL, 2)] {
                stencil_gate(gl, func, 0xff);
                value(decision);
                draw_receivers(ctx, ff, receivers, offset);
            }
        }
        LitShadow::None => {
            value(1);
            draw_receivers(ctx, ff, receivers, offset);
        }
        _ => {
            for s in maps {
                // Every fragment of the view first, then the lit ones over it.
                for decision in [2, 1] {
                    projection();
                    // SAFETY: the legacy context is current.
                    unsafe { bind_map(ctx, ff, s, false) };
                    if decision == 2 {
                        // SAFETY: fixed-function state: unit 1 only for its clip planes.
                        unsafe {
                            gl.active_texture(glow::TEXTURE1);
                            gl.disable(glow::TEXTURE_2D);
                            gl.active_texture(glow::TEXTURE0);
                        }
                    } else {
                        compare_alpha_test(ctx, l, true);
                    }
                    value(decision);
                    draw_receivers(ctx, ff, receivers, offset);
                    ff.reset(gl);
                }
                unbind_map(gl, s);
            }
        }
    }
    ff.reset(gl);
    // SAFETY: fixed-function state.
    unsafe { gl.depth_func(glow::LEQUAL) };
    finish(gl);
}
