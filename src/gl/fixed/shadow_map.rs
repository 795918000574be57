//! The light's view into its depth map with legacy state (paper 3.1): the light's matrices on
//! the matrix stacks, glPolygonOffset, alpha-tested casters through glAlphaFunc on the
//! texture's alpha; the frame's depth is then copied with glCopyTexSubImage2D as on the shader
//! path (`passes::shadow_map::copy_depth`).

use super::FixedFunction;
use crate::gl::legacy;
use crate::gl::passes::PassContext;
use crate::gl::passes::shadow_map::{DepthTarget, MapView, begin, caster_cull, caster_items, end};
use crate::options::AlphaCasters;
use glam::Mat4;
use glow::HasContext;

/// Draws the view's casters into `target`.
pub fn render(ctx: &PassContext, ff: &FixedFunction, view: &MapView, target: &DepthTarget) {
    begin(ctx, view, target);
    let gl = ctx.gl;
    let o = &ctx.settings.shadow_map;
    let alpha_casters = o.alpha_casters == AlphaCasters::Test;
    // SAFETY: fixed-function state; the light's view and projection as one projection.
    unsafe {
        gl.use_program(None);
        ff.legacy.load_matrix(legacy::PROJECTION, &view.view_proj);
        gl.active_texture(glow::TEXTURE0);
        // The texture only feeds the alpha test.
        if alpha_casters {
            gl.enable(glow::TEXTURE_2D);
            ff.legacy.env(legacy::TEXTURE_ENV_MODE, legacy::MODULATE);
        }
    }
    ff.bind_scene(ctx);
    let materials = &ctx.scene.materials;
    ff.draw_items(
        ctx,
        &Mat4::IDENTITY,
        &caster_items(ctx, view),
        caster_cull(o.cull),
        |item| {
            let test = materials[item.material]
                .alpha_test
                .filter(|_| alpha_casters);
            ff.material_alpha_test(gl, test);
        },
    );
    ff.unbind(gl);
    ff.reset(gl);
    end(gl, view, target);
}
