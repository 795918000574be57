//! The sampled reference: each frame, per light, a few hundred receiver pixels traced exactly and
//! compared with the technique's decision there, instead of every pixel.
//!
//! The population is the one the full comparison ([`super::compare`]) rates: pixels that the
//! rendered mask and the reference both count as receivers of the light. Its pixels are taken in
//! 16×16 tiles, row by row, and cut into `n` strata of equal length (±1); one pixel is drawn
//! uniformly from each stratum, so the samples spread over the light's part of the screen and
//! every pixel is equally likely (up to the ±1). A stratum whose pixel the reference does not
//! count as a receiver (a receiver mismatch, left out of the rates) drops out.
//!
//! The estimate is the weighted share of sampled pixels whose decision differs from the exact
//! one (each weighted by its stratum's length). Its 95% interval is Wilson's score interval on
//! Kish's effective sample size; stratification only narrows the real spread, so the interval is
//! conservative. With as many samples as pixels, every pixel is traced and the interval closes.

use super::reference::{Reference, shadow_ray_origin};
use super::tile_order::TileOrder;
use crate::images::{Mask, MaskValue, Surfaces};
use crate::scene::Light;
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

/// Standard normal quantile of the 95% two-sided interval.
const Z95: f64 = 1.959_964;

/// A share with its 95% interval.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Interval {
    /// The estimate, a fraction.
    pub value: f64,
    pub low: f64,
    pub high: f64,
}

impl Interval {
    /// Wilson's score interval for share `p` observed on `n` (effective) samples; exact (closed)
    /// when `exact`, empty-sample intervals span everything.
    pub fn wilson(p: f64, n: f64, exact: bool) -> Interval {
        if exact {
            return Interval {
                value: p,
                low: p,
                high: p,
            };
        }
        if n <= 0.0 {
            return Interval {
                value: p,
                low: 0.0,
                high: 1.0,
            };
        }
        let z2 = Z95 * Z95;
        let denom = 1.0 + z2 / n;
        let centre = (p + z2 / (2.0 * n)) / denom;
        let half = Z95 * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denom;
        Interval {
            value: p,
            low: (centre - half).max(0.0),
            high: (centre + half).min(1.0),
        }
    }

    /// Whether `x` lies in the interval (with a little room for rounding).
    pub fn holds(&self, x: f64) -> bool {
        x >= self.low - 1e-12 && x <= self.high + 1e-12
    }
}

/// One light's sampled error in one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LightSample {
    pub light: usize,
    /// Pixels both the mask and the reference count as receivers (estimated from the samples
    /// where some were mismatches).
    pub receivers: f64,
    /// Receiver pixels traced.
    pub samples: usize,
    /// Kish's effective sample size of the weighted samples.
    pub effective: f64,
    /// Whether every receiver pixel was traced.
    pub exact: bool,
    pub error: Interval,
    /// The share of receivers the reference lights through a hole of an alpha-tested caster
    /// (a texel its alpha test rejects): what drawing those casters solid, as shadow volumes
    /// do, shadows wrongly, whatever technique the frame ran.
    pub alpha_holes: Interval,
}

/// A frame's sampled error: per light, and over every light's receiver pixels.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct FrameSample {
    pub per_light: Vec<LightSample>,
    pub total: Interval,
    /// Shadow rays traced.
    pub rays: usize,
}

/// The pixel of each stratum: `n` strata over the `m` pixels `nth` numbers (in tile order),
/// one uniform pick in each, with the stratum's length as weight. Every pixel when `n` covers
/// them all.
fn stratified(
    m: usize,
    n: usize,
    rng: &mut fastrand::Rng,
    nth: impl Fn(usize) -> Option<u32>,
) -> Vec<(u32, f64)> {
    if n == 0 || m == 0 {
        return Vec::new();
    }
    if n >= m {
        return (0..m).filter_map(|k| Some((nth(k)?, 1.0))).collect();
    }
    (0..n)
        .filter_map(|k| {
            let (start, end) = (k * m / n, (k + 1) * m / n);
            Some((nth(rng.usize(start..end))?, (end - start) as f64))
        })
        .collect()
}

/// The random stream of light `light` in frame `frame`: the same seed, frame and light give the
/// same samples; each frame and light its own.
pub fn stream(seed: u64, frame: u64, light: usize) -> fastrand::Rng {
    let mix = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(frame.wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add((light as u64).wrapping_mul(0x1656_67B1_9E37_79F9));
    fastrand::Rng::with_seed(mix)
}

/// What the exact reference says at pixel `i` (shadowed, and lit through an alpha-tested
/// caster's hole): `None` where the light does not reach it.
fn exact_at(
    reference: &Reference,
    surfaces: &impl Surfaces,
    light: &Light,
    i: usize,
) -> Option<(bool, bool)> {
    let (p, n) = surfaces.receiver_at(i)?;
    let (p, n) = (Vec3::from_array(p), Vec3::from_array(n));
    if !light.reaches(p.as_dvec3(), n.as_dvec3()) {
        return None;
    }
    Some(reference.occluded_or_through_hole(shadow_ray_origin(p, n), light.position.as_dvec3()))
}

/// The pixels of light `light`'s mask a sample traces: `n` stratified picks over its receiver
/// pixels, with their weights, and how many receiver pixels there are.
#[derive(Debug, Clone, PartialEq)]
pub struct Picks {
    pub light: usize,
    pub picks: Vec<(u32, f64)>,
    pub receivers: usize,
}

/// `mask`'s picks for `n` samples from `rng`.
pub fn picks_of(mask: &Mask, n: usize, rng: &mut fastrand::Rng) -> Picks {
    let order = TileOrder::of(mask);
    Picks {
        light: mask.light,
        picks: stratified(order.receivers(), n, rng, |k| order.nth(k)),
        receivers: order.receivers(),
    }
}

/// The picks of a frame's masks (those of lights in `lights`; `frame` numbers it for the
/// random streams): what [`sample_frame`] traces.
pub fn frame_picks(
    lights: &[Light],
    masks: &[Mask],
    n: usize,
    seed: u64,
    frame: u64,
) -> Vec<Picks> {
    masks
        .par_iter()
        .filter(|m| m.light < lights.len())
        .map(|m| picks_of(m, n, &mut stream(seed, frame, m.light)))
        .collect()
}

/// Every pixel of `picks`, sorted, each once: what a sample reads of the G-buffer.
pub fn picked_pixels(picks: &[Picks]) -> Vec<u32> {
    let mut pixels: Vec<u32> = picks
        .iter()
        .flat_map(|p| p.picks.iter().map(|&(i, _)| i))
        .collect();
    pixels.sort_unstable();
    pixels.dedup();
    pixels
}

/// Samples light `light`'s rendered `mask` over the G-buffer's `surfaces` at its `picks`,
/// traced against `reference`.
pub fn sample_light(
    reference: &Reference,
    surfaces: &impl Surfaces,
    light: &Light,
    mask: &Mask,
    picks: &Picks,
) -> LightSample {
    let (picks, pixels) = (&picks.picks, picks.receivers);
    let exact = picks.len() == pixels;
    // (weight, wrong, lit through a hole) per pick the reference also counts as a receiver.
    let judged: Vec<(f64, bool, bool)> = picks
        .par_iter()
        .filter_map(|&(i, w)| {
            let (shadowed, hole) = exact_at(reference, surfaces, light, i as usize)?;
            let rendered_shadowed = mask.values[i as usize] == MaskValue::Shadowed as u8;
            Some((w, shadowed != rendered_shadowed, hole))
        })
        .collect();
    let (sum_w, sum_w2, wrong_w, hole_w) =
        judged
            .iter()
            .fold((0.0, 0.0, 0.0, 0.0), |(s, s2, e, h), &(w, wrong, hole)| {
                let (e, h) = (
                    e + if wrong { w } else { 0.0 },
                    h + if hole { w } else { 0.0 },
                );
                (s + w, s2 + w * w, e, h)
            });
    let share = if sum_w > 0.0 { wrong_w / sum_w } else { 0.0 };
    let holes = if sum_w > 0.0 { hole_w / sum_w } else { 0.0 };
    let effective = if sum_w2 > 0.0 {
        sum_w * sum_w / sum_w2
    } else {
        0.0
    };
    // The picks' weights sum to the mask's receivers; the kept ones estimate the shared ones.
    let picked_w: f64 = picks.iter().map(|p| p.1).sum();
    let receivers = if picked_w > 0.0 {
        pixels as f64 * sum_w / picked_w
    } else {
        0.0
    };
    LightSample {
        light: mask.light,
        receivers,
        samples: judged.len(),
        effective,
        exact,
        error: Interval::wilson(share, effective, exact),
        alpha_holes: Interval::wilson(holes, effective, exact),
    }
}

/// Samples every mask of a frame (`frame` numbers it for the random streams).
pub fn sample_frame(
    reference: &Reference,
    surfaces: &impl Surfaces,
    lights: &[Light],
    masks: &[Mask],
    n: usize,
    seed: u64,
    frame: u64,
) -> FrameSample {
    let picks = frame_picks(lights, masks, n, seed, frame);
    sample_picked(reference, surfaces, lights, masks, &picks)
}

/// [`sample_frame`] at picks made before ([`frame_picks`] of the same masks).
pub fn sample_picked(
    reference: &Reference,
    surfaces: &impl Surfaces,
    lights: &[Light],
    masks: &[Mask],
    picks: &[Picks],
) -> FrameSample {
    let per_light: Vec<LightSample> = picks
        .iter()
        .filter_map(|p| {
            let mask = masks.iter().find(|m| m.light == p.light)?;
            Some(sample_light(reference, surfaces, &lights[p.light], mask, p))
        })
        .collect();
    let rays = per_light.iter().map(|l| l.samples).sum();
    FrameSample {
        total: pooled(&per_light),
        per_light,
        rays,
    }
}

/// Several lights' (or frames') estimates as one share of all their receivers: each weighted by
/// its receivers, the interval on the summed effective sizes.
pub fn pooled(parts: &[LightSample]) -> Interval {
    pooled_by(parts, |p| p.error.value)
}

/// [`pooled`] of another share each part estimates (`value`), e.g. its `alpha_holes`.
pub fn pooled_by(parts: &[LightSample], value: impl Fn(&LightSample) -> f64) -> Interval {
    let receivers: f64 = parts.iter().map(|p| p.receivers).sum();
    if receivers <= 0.0 {
        return Interval::wilson(0.0, 0.0, parts.iter().all(|p| p.exact));
    }
    let share = parts.iter().map(|p| p.receivers * value(p)).sum::<f64>() / receivers;
    // The effective size of a stratified share with strata weights f_l = receivers_l / R and
    // equal spreads: 1 / sum(f_l^2 / n_l). Exact lights (every pixel traced) add no spread.
    let spread: f64 = parts
        .iter()
        .filter(|p| !p.exact)
        .map(|p| (p.receivers / receivers).powi(2) / p.effective.max(1.0))
        .sum();
    if spread <= 0.0 {
        return Interval::wilson(share, 0.0, true);
    }
    Interval::wilson(share, 1.0 / spread, false)
}

/// One light's estimate pooled over its last frames, for the running display and `auto`.
#[derive(Debug, Clone, Default)]
pub struct Running {
    window: usize,
    frames: std::collections::VecDeque<LightSample>,
}

impl Running {
    pub fn new(window: usize) -> Running {
        Running {
            window: window.max(1),
            frames: std::collections::VecDeque::new(),
        }
    }

    pub fn push(&mut self, s: LightSample) {
        if self.frames.len() == self.window {
            self.frames.pop_front();
        }
        self.frames.push_back(s);
    }

    /// Forgets the frames (the light or its technique's options changed).
    pub fn clear(&mut self) {
        self.frames.clear();
    }

    pub fn frames(&self) -> usize {
        self.frames.len()
    }

    /// The error over the window's frames, each weighted by its receivers.
    pub fn estimate(&self) -> Option<Interval> {
        if self.frames.is_empty() {
            return None;
        }
        let parts: Vec<LightSample> = self.frames.iter().copied().collect();
        Some(pooled(&parts))
    }

    /// The share lit through alpha-tested casters' holes over the window's frames.
    pub fn alpha_holes(&self) -> Option<Interval> {
        if self.frames.is_empty() {
            return None;
        }
        let parts: Vec<LightSample> = self.frames.iter().copied().collect();
        Some(pooled_by(&parts, |p| p.alpha_holes.value))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_matches_a_worked_value_and_closes_when_exact() {
        // 10 wrong of 100: Wilson's 95% interval is [0.0552, 0.1744].
        let i = Interval::wilson(0.1, 100.0, false);
        assert!((i.low - 0.0552).abs() < 5e-4, "{i:?}");
        assert!((i.high - 0.1744).abs() < 5e-4, "{i:?}");
        // Nothing wrong in 512: the upper end is about 3.7/512, not 0.
        let z = Interval::wilson(0.0, 512.0, false);
        assert_eq!(z.low, 0.0);
        assert!(z.high > 0.006 && z.high < 0.008, "{z:?}");
        let e = Interval::wilson(0.25, 4.0, true);
        assert_eq!((e.low, e.high), (0.25, 0.25));
    }

    #[test]
    fn strata_cover_the_pixels_evenly_and_every_pixel_when_few() {
        let pixels: Vec<u32> = (0..1000).collect();
        let mut rng = fastrand::Rng::with_seed(7);
        let picks = stratified(1000, 100, &mut rng, |k| pixels.get(k).copied());
        assert_eq!(picks.len(), 100);
        for (k, (p, w)) in picks.iter().enumerate() {
            assert_eq!(*w, 10.0);
            assert_eq!(*p as usize / 10, k, "pick {k} outside its stratum");
        }
        let all = stratified(50, 100, &mut rng, |k| pixels.get(k).copied());
        assert_eq!(all.len(), 50);
        assert!(all.iter().all(|p| p.1 == 1.0));
    }

    #[test]
    fn pooled_shares_weigh_lights_by_receivers() {
        let part = |receivers: f64, value: f64, exact: bool| LightSample {
            light: 0,
            receivers,
            samples: 100,
            effective: 100.0,
            exact,
            error: Interval::wilson(value, 100.0, exact),
            alpha_holes: Interval::default(),
        };
        let p = pooled(&[part(300.0, 0.1, false), part(100.0, 0.5, false)]);
        assert!((p.value - 0.2).abs() < 1e-12);
        assert!(p.low < 0.2 && p.high > 0.2);
        let e = pooled(&[part(100.0, 0.1, true), part(100.0, 0.3, true)]);
        assert_eq!((e.value, e.low, e.high), (0.2, 0.2, 0.2));
    }
}
