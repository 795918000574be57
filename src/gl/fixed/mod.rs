//! The paper's passes drawn with the legacy calls themselves (`gl.pipeline = fixed_function`),
//! on a compatibility-profile context: no program is bound while they draw.
//!
//! They execute the same plan as the shader passes (`gl::passes`) and leave the same buffers
//! behind: the depth of the unlit world, each light's stencil counts or shadow maps. Choices
//! the legacy calls cannot express were replaced before planning (`plan::fixed_function`).
//! Matrices are loaded as the paper loads them: the camera's projection, the camera's view
//! times the owner's model matrix as the modelview, so eye-linear texgen planes and clip
//! planes given in world space under the camera's view land in eye space.

pub mod base;
pub mod lit;
pub mod shadow_map;
pub mod stencil;

use super::legacy::{self, Legacy};
use super::passes::{PassContext, apply_cull};
use super::upload::DrawItem;
use crate::scene::{AlphaFunc, Vertex};
use crate::shadow::volume::group_transform;
use glam::Mat4;
use glow::HasContext;
use std::rc::Rc;

/// The legacy entry points and the vertex array the client arrays are recorded in.
pub struct FixedFunction {
    pub legacy: Rc<Legacy>,
    vao: glow::VertexArray,
}

impl FixedFunction {
    pub fn new(gl: &glow::Context, legacy: Rc<Legacy>) -> Result<FixedFunction, String> {
        // SAFETY: a vertex array of our own.
        let vao = unsafe { gl.create_vertex_array()? };
        Ok(FixedFunction { legacy, vao })
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: our own vertex array, deleted once.
        unsafe { gl.delete_vertex_array(self.vao) };
    }

    /// Points the client arrays at the scene's vertex buffer: position, normal, colour, the
    /// surface texture's coordinates on unit 0 and the lightmap's on unit 1.
    pub fn bind_scene(&self, ctx: &PassContext) {
        let (gl, l) = (ctx.gl, &self.legacy);
        let (vbo, ibo) = ctx.gpu.buffers();
        let stride = std::mem::size_of::<Vertex>() as i32;
        let at = |offset: usize| offset as *const std::ffi::c_void;
        // SAFETY: the offsets lie inside `Vertex` (position 0, normal 12, uv 24, lightmap uv
        // 32, colour 40); the buffers are the scene's.
        unsafe {
            gl.bind_vertex_array(Some(self.vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(ibo));
            (l.enable_client_state)(legacy::VERTEX_ARRAY);
            (l.vertex_pointer)(3, glow::FLOAT, stride, at(0));
            (l.enable_client_state)(legacy::NORMAL_ARRAY);
            (l.normal_pointer)(glow::FLOAT, stride, at(12));
            (l.color_pointer)(4, glow::UNSIGNED_BYTE, stride, at(40));
            for (unit, offset) in [(glow::TEXTURE0, 24), (glow::TEXTURE1, 32)] {
                (l.client_active_texture)(unit);
                (l.enable_client_state)(legacy::TEXTURE_COORD_ARRAY);
                (l.tex_coord_pointer)(2, glow::FLOAT, stride, at(offset));
            }
            (l.client_active_texture)(glow::TEXTURE0);
        }
    }

    /// Points the vertex array at a light's homogeneous volume vertices (w = 0 at infinity).
    pub fn bind_volumes(&self, gl: &glow::Context, vbo: glow::Buffer, ebo: glow::Buffer) {
        let l = &self.legacy;
        // SAFETY: the light's own buffers of vec4 positions.
        unsafe {
            gl.bind_vertex_array(Some(self.vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(ebo));
            for unit in [glow::TEXTURE0, glow::TEXTURE1] {
                (l.client_active_texture)(unit);
                (l.disable_client_state)(legacy::TEXTURE_COORD_ARRAY);
            }
            (l.client_active_texture)(glow::TEXTURE0);
            (l.disable_client_state)(legacy::NORMAL_ARRAY);
            (l.disable_client_state)(legacy::COLOR_ARRAY);
            (l.enable_client_state)(legacy::VERTEX_ARRAY);
            (l.vertex_pointer)(4, glow::FLOAT, 16, std::ptr::null());
        }
    }

    /// Unbinds the vertex array (its buffers stay recorded in it).
    pub fn unbind(&self, gl: &glow::Context) {
        // SAFETY: binding state only.
        unsafe { gl.bind_vertex_array(None) };
    }

    /// Switches off every legacy state the passes enable, so that the next pass (or the shader
    /// passes that measure the frame) start from GL's defaults.
    pub fn reset(&self, gl: &glow::Context) {
        let l = &self.legacy;
        // SAFETY: state of the current compatibility context only.
        unsafe {
            gl.disable(legacy::ALPHA_TEST);
            gl.disable(legacy::LIGHTING);
            gl.disable(legacy::NORMALIZE);
            for i in 0..6 {
                gl.disable(legacy::CLIP_PLANE0 + i);
            }
            for unit in [glow::TEXTURE1, glow::TEXTURE0] {
                gl.active_texture(unit);
                gl.disable(glow::TEXTURE_2D);
                for generate in [
                    legacy::TEXTURE_GEN_S,
                    legacy::TEXTURE_GEN_T,
                    legacy::TEXTURE_GEN_R,
                    legacy::TEXTURE_GEN_Q,
                ] {
                    gl.disable(generate);
                }
                l.env(legacy::TEXTURE_ENV_MODE, legacy::MODULATE);
                // The combiner's scale outlives its mode: a lightmap's overbright 2 would
                // double the mask's values in a later pass.
                (l.tex_env_fv)(legacy::TEXTURE_ENV, legacy::RGB_SCALE, [1.0].as_ptr());
            }
            (l.color_4f)(1.0, 1.0, 1.0, 1.0);
            l.load_matrix(legacy::PROJECTION, &Mat4::IDENTITY);
            l.load_matrix(legacy::MODELVIEW, &Mat4::IDENTITY);
        }
    }

    /// Enables the four user clip planes every camera pass runs with: `planes` (world space,
    /// loaded under the camera's view, which must be on the modelview stack), or planes that
    /// keep everything. Mesa's fixed-function vertex stage computes the position another way
    /// when user clip planes are on, so a pass with planes and one without would not lay
    /// fragments at equal depths (stripes where the lit pass loses against the unlit one); with
    /// planes always on, every camera pass runs the same transform.
    pub fn clip_planes(&self, gl: &glow::Context, planes: Option<&[glam::Vec4]>) {
        const KEEP_ALL: glam::Vec4 = glam::Vec4::W;
        for i in 0..4 {
            let plane = planes.map_or(KEEP_ALL, |p| p[i]).as_dvec4().to_array();
            // SAFETY: fixed-function state; four doubles per plane.
            unsafe {
                (self.legacy.clip_plane)(legacy::CLIP_PLANE0 + i as u32, plane.as_ptr());
                gl.enable(legacy::CLIP_PLANE0 + i as u32);
            }
        }
    }

    /// The material's alpha test as glAlphaFunc (the fragment's alpha is the texture's), or
    /// the test switched off.
    pub fn material_alpha_test(&self, gl: &glow::Context, test: Option<AlphaFunc>) {
        // 128/255 exactly: the 8-bit texel 128 passes GEQUAL and 127 fails, as
        // `AlphaFunc::passes` decides on the CPU.
        const HALF: f32 = 128.0 / 255.0;
        // SAFETY: fixed-function state.
        unsafe {
            match test {
                None => gl.disable(legacy::ALPHA_TEST),
                Some(f) => {
                    gl.enable(legacy::ALPHA_TEST);
                    let (func, reference) = match f {
                        AlphaFunc::Gt0 => (glow::GREATER, 0.0),
                        AlphaFunc::Lt128 => (glow::LESS, HALF),
                        AlphaFunc::Ge128 => (glow::GEQUAL, HALF),
                    };
                    (self.legacy.alpha_func)(func, reference);
                }
            }
        }
    }

    /// Draws `items` of the bound scene arrays: per owner the modelview `view` × model, per
    /// item the material's texture on unit 0 and its culling (through `cull`); `extra` sets
    /// anything else per item.
    pub fn draw_items(
        &self,
        ctx: &PassContext,
        view: &Mat4,
        items: &[DrawItem],
        cull: impl Fn(crate::scene::Cull) -> crate::scene::Cull,
        mut extra: impl FnMut(&DrawItem),
    ) {
        let gl = ctx.gl;
        let mut last_owner = None;
        // SAFETY: the scene's buffers are bound by `bind_scene`; ranges lie inside them.
        unsafe {
            for item in items {
                if last_owner != Some(item.owner) {
                    let model = group_transform(ctx.scene, item.owner);
                    self.legacy.load_matrix(legacy::MODELVIEW, &(*view * model));
                    last_owner = Some(item.owner);
                }
                let material = &ctx.scene.materials[item.material];
                gl.active_texture(glow::TEXTURE0);
                gl.bind_texture(
                    glow::TEXTURE_2D,
                    Some(ctx.gpu.texture_for(ctx.scene, item.material)),
                );
                apply_cull(gl, cull(material.cull));
                extra(item);
                gl.draw_elements(
                    glow::TRIANGLES,
                    item.index_count as i32,
                    glow::UNSIGNED_INT,
                    (item.first_index as usize * 4) as i32,
                );
                super::passes::count_surface_draw();
            }
        }
    }
}
