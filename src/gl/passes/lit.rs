//! One light's additive pass (paper 3.1 and 4: "draw lit world with additive blending"), and its
//! mask variant, which writes the same fragments' decision instead of light.

use super::state::DrawState;
use super::{PassContext, draw_items};
use crate::gl::program::{Program, has_clip_distances};
use crate::options::{OffsetPass, Outside, ShadowMapOptions, TexgenSpace};
use crate::plan::LightPlan;
use crate::scene::{LightKind, light::SPOT_INNER_FRACTION};
use crate::shadow::views::{ShadowView, ViewKind};
use crate::truth::reference::ORIGIN_LIFT;
use glam::{Mat4, Vec3};
use glow::HasContext;

/// A shadow map to test the light's fragments against.
pub struct ShadowBinding<'a> {
    pub view: &'a ShadowView,
    /// The depth texture, or an ID buffer's colour.
    pub texture: glow::Texture,
    /// The per-triangle table of ID and priority buffers.
    pub table: Option<glow::Texture>,
}

/// How the lit pass learns what is in shadow.
pub enum LitShadow<'a> {
    None,
    Map(&'a ShadowBinding<'a>),
    /// An omni light's six spot maps in one pass (the `SIX_SPOTS` program).
    Faces(&'a [&'a ShadowBinding<'a>]),
    /// The stencil counts of this light's volumes; `test` = light only where the count is 0
    /// (off for the fill-quad shading, which darkens afterwards).
    Stencil {
        test: bool,
    },
    /// Chan & Durand's hybrid: the maps (`Map` or `Faces`) decide where their compares
    /// agree, the stencil counts at the other pixels (the low seven bits; the top bit marks
    /// the pixels the map decides, see `passes::hybrid`).
    Hybrid(&'a LitShadow<'a>),
}

/// The stencil bit of the hybrid's computation mask: set where the map decides.
pub const MAP_DECIDES: u32 = 0x80;
/// The stencil bits that count volumes under the hybrid.
pub const COUNT_BITS: u32 = 0x7f;

/// Binds `program` with the light's uniforms and, with a shadow map, the texgen, the map and
/// the fixed-function state of the technique; the hybrid's program shades (stage 1).
pub fn bind_light(ctx: &PassContext, program: &Program, lp: &LightPlan, shadow: &LitShadow) {
    match shadow {
        LitShadow::Hybrid(maps) => {
            bind_maps(ctx, program, lp, maps);
            program.set_i32(ctx.gl, "u_hybrid_stage", 1);
            program.set_i32(ctx.gl, "u_hybrid_radius", ctx.settings.hybrid.radius as i32);
        }
        _ => bind_maps(ctx, program, lp, shadow),
    }
}

fn bind_maps(ctx: &PassContext, program: &Program, lp: &LightPlan, shadow: &LitShadow) {
    let gl = ctx.gl;
    program.bind(gl);
    set_light(ctx, program, lp);
    let o = &ctx.settings.shadow_map;
    set_offset_and_clips(gl, o, lp, shadow);
    let lift = match o.normal_offset {
        true => ORIGIN_LIFT,
        false => (0.0, 0.0),
    };
    program.set_vec2(
        gl,
        "u_normal_offset",
        glam::Vec2::new(lift.0 as f32, lift.1 as f32),
    );
    let space = TexgenFrame::of(ctx, lp);
    let table = match shadow {
        LitShadow::Map(s) => s.table,
        LitShadow::Faces(maps) => maps.first().and_then(|m| m.table),
        _ => None,
    };
    if let Some(table) = table {
        super::shadow_map::bind_table(gl, program, table);
        program.set_u32(gl, "u_id_mask", super::shadow_map::id_mask(o.id_bits));
        program.set_f32(gl, "u_priority_bias", o.priority_bias);
    }
    match shadow {
        LitShadow::Faces(maps) => bind_six_spots(gl, program, o, &space, maps),
        LitShadow::Map(s) => bind_one_map(gl, program, o, &space, s),
        _ => {}
    }
}

/// The light's camera, colour and cone.
pub fn set_light(ctx: &PassContext, program: &Program, lp: &LightPlan) {
    let gl = ctx.gl;
    let light = &ctx.scene.lights[lp.light];
    program.set_mat4(gl, "u_view_proj", &ctx.plan.camera.view_proj);
    program.set_i32(gl, "u_texture", 0);
    program.set_vec3(gl, "u_light_pos", light.position);
    program.set_vec3(
        gl,
        "u_light_color",
        light.color * ctx.settings.lighting.intensity,
    );
    let (dir, cos_cutoff, cos_inner) = cone_of(light);
    program.set_vec3(gl, "u_spot_dir", dir);
    program.set_f32(gl, "u_cos_cutoff", cos_cutoff);
    program.set_f32(gl, "u_cos_inner", cos_inner);
    program.set_f32(gl, "u_radius", light.radius);
}

/// A light's cone as the shaders take it: direction, cosine of the cutoff (-1: omni) and of
/// where the edge starts to soften.
pub fn cone_of(light: &crate::scene::Light) -> (Vec3, f32, f32) {
    match light.kind {
        LightKind::Spot {
            direction,
            cutoff_deg,
        } => (
            direction.normalize(),
            cutoff_deg.to_radians().cos(),
            (cutoff_deg * SPOT_INNER_FRACTION).to_radians().cos(),
        ),
        LightKind::Omni => (Vec3::Z, -1.0, -1.0),
    }
}

/// The lit pass's polygon offset (the paper's, toward the camera, with a map) and no clip
/// distance left on from an earlier draw.
fn set_offset_and_clips(
    gl: &glow::Context,
    o: &ShadowMapOptions,
    lp: &LightPlan,
    shadow: &LitShadow,
) {
    // SAFETY: fixed-function state only.
    unsafe {
        match (
            lp.map_offset,
            o.offset_pass,
            matches!(shadow, LitShadow::Map(_) | LitShadow::Faces(_)),
        ) {
            // The paper's lit-pass offset pulls the lit world toward the camera.
            (Some((factor, units)), OffsetPass::Lit | OffsetPass::Both, true) => {
                gl.enable(glow::POLYGON_OFFSET_FILL);
                gl.polygon_offset(-factor, -units);
            }
            _ => gl.disable(glow::POLYGON_OFFSET_FILL),
        }
        // ES has no CLIP_DISTANCEi switches (GLSL ES 3.00 has no gl_ClipDistance).
        if has_clip_distances(gl) {
            for i in 0..4 {
                gl.disable(glow::CLIP_DISTANCE0 + i);
            }
        }
    }
}

/// An omni light's six spot maps at once (`SIX_SPOTS`), on units 1-6.
fn bind_six_spots(
    gl: &glow::Context,
    program: &Program,
    o: &ShadowMapOptions,
    space: &TexgenFrame,
    maps: &[&ShadowBinding],
) {
    program.set_mat4(gl, "u_view", &space.to_texgen_space);
    program.set_f32(gl, "u_map_size", o.size as f32);
    program.set_i32(gl, "u_pcf_size", o.pcf_size as i32);
    program.set_i32(gl, "u_sm_alpha_func", o.alpha_func as i32);
    program.set_f32(gl, "u_sm_alpha_ref", o.alpha_ref);
    program.set_i32(gl, "u_face", -1);
    for (i, m) in maps.iter().enumerate() {
        let (texgen, depth) = space.texgens(m.view);
        program.set_mat4(gl, &format!("u_texgens[{i}]"), &texgen);
        program.set_mat4(gl, &format!("u_texgen_depths[{i}]"), &depth);
        program.set_i32(gl, &format!("u_face_maps[{i}]"), 1 + i as i32);
        // SAFETY: binds our depth textures to units 1-6.
        unsafe {
            gl.active_texture(glow::TEXTURE1 + i as u32);
            gl.bind_texture(glow::TEXTURE_2D, Some(m.texture));
        }
    }
    // SAFETY: back to unit 0 for the material textures.
    unsafe { gl.active_texture(glow::TEXTURE0) };
}

/// One map (a spot's, a face's, a cube) on unit 1, with its texgen and clip planes.
fn bind_one_map(
    gl: &glow::Context,
    program: &Program,
    o: &ShadowMapOptions,
    space: &TexgenFrame,
    s: &ShadowBinding,
) {
    let (texgen, depth) = space.texgens(s.view);
    program.set_mat4(gl, "u_view", &space.to_texgen_space);
    program.set_mat4(gl, "u_texgen", &texgen);
    program.set_mat4(gl, "u_texgen_depth", &depth);
    program.set_f32(gl, "u_map_size", s.view.map_size() as f32);
    program.set_i32(gl, "u_pcf_size", o.pcf_size as i32);
    program.set_i32(gl, "u_sm_alpha_func", o.alpha_func as i32);
    program.set_f32(gl, "u_sm_alpha_ref", o.alpha_ref);
    let face = match s.view.kind {
        ViewKind::Face(f) => f as i32,
        _ => -1,
    };
    program.set_i32(gl, "u_face", face);
    // One of several frusta lights its cell of the face; min > max: the whole face.
    let cell = s
        .view
        .part
        .map_or(glam::Vec4::new(1.0, 1.0, -1.0, -1.0), |p| {
            p.cell.min.extend(p.cell.max.x).extend(p.cell.max.y)
        });
    program.set_vec4(gl, "u_cell", cell);
    program.set_mat3(gl, "u_face_rot", &glam::Mat3::from_mat4(s.view.view));
    program.set_vec2(
        gl,
        "u_cube_near_far",
        glam::Vec2::new(s.view.near, s.view.far),
    );
    let cube = s.view.kind == ViewKind::Cube;
    // SAFETY: binds our depth texture to unit 1 and enables the clip distances the shader writes.
    unsafe {
        gl.active_texture(glow::TEXTURE1);
        if cube {
            gl.bind_texture(glow::TEXTURE_CUBE_MAP, Some(s.texture));
            program.set_i32(gl, "u_shadow_cube", 1);
        } else {
            gl.bind_texture(glow::TEXTURE_2D, Some(s.texture));
            program.set_i32(gl, "u_shadow_map", 1);
        }
        gl.active_texture(glow::TEXTURE0);
        if o.outside == Outside::ClipPlanes && !cube {
            let planes = s.view.clip_planes();
            for (i, p) in planes.iter().take(4).enumerate() {
                program.set_vec4(gl, &format!("u_clip_planes[{i}]"), *p);
                gl.enable(glow::CLIP_DISTANCE0 + i as u32);
            }
        }
    }
}

/// The space the lit pass's texgen planes apply in (`shadow_map.texgen`): the vertex shader
/// computes `texgen · (to_texgen_space · world)`.
struct TexgenFrame {
    to_texgen_space: Mat4,
    /// Eye-linear: the camera's view; relative to the light: the light's position.
    kind: TexgenSpace,
    camera_view: Mat4,
    light: Vec3,
}

impl TexgenFrame {
    fn of(ctx: &PassContext, lp: &LightPlan) -> TexgenFrame {
        let camera_view = ctx.plan.camera.view;
        let light = ctx.scene.lights[lp.light].position;
        let kind = ctx.settings.shadow_map.texgen;
        TexgenFrame {
            to_texgen_space: match kind {
                TexgenSpace::EyeLinear => camera_view,
                TexgenSpace::Light | TexgenSpace::Fragment => Mat4::from_translation(-light),
            },
            kind,
            camera_view,
            light,
        }
    }

    /// A view's texgen and its depth texgen in this space.
    fn texgens(&self, view: &ShadowView) -> (Mat4, Mat4) {
        match self.kind {
            TexgenSpace::EyeLinear => (
                view.texgen(&self.camera_view),
                view.depth_texgen(&self.camera_view),
            ),
            TexgenSpace::Light | TexgenSpace::Fragment => (
                view.texgen_relative(self.light),
                view.depth_texgen_relative(self.light),
            ),
        }
    }
}

/// Draw only where the stencil's `bits` compare to 0 with `func` (EQUAL: lit; NOTEQUAL:
/// shadowed).
pub fn stencil_gate(gl: &glow::Context, func: u32, bits: u32) {
    // SAFETY: fixed-function state.
    unsafe {
        gl.enable(glow::STENCIL_TEST);
        gl.stencil_func(func, 0, bits);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
        // No stencil writes: llvmpipe then tests depth and stencil before the shader runs
        // (early test) even though the shader discards, so hidden fragments cost nothing.
        gl.stencil_mask(0);
    }
}

/// The lit pass's stencil state: under shadow volumes, add only where the count is 0; with
/// `lighting.light_once`, also only where no earlier fragment of this light added, marking
/// where this one does (the count is 0 there too, so one test does both). Under the fill
/// shading the lit pass draws everywhere and the fill quad reads the counts: no marks.
pub fn lit_stencil(gl: &glow::Context, shadow: &LitShadow, once: bool) {
    match (shadow, once) {
        (LitShadow::Stencil { test: false }, _) => {}
        // Count zero or decided by the map (the top bit is not compared); the shader drops
        // what the map shadows. Marks add one to the count bits.
        (LitShadow::Hybrid(_), true) => {
            // SAFETY: fixed-function state.
            unsafe {
                gl.enable(glow::STENCIL_TEST);
                gl.stencil_func(glow::EQUAL, 0, COUNT_BITS);
                gl.stencil_op(glow::KEEP, glow::KEEP, glow::INCR);
                gl.stencil_mask(0xff);
            }
        }
        (LitShadow::Hybrid(_), false) => stencil_gate(gl, glow::EQUAL, COUNT_BITS),
        (_, true) => {
            // SAFETY: fixed-function state.
            unsafe {
                gl.enable(glow::STENCIL_TEST);
                gl.stencil_func(glow::EQUAL, 0, 0xff);
                gl.stencil_op(glow::KEEP, glow::KEEP, glow::INCR);
                gl.stencil_mask(0xff);
            }
        }
        (LitShadow::Stencil { test: true }, false) => stencil_gate(gl, glow::EQUAL, 0xff),
        (_, false) => {}
    }
}

/// Clears the stencil (within the scissor) before a light whose lit pass marks it and whose
/// stencil no volume pass has just cleared.
pub fn clear_marks(gl: &glow::Context) {
    // SAFETY: fixed-function state and a clear of the bound target's stencil.
    unsafe {
        gl.stencil_mask(0xff);
        gl.clear_stencil(0);
        gl.clear(glow::STENCIL_BUFFER_BIT);
    }
}

pub fn finish(gl: &glow::Context) {
    // SAFETY: state this pass enabled, switched off for the passes that do not set it.
    unsafe {
        gl.disable(glow::STENCIL_TEST);
        gl.stencil_mask(0xff);
        gl.disable(glow::POLYGON_OFFSET_FILL);
        // ES has no CLIP_DISTANCEi switches (GLSL ES 3.00 has no gl_ClipDistance).
        if has_clip_distances(gl) {
            for i in 0..4 {
                gl.disable(glow::CLIP_DISTANCE0 + i);
            }
        }
    }
}

/// Where a light's lit pass marks the stencil so that it adds to each pixel once
/// (`lighting.light_once`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marks {
    /// Nowhere: the light is added wherever a fragment passes (the paper's additive passes).
    Off,
    /// On the surfaces whose own triangles overlap ([`crate::scene::Surface::overlapping`]),
    /// drawn first; the others only test the marks, without writing, which keeps the early
    /// depth test (llvmpipe drops it for a pass that writes stencil from a shader that may
    /// discard: the marks everywhere doubled its lit passes).
    Overlapping,
    /// On every surface: the light has several lit passes (one per map view), whose receivers
    /// may meet where the views do; the stencil is cleared once before the first.
    Everywhere,
}

impl Marks {
    /// The marks a light drawn in `lit_passes` lit passes needs.
    pub fn of(light_once: bool, lit_passes: usize) -> Marks {
        match (light_once, lit_passes > 1) {
            (false, _) => Marks::Off,
            (true, false) => Marks::Overlapping,
            (true, true) => Marks::Everywhere,
        }
    }
}

/// Adds the light's contribution to `receivers` (the plan's surfaces for this light or view)
/// where the depth equals the unlit pass's.
pub fn draw(
    ctx: &PassContext,
    program: &Program,
    lp: &LightPlan,
    shadow: &LitShadow,
    (receivers, marks): (&[u32], Marks),
) {
    let gl = ctx.gl;
    // Test against the unlit pass, never write depth; add the light.
    DrawState {
        blend: Some((glow::ONE, glow::ONE)),
        ..DrawState::OVER_DEPTH
    }
    .apply(gl);
    bind_light(ctx, program, lp, shadow);
    let draw_surfaces = |surfaces: &[u32]| {
        let items = ctx
            .gpu
            .draw_list_of(ctx.scene, crate::gl::upload::Merge::ByMaterial, surfaces);
        draw_items(ctx, program, &items, |_| {});
    };
    if marks != Marks::Overlapping {
        lit_stencil(gl, shadow, marks == Marks::Everywhere);
        draw_surfaces(receivers);
        finish(gl);
        return;
    }
    let (twice, once): (Vec<u32>, Vec<u32>) = receivers
        .iter()
        .partition(|&&s| ctx.scene.surfaces[s as usize].overlapping);
    if !twice.is_empty() {
        // Under volumes (and the hybrid) the stencil holds the counts the marks add to; the
        // map and unshadowed passes start from a clear one.
        if !matches!(shadow, LitShadow::Stencil { .. } | LitShadow::Hybrid(_)) {
            clear_marks(gl);
        }
        lit_stencil(gl, shadow, true);
        draw_surfaces(&twice);
    }
    lit_gate(gl, shadow, !twice.is_empty());
    draw_surfaces(&once);
    finish(gl);
}

/// The lit pass's stencil state over surfaces that are not marked: as without marks, and
/// where `marked` (surfaces drawn before marked the stencil), a test that no mark is there,
/// which writes nothing.
fn lit_gate(gl: &glow::Context, shadow: &LitShadow, marked: bool) {
    match shadow {
        LitShadow::Stencil { .. } | LitShadow::Hybrid(_) => lit_stencil(gl, shadow, false),
        _ if marked => stencil_gate(gl, glow::EQUAL, 0xff),
        _ => {
            // SAFETY: fixed-function state.
            unsafe { gl.disable(glow::STENCIL_TEST) };
        }
    }
}

/// Writes the light's decision into the bound mask target (cleared to "not a receiver"). Under
/// shadow volumes the stencil decides: count 0 is lit, any other count shadowed.
pub fn draw_mask(
    ctx: &PassContext,
    program: &Program,
    lp: &LightPlan,
    shadow: &LitShadow,
    receivers: &[u32],
) {
    let gl = ctx.gl;
    DrawState::OVER_DEPTH.apply(gl);
    bind_light(ctx, program, lp, shadow);
    let items = ctx.gpu.draw_list_of(
        ctx.scene,
        crate::gl::upload::Merge::ByMaterial,
        &lp.masked(receivers),
    );
    let counted = match shadow {
        LitShadow::Stencil { .. } => Some((0xff, 1)),
        // Where the count bits are zero the shader decides (the map, or lit at a silhouette).
        LitShadow::Hybrid(_) => Some((COUNT_BITS, 0)),
        _ => None,
    };
    if let Some((bits, zero)) = counted {
        for (func, decision) in [(glow::EQUAL, zero), (glow::NOTEQUAL, 2)] {
            stencil_gate(gl, func, bits);
            program.set_i32(gl, "u_mask_value", decision);
            draw_items(ctx, program, &items, |_| {});
        }
    } else {
        program.set_i32(gl, "u_mask_value", 0);
        draw_items(ctx, program, &items, |_| {});
    }
    finish(gl);
}

/// Adds (0, 1) to the bound decision layer (`gl::record`) wherever the G-buffer (`textures`:
/// position, normal) shows a receiving surface the light reaches: the pixels its lit pass left
/// undrawn there are the ones its stencil shadowed. A full-screen triangle
/// within the bound scissor.
pub fn draw_reached(
    ctx: &PassContext,
    program: &Program,
    lp: &LightPlan,
    (position, normal): (glow::Texture, glow::Texture),
    vao: glow::VertexArray,
) {
    let gl = ctx.gl;
    DrawState {
        color_write: true,
        depth_write: false,
        depth_test: None,
        blend: Some((glow::ONE, glow::ONE)),
        stencil_test: false,
        polygon_offset: None,
    }
    .apply(gl);
    program.bind(gl);
    set_light(ctx, program, lp);
    program.set_i32(gl, "u_position", 0);
    program.set_i32(gl, "u_normal", 1);
    // SAFETY: binds the G-buffer's textures to units 0 and 1 and draws a full-screen triangle
    // from gl_VertexID.
    unsafe {
        gl.disable(glow::CULL_FACE);
        gl.active_texture(glow::TEXTURE1);
        gl.bind_texture(glow::TEXTURE_2D, Some(normal));
        gl.active_texture(glow::TEXTURE0);
        gl.bind_texture(glow::TEXTURE_2D, Some(position));
        gl.bind_vertex_array(Some(vao));
        gl.draw_arrays(glow::TRIANGLES, 0, 3);
        gl.bind_vertex_array(None);
        gl.disable(glow::BLEND);
        gl.enable(glow::DEPTH_TEST);
    }
}
