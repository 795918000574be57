//! A light's mask from what its own lit pass recorded as it shaded (`gl::record`), read back
//! after the frame: the same decisions as its mask drawn again, without drawing it.

use crate::images::{Mask, MaskValue};

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

/// Rows and columns, top row first, a light's pass could draw: its scissor (x, y, width,
/// height in GL's window coordinates, bottom row first) within the frame, or all of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Rect {
    pub fn of_scissor(s: Option<[i32; 4]>, width: u32, height: u32) -> Rect {
        let Some([x, y, w, h]) = s else {
            return Rect {
                x0: 0,
                y0: 0,
                x1: width,
                y1: height,
            };
        };
        let clamp = |v: i32, hi: u32| v.clamp(0, hi as i32) as u32;
        let (x0, x1) = (clamp(x, width), clamp(x + w, width));
        let (bottom, top) = (clamp(y, height), clamp(y + h, height));
        Rect {
            x0,
            y0: height - top,
            x1,
            y1: height - bottom,
        }
    }
}

/// Light `index`'s mask of a `width`×`height` frame from `record` (top row first, a (lit,
/// shadowed) pair per pixel), read within `rect` (the layer's pixels outside it are a former
/// frame's). A pixel nothing was recorded at is no receiver, but where `reach` (per pixel, top
/// row first, and the light's bit) says the light reaches it: its pass dropped the shadowed
/// fragments there, so it is shadowed.
pub fn mask_from_record(
    index: usize,
    (width, height): (u32, u32),
    record: &[[u8; 2]],
    rect: Rect,
    reach: Option<(&[u32], u32)>,
) -> Mask {
    let reached = |i: usize| reach.is_some_and(|(bits, b)| bits[i] >> b & 1 == 1);
    let w = width as usize;
    let mut values = vec![MaskValue::NotReceiver as u8; w * height as usize];
    for y in rect.y0 as usize..rect.y1 as usize {
        let row = y * w + rect.x0 as usize..y * w + rect.x1 as usize;
        let start = row.start;
        let pairs = values[row.clone()].iter_mut().zip(&record[row]);
        for (k, (value, &pixel)) in pairs.enumerate() {
            *value = match Recorded::of(pixel) {
                Recorded::Lit => MaskValue::Lit,
                Recorded::Shadowed => MaskValue::Shadowed,
                Recorded::Nothing if reached(start + k) => MaskValue::Shadowed,
                Recorded::Nothing => MaskValue::NotReceiver,
            } as u8;
        }
    }
    Mask {
        light: index,
        width,
        height,
        values,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scissor_counts_rows_from_the_bottom_and_clamps_to_the_frame() {
        let r = Rect::of_scissor(Some([-2, 1, 3, 10]), 4, 2);
        assert_eq!((r.x0, r.x1, r.y0, r.y1), (0, 1, 0, 1));
        let all = Rect::of_scissor(None, 4, 2);
        assert_eq!((all.x0, all.x1, all.y0, all.y1), (0, 4, 0, 2));
    }

    #[test]
    fn a_set_channel_decides_and_outside_the_rectangle_is_no_receiver() {
        let mut record = vec![[0u8, 0u8]; 8];
        record[0] = [1, 0];
        record[1] = [0, 1];
        // Drawn twice, lit once and shadowed once: the light added, so lit.
        record[2] = [2, 1];
        record[5] = [0, 1];
        let v = |m: &Mask| {
            m.values
                .iter()
                .map(|&v| MaskValue::from_u8(v))
                .collect::<Vec<_>>()
        };
        use MaskValue::{Lit as L, NotReceiver as N, Shadowed as S};
        let all = Rect::of_scissor(None, 4, 2);
        let m = mask_from_record(3, (4, 2), &record, all, None);
        assert_eq!((m.light, m.width, m.height), (3, 4, 2));
        assert_eq!(v(&m), [L, S, L, N, N, S, N, N]);
        // Bit 2 set at pixels 0 (lit: stays lit), 3 and 6 (undrawn: shadowed); bit 1 at 4.
        let bits = [0b100, 0, 0, 0b100, 0b010, 0, 0b110, 0];
        let m = mask_from_record(3, (4, 2), &record, all, Some((&bits, 2)));
        assert_eq!(v(&m), [L, S, L, S, N, S, S, N]);
        let left_half = Rect {
            x0: 0,
            y0: 0,
            x1: 2,
            y1: 2,
        };
        let m = mask_from_record(3, (4, 2), &record, left_half, None);
        assert_eq!(v(&m), [L, S, N, N, N, S, N, N]);
    }
}
