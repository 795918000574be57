//! The unlit world with legacy state (paper 2.4): texture × lightmap through two texture units
//! (ARB_multitexture, ARB_texture_env_combine with RGB_SCALE for Quake 3's overbright), vertex
//! colours through the colour array, a constant level through glColor; glAlphaFunc for
//! alpha-tested materials.

use super::FixedFunction;
use crate::gl::legacy::{self, Legacy};
use crate::gl::passes::PassContext;
use crate::gl::passes::state::DrawState;
use crate::scene::{BakedLight, SurfaceOwner};
use glow::HasContext;

/// Unit 1 multiplies the previous result by its texture and by `scale`.
///
/// SAFETY (caller): the legacy context is current and unit 1 is active.
unsafe fn modulate_scaled(l: &Legacy, scale: f32) {
    // SAFETY: see the caller's contract.
    unsafe {
        l.env(legacy::TEXTURE_ENV_MODE, legacy::COMBINE);
        l.env(legacy::COMBINE_RGB, legacy::MODULATE);
        l.env(legacy::SOURCE0_RGB, legacy::PREVIOUS);
        l.env(legacy::OPERAND0_RGB, legacy::SRC_COLOR);
        l.env(legacy::SOURCE1_RGB, legacy::TEXTURE);
        l.env(legacy::OPERAND1_RGB, legacy::SRC_COLOR);
        l.env(legacy::COMBINE_ALPHA, legacy::REPLACE);
        l.env(legacy::SOURCE0_ALPHA, legacy::PREVIOUS);
        l.env(legacy::OPERAND0_ALPHA, legacy::SRC_ALPHA);
        (l.tex_env_fv)(legacy::TEXTURE_ENV, legacy::RGB_SCALE, [scale].as_ptr());
    }
}

pub fn draw(ctx: &PassContext, ff: &FixedFunction) {
    let gl = ctx.gl;
    let l = &ff.legacy;
    DrawState::OPAQUE.apply(gl);
    let scale = (1u32 << ctx.settings.overbright_bits) as f32;
    // SAFETY: fixed-function state on the bound framebuffer.
    unsafe {
        gl.use_program(None);
        gl.stencil_mask(0xff);
        gl.clear_color(0.0, 0.0, 0.0, 1.0);
        gl.clear_depth_f64(1.0);
        gl.clear_stencil(0);
        gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
        l.load_matrix(legacy::PROJECTION, &ctx.plan.camera.projection);
        gl.active_texture(glow::TEXTURE0);
        gl.enable(glow::TEXTURE_2D);
        l.env(legacy::TEXTURE_ENV_MODE, legacy::MODULATE);
    }
    ff.clip_planes(gl, None);
    ff.bind_scene(ctx);
    let items = ctx
        .gpu
        .draw_list(ctx.scene, crate::gl::upload::Merge::ByLightmap, |s| {
            ctx.plan.visible[s]
        });
    let lighting = &ctx.settings.lighting;
    let view = ctx.plan.camera.view;
    ff.draw_items(
        ctx,
        &view,
        &items,
        |c| c,
        |item| {
            let material = &ctx.scene.materials[item.material];
            ff.material_alpha_test(gl, material.alpha_test);
            let level = match item.owner {
                SurfaceOwner::World => lighting.ambient,
                SurfaceOwner::Model(_) => lighting.model_ambient,
            };
            let lightmap = item
                .lightmap
                .and_then(|lm| ctx.gpu.images().lightmaps.get(lm).copied());
            let baked = match (item.baked, lightmap) {
                _ if !lighting.baked => None,
                (BakedLight::Lightmap, Some(lm)) => Some(Some(lm)),
                (BakedLight::Vertex, _) => Some(None),
                _ => None,
            };
            // SAFETY: fixed-function state; textures of our own.
            unsafe {
                // Unit 0's scale is only raised for vertex-lit items.
                gl.active_texture(glow::TEXTURE0);
                (l.tex_env_fv)(legacy::TEXTURE_ENV, legacy::RGB_SCALE, [1.0].as_ptr());
                match baked {
                    // Lightmapped: texture × lightmap × 2^overbright on unit 1.
                    Some(Some(lm)) => {
                        (l.disable_client_state)(legacy::COLOR_ARRAY);
                        (l.color_4f)(1.0, 1.0, 1.0, 1.0);
                        gl.active_texture(glow::TEXTURE1);
                        gl.enable(glow::TEXTURE_2D);
                        gl.bind_texture(glow::TEXTURE_2D, Some(lm));
                        modulate_scaled(l, scale);
                    }
                    // Vertex-lit: texture × vertex colour × 2^overbright, on unit 0.
                    Some(None) => {
                        (l.enable_client_state)(legacy::COLOR_ARRAY);
                        gl.active_texture(glow::TEXTURE1);
                        gl.disable(glow::TEXTURE_2D);
                        gl.active_texture(glow::TEXTURE0);
                        l.env(legacy::TEXTURE_ENV_MODE, legacy::COMBINE);
                        l.env(legacy::COMBINE_RGB, legacy::MODULATE);
                        l.env(legacy::SOURCE0_RGB, legacy::TEXTURE);
                        l.env(legacy::OPERAND0_RGB, legacy::SRC_COLOR);
                        l.env(legacy::SOURCE1_RGB, legacy::PRIMARY_COLOR);
                        l.env(legacy::OPERAND1_RGB, legacy::SRC_COLOR);
                        l.env(legacy::COMBINE_ALPHA, legacy::REPLACE);
                        l.env(legacy::SOURCE0_ALPHA, legacy::TEXTURE);
                        l.env(legacy::OPERAND0_ALPHA, legacy::SRC_ALPHA);
                        (l.tex_env_fv)(legacy::TEXTURE_ENV, legacy::RGB_SCALE, [scale].as_ptr());
                    }
                    // A constant level: texture × glColor.
                    None => {
                        (l.disable_client_state)(legacy::COLOR_ARRAY);
                        (l.color_4f)(level, level, level, 1.0);
                        gl.active_texture(glow::TEXTURE1);
                        gl.disable(glow::TEXTURE_2D);
                        gl.active_texture(glow::TEXTURE0);
                        l.env(legacy::TEXTURE_ENV_MODE, legacy::MODULATE);
                    }
                }
                gl.active_texture(glow::TEXTURE0);
                if baked != Some(None) {
                    l.env(legacy::TEXTURE_ENV_MODE, legacy::MODULATE);
                }
            }
        },
    );
    ff.unbind(gl);
    ff.reset(gl);
}
