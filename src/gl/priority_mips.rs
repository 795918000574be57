//! The mip chain of a priority buffer (`shadow_map.priority_mipmap`, Forsyth: priority buffers
//! "can be filtered and mipmapped"): each level drawn from the one below by a shader that keeps
//! a median of four texels (`shaders/priority_mips.frag` says why not their mean). The
//! lit pass then reads the level of the fragment's footprint, so a map much finer than the
//! screen decides by about half of the texels a pixel covers instead of by one of them.

use super::program::Program;
use glow::HasContext;

/// The side of level `level` of a map of side `size`.
pub fn level_size(size: u32, level: u32) -> u32 {
    (size >> level).max(1)
}

/// Draws levels 1.. of `texture` (a 2D depth texture of side `size` with `levels` levels,
/// level 0 drawn) through `fbo`. Leaves `fbo` bound with no attachment, the texture's
/// levels 0..levels open to sampling and its compare mode off (the caller configures it).
pub fn build(
    gl: &glow::Context,
    program: &Program,
    empty_vao: glow::VertexArray,
    fbo: glow::Framebuffer,
    (texture, size, levels): (glow::Texture, u32, u32),
) {
    // SAFETY: our own framebuffer and texture. While level L is drawn, the texture's base and
    // max level are L - 1, so the level sampled is never the one attached (no feedback loop).
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.draw_buffers(&[glow::NONE]);
        gl.read_buffer(glow::NONE);
        gl.disable(glow::STENCIL_TEST);
        gl.disable(glow::SCISSOR_TEST);
        gl.disable(glow::BLEND);
        gl.disable(glow::CULL_FACE);
        gl.disable(glow::POLYGON_OFFSET_FILL);
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::ALWAYS);
        gl.depth_mask(true);
        gl.active_texture(glow::TEXTURE0);
        gl.bind_texture(glow::TEXTURE_2D, Some(texture));
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_COMPARE_MODE,
            glow::NONE as i32,
        );
        for p in [glow::TEXTURE_MIN_FILTER, glow::TEXTURE_MAG_FILTER] {
            gl.tex_parameter_i32(glow::TEXTURE_2D, p, glow::NEAREST as i32);
        }
        program.bind(gl);
        program.set_i32(gl, "u_below", 0);
        gl.bind_vertex_array(Some(empty_vao));
        for level in 1..levels {
            let below = level_size(size, level - 1);
            let side = level_size(size, level);
            let l = (level - 1) as i32;
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_BASE_LEVEL, l);
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_MAX_LEVEL, l);
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(texture),
                level as i32,
            );
            gl.viewport(0, 0, side as i32, side as i32);
            program.set_ivec2(gl, "u_below_size", [below as i32, below as i32]);
            program.set_i32(gl, "u_level", level as i32);
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
        }
        gl.bind_vertex_array(None);
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::DEPTH_ATTACHMENT,
            glow::TEXTURE_2D,
            None,
            0,
        );
        gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_BASE_LEVEL, 0);
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_MAX_LEVEL,
            levels.saturating_sub(1) as i32,
        );
        gl.bind_texture(glow::TEXTURE_2D, None);
        gl.depth_func(glow::LESS);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_reach_one_texel() {
        let levels = |size| {
            crate::plan::map_memory::view_levels(
                crate::options::MapBuffer::Priority,
                true,
                false,
                size,
            )
        };
        assert_eq!(levels(1), 1);
        assert_eq!(levels(2048), 12);
        assert_eq!(levels(876), 10);
        assert_eq!(level_size(876, 9), 1);
        assert_eq!(level_size(876, 3), 109);
    }
}
