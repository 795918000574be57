//! Scratch objects for the capability probes: their programs, vertices, and a square texture
//! attached to a framebuffer, which the probes draw into, read or time, and delete.

use glow::HasContext;

/// Allocates `tex` as a `side`×`side` texture of `internal_format` (uploaded from nothing as
/// `format`/`ty`), attaches it to `fbo` at `attachment` and leaves both bound.
///
/// # Safety
/// `tex` and `fbo` are live objects of `gl`'s current context.
pub(super) unsafe fn bind_target(
    gl: &glow::Context,
    (tex, fbo): (glow::Texture, glow::Framebuffer),
    side: i32,
    (internal_format, format, ty): (u32, u32, u32),
    attachment: u32,
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
            attachment,
            glow::TEXTURE_2D,
            Some(tex),
            0,
        );
    }
}

/// A drawing probe's objects: its program, a vertex array of positions in attribute 0, and a
/// texture and framebuffer to draw into.
pub(super) struct ScratchDraw {
    pub program: glow::Program,
    tex: glow::Texture,
    fbo: glow::Framebuffer,
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    side: i32,
}

/// What a drawing probe draws into: a square texture `side` pixels wide, stored as
/// (internal format, format, type), attached at `attachment`.
pub(super) struct TargetSpec {
    pub side: i32,
    pub storage: (u32, u32, u32),
    pub attachment: u32,
}

impl ScratchDraw {
    /// Links `program` from its (vertex, fragment) sources, uploads `positions` (`components`
    /// floats a vertex) and binds them, and binds a `target` texture in a framebuffer; the
    /// program stays unbound. Where something cannot be made, says what and leaves nothing.
    ///
    /// # Safety
    /// `gl`'s context is current.
    pub unsafe fn open(
        gl: &glow::Context,
        (vertex, fragment): (&str, &str),
        (positions, components): (&[f32], i32),
        target: &TargetSpec,
    ) -> Result<ScratchDraw, &'static str> {
        // SAFETY: the caller's promise; what is created here is deleted by `delete`.
        unsafe {
            let program = link(gl, vertex, fragment).ok_or("its program did not link")?;
            let created = (
                gl.create_vertex_array(),
                gl.create_buffer(),
                gl.create_texture(),
                gl.create_framebuffer(),
            );
            let (Ok(vao), Ok(vbo), Ok(tex), Ok(fbo)) = created else {
                // Delete what was made before the one that failed.
                let (vao, vbo, tex, fbo) = created;
                if let Ok(v) = vao {
                    gl.delete_vertex_array(v);
                }
                if let Ok(b) = vbo {
                    gl.delete_buffer(b);
                }
                if let Ok(t) = tex {
                    gl.delete_texture(t);
                }
                if let Ok(f) = fbo {
                    gl.delete_framebuffer(f);
                }
                gl.delete_program(program);
                return Err("scratch objects unavailable");
            };
            let bytes: Vec<u8> = positions.iter().flat_map(|c| c.to_le_bytes()).collect();
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.buffer_data_u8_slice(glow::ARRAY_BUFFER, &bytes, glow::STATIC_DRAW);
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, components, glow::FLOAT, false, 4 * components, 0);
            bind_target(
                gl,
                (tex, fbo),
                target.side,
                target.storage,
                target.attachment,
            );
            gl.viewport(0, 0, target.side, target.side);
            Ok(ScratchDraw {
                program,
                tex,
                fbo,
                vao,
                vbo,
                side: target.side,
            })
        }
    }

    /// The target's pixels as floats, `per_pixel` of them each in `format`, bottom row first.
    pub fn read_floats(&self, gl: &glow::Context, format: u32, per_pixel: usize) -> Vec<f32> {
        let side = self.side as u32;
        super::target::read_pixels_bottom_up(
            gl,
            Some(self.fbo),
            None,
            (side, side),
            (format, glow::FLOAT),
            per_pixel,
        )
    }

    /// Resets the bindings these replaced to 0 and deletes them.
    ///
    /// # Safety
    /// `gl` is the context they were created in, current.
    pub unsafe fn delete(self, gl: &glow::Context) {
        // SAFETY: the caller's promise.
        unsafe {
            gl.use_program(None);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            gl.bind_vertex_array(None);
            gl.delete_framebuffer(self.fbo);
            gl.delete_texture(self.tex);
            gl.delete_buffer(self.vbo);
            gl.delete_vertex_array(self.vao);
            gl.delete_program(self.program);
        }
    }
}

/// A probe's program from `vertex` and `fragment` sources, or None where it does not compile
/// or link.
///
/// # Safety
/// `gl`'s context is current.
unsafe fn link(gl: &glow::Context, vertex: &str, fragment: &str) -> Option<glow::Program> {
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
