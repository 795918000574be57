//! Image helpers for reports: saving, and cropping a zoomed window around shadow boundaries.

use crate::images::{Mask, MaskValue, Rgba};

impl Rgba {
    /// The window at (x, y) of size w × h (clamped to the image), each pixel repeated `zoom`
    /// times in both directions (nearest neighbour, so texels and aliasing stay visible).
    pub fn crop_zoom(&self, x: u32, y: u32, w: u32, h: u32, zoom: u32) -> Rgba {
        let x = x.min(self.width.saturating_sub(1));
        let y = y.min(self.height.saturating_sub(1));
        let w = w.min(self.width - x).max(1);
        let h = h.min(self.height - y).max(1);
        let zoom = zoom.max(1);
        let (ow, oh) = (w * zoom, h * zoom);
        let mut data = Vec::with_capacity((ow * oh * 4) as usize);
        for oy in 0..oh {
            for ox in 0..ow {
                let i = (((y + oy / zoom) * self.width + x + ox / zoom) * 4) as usize;
                data.extend_from_slice(&self.data[i..i + 4]);
            }
        }
        Rgba {
            width: ow,
            height: oh,
            data,
        }
    }
}

/// Whether pixel `i` of the mask lies on a shadow boundary: a receiver with both lit and
/// shadowed receivers in its 3×3 neighbourhood.
fn on_boundary(mask: &Mask, x: u32, y: u32) -> bool {
    let (mut lit, mut shadowed) = (false, false);
    for dy in -1i32..=1 {
        for dx in -1i32..=1 {
            let (nx, ny) = (x as i32 + dx, y as i32 + dy);
            if nx < 0 || ny < 0 || nx >= mask.width as i32 || ny >= mask.height as i32 {
                continue;
            }
            match mask.get(nx as u32, ny as u32) {
                MaskValue::Lit => lit = true,
                MaskValue::Shadowed => shadowed = true,
                MaskValue::NotReceiver => {}
            }
        }
    }
    lit && shadowed
}

/// The top-left corner of the w × h window holding the most boundary pixels of any of the
/// masks (a summed-area table over the boundary map).
pub fn boundary_window(masks: &[&Mask], w: u32, h: u32) -> Option<(u32, u32)> {
    let first = masks.first()?;
    let (mw, mh) = (first.width, first.height);
    if w > mw || h > mh || masks.iter().any(|m| (m.width, m.height) != (mw, mh)) {
        return None;
    }
    let stride = (mw + 1) as usize;
    let mut sum = vec![0u32; stride * (mh + 1) as usize];
    for y in 0..mh {
        for x in 0..mw {
            let b = masks.iter().any(|m| on_boundary(m, x, y)) as u32;
            let i = (y + 1) as usize * stride + (x + 1) as usize;
            sum[i] = b + sum[i - 1] + sum[i - stride] - sum[i - stride - 1];
        }
    }
    let at = |x: u32, y: u32| sum[y as usize * stride + x as usize];
    let mut best = (0, (0, 0));
    for y in 0..=mh - h {
        for x in 0..=mw - w {
            let n = at(x + w, y + h) + at(x, y) - at(x + w, y) - at(x, y + h);
            if n > best.0 {
                best = (n, (x, y));
            }
        }
    }
    (best.0 > 0).then_some(best.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_lands_on_the_boundary_and_crops_zoom() {
        // 40 × 20: shadowed left of x = 30, lit right of it.
        let (w, h) = (40u32, 20u32);
        let values = (0..w * h)
            .map(|i| {
                if i % w < 30 {
                    MaskValue::Shadowed as u8
                } else {
                    MaskValue::Lit as u8
                }
            })
            .collect();
        let mask = Mask {
            light: 0,
            width: w,
            height: h,
            values,
        };
        let (x, y) = boundary_window(&[&mask], 4, 4).unwrap();
        assert!((27..=29).contains(&x), "x = {x}");
        assert!(y <= 16);
        let img = Rgba {
            width: 2,
            height: 1,
            data: vec![1, 2, 3, 4, 5, 6, 7, 8],
        };
        let z = img.crop_zoom(1, 0, 5, 5, 2);
        assert_eq!((z.width, z.height), (2, 2));
        assert_eq!(z.data, [5, 6, 7, 8].repeat(4));
    }
}
