//! A mask's receiver pixels in tile order, the order the sampled reference's strata follow:
//! 16×16 tiles left to right and top to bottom, each row by row. Counted per row of a tile,
//! so that the k-th receiver is found without listing them all: a light's mask holds up to a frame's
//! pixels while a sample picks a few hundred of them.

use crate::images::{Mask, MaskValue};

/// Side of the square tiles.
pub const TILE: usize = 16;

/// A mask's receivers counted in tile order.
pub struct TileOrder<'a> {
    mask: &'a Mask,
    /// Each tile's row holding receivers, in tile order: its first pixel (row-major index),
    /// its last pixel plus one, and the receivers before it.
    runs: Vec<(usize, usize, usize)>,
    receivers: usize,
}

/// How many of `run`'s pixels are receivers (not 0), sixteen at a time where it can.
fn receivers_in(run: &[u8]) -> usize {
    const LOW7: u128 = u128::from_ne_bytes([0x7f; 16]);
    const HIGH: u128 = u128::from_ne_bytes([0x80; 16]);
    let (chunks, rest) = run.as_chunks::<16>();
    let wide: u32 = chunks
        .iter()
        .map(|c| {
            let x = u128::from_ne_bytes(*c);
            // A byte's high bit ends set where the byte is not 0: its low seven bits plus
            // 0x7f carry into it, or it was set already; no carry crosses bytes.
            (((x & LOW7) + LOW7) | x) & HIGH
        })
        .map(u128::count_ones)
        .sum();
    let narrow = rest
        .iter()
        .filter(|&&v| v != MaskValue::NotReceiver as u8)
        .count();
    wide as usize + narrow
}

impl<'a> TileOrder<'a> {
    pub fn of(mask: &'a Mask) -> TileOrder<'a> {
        let (w, h) = (mask.width as usize, mask.height as usize);
        let (mut runs, mut receivers) = (Vec::new(), 0);
        for ty in (0..h).step_by(TILE) {
            let rows = ty..(ty + TILE).min(h);
            // Most of a light's mask is no receiver (its scissor, its range): a band of
            // tiles without one is passed over whole.
            if receivers_in(&mask.values[rows.start * w..rows.end * w]) == 0 {
                continue;
            }
            for tx in (0..w).step_by(TILE) {
                for y in rows.clone() {
                    let (start, end) = (y * w + tx, y * w + (tx + TILE).min(w));
                    let count = receivers_in(&mask.values[start..end]);
                    if count > 0 {
                        runs.push((start, end, receivers));
                        receivers += count;
                    }
                }
            }
        }
        TileOrder {
            mask,
            runs,
            receivers,
        }
    }

    /// How many receivers the mask holds.
    pub fn receivers(&self) -> usize {
        self.receivers
    }

    /// The `k`-th receiver's pixel (row-major index); None past the last.
    pub fn nth(&self, k: usize) -> Option<u32> {
        let r = self.runs.partition_point(|&(_, _, before)| before <= k);
        let &(start, end, before) = self.runs.get(r.checked_sub(1)?)?;
        let (x, _) = self.mask.values[start..end]
            .iter()
            .enumerate()
            .filter(|&(_, &v)| v != MaskValue::NotReceiver as u8)
            .nth(k - before)?;
        Some((start + x) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The walk tile by tile, row by row within a tile, pixel by pixel: what the counted
    /// order must give.
    fn plain(m: &Mask) -> Vec<u32> {
        let (w, h) = (m.width as usize, m.height as usize);
        let mut out = Vec::new();
        for ty in (0..h).step_by(TILE) {
            for tx in (0..w).step_by(TILE) {
                for y in ty..(ty + TILE).min(h) {
                    for x in tx..(tx + TILE).min(w) {
                        if m.values[y * w + x] != 0 {
                            out.push((y * w + x) as u32);
                        }
                    }
                }
            }
        }
        out
    }

    fn all(order: &TileOrder) -> Vec<u32> {
        (0..order.receivers())
            .filter_map(|k| order.nth(k))
            .collect()
    }

    #[test]
    fn receivers_counted_sixteen_at_a_time_as_one_by_one() {
        let bytes: Vec<u8> = (0..=255u8).chain([0; 40]).chain(1..=20).collect();
        for start in [0, 3, 100, 250] {
            let run = &bytes[start..];
            let naive = run.iter().filter(|&&v| v != 0).count();
            assert_eq!(receivers_in(run), naive, "from {start}");
        }
    }

    #[test]
    fn receivers_only_and_tile_by_tile() {
        let mut m = Mask {
            light: 0,
            width: 40,
            height: 2,
            values: vec![1; 80],
        };
        m.values[3] = 0;
        let order = TileOrder::of(&m);
        let pixels = all(&order);
        assert_eq!(pixels.len(), 79);
        // The first tile (x < 16) finishes both rows before x = 16 starts.
        assert_eq!(pixels[15], 40);
        assert_eq!(pixels[31], 16);
        assert_eq!(order.nth(79), None);
    }

    #[test]
    fn equals_the_plain_walk_on_ragged_sizes() {
        let mut rng = fastrand::Rng::with_seed(11);
        for (w, h, density) in [
            (37, 21, 0.3),
            (50, 35, 0.02),
            (16, 16, 0.9),
            (17, 1, 0.5),
            (33, 40, 0.0),
        ] {
            let values = (0..w * h)
                .map(|_| match rng.f64() < density {
                    true => 1 + rng.u8(0..2),
                    false => 0,
                })
                .collect();
            let m = Mask {
                light: 0,
                width: w,
                height: h,
                values,
            };
            let order = TileOrder::of(&m);
            assert_eq!(all(&order), plain(&m), "{w}x{h}");
            assert_eq!(order.nth(order.receivers()), None, "{w}x{h}");
        }
    }
}
