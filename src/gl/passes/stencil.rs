//! One light's shadow volumes into the stencil buffer (paper 4.1 "Rendering Shadow Volumes").
//!
//! Depth-fail (the paper): back faces increment where the depth test fails, then front faces
//! decrement where it fails; caps close the volumes. Depth-pass: front faces increment where the
//! test passes, then back faces decrement; no caps. Two passes with culling (the paper's card), or
//! one pass with glStencilOpSeparate. Colour and depth writes are off; the stencil is cleared
//! first. Parts counted either way add up in the same buffer.
//!
//! Each draw is restricted as the plan says: clip planes behind the depth buffer
//! (`gl_ClipDistance`, `plan.depth_clip`) or, where the GL has it, `EXT_depth_bounds_test` over
//! the stored depth (`plan.depth_bounds_test`).

use super::PassContext;
use super::lit::{COUNT_BITS, MAP_DECIDES};
use super::state::DrawState;
use crate::gl::depth_bounds_ext::{self, DepthBoundsExt};
use crate::gl::fragments::LightFragmentDraw;
use crate::gl::program::{Program, has_clip_distances};
use crate::gl::volumes::LightVolumes;
use crate::options::{
    ShadowVolumeOptions, StencilPasses, StencilWrap, VolumeCasters, VolumeProjection,
};
use crate::plan::depth_bounds::MAX_PLANES;
use crate::plan::scissor::Scissor;
use crate::shadow::extrusion::Role;
use crate::shadow::volume::Counting;
use glow::HasContext;

/// (increment, decrement) operations. One pass always wraps: front and back faces arrive
/// interleaved, and a saturating DECR at 0 before its INCR would lose a count (the paper pairs
/// two-sided stencil with EXT_stencil_wrap for this reason).
fn ops(wrap: StencilWrap, passes: StencilPasses) -> (u32, u32) {
    match (wrap, passes) {
        (StencilWrap::Saturate, StencilPasses::TwoPass) => (glow::INCR, glow::DECR),
        _ => (glow::INCR_WRAP, glow::DECR_WRAP),
    }
}

/// glStencilOp arguments (sfail, dpfail, dppass) for a face that increments or decrements.
fn face_op(counting: Counting, op: u32) -> (u32, u32, u32) {
    match counting {
        Counting::ZFail => (glow::KEEP, op, glow::KEEP),
        Counting::ZPass => (glow::KEEP, glow::KEEP, op),
    }
}

/// The volume shader's clip plane uniforms, one per `gl_ClipDistance`.
const DEPTH_CLIP_UNIFORMS: [&str; MAX_PLANES] = [
    "u_depth_clip[0]",
    "u_depth_clip[1]",
    "u_depth_clip[2]",
    "u_depth_clip[3]",
];

fn draw_parts(
    gl: &glow::Context,
    program: &Program,
    v: &LightVolumes<'_>,
    counting: Counting,
    bounds: Option<DepthBoundsExt>,
) {
    // SAFETY: the light's own vertex array; ranges lie inside its buffer. The depth bounds
    // entry point is given only where the GL has the extension.
    unsafe {
        gl.bind_vertex_array(Some(v.vao));
        // What the last draw set: a light's parts mostly share their model and many their
        // clip planes and bounds, so each is set only where it changes (the first draw sets
        // all of them).
        let (mut model, mut clip, mut range) = (None, None, None);
        for d in v.draws.iter().filter(|d| d.counting == counting) {
            if d.scissor.is_some() {
                super::set_scissor(gl, d.scissor);
            }
            if let Some(ext) = bounds
                && range != Some(d.depth_bounds)
            {
                match d.depth_bounds {
                    Some(r) => ext.enable(gl, r),
                    None => ext.disable(gl),
                }
                range = Some(d.depth_bounds);
            }
            if model != Some(d.model) {
                program.set_mat4(gl, "u_model", &d.model);
                model = Some(d.model);
            }
            if clip != Some(d.depth_clip) {
                for (name, plane) in DEPTH_CLIP_UNIFORMS.iter().zip(&d.depth_clip) {
                    program.set_vec4(gl, name, glam::Vec4::from_array(*plane));
                }
                clip = Some(d.depth_clip);
            }
            if d.indexed {
                gl.draw_elements(glow::TRIANGLES, d.count, glow::UNSIGNED_INT, d.first * 4);
            } else {
                gl.draw_arrays(glow::TRIANGLES, d.first, d.count);
            }
        }
        gl.bind_vertex_array(None);
    }
}

/// The light's groups the GPU extrudes that count `counting`: sides, and caps for depth-fail.
fn draw_extruded(
    ctx: &PassContext,
    program: &Program,
    v: &LightVolumes<'_>,
    counting: Counting,
    light_scissor: Option<Scissor>,
) {
    let gl = ctx.gl;
    let o = &ctx.settings.shadow_volume;
    let mut drawn = v
        .extruded
        .iter()
        .filter(|d| d.counting == counting)
        .peekable();
    if drawn.peek().is_none() {
        return;
    }
    // The built parts' rectangles are theirs; these volumes get the light's.
    super::set_scissor(gl, light_scissor);
    program.bind(gl);
    program.set_mat4(gl, "u_view_proj", &ctx.plan.camera.view_proj);
    program.set_f32(gl, "u_epsilon", o.facing_epsilon);
    program.set_i32(
        gl,
        "u_two_sided",
        i32::from(o.casters == VolumeCasters::Both),
    );
    let roles: &[Role] = match counting {
        Counting::ZFail => &[Role::Sides, Role::FrontCap, Role::BackCap],
        Counting::ZPass => &[Role::Sides],
    };
    for d in drawn {
        program.set_mat4(gl, "u_model", &d.model);
        program.set_vec3(gl, "u_light", d.light);
        // SAFETY: the group's own vertex array; ranges lie inside its index buffer.
        unsafe {
            gl.bind_vertex_array(Some(d.vao));
            for &role in roles {
                let (first, count) = d.range(role);
                program.set_i32(gl, "u_role", role.code());
                gl.draw_elements(glow::TRIANGLES, count, glow::UNSIGNED_INT, first * 4);
            }
            gl.bind_vertex_array(None);
        }
    }
}

/// The two volume programs: built on the CPU (`shaders/volume.vert`) and extruded on the GPU
/// (`shaders/volume_gpu.vert`).
pub struct VolumePrograms {
    pub built: Program,
    pub extruded: Program,
}

/// Every part of the light's volumes, whatever its counting, without depth bounds.
pub fn draw_all_parts(
    ctx: &PassContext,
    programs: &VolumePrograms,
    v: &LightVolumes<'_>,
    light_scissor: Option<Scissor>,
) {
    for counting in [Counting::ZFail, Counting::ZPass] {
        programs.built.bind(ctx.gl);
        program_camera(ctx, &programs.built);
        draw_parts(ctx.gl, &programs.built, v, counting, None);
        draw_extruded(ctx, &programs.extruded, v, counting, light_scissor);
    }
    super::set_scissor(ctx.gl, light_scissor);
}

fn program_camera(ctx: &PassContext, program: &Program) {
    program.set_mat4(ctx.gl, "u_view_proj", &ctx.plan.camera.view_proj);
}

/// Clears the stencil and counts the light's volumes into it. Parts with a rectangle of their
/// own draw inside it; the scissor is left as `light_scissor` (the caller's) afterwards.
/// `masked`: the hybrid's computation mask is in the stencil already (not cleared); counts go
/// to its count bits where its mask bit is clear (`passes::hybrid`).
pub fn draw(
    ctx: &PassContext,
    programs: &VolumePrograms,
    volumes: &LightVolumes<'_>,
    light_scissor: Option<Scissor>,
    masked: bool,
) {
    let gl = ctx.gl;
    let o = &ctx.settings.shadow_volume;
    begin(gl, o, !masked);
    if masked {
        // Count only where the mask bit is clear, into the count bits.
        // SAFETY: fixed-function state.
        unsafe {
            gl.stencil_func(glow::EQUAL, 0, MAP_DECIDES);
            gl.stencil_mask(COUNT_BITS);
        }
    }
    // SAFETY: fixed-function state.
    unsafe {
        // Each draw's depth clip planes (zero where it has none); none on ES.
        if has_clip_distances(gl) {
            for i in 0..MAX_PLANES as u32 {
                gl.enable(glow::CLIP_DISTANCE0 + i);
            }
        }
    }
    // The plan asks for the depth bounds test only where the probe found the extension and
    // its entry point (plan::fallback); counts are right without it, only slower.
    let bounds = volumes
        .draws
        .iter()
        .any(|d| d.depth_bounds.is_some())
        .then(depth_bounds_ext::current)
        .flatten();
    count(gl, volumes, ctx.plan.stencil, o.wrap, |counting| {
        let program = &programs.built;
        program.bind(gl);
        program_camera(ctx, program);
        draw_parts(gl, program, volumes, counting, bounds);
        if let Some(ext) = bounds.filter(|_| !volumes.extruded.is_empty()) {
            // SAFETY: the entry point exists (the probe found it); the extruded volumes have
            // no depth range of their own.
            unsafe { ext.disable(gl) };
        }
        draw_extruded(ctx, &programs.extruded, volumes, counting, light_scissor);
    });
    super::set_scissor(gl, light_scissor);
    // SAFETY: state reset for the lit pass; only what was enabled (ES may lack the switch).
    unsafe {
        if let Some(ext) = bounds {
            ext.disable(gl);
        }
        if has_clip_distances(gl) {
            for i in 0..MAX_PLANES as u32 {
                gl.disable(glow::CLIP_DISTANCE0 + i);
            }
        }
    }
    end(gl, o);
}

/// The state every volume pass counts with (shader or fixed-function): the stencil cleared
/// (with `clear`) and always passing, colour and depth writes off, depth test LESS, the
/// options' offset and depth clamp.
pub fn begin(gl: &glow::Context, o: &ShadowVolumeOptions, clear: bool) {
    // SAFETY: fixed-function state on the bound framebuffer.
    unsafe {
        gl.stencil_mask(0xff);
        if clear {
            gl.clear_stencil(0);
            gl.clear(glow::STENCIL_BUFFER_BIT);
        }
        gl.color_mask(false, false, false, false);
        gl.depth_mask(false);
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::LESS);
        gl.disable(glow::BLEND);
        gl.enable(glow::STENCIL_TEST);
        gl.stencil_func(glow::ALWAYS, 0, 0xff);
        if o.depth_offset {
            // Doom 3: push the volumes a hair away so caps lose against their own surfaces.
            gl.enable(glow::POLYGON_OFFSET_FILL);
            gl.polygon_offset(0.0, 1.0);
        } else {
            gl.disable(glow::POLYGON_OFFSET_FILL);
        }
        if o.projection == VolumeProjection::DepthClamp {
            gl.enable(glow::DEPTH_CLAMP);
        }
    }
}

/// Counts each counting mode's parts: the face that increments (back faces under depth-fail,
/// front faces under depth-pass) and the one that decrements, in two passes with culling or
/// in one with glStencilOpSeparate; `draw` draws the parts of one counting mode.
pub fn count(
    gl: &glow::Context,
    volumes: &LightVolumes<'_>,
    passes: StencilPasses,
    wrap: StencilWrap,
    mut draw: impl FnMut(Counting),
) {
    let (incr, decr) = ops(wrap, passes);
    for counting in [Counting::ZFail, Counting::ZPass] {
        if !volumes.counts(counting) {
            continue;
        }
        let (incr_face, decr_face) = match counting {
            Counting::ZFail => (glow::BACK, glow::FRONT),
            Counting::ZPass => (glow::FRONT, glow::BACK),
        };
        let faces = [(incr_face, incr), (decr_face, decr)];
        match passes {
            StencilPasses::TwoPass => {
                for (face, op) in faces {
                    let (sfail, dpfail, dppass) = face_op(counting, op);
                    // SAFETY: fixed-function state: draw only `face`, cull the other.
                    unsafe {
                        gl.enable(glow::CULL_FACE);
                        gl.cull_face(if face == glow::BACK {
                            glow::FRONT
                        } else {
                            glow::BACK
                        });
                        gl.stencil_op(sfail, dpfail, dppass);
                    }
                    draw(counting);
                }
            }
            StencilPasses::Separate => {
                // SAFETY: fixed-function state.
                unsafe {
                    gl.disable(glow::CULL_FACE);
                    for (face, op) in faces {
                        let (sfail, dpfail, dppass) = face_op(counting, op);
                        gl.stencil_op_separate(face, sfail, dpfail, dppass);
                    }
                }
                draw(counting);
            }
        }
    }
}

/// Resets what [`begin`] and [`count`] set, for the lit pass (which sets what it needs).
pub fn end(gl: &glow::Context, o: &ShadowVolumeOptions) {
    // SAFETY: fixed-function state; only what was enabled (ES may lack depth clamp).
    unsafe {
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
        gl.stencil_mask(0xff);
        gl.disable(glow::POLYGON_OFFSET_FILL);
        if o.projection == VolumeProjection::DepthClamp {
            gl.disable(glow::DEPTH_CLAMP);
        }
        gl.color_mask(true, true, true, true);
    }
}

/// Bestimt and Freitag's fill: where the stencil is not zero, scale the frame by `shade` and zero
/// the stencil (one full-screen triangle).
pub fn fill(gl: &glow::Context, program: &Program, vao: glow::VertexArray, shade: f32) {
    // Scale the frame by `shade` where the stencil is set, depth untouched.
    DrawState {
        color_write: true,
        depth_write: false,
        depth_test: None,
        blend: Some((glow::DST_COLOR, glow::ZERO)),
        stencil_test: true,
        polygon_offset: None,
    }
    .apply(gl);
    // SAFETY: fixed-function state; a full-screen triangle from gl_VertexID.
    unsafe {
        gl.disable(glow::CULL_FACE);
        gl.stencil_func(glow::NOTEQUAL, 0, 0xff);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::ZERO);
        program.bind(gl);
        program.set_f32(gl, "u_shade", shade);
        gl.bind_vertex_array(Some(vao));
        gl.draw_arrays(glow::TRIANGLES, 0, 3);
        gl.bind_vertex_array(None);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
        gl.disable(glow::BLEND);
        gl.enable(glow::DEPTH_TEST);
    }
}

/// glPolygonOffset (factor, units) the subdivision's fragments are marked with: units only.
/// A slope factor pulls a wall seen edge-on past the floor it meets, a line of false shadow
/// along every crease (docs/subdivision.md: oa_dm1 0.30% outside the band at (-1, -2)).
pub const FRAGMENT_OFFSET: (f32, f32) = (0.0, -4.0);

/// How far `shaders/fragments.vert` pulls each corner towards the camera, in f32 spacings of
/// its coordinates: the rounding of the f64 corners is what the depth test must forgive, and
/// near the camera the offset's units do not (docs/subdivision.md).
pub const FRAGMENT_PULL_ULPS: f32 = 8.0;

/// The fixed-function pipeline's pull (no vertex shader): every corner towards the camera by
/// this fraction of its distance, through the modelview matrix.
pub const FIXED_FRAGMENT_PULL: f32 = 1e-4;

/// Vector's subdivision: clears the stencil (with `clear`; else it holds the models' volume
/// counts) and sets it to 1 where one of the light's shadowed fragments is the visible surface
/// (drawn over the frame's depth, no colour or depth writes, each surface's fragments culled
/// as the surface is); the lit pass then draws where it is 0, as after a volume pass.
pub fn mark_fragments(
    ctx: &PassContext,
    program: &Program,
    fragments: &LightFragmentDraw,
    clear: bool,
) {
    let gl = ctx.gl;
    mark_state(gl, clear);
    program.bind(gl);
    program_camera(ctx, program);
    program.set_vec3(gl, "u_camera", ctx.plan.camera.position);
    program.set_f32(gl, "u_pull_ulps", FRAGMENT_PULL_ULPS);
    // SAFETY: the light's own vertex array; the ranges lie inside it.
    unsafe {
        gl.bind_vertex_array(Some(fragments.vao));
        for m in fragments.marks.iter().filter(|m| m.count > 0) {
            super::apply_cull(gl, m.cull);
            gl.draw_arrays(glow::TRIANGLES, m.first, m.count);
        }
        gl.bind_vertex_array(None);
    }
    end_marks(gl);
}

/// A model matrix that moves every point towards `camera` by `pull` of its distance.
pub fn towards_camera(camera: glam::Vec3, pull: f32) -> glam::Mat4 {
    glam::Mat4::from_translation(camera)
        * glam::Mat4::from_scale(glam::Vec3::splat(1.0 - pull))
        * glam::Mat4::from_translation(-camera)
}

/// The state fragments are marked with (shader or fixed-function), the stencil cleared with
/// `clear`. A mark replaces a volume count: shadowed either way.
pub fn mark_state(gl: &glow::Context, clear: bool) {
    DrawState {
        color_write: false,
        depth_write: false,
        depth_test: Some(glow::LEQUAL),
        blend: None,
        stencil_test: true,
        polygon_offset: Some(FRAGMENT_OFFSET),
    }
    .apply(gl);
    // SAFETY: fixed-function state and a clear of the bound target's stencil (within the
    // light's scissor).
    unsafe {
        gl.stencil_mask(0xff);
        if clear {
            gl.clear_stencil(0);
            gl.clear(glow::STENCIL_BUFFER_BIT);
        }
        gl.stencil_func(glow::ALWAYS, 1, 0xff);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
    }
}

/// Undoes [`mark_state`]'s stencil operation and offset.
pub fn end_marks(gl: &glow::Context) {
    // SAFETY: fixed-function state.
    unsafe {
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
        gl.disable(glow::POLYGON_OFFSET_FILL);
        gl.color_mask(true, true, true, true);
    }
}
