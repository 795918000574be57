//! Our own framebuffers: every path (EGL, OSMesa, window) renders into one of these, never into the
//! window system's buffer, so results are identical everywhere and can be read back.

use glow::HasContext;

/// The frame's "screen": RGBA8 colour plus a packed depth/stencil texture (24-bit depth, 8-bit
/// stencil, as the paper's card had; 32-bit float depth on request).
///
/// The frame occupies `width`×`height` at the origin; the storage may be larger (`alloc`), so that
/// the paper's shadow maps, drawn into the screen's depth buffer before being copied, fit even when
/// they are bigger than the frame.
pub struct Framebuffer {
    pub fbo: glow::Framebuffer,
    pub color: glow::Texture,
    pub depth_stencil: glow::Texture,
    pub width: u32,
    pub height: u32,
    pub alloc: (u32, u32),
    pub float_depth: bool,
}

impl Framebuffer {
    pub fn new(gl: &glow::Context, width: u32, height: u32) -> Result<Framebuffer, String> {
        Framebuffer::with_storage(gl, width, height, (width, height), false)
    }

    /// A `width`×`height` frame in storage of at least `alloc`, with 32F depth if asked.
    pub fn with_storage(
        gl: &glow::Context,
        width: u32,
        height: u32,
        alloc: (u32, u32),
        float_depth: bool,
    ) -> Result<Framebuffer, String> {
        let alloc = (alloc.0.max(width), alloc.1.max(height));
        let (aw, ah) = alloc;
        // SAFETY: objects are created here and owned by the returned value; bindings reset to 0.
        unsafe {
            let color = gl.create_texture()?;
            gl.bind_texture(glow::TEXTURE_2D, Some(color));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA8 as i32,
                aw as i32,
                ah as i32,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            set_nearest_clamp(gl);
            let depth_stencil = gl.create_texture()?;
            gl.bind_texture(glow::TEXTURE_2D, Some(depth_stencil));
            let (internal, ty) = if float_depth {
                (
                    glow::DEPTH32F_STENCIL8,
                    glow::FLOAT_32_UNSIGNED_INT_24_8_REV,
                )
            } else {
                (glow::DEPTH24_STENCIL8, glow::UNSIGNED_INT_24_8)
            };
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                internal as i32,
                aw as i32,
                ah as i32,
                0,
                glow::DEPTH_STENCIL,
                ty,
                glow::PixelUnpackData::Slice(None),
            );
            set_nearest_clamp(gl);
            gl.bind_texture(glow::TEXTURE_2D, None);
            let fbo = gl.create_framebuffer()?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(color),
                0,
            );
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_STENCIL_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(depth_stencil),
                0,
            );
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            let fb = Framebuffer {
                fbo,
                color,
                depth_stencil,
                width,
                height,
                alloc,
                float_depth,
            };
            if status != glow::FRAMEBUFFER_COMPLETE {
                fb.delete(gl);
                return Err(format!(
                    "framebuffer {aw}x{ah} is incomplete (status 0x{status:x})"
                ));
            }
            Ok(fb)
        }
    }

    pub fn bind(&self, gl: &glow::Context) {
        // SAFETY: the framebuffer is complete.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            gl.viewport(0, 0, self.width as i32, self.height as i32);
        }
    }

    /// Bits of depth and stencil of the attachment, as GL reports them.
    pub fn depth_stencil_bits(&self, gl: &glow::Context) -> (i32, i32) {
        // SAFETY: attachment queries on our complete framebuffer.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            let d = gl.get_framebuffer_attachment_parameter_i32(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                glow::FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE,
            );
            let s = gl.get_framebuffer_attachment_parameter_i32(
                glow::FRAMEBUFFER,
                glow::STENCIL_ATTACHMENT,
                glow::FRAMEBUFFER_ATTACHMENT_STENCIL_SIZE,
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            (d, s)
        }
    }

    /// The colour attachment, top row first (GL's rows are bottom-up).
    pub fn read_rgba(&self, gl: &glow::Context) -> Vec<u8> {
        read_pixels(
            gl,
            Some(self.fbo),
            Some(glow::COLOR_ATTACHMENT0),
            (self.width, self.height),
            (glow::RGBA, glow::UNSIGNED_BYTE),
            4,
        )
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: called once by the owner.
        unsafe {
            gl.delete_framebuffer(self.fbo);
            gl.delete_texture(self.color);
            gl.delete_texture(self.depth_stencil);
        }
    }
}

/// Reads the `w`×`h` corner of `fbo` (None: the default framebuffer) from colour buffer
/// `buffer` (None: the depth or stencil the format names) into a buffer of `T`, top row first
/// (GL's rows are bottom-up). `T` must be plain data whose size is one pixel of `format`/`ty`
/// or a whole multiple of it.
pub fn read_pixels<T: Copy + Default>(
    gl: &glow::Context,
    fbo: Option<glow::Framebuffer>,
    buffer: Option<u32>,
    size: (u32, u32),
    format: (u32, u32),
    per_pixel: usize,
) -> Vec<T> {
    let mut data = read_pixels_bottom_up(gl, fbo, buffer, size, format, per_pixel);
    flip_rows(&mut data, size.0 as usize * per_pixel);
    data
}

/// [`read_pixels`] in GL's row order (bottom row first), for readers that work in window
/// coordinates.
///
/// ES 3.0 guarantees only RGBA reads of colour buffers (RGBA/UNSIGNED_BYTE for fixed point,
/// RGBA/FLOAT for float buffers): there RED and RG reads are made as RGBA and the channels
/// asked for are kept.
pub fn read_pixels_bottom_up<T: Copy + Default>(
    gl: &glow::Context,
    fbo: Option<glow::Framebuffer>,
    buffer: Option<u32>,
    size: (u32, u32),
    (format, ty): (u32, u32),
    per_pixel: usize,
) -> Vec<T> {
    let (channels, rgba) = match format {
        glow::RED => (1, glow::RGBA),
        glow::RG => (2, glow::RGBA),
        glow::RED_INTEGER => (1, glow::RGBA_INTEGER),
        _ => (0, format),
    };
    if channels == 0 || !gl.version().is_embedded {
        return read_as_asked(gl, fbo, buffer, size, (format, ty), per_pixel);
    }
    // Values of T per channel, then per RGBA pixel.
    let per_channel = per_pixel / channels;
    let rgba: Vec<T> = read_as_asked(gl, fbo, buffer, size, (rgba, ty), 4 * per_channel);
    rgba.chunks_exact(4 * per_channel)
        .flat_map(|p| p[..per_pixel].iter().copied())
        .collect()
}

fn read_as_asked<T: Copy + Default>(
    gl: &glow::Context,
    fbo: Option<glow::Framebuffer>,
    buffer: Option<u32>,
    (w, h): (u32, u32),
    (format, ty): (u32, u32),
    per_pixel: usize,
) -> Vec<T> {
    let (w, h) = (w as usize, h as usize);
    let mut data = vec![T::default(); w * h * per_pixel];
    // SAFETY: `data` holds w*h pixels of `format`/`ty` (the caller's `per_pixel` values of T
    // each, T plain data); pack alignment 1 avoids row padding.
    unsafe {
        let bytes = std::slice::from_raw_parts_mut(
            data.as_mut_ptr() as *mut u8,
            std::mem::size_of_val(data.as_slice()),
        );
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, fbo);
        if let Some(b) = buffer {
            gl.read_buffer(b);
        }
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        gl.read_pixels(
            0,
            0,
            w as i32,
            h as i32,
            format,
            ty,
            glow::PixelPackData::Slice(Some(bytes)),
        );
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    }
    super::syncs::count(super::syncs::SyncKind::ReadBack);
    data
}

/// Reverses the order of rows of `row_bytes` bytes each.
pub fn flip_rows<T: Copy>(data: &mut [T], row_len: usize) {
    if row_len == 0 {
        return;
    }
    let rows = data.len() / row_len;
    for y in 0..rows / 2 {
        let (top, bottom) = data.split_at_mut((rows - 1 - y) * row_len);
        top[y * row_len..(y + 1) * row_len].swap_with_slice(&mut bottom[..row_len]);
    }
}

/// Nearest filtering, clamped: for attachments and lookup tables.
pub fn set_nearest_clamp(gl: &glow::Context) {
    // SAFETY: parameters of the bound 2D texture.
    unsafe {
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_MIN_FILTER,
            glow::NEAREST as i32,
        );
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_MAG_FILTER,
            glow::NEAREST as i32,
        );
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_WRAP_S,
            glow::CLAMP_TO_EDGE as i32,
        );
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_WRAP_T,
            glow::CLAMP_TO_EDGE as i32,
        );
    }
}

pub(crate) fn texture_2d(
    gl: &glow::Context,
    internal: u32,
    format: u32,
    ty: u32,
    width: u32,
    height: u32,
) -> Result<glow::Texture, String> {
    // SAFETY: allocates storage for a new texture; binding reset to 0.
    unsafe {
        let t = gl.create_texture()?;
        gl.bind_texture(glow::TEXTURE_2D, Some(t));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            internal as i32,
            width as i32,
            height as i32,
            0,
            format,
            ty,
            glow::PixelUnpackData::Slice(None),
        );
        set_nearest_clamp(gl);
        gl.bind_texture(glow::TEXTURE_2D, None);
        Ok(t)
    }
}

/// A framebuffer drawing into `color` (and testing against `depth_stencil`), checked
/// complete; deleted again if it is not. Leaves framebuffer 0 bound.
pub(crate) fn framebuffer_of(
    gl: &glow::Context,
    color: glow::Texture,
    depth_stencil: Option<glow::Texture>,
    what: &str,
) -> Result<glow::Framebuffer, String> {
    // SAFETY: a framebuffer of our own with the caller's textures attached.
    unsafe {
        let fbo = gl.create_framebuffer()?;
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT0,
            glow::TEXTURE_2D,
            Some(color),
            0,
        );
        if let Some(ds) = depth_stencil {
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_STENCIL_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(ds),
                0,
            );
        }
        let ok = check_complete(gl, what);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        if ok.is_err() {
            gl.delete_framebuffer(fbo);
        }
        ok.map(|()| fbo)
    }
}

pub(crate) fn check_complete(gl: &glow::Context, what: &str) -> Result<(), String> {
    // SAFETY: status query of the bound framebuffer.
    let status = unsafe { gl.check_framebuffer_status(glow::FRAMEBUFFER) };
    if status == glow::FRAMEBUFFER_COMPLETE {
        Ok(())
    } else {
        Err(format!(
            "{what} framebuffer is incomplete (status 0x{status:x})"
        ))
    }
}

/// G-buffer for the exact reference: world position and normal as 32-bit floats, which of
/// the recording lights reach each pixel (a bit each), own depth.
/// Where the G-buffer's position, normal and reach bits are attached, in its own framebuffer
/// and in the frame's during its base pass: outputs 1–3 of `unlit.frag` (and `gather.frag`),
/// as ES wants output k at attachment k, with 0 the frame's colour.
pub const GBUFFER_OUTPUTS: [u32; 3] = [
    glow::COLOR_ATTACHMENT1,
    glow::COLOR_ATTACHMENT2,
    glow::COLOR_ATTACHMENT3,
];

pub struct GBufferTarget {
    pub fbo: glow::Framebuffer,
    position: glow::Texture,
    normal: glow::Texture,
    reach: glow::Texture,
    depth: glow::Texture,
    pub width: u32,
    pub height: u32,
}

impl GBufferTarget {
    pub fn new(gl: &glow::Context, width: u32, height: u32) -> Result<GBufferTarget, String> {
        let position = texture_2d(gl, glow::RGBA32F, glow::RGBA, glow::FLOAT, width, height)?;
        let normal = texture_2d(gl, glow::RGBA32F, glow::RGBA, glow::FLOAT, width, height)?;
        let reach = texture_2d(
            gl,
            glow::R32UI,
            glow::RED_INTEGER,
            glow::UNSIGNED_INT,
            width,
            height,
        )?;
        let depth = texture_2d(
            gl,
            glow::DEPTH_COMPONENT24,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_INT,
            width,
            height,
        )?;
        // SAFETY: attaches the textures created above to a new framebuffer.
        unsafe {
            let fbo = gl.create_framebuffer()?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::DEPTH_ATTACHMENT,
                glow::TEXTURE_2D,
                Some(depth),
                0,
            );
            let t = GBufferTarget {
                fbo,
                position,
                normal,
                reach,
                depth,
                width,
                height,
            };
            t.attach_to_bound(gl);
            // Output 0 (the frame's colour, in the unlit pass) goes nowhere here.
            gl.draw_buffers(&[
                glow::NONE,
                GBUFFER_OUTPUTS[0],
                GBUFFER_OUTPUTS[1],
                GBUFFER_OUTPUTS[2],
            ]);
            let ok = check_complete(gl, "G-buffer");
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            if let Err(e) = ok {
                t.delete(gl);
                return Err(e);
            }
            Ok(t)
        }
    }

    /// Attaches the position, normal and reach textures to the bound framebuffer at
    /// [`GBUFFER_OUTPUTS`] (the frame's, for its base pass to write them too: `unlit.frag`
    /// with `GBUFFER`), draw buffers left as they are.
    pub fn attach_to_bound(&self, gl: &glow::Context) {
        for (attachment, tex) in
            GBUFFER_OUTPUTS
                .into_iter()
                .zip([self.position, self.normal, self.reach])
        {
            // SAFETY: our own textures, on the bound framebuffer.
            unsafe {
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    attachment,
                    glow::TEXTURE_2D,
                    Some(tex),
                    0,
                );
            }
        }
    }

    /// The bound frame framebuffer writing the G-buffer as well as its colour (after
    /// `attach_to_bound`).
    pub fn draw_into_bound(gl: &glow::Context) {
        let mut buffers = vec![glow::COLOR_ATTACHMENT0];
        buffers.extend(GBUFFER_OUTPUTS);
        // SAFETY: draw buffers of the bound framebuffer, attached by `attach_to_bound`.
        unsafe { gl.draw_buffers(&buffers) };
    }

    /// The bound frame framebuffer back to its one colour output, the G-buffer's textures
    /// detached.
    pub fn detach_from_bound(gl: &glow::Context) {
        // SAFETY: the bound framebuffer's own attachments.
        unsafe {
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0]);
            for attachment in GBUFFER_OUTPUTS {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, attachment, glow::TEXTURE_2D, None, 0);
            }
        }
    }

    /// Reads the position (0) or normal (1) attachment, top row first.
    pub fn read(&self, gl: &glow::Context, attachment: usize) -> Vec<[f32; 4]> {
        read_pixels(
            gl,
            Some(self.fbo),
            Some(GBUFFER_OUTPUTS[attachment]),
            (self.width, self.height),
            (glow::RGBA, glow::FLOAT),
            1,
        )
    }

    /// Position and normal texels as read back (`unlit.frag`'s G-buffer outputs) made the
    /// G-buffer's fields: positions, normals, and each pixel's kind from the normal's w.
    pub fn fields(
        position: &[[f32; 4]],
        normal: &[[f32; 4]],
    ) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u8>) {
        (
            position.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            normal.iter().map(|n| [n[0], n[1], n[2]]).collect(),
            normal
                .iter()
                .map(|n| n[3].round().clamp(0.0, 2.0) as u8)
                .collect(),
        )
    }

    /// The reach bits, top row first.
    pub fn read_reach(&self, gl: &glow::Context) -> Vec<u32> {
        read_pixels(
            gl,
            Some(self.fbo),
            Some(GBUFFER_OUTPUTS[2]),
            (self.width, self.height),
            (glow::RED_INTEGER, glow::UNSIGNED_INT),
            1,
        )
    }

    /// The position and normal textures.
    pub fn textures(&self) -> (glow::Texture, glow::Texture) {
        (self.position, self.normal)
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: called once by the owner.
        unsafe {
            gl.delete_framebuffer(self.fbo);
            gl.delete_texture(self.position);
            gl.delete_texture(self.normal);
            gl.delete_texture(self.reach);
            gl.delete_texture(self.depth);
        }
    }
}

/// One-channel decision mask drawn over the frame's own depth and stencil.
pub struct MaskTarget {
    pub fbo: glow::Framebuffer,
    mask: glow::Texture,
    pub width: u32,
    pub height: u32,
}

impl MaskTarget {
    /// Shares `frame`'s depth/stencil texture, so a mask pass tests against the frame's depth.
    pub fn new(gl: &glow::Context, frame: &Framebuffer) -> Result<MaskTarget, String> {
        let mask = texture_2d(
            gl,
            glow::R8,
            glow::RED,
            glow::UNSIGNED_BYTE,
            frame.width,
            frame.height,
        )?;
        match framebuffer_of(gl, mask, Some(frame.depth_stencil), "mask") {
            Ok(fbo) => Ok(MaskTarget {
                fbo,
                mask,
                width: frame.width,
                height: frame.height,
            }),
            Err(e) => {
                // SAFETY: the texture made above, attached to nothing now.
                unsafe { gl.delete_texture(mask) };
                Err(e)
            }
        }
    }

    pub fn bind(&self, gl: &glow::Context) {
        // SAFETY: the framebuffer is complete.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            gl.viewport(0, 0, self.width as i32, self.height as i32);
        }
    }

    /// The mask, top row first.
    pub fn read(&self, gl: &glow::Context) -> Vec<u8> {
        read_pixels(
            gl,
            Some(self.fbo),
            Some(glow::COLOR_ATTACHMENT0),
            (self.width, self.height),
            (glow::RED, glow::UNSIGNED_BYTE),
            1,
        )
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: called once by the owner; the shared depth texture belongs to the frame.
        unsafe {
            gl.delete_framebuffer(self.fbo);
            gl.delete_texture(self.mask);
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn flip_rows_reverses_row_order() {
        let mut d = vec![1, 1, 2, 2, 3, 3];
        super::flip_rows(&mut d, 2);
        assert_eq!(d, vec![3, 3, 2, 2, 1, 1]);
        let mut e = vec![1, 2, 3, 4];
        super::flip_rows(&mut e, 2);
        assert_eq!(e, vec![3, 4, 1, 2]);
    }
}
