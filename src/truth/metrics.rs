//! How far a renderer's masks are from the exact ones.
//!
//! Rates are fractions of the reference's receiver pixels. False shadow = the renderer shadows a
//! pixel the reference lights (acne, over-darkening); false lit = the renderer lights a pixel the
//! reference shadows (light leaks, peter panning). The `_excl_boundary` rates leave out pixels
//! within 1 px of a reference shadow boundary (a pixel whose 3×3 neighbourhood holds both lit and
//! shadowed reference receivers), where rasterization alone decides. Pixels that one side counts
//! as a receiver and the other does not (cone edges, terminators, at float precision) are counted
//! apart as `receiver_mismatch` and left out of the rates.

use crate::images::{Mask, MaskValue};
use serde::Serialize;

/// Counts for one light (or summed over lights).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Counts {
    pub receiver_pixels: usize,
    pub reference_shadowed: usize,
    pub false_shadow: usize,
    pub false_lit: usize,
    /// Receivers away from the boundary band.
    pub receivers_excl_boundary: usize,
    pub false_shadow_excl_boundary: usize,
    pub false_lit_excl_boundary: usize,
    pub receiver_mismatch: usize,
}

/// Rates as fractions of receiver pixels (0 when there are none).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Rates {
    pub receiver_pixels: usize,
    pub false_shadow: f64,
    pub false_lit: f64,
    pub total: f64,
    pub total_excl_boundary: f64,
}

/// `a / b`, 0 when `b` is 0.
pub fn ratio(a: usize, b: usize) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

impl Counts {
    pub fn add(&mut self, o: &Counts) {
        self.receiver_pixels += o.receiver_pixels;
        self.reference_shadowed += o.reference_shadowed;
        self.false_shadow += o.false_shadow;
        self.false_lit += o.false_lit;
        self.receivers_excl_boundary += o.receivers_excl_boundary;
        self.false_shadow_excl_boundary += o.false_shadow_excl_boundary;
        self.false_lit_excl_boundary += o.false_lit_excl_boundary;
        self.receiver_mismatch += o.receiver_mismatch;
    }

    pub fn rates(&self) -> Rates {
        Rates {
            receiver_pixels: self.receiver_pixels,
            false_shadow: ratio(self.false_shadow, self.receiver_pixels),
            false_lit: ratio(self.false_lit, self.receiver_pixels),
            total: ratio(self.false_shadow + self.false_lit, self.receiver_pixels),
            total_excl_boundary: ratio(
                self.false_shadow_excl_boundary + self.false_lit_excl_boundary,
                self.receivers_excl_boundary,
            ),
        }
    }
}

/// Whether pixel `i` lies within 1 px of a boundary between lit and shadowed reference pixels.
pub fn near_boundary(reference: &Mask, x: u32, y: u32) -> bool {
    let (mut lit, mut shadowed) = (false, false);
    for yy in y.saturating_sub(1)..=(y + 1).min(reference.height - 1) {
        for xx in x.saturating_sub(1)..=(x + 1).min(reference.width - 1) {
            match reference.get(xx, yy) {
                MaskValue::Lit => lit = true,
                MaskValue::Shadowed => shadowed = true,
                MaskValue::NotReceiver => {}
            }
        }
    }
    lit && shadowed
}

/// Compares one light's renderer mask with the reference mask of the same light and frame.
pub fn compare(rendered: &Mask, reference: &Mask) -> Counts {
    compare_where(rendered, reference, |_| true)
}

/// [`compare`] over the pixels (row-major indices) that `include` admits; the boundary band is
/// still judged on the whole reference.
pub fn compare_where(rendered: &Mask, reference: &Mask, include: impl Fn(usize) -> bool) -> Counts {
    assert_eq!(
        (rendered.width, rendered.height),
        (reference.width, reference.height),
        "masks of different sizes"
    );
    let mut c = Counts::default();
    for y in 0..reference.height {
        for x in 0..reference.width {
            if !include((y * reference.width + x) as usize) {
                continue;
            }
            let (r, t) = (rendered.get(x, y), reference.get(x, y));
            match (r, t) {
                (MaskValue::NotReceiver, MaskValue::NotReceiver) => continue,
                (MaskValue::NotReceiver, _) | (_, MaskValue::NotReceiver) => {
                    c.receiver_mismatch += 1;
                    continue;
                }
                _ => {}
            }
            c.receiver_pixels += 1;
            c.reference_shadowed += (t == MaskValue::Shadowed) as usize;
            let false_shadow = r == MaskValue::Shadowed && t == MaskValue::Lit;
            let false_lit = r == MaskValue::Lit && t == MaskValue::Shadowed;
            c.false_shadow += false_shadow as usize;
            c.false_lit += false_lit as usize;
            if !near_boundary(reference, x, y) {
                c.receivers_excl_boundary += 1;
                c.false_shadow_excl_boundary += false_shadow as usize;
                c.false_lit_excl_boundary += false_lit as usize;
            }
        }
    }
    c
}

/// How two masks of one light and view differ: in all, and outside the edge band.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct MaskDifference {
    pub differing: usize,
    /// Differing pixels not within 1 px of an edge (a change of value: lit, shadowed, not a
    /// receiver) in both masks. Where a shadow or a receiver ends, two rasterisers may put the
    /// edge a pixel apart (coverage rules, interpolation precision), and so may two ways of
    /// drawing the same geometry (clipped or bounded volumes); away from the edges of both
    /// masks, a difference is a decision of its own (a speck of acne, a leak) and counts.
    pub outside_band: usize,
}

/// Whether (x, y) lies within 1 px of an edge of `m`: its 3×3 neighbourhood holds two values.
fn near_edge(m: &Mask, x: u32, y: u32) -> bool {
    let here = m.get(x, y);
    (y.saturating_sub(1)..=(y + 1).min(m.height - 1))
        .any(|yy| (x.saturating_sub(1)..=(x + 1).min(m.width - 1)).any(|xx| m.get(xx, yy) != here))
}

/// Compares two masks of the same light and frame size (e.g. one drawn on two GL paths).
pub fn mask_difference(a: &Mask, b: &Mask) -> MaskDifference {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "masks of different sizes"
    );
    let mut d = MaskDifference::default();
    for y in 0..a.height {
        for x in 0..a.width {
            let i = (y * a.width + x) as usize;
            if a.values[i] == b.values[i] {
                continue;
            }
            d.differing += 1;
            if !(near_edge(a, x, y) && near_edge(b, x, y)) {
                d.outside_band += 1;
            }
        }
    }
    d
}

/// How one pixel compares, worst first (the order in which lights' answers are merged).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum PixelError {
    FalseShadow,
    FalseLit,
    ReceiverMismatch,
    Shadowed,
    Lit,
    NotReceiver,
}

impl PixelError {
    fn of(rendered: u8, reference: u8) -> PixelError {
        match (MaskValue::from_u8(rendered), MaskValue::from_u8(reference)) {
            (MaskValue::NotReceiver, MaskValue::NotReceiver) => PixelError::NotReceiver,
            (MaskValue::NotReceiver, _) | (_, MaskValue::NotReceiver) => {
                PixelError::ReceiverMismatch
            }
            (MaskValue::Shadowed, MaskValue::Lit) => PixelError::FalseShadow,
            (MaskValue::Lit, MaskValue::Shadowed) => PixelError::FalseLit,
            (MaskValue::Lit, MaskValue::Lit) => PixelError::Lit,
            (MaskValue::Shadowed, MaskValue::Shadowed) => PixelError::Shadowed,
        }
    }

    fn colour(self) -> [u8; 4] {
        match self {
            PixelError::NotReceiver => [0, 0, 0, 255],
            PixelError::ReceiverMismatch => [255, 220, 0, 255],
            PixelError::FalseShadow => [255, 0, 0, 255],
            PixelError::FalseLit => [0, 80, 255, 255],
            PixelError::Lit => [150, 150, 150, 255],
            PixelError::Shadowed => [60, 60, 60, 255],
        }
    }
}

/// RGBA image of one light's errors: red = false shadow, blue = false lit, grey = correct lit,
/// dark grey = correct shadow, black = not a receiver, yellow = receiver mismatch.
pub fn error_image(rendered: &Mask, reference: &Mask) -> Vec<u8> {
    error_image_all(&[rendered], &[reference])
}

/// The same over several lights (pairs in order): each pixel shows its worst answer.
pub fn error_image_all(rendered: &[&Mask], reference: &[&Mask]) -> Vec<u8> {
    let n = reference.first().map_or(0, |m| m.values.len());
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        let worst = rendered
            .iter()
            .zip(reference)
            .map(|(r, t)| PixelError::of(r.values[i], t.values[i]))
            .min()
            .unwrap_or(PixelError::NotReceiver);
        out.extend_from_slice(&worst.colour());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(rows: &[&str]) -> Mask {
        let values = rows
            .iter()
            .flat_map(|r| {
                r.bytes().map(|b| match b {
                    b'L' => 1,
                    b'S' => 2,
                    _ => 0,
                })
            })
            .collect();
        Mask {
            light: 0,
            width: rows[0].len() as u32,
            height: rows.len() as u32,
            values,
        }
    }

    #[test]
    fn counts_and_rates_by_hand() {
        let reference = mask(&["LLLLSS", "LLLLSS", "LLLLSS", ".LLLLL"]);
        let rendered = mask(&["SLLLLS", "LLLLSS", "LLLLSS", "LLLLL."]);
        let c = compare(&rendered, &reference);
        // 24 pixels; (0,3) and (5,3) are a receiver on one side only.
        assert_eq!(c.receiver_mismatch, 2);
        assert_eq!(c.receiver_pixels, 22);
        assert_eq!(c.reference_shadowed, 6);
        assert_eq!(c.false_shadow, 1); // (0,0)
        assert_eq!(c.false_lit, 1); // (4,0)
        // (4,0) touches the boundary (lit and shadowed neighbours); (0,0) does not.
        assert_eq!(c.false_shadow_excl_boundary, 1);
        assert_eq!(c.false_lit_excl_boundary, 0);
        let r = c.rates();
        assert!((r.total - 2.0 / 22.0).abs() < 1e-12);
        // The band: columns 3-4 of every row, and (5,2) whose neighbours below are lit.
        assert_eq!(c.receivers_excl_boundary, 22 - 9);
        assert!((r.total_excl_boundary - 1.0 / 13.0).abs() < 1e-12);
    }

    #[test]
    fn an_edge_a_pixel_apart_is_in_the_band_and_a_speck_is_not() {
        // The shadow starts a column later in b, and the receiver ends a column later; b has
        // an isolated speck of shadow at (1, 3) in a lit region.
        let a = mask(&["LLLSSSSS..", "LLLSSSSS..", "LLLSSSSS..", "LLLSSSSS.."]);
        let b = mask(&["LLLLSSSSS.", "LLLLSSSSS.", "LLLLSSSSS.", "LSLLSSSSS."]);
        let d = mask_difference(&a, &b);
        // Columns 3 and 8 of four rows differ at edges; the speck differs away from them.
        assert_eq!(d.differing, 9);
        assert_eq!(d.outside_band, 1);
        assert_eq!(mask_difference(&a, &a), MaskDifference::default());
        // A speck in the middle of a region, in one mask only, is never in the band.
        let lit = mask(&["LLL", "LLL", "LLL"]);
        let speck = mask(&["LLL", "LSL", "LLL"]);
        assert_eq!(
            mask_difference(&lit, &speck),
            MaskDifference {
                differing: 1,
                outside_band: 1
            }
        );
    }

    #[test]
    fn identical_masks_have_no_error_and_the_image_colours_errors() {
        let m = mask(&["LS.", "SL."]);
        let c = compare(&m, &m);
        assert_eq!(
            (c.false_shadow, c.false_lit, c.receiver_mismatch),
            (0, 0, 0)
        );
        assert_eq!(c.rates().total, 0.0);
        let img = error_image(&mask(&["SL"]), &mask(&["LS"]));
        assert_eq!(&img[0..4], &[255, 0, 0, 255]);
        assert_eq!(&img[4..8], &[0, 80, 255, 255]);
    }
}
