//! Scratch objects for the capability probes: their programs, and a square colour texture
//! attached to a framebuffer, which the probes draw into, read or time, and delete.

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

/// A probe's program from `vertex` and `fragment` sources, or None where it does not compile
/// or link.
///
/// # Safety
/// `gl`'s context is current.
pub(super) unsafe fn link(
    gl: &glow::Context,
    vertex: &str,
    fragment: &str,
) -> Option<glow::Program> {
    // SAFETY: the caller's promise; shaders are deleted once linked (or not).
    unsafe {
        let program = gl.create_program().ok()?;
        let mut shaders = Vec::new();
        for (kind, source) in [
            (glow::VERTEX_SHADER, vertex),
            (glow::FRAGMENT_SHADER, fragment),
        ] {
            let Ok(shader) = gl.create_shader(kind) else {
                gl.delete_program(program);
                return None;
            };
            gl.shader_source(shader, source);
            gl.compile_shader(shader);
            gl.attach_shader(program, shader);
            shaders.push(shader);
        }
        gl.link_program(program);
        let linked = gl.get_program_link_status(program);
        for s in shaders {
            gl.detach_shader(program, s);
            gl.delete_shader(s);
        }
        if linked {
            Some(program)
        } else {
            gl.delete_program(program);
            None
        }
    }
}
