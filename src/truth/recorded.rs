//! A light's mask from what its own lit pass recorded as it shaded (`gl::record`), read back
//! after the frame: the same decisions as its mask drawn again, without drawing it.

use crate::images::{GBuffer, Mask, MaskValue};
use crate::scene::Light;
use rayon::prelude::*;

/// What a light's lit pass recorded at one pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Recorded {
    Lit,
    Shadowed,
    /// No fragment of the light's lit pass ran there.
    Nothing,
}

impl Recorded {
    /// The recorded (lit, shadowed) channels of one pixel: which is non-zero, since a pixel
    /// drawn twice adds twice.
    pub fn of(pixel: [u8; 2]) -> Recorded {
        match pixel {
            [l, _] if l > 0 => Recorded::Lit,
            [_, s] if s > 0 => Recorded::Shadowed,
            _ => Recorded::Nothing,
        }
    }
}

/// What a pixel the lit pass did not draw means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Undrawn {
    /// The pass's shader decides every reached fragment: an undrawn pixel is no receiver.
    NotReceiver,
    /// The pass drops shadowed fragments before its shader (the stencil test) or with it
    /// (the alpha test of `shadow_map.result = alpha`): an undrawn pixel the light reaches
    /// (`Light::reaches`, the test the reference makes) is shadowed.
    ShadowedWhereReached,
}

/// Rows and columns, top row first, a light's pass could draw: its scissor (GL's window
/// coordinates, bottom row first) within the frame, or all of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Rect {
    pub fn of_scissor(s: Option<crate::plan::scissor::Scissor>, width: u32, height: u32) -> Rect {
        let Some(s) = s else {
            return Rect {
                x0: 0,
                y0: 0,
                x1: width,
                y1: height,
            };
        };
        let clamp = |v: i32, hi: u32| v.clamp(0, hi as i32) as u32;
        let (x0, x1) = (clamp(s.x, width), clamp(s.x + s.width, width));
        let (bottom, top) = (clamp(s.y, height), clamp(s.y + s.height, height));
        Rect {
            x0,
            y0: height - top,
            x1,
            y1: height - bottom,
        }
    }
}

/// Light `index`'s mask over `gbuffer` from `record` (top row first, a (lit, shadowed) pair
/// per pixel), read within `rect` (the layer's pixels outside it are a former frame's).
pub fn mask_from_record(
    (light, index): (&Light, usize),
    gbuffer: &GBuffer,
    record: &[[u8; 2]],
    rect: Rect,
    undrawn: Undrawn,
) -> Mask {
    let (w, h) = (gbuffer.width, gbuffer.height);
    let mut values = vec![MaskValue::NotReceiver as u8; (w * h) as usize];
    let rows = (rect.y0 as usize)..(rect.y1 as usize);
    let span = (rect.x0 as usize)..(rect.x1 as usize);
    values
        .par_chunks_mut(w as usize)
        .enumerate()
        .filter(|(y, _)| rows.contains(y))
        .for_each(|(y, row)| {
            for x in span.clone() {
                let i = y * w as usize + x;
                row[x] = match Recorded::of(record[i]) {
                    Recorded::Lit => MaskValue::Lit,
                    Recorded::Shadowed => MaskValue::Shadowed,
                    Recorded::Nothing
                        if undrawn == Undrawn::ShadowedWhereReached
                            && reaches(light, gbuffer, i) =>
                    {
                        MaskValue::Shadowed
                    }
                    Recorded::Nothing => MaskValue::NotReceiver,
                } as u8;
            }
        });
    Mask {
        light: index,
        width: w,
        height: h,
        values,
    }
}

/// Whether pixel `i` shows a receiving surface `light` reaches.
pub fn reaches(light: &Light, gbuffer: &GBuffer, i: usize) -> bool {
    gbuffer.is_receiver_surface(i) && {
        let p = glam::Vec3::from_array(gbuffer.position[i]).as_dvec3();
        let n = glam::Vec3::from_array(gbuffer.normal[i]).as_dvec3();
        light.reaches(p, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::scissor::Scissor;
    use glam::Vec3;

    /// A 4×2 G-buffer of a floor at z = 0 facing up, but pixel 3 (background) and pixel 7
    /// (a surface that takes no dynamic light).
    fn floor() -> GBuffer {
        let n = 8;
        let mut kind = vec![1; n];
        kind[3] = 0;
        kind[7] = 2;
        GBuffer {
            width: 4,
            height: 2,
            position: (0..n).map(|i| [i as f32, 0.0, 0.0]).collect(),
            normal: vec![[0.0, 0.0, 1.0]; n],
            kind,
        }
    }

    #[test]
    fn a_scissor_counts_rows_from_the_bottom_and_clamps_to_the_frame() {
        let s = Scissor {
            x: -2,
            y: 1,
            width: 3,
            height: 10,
        };
        let r = Rect::of_scissor(Some(s), 4, 2);
        assert_eq!((r.x0, r.x1, r.y0, r.y1), (0, 1, 0, 1));
        let all = Rect::of_scissor(None, 4, 2);
        assert_eq!((all.x0, all.x1, all.y0, all.y1), (0, 4, 0, 2));
    }

    #[test]
    fn undrawn_pixels_are_shadowed_only_where_the_light_reaches_a_receiver() {
        let g = floor();
        // Reaches x <= 5 (radius 5.5 from (0, 0, 1)): pixel 3 is background, 6 out of
        // range, 7 takes no light.
        let light = Light::omni("l", Vec3::new(0.0, 0.0, 1.0), 5.5);
        let mut record = vec![[0u8, 0u8]; 8];
        record[0] = [1, 0];
        record[1] = [0, 1];
        record[2] = [2, 1];
        let all = Rect::of_scissor(None, 4, 2);
        let stenciled =
            mask_from_record((&light, 0), &g, &record, all, Undrawn::ShadowedWhereReached);
        let v = |m: &Mask| {
            m.values
                .iter()
                .map(|&v| MaskValue::from_u8(v))
                .collect::<Vec<_>>()
        };
        use MaskValue::{Lit as L, NotReceiver as N, Shadowed as S};
        assert_eq!(v(&stenciled), [L, S, L, N, S, S, N, N]);
        let shaded = mask_from_record((&light, 0), &g, &record, all, Undrawn::NotReceiver);
        assert_eq!(v(&shaded), [L, S, L, N, N, N, N, N]);
        // Outside the rectangle the layer holds a former frame's values: no receiver.
        let left_half = Rect {
            x0: 0,
            y0: 0,
            x1: 2,
            y1: 2,
        };
        let m = mask_from_record((&light, 0), &g, &record, left_half, Undrawn::NotReceiver);
        assert_eq!(v(&m), [L, S, N, N, N, N, N, N]);
    }
}
