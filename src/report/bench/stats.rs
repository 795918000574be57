//! The statistics bench reports of a run of frame times: median, spread, tail, and each
//! frame's ratio to the shadows-off frame.

use serde::Serialize;

/// Frame times of the measured frames: median, spread and the tail a person sees as stutter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct MsStats {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    /// 95th and 99th percentiles (nearest rank: the smallest time at least that share of
    /// frames do not exceed).
    pub p95: f64,
    pub p99: f64,
}

impl MsStats {
    /// The 99th percentile over the median (1 for perfectly even frames).
    pub fn p99_over_median(&self) -> f64 {
        if self.median > 0.0 {
            self.p99 / self.median
        } else {
            0.0
        }
    }
}

/// Nearest-rank percentile `q` (0..=1) of sorted `v`.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Median {
    pub median: f64,
}

pub(super) fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

pub(super) fn stats(v: &[f64]) -> MsStats {
    let mut s = v.to_vec();
    MsStats {
        median: median(&mut s),
        min: s.first().copied().unwrap_or(0.0),
        max: s.last().copied().unwrap_or(0.0),
        p95: percentile(&s, 0.95),
        p99: percentile(&s, 0.99),
    }
}

/// Each frame's time over the shadows-off frame at the same path frame (`off_ms[i]` beside
/// `frame_ms[i]`, both indexed by path frame); a frame without a positive baseline counts 0.
pub(super) fn frame_ratios(frame_ms: &[f64], off_ms: &[f64]) -> Vec<f64> {
    debug_assert_eq!(frame_ms.len(), off_ms.len());
    frame_ms
        .iter()
        .zip(off_ms)
        .map(|(ms, off)| if *off > 0.0 { ms / off } else { 0.0 })
        .collect()
}
