//! Scratch render targets for the capability probes: a square colour texture attached to a
//! framebuffer, which the probes draw into, read or time, and delete.

use glow::HasContext;

/// Allocates `tex` as a `side`×`side` colour texture of `internal_format` (uploaded from
/// nothing as `format`/`ty`), attaches it to `fbo` as colour attachment 0 and leaves both bound.
///
/// # Safety
/// `tex` and `fbo` are live objects of `gl`'s current context.
pub(super) unsafe fn bind_colour_target(
    gl: &glow::Context,
    tex: glow::Texture,
    fbo: glow::Framebuffer,
    side: i32,
    (internal_format, format, ty): (u32, u32, u32),
) {
    // SAFETY: the caller passes live objects of the current context.
    unsafe {
        gl.bind_texture(glow::TEXTURE_2D, Some(tex));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            internal_format as i32,
            side,
            side,
            0,
            format,
            ty,
            glow::PixelUnpackData::Slice(None),
        );
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT0,
            glow::TEXTURE_2D,
            Some(tex),
            0,
        );
    }
}
