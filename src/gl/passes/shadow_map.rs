//! The light's view into a depth texture (paper 3.1; thesis 2.2.3–2.2.4, 2.2.8, 2.2.10): depth
//! only, colour writes off, viewport = map size, the polygon offset, then — on the paper's path —
//! a copy of the depth buffer into the texture (glCopyTexSubImage2D).

use super::{PassContext, draw_items_with};
use crate::gl::program::Program;
use crate::gl::target::Framebuffer;
use crate::gl::upload::Merge;
use crate::options::{
    AlphaCasters, CasterFaces, DepthBits, DepthSource, MapBuffer, OffsetPass, ShadowMapOptions,
};
use crate::scene::Cull;
use glam::Mat4;
use glow::HasContext;

/// Binds an ID or priority buffer's per-triangle table to unit 7 (`u_table`).
pub fn bind_table(gl: &glow::Context, program: &Program, table: glow::Texture) {
    program.set_i32(gl, "u_table", 7);
    // SAFETY: our table texture on a unit the passes leave alone; back to unit 0.
    unsafe {
        gl.active_texture(glow::TEXTURE7);
        gl.bind_texture(glow::TEXTURE_2D, Some(table));
        gl.active_texture(glow::TEXTURE0);
    }
}

/// The mask that keeps `bits` of an ID.
pub fn id_mask(bits: u32) -> u32 {
    if bits >= 32 {
        u32::MAX
    } else {
        (1u32 << bits) - 1
    }
}

/// Where the depth pass draws.
pub enum DepthTarget<'a> {
    /// The frame's own depth buffer, then a copy into `texture` (the paper).
    Copy {
        frame: &'a Framebuffer,
        texture: glow::Texture,
    },
    /// Straight into `texture` through `fbo`, with the ID buffer's `colour` when it has one.
    Fbo {
        fbo: glow::Framebuffer,
        texture: glow::Texture,
        colour: Option<glow::Texture>,
    },
}

/// Which texture image a view writes: a 2D map, or one face of a cube map.
pub fn image_target(cube_face: Option<usize>) -> u32 {
    match cube_face {
        Some(f) => glow::TEXTURE_CUBE_MAP_POSITIVE_X + f as u32,
        None => glow::TEXTURE_2D,
    }
}

/// One light view to draw into a map.
pub struct MapView<'a> {
    pub view_proj: Mat4,
    /// The map's side in texels (the viewport).
    pub size: u32,
    /// The cube face drawn into (cube maps).
    pub cube_face: Option<usize>,
    /// The light's glPolygonOffset (factor, units), None where it is off (`LightPlan::map_offset`).
    pub offset: Option<(f32, f32)>,
    /// The plan's casters for this view; `None` draws every caster.
    pub casters: Option<&'a [u32]>,
    /// The matrix whose depth is stored, when not `view_proj` (trapezoidal maps: drawn with
    /// the depth program's `WARP_DEPTH` variant, which offsets in the shader).
    pub depth_view_proj: Option<Mat4>,
    /// What the map stores, and for ID and priority buffers their per-triangle table.
    pub buffer: MapBuffer,
    pub table: Option<glow::Texture>,
    pub light_position: glam::Vec3,
    /// What `view_proj` and `depth_view_proj` take positions relative to (zero: world
    /// positions; `shadow_map.caster_space`).
    pub origin: glam::Vec3,
    /// Draw over what the map holds (a copy of its static map) instead of clearing it.
    pub over: bool,
}

/// The smallest depth step of a map's format: glPolygonOffset's unit `r`.
fn depth_resolution(bits: DepthBits) -> f32 {
    match bits {
        DepthBits::D16 => 1.0 / 65536.0,
        DepthBits::D24 => 1.0 / 16_777_216.0,
        // A float's step near 1, where a map's depths gather.
        DepthBits::D32f => 1.0 / 8_388_608.0,
    }
}

/// Draws the view's casters into `target`.
pub fn render(ctx: &PassContext, program: &Program, view: &MapView, target: &DepthTarget) {
    begin(ctx, view, target);
    let gl = ctx.gl;
    let o = &ctx.settings.shadow_map;
    program.bind(gl);
    program.set_mat4(gl, "u_view_proj", &view.view_proj);
    program.set_vec3(gl, "u_origin", view.origin);
    program.set_i32(gl, "u_texture", 0);
    if let Some(depth) = view.depth_view_proj {
        program.set_mat4(gl, "u_depth_view_proj", &depth);
        let (factor, units) = match (view.offset, o.offset_pass) {
            (Some(f), OffsetPass::ShadowMap | OffsetPass::Both) => f,
            _ => (0.0, 0.0),
        };
        let r = depth_resolution(o.depth_bits);
        program.set_vec2(gl, "u_offset", glam::Vec2::new(factor, units * r));
        // SAFETY: the offset is the shader's here.
        unsafe { gl.disable(glow::POLYGON_OFFSET_FILL) };
    }
    if let Some(table) = view.table {
        bind_table(gl, program, table);
        program.set_vec3(gl, "u_light_pos", view.light_position);
        program.set_u32(gl, "u_id_mask", id_mask(o.id_bits));
    }
    draw_items_with(
        ctx,
        program,
        &caster_items(ctx, view),
        caster_cull(o.cull),
        o.alpha_casters == AlphaCasters::Test,
        |_| {},
    );
    end(gl, view, target);
}

/// Binds `target` and sets the depth pass's state: viewport, depth only, cleared (unless the
/// view draws over the map), the offset.
pub fn begin(ctx: &PassContext, view: &MapView, target: &DepthTarget) {
    let gl = ctx.gl;
    let o = &ctx.settings.shadow_map;
    let (size, cube_face) = (view.size, view.cube_face);
    // SAFETY: fixed-function state and a depth attachment of our own texture.
    unsafe {
        match target {
            DepthTarget::Copy { frame, .. } => {
                gl.bind_framebuffer(glow::FRAMEBUFFER, Some(frame.fbo));
            }
            DepthTarget::Fbo {
                fbo,
                texture,
                colour,
            } => {
                gl.bind_framebuffer(glow::FRAMEBUFFER, Some(*fbo));
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    image_target(cube_face),
                    Some(*texture),
                    0,
                );
                if let Some(ids) = colour {
                    gl.framebuffer_texture_2d(
                        glow::FRAMEBUFFER,
                        glow::COLOR_ATTACHMENT0,
                        glow::TEXTURE_2D,
                        Some(*ids),
                        0,
                    );
                    gl.draw_buffers(&[glow::COLOR_ATTACHMENT0]);
                    gl.read_buffer(glow::COLOR_ATTACHMENT0);
                } else {
                    // glDrawBuffers: ES 3.0 has no glDrawBuffer.
                    gl.draw_buffers(&[glow::NONE]);
                    gl.read_buffer(glow::NONE);
                }
            }
        }
        gl.viewport(0, 0, size as i32, size as i32);
        gl.depth_mask(true);
        gl.clear_depth(1.0);
        if matches!(
            target,
            DepthTarget::Fbo {
                colour: Some(_),
                ..
            }
        ) {
            // No ID yet: all ones (an ID no triangle has below 2^32 - 1).
            gl.color_mask(true, true, true, true);
            gl.clear_color(1.0, 1.0, 1.0, 1.0);
            gl.clear(glow::DEPTH_BUFFER_BIT | glow::COLOR_BUFFER_BIT);
        } else {
            gl.color_mask(false, false, false, false);
            if !view.over {
                gl.clear(glow::DEPTH_BUFFER_BIT);
            }
        }
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::LESS);
        gl.disable(glow::BLEND);
        gl.disable(glow::STENCIL_TEST);
        // ID and priority buffers write no depth the offset could move: no bias.
        match (view.offset, o.offset_pass) {
            _ if view.buffer != MapBuffer::Depth => gl.disable(glow::POLYGON_OFFSET_FILL),
            (Some((factor, units)), OffsetPass::ShadowMap | OffsetPass::Both) => {
                gl.enable(glow::POLYGON_OFFSET_FILL);
                gl.polygon_offset(factor, units);
            }
            _ => gl.disable(glow::POLYGON_OFFSET_FILL),
        }
    }
}

/// The plan's casters for this view, or every caster.
pub fn caster_items(ctx: &PassContext, view: &MapView) -> Vec<crate::gl::upload::DrawItem> {
    let merge = Merge::Depth {
        alpha_test: ctx.settings.shadow_map.alpha_casters == AlphaCasters::Test,
    };
    match view.casters {
        Some(list) => ctx.gpu.draw_list_of(ctx.scene, merge, list),
        None => ctx.gpu.draw_list(ctx.scene, merge, |s| ctx.plan.casters[s]),
    }
}

/// A material's culling in the depth pass: back faces instead of front faces (thesis 2.2.8)
/// flips every one-sided material's.
pub fn caster_cull(faces: CasterFaces) -> impl Fn(Cull) -> Cull {
    move |c: Cull| match (faces, c) {
        (CasterFaces::Front, c) => c,
        (CasterFaces::Back, Cull::Back) => Cull::Front,
        (CasterFaces::Back, Cull::Front) => Cull::Back,
        (CasterFaces::Back, Cull::None) => Cull::None,
        (CasterFaces::Both, _) => Cull::None,
    }
}

/// Resets the state `begin` set and detaches the texture from the depth framebuffer.
pub fn end(gl: &glow::Context, view: &MapView, target: &DepthTarget) {
    // SAFETY: state reset for what follows; the copy reads our own framebuffer.
    unsafe {
        gl.disable(glow::POLYGON_OFFSET_FILL);
        gl.color_mask(true, true, true, true);
        if let DepthTarget::Fbo { colour, .. } = target {
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                image_target(view.cube_face),
                None,
                0,
            );
            if colour.is_some() {
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::COLOR_ATTACHMENT0,
                    glow::TEXTURE_2D,
                    None,
                    0,
                );
            }
        }
    }
}

/// glCopyTexSubImage2D of the frame's depth buffer (`size`² at the origin) into the map.
pub fn copy_depth(
    gl: &glow::Context,
    frame: &Framebuffer,
    texture: glow::Texture,
    size: u32,
    cube_face: Option<usize>,
) {
    let bind_target = if cube_face.is_some() {
        glow::TEXTURE_CUBE_MAP
    } else {
        glow::TEXTURE_2D
    };
    // SAFETY: the frame's depth holds the light's view; the texture has size² storage.
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(frame.fbo));
        gl.bind_texture(bind_target, Some(texture));
        gl.copy_tex_sub_image_2d(
            image_target(cube_face),
            0,
            0,
            0,
            0,
            0,
            size as i32,
            size as i32,
        );
        gl.bind_texture(bind_target, None);
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    }
}

/// Whether the options draw maps into the frame's own depth buffer.
pub fn copies_from_frame(o: &ShadowMapOptions) -> bool {
    o.depth_source == DepthSource::Copy
}
