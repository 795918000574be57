//! Reading buffers back as images for the debug views and the walkthrough: depth (of the frame
//! or a shadow map) as grey, stencil counts as a heat map.
//!
//! OpenGL ES 3.0 reads neither depth nor stencil (glReadPixels takes colour only) and has no
//! glGetTexImage. There these readers return cleared values (depth 1.0, stencil 0) without a GL
//! call, so the debug images are blank rather than the frame failing on a GL error; the planner's
//! own depth read takes the `depth_read` fallback (plan::fallback) instead.

use super::target::{flip_rows, read_pixels, read_pixels_bottom_up};
use crate::images::Rgba;
use glow::HasContext;

/// Whether depth and stencil can be read back here (not on ES); logs once when not.
fn readable(gl: &glow::Context) -> bool {
    static WARNED: std::sync::Once = std::sync::Once::new();
    let es = gl.version().is_embedded;
    if es {
        WARNED.call_once(|| {
            log::warn!("OpenGL ES reads back no depth or stencil: the debug images are blank")
        });
    }
    !es
}

/// The depth values of a framebuffer's `w`×`h` corner in GL's row order (bottom row first),
/// as the depth pyramid takes them.
pub fn read_depth_bottom_up(
    gl: &glow::Context,
    fbo: glow::Framebuffer,
    w: u32,
    h: u32,
) -> Vec<f32> {
    if !readable(gl) {
        return vec![1.0; (w * h) as usize];
    }
    read_pixels_bottom_up(
        gl,
        Some(fbo),
        None,
        (w, h),
        (glow::DEPTH_COMPONENT, glow::FLOAT),
        1,
    )
}

/// The depth values of a framebuffer's `w`×`h` corner, top row first.
pub fn read_depth(gl: &glow::Context, fbo: glow::Framebuffer, w: u32, h: u32) -> Vec<f32> {
    if !readable(gl) {
        return vec![1.0; (w * h) as usize];
    }
    read_pixels(
        gl,
        Some(fbo),
        None,
        (w, h),
        (glow::DEPTH_COMPONENT, glow::FLOAT),
        1,
    )
}

/// The stencil values of a framebuffer's `w`×`h` corner, top row first.
pub fn read_stencil(gl: &glow::Context, fbo: glow::Framebuffer, w: u32, h: u32) -> Vec<u8> {
    if !readable(gl) {
        return vec![0; (w * h) as usize];
    }
    read_pixels(
        gl,
        Some(fbo),
        None,
        (w, h),
        (glow::STENCIL_INDEX, glow::UNSIGNED_BYTE),
        1,
    )
}

/// A depth texture's texels (one cube face when `face` is given), top row first.
pub fn read_depth_texture(
    gl: &glow::Context,
    texture: glow::Texture,
    face: Option<usize>,
    size: u32,
) -> Vec<f32> {
    let mut data = vec![1f32; (size * size) as usize];
    if !readable(gl) {
        return data;
    }
    let (bind, target) = match face {
        Some(f) => (
            glow::TEXTURE_CUBE_MAP,
            glow::TEXTURE_CUBE_MAP_POSITIVE_X + f as u32,
        ),
        None => (glow::TEXTURE_2D, glow::TEXTURE_2D),
    };
    // SAFETY: `data` holds size*size floats, the texture's level 0 is size x size depth.
    unsafe {
        gl.active_texture(glow::TEXTURE0);
        gl.bind_texture(bind, Some(texture));
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
        gl.get_tex_image(
            target,
            0,
            glow::DEPTH_COMPONENT,
            glow::FLOAT,
            glow::PixelPackData::Slice(Some(bytes_of_mut(&mut data))),
        );
        gl.bind_texture(bind, None);
    }
    super::syncs::count(super::syncs::SyncKind::ReadBack);
    flip_rows(&mut data, size as usize);
    data
}

/// An ID buffer's texels (`shadow_map.buffer = id`) as colours: each ID a hue of its own (a
/// multiplicative hash, so neighbouring IDs differ), texels no triangle wrote black.
pub fn id_image(gl: &glow::Context, texture: glow::Texture, size: u32) -> Rgba {
    let mut data = vec![0u8; (size * size * 4) as usize];
    if readable(gl) {
        // SAFETY: `data` holds size*size RGBA8 texels, the texture's level 0 is size x size RGBA8.
        unsafe {
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(texture));
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
            gl.get_tex_image(
                glow::TEXTURE_2D,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(&mut data)),
            );
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
        super::syncs::count(super::syncs::SyncKind::ReadBack);
    }
    let mut out = Vec::with_capacity(data.len());
    for texel in data.chunks_exact(4) {
        let id = u32::from_le_bytes([texel[0], texel[1], texel[2], texel[3]]);
        if id == u32::MAX {
            out.extend_from_slice(&[0, 0, 0, 255]);
        } else {
            let h = id.wrapping_mul(0x9E37_79B9).to_le_bytes();
            out.extend_from_slice(&[h[3] | 0x40, h[2] | 0x40, h[1] | 0x40, 255]);
        }
    }
    let mut rows: Vec<u32> = out
        .chunks_exact(4)
        .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]]))
        .collect();
    flip_rows(&mut rows, size as usize);
    Rgba {
        width: size,
        height: size,
        data: rows.iter().flat_map(|p| p.to_le_bytes()).collect(),
    }
}

fn bytes_of_mut(v: &mut [f32]) -> &mut [u8] {
    // SAFETY: f32 has no invalid bit patterns and u8 has alignment 1.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr() as *mut u8, std::mem::size_of_val(v)) }
}

/// Depth as grey: the nearest written depth white, the farthest dark, cleared (1.0) black; the
/// written range is stretched so that perspective depth's crowding near 1 stays visible.
pub fn depth_image(values: &[f32], width: u32, height: u32) -> Rgba {
    let written = values.iter().copied().filter(|d| *d < 1.0);
    let (lo, hi) = written.fold((f32::MAX, f32::MIN), |(a, b), d| (a.min(d), b.max(d)));
    let span = (hi - lo).max(1e-9);
    let mut data = Vec::with_capacity(values.len() * 4);
    for &d in values {
        let g = if d >= 1.0 {
            0
        } else {
            (255.0 * (1.0 - 0.85 * ((d - lo) / span).sqrt())) as u8
        };
        data.extend_from_slice(&[g, g, g, 255]);
    }
    Rgba {
        width,
        height,
        data,
    }
}

/// The colour of a stencil count: 0 clear, 1-255 a ramp from blue through green and yellow to
/// red at 8 and above; counts above 127 under wrapping arithmetic are negative: magenta.
pub fn stencil_colour(count: u8, wrapping: bool) -> [u8; 4] {
    if count == 0 {
        return [0, 0, 0, 0];
    }
    if wrapping && count > 127 {
        return [230, 0, 230, 200];
    }
    let t = ((count as f32 - 1.0) / 7.0).min(1.0);
    let ramp = [
        [40.0, 90.0, 255.0],
        [40.0, 220.0, 90.0],
        [250.0, 230.0, 40.0],
        [250.0, 40.0, 30.0],
    ];
    let x = t * 3.0;
    let i = (x.floor() as usize).min(2);
    let f = x - i as f32;
    let c: Vec<u8> = (0..3)
        .map(|k| (ramp[i][k] * (1.0 - f) + ramp[i + 1][k] * f) as u8)
        .collect();
    [c[0], c[1], c[2], 200]
}

/// Stencil counts as a heat map over black.
pub fn stencil_image(values: &[u8], width: u32, height: u32, wrapping: bool) -> Rgba {
    let mut data = Vec::with_capacity(values.len() * 4);
    for &v in values {
        let [r, g, b, a] = stencil_colour(v, wrapping);
        let k = a as u32;
        data.extend_from_slice(&[
            (r as u32 * k / 255) as u8,
            (g as u32 * k / 255) as u8,
            (b as u32 * k / 255) as u8,
            255,
        ]);
    }
    Rgba {
        width,
        height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_is_grey_nearest_brightest_and_cleared_black() {
        let img = depth_image(&[0.5, 0.75, 1.0], 3, 1);
        assert_eq!(&img.data[0..4], &[255, 255, 255, 255]);
        assert_eq!(img.data[4], (255.0 * 0.15) as u8);
        assert_eq!(&img.data[8..12], &[0, 0, 0, 255]);
    }

    #[test]
    fn stencil_ramp_runs_from_blue_to_red_and_marks_negative_counts() {
        assert_eq!(stencil_colour(0, false)[3], 0);
        assert_eq!(stencil_colour(1, false)[..3], [40, 90, 255]);
        assert_eq!(stencil_colour(8, false)[..3], [250, 40, 30]);
        assert_eq!(stencil_colour(200, false)[..3], [250, 40, 30]);
        assert_eq!(stencil_colour(255, true)[..3], [230, 0, 230]);
    }
}
