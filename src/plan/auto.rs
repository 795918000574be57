//! `technique = auto`: per light, the cheaper technique whose estimated error meets the
//! `accuracy` target. Costs are measured (each light's own pass times, averaged over frames);
//! errors are estimated from what this project measured against the exact reference:
//!
//! - shadow volumes are exact up to rasterization at shadow edges (0.005-0.055% of receivers
//!   on the benchmark maps: 0.05% is assumed), but cannot follow alpha-tested casters (the
//!   built-in grate: 0.75%; 1% is assumed when such casters are in range);
//! - shadow maps alias: 0.41% at 512x512 on oa_dm1, 2.66% at 64x64 and 0.19% at 2048x2048,
//!   which `0.41% × (512 / size)^0.75` follows within a factor 1.4; 16-bit depth multiplies it
//!   by 19 (7.75% against 0.41% on the built-in scene).

use super::pass::PassTime;
use crate::options::{DepthBits, Options, Technique};
use std::collections::HashMap;

/// Weight of the newest frame in the cost average.
const NEWEST: f64 = 0.3;

/// Frames a one-frame command renders first so that `auto` has measured both techniques of
/// every light (one frame each) and then the cheaper again with its caches warm.
pub const LEARNING_FRAMES: usize = 4;

/// Each light's measured milliseconds per technique (an exponential moving average).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CostMemory {
    costs: HashMap<(usize, Technique), f64>,
}

impl CostMemory {
    pub fn cost(&self, light: usize, technique: Technique) -> Option<f64> {
        self.costs.get(&(light, technique)).copied()
    }

    /// Adds a frame's passes: each light's pass times summed, under the technique
    /// the light ran with.
    pub fn record(&mut self, passes: &[PassTime], techniques: &[(usize, Technique)]) {
        let mut per_light: HashMap<usize, f64> = HashMap::new();
        for p in passes {
            if let Some(i) = p.pass.light {
                *per_light.entry(i).or_default() += p.ms;
            }
        }
        for &(light, technique) in techniques {
            if !matches!(technique, Technique::ShadowMap | Technique::ShadowVolume) {
                continue;
            }
            let ms = per_light.get(&light).copied().unwrap_or(0.0);
            self.costs
                .entry((light, technique))
                .and_modify(|e| *e = (1.0 - NEWEST) * *e + NEWEST * ms)
                .or_insert(ms);
        }
    }
}

/// The expected error, as a fraction of receiver pixels, of `technique` for a light.
pub fn estimated_error(technique: Technique, options: &Options, alpha_casters: bool) -> f64 {
    match technique {
        Technique::ShadowVolume => {
            if alpha_casters {
                0.01
            } else {
                0.0005
            }
        }
        Technique::ShadowMap => {
            let o = &options.shadow_map;
            let size = (512.0 / o.size.max(1) as f64).powf(0.75);
            let depth = if o.depth_bits == DepthBits::D16 {
                19.0
            } else {
                1.0
            };
            0.0041 * size * depth
        }
        Technique::None | Technique::Auto => 1.0,
    }
}

/// What `auto` picked for a light, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Choice {
    pub technique: Technique,
    pub reason: String,
}

/// Picks a technique for `light`: among those whose estimated error meets `options.accuracy`
/// (percent), one not yet measured first, else the cheaper; if neither meets it, the more
/// accurate.
pub fn choose(light: usize, options: &Options, memory: &CostMemory, alpha_casters: bool) -> Choice {
    let target = options.accuracy as f64 / 100.0;
    let both = [Technique::ShadowMap, Technique::ShadowVolume];
    let error = |t| estimated_error(t, options, alpha_casters);
    let pct = |x: f64| format!("{:.2}%", 100.0 * x);
    let meeting: Vec<Technique> = both.into_iter().filter(|t| error(*t) <= target).collect();
    if meeting.is_empty() {
        let t = if error(Technique::ShadowMap) <= error(Technique::ShadowVolume) {
            Technique::ShadowMap
        } else {
            Technique::ShadowVolume
        };
        return Choice {
            technique: t,
            reason: format!(
                "neither meets {} (maps ~{}, volumes ~{}): the more accurate",
                pct(target),
                pct(error(Technique::ShadowMap)),
                pct(error(Technique::ShadowVolume))
            ),
        };
    }
    if let Some(t) = meeting.iter().find(|t| memory.cost(light, **t).is_none()) {
        return Choice {
            technique: *t,
            reason: format!(
                "~{} meets {}; cost not measured yet",
                pct(error(*t)),
                pct(target)
            ),
        };
    }
    let cheapest = meeting
        .iter()
        .copied()
        .min_by(|a, b| {
            let (ca, cb) = (memory.cost(light, *a), memory.cost(light, *b));
            ca.unwrap_or(f64::MAX).total_cmp(&cb.unwrap_or(f64::MAX))
        })
        .unwrap_or(Technique::ShadowVolume);
    let costs: Vec<String> = both
        .iter()
        .filter_map(|t| memory.cost(light, *t).map(|c| format!("{t} {c:.2} ms")))
        .collect();
    let missing: Vec<String> = both
        .iter()
        .filter(|t| !meeting.contains(t))
        .map(|t| {
            let why = if *t == Technique::ShadowVolume && alpha_casters {
                " (alpha-tested casters)"
            } else {
                ""
            };
            format!("; {t} ~{} misses it{why}", pct(error(*t)))
        })
        .collect();
    Choice {
        technique: cheapest,
        reason: format!(
            "~{} meets {}; cheapest ({}){}",
            pct(error(cheapest)),
            pct(target),
            costs.join(", "),
            missing.concat()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(name: &str, ms: f64) -> PassTime {
        PassTime {
            pass: super::super::pass::PassId::parse(name).unwrap(),
            ms,
            clock: super::super::pass::Clock::Cpu,
        }
    }

    #[test]
    fn auto_measures_both_then_takes_the_cheaper_that_meets_the_target() {
        let o = Options::default();
        let mut m = CostMemory::default();
        let first = choose(0, &o, &m, false);
        assert_eq!(first.technique, Technique::ShadowMap);
        m.record(
            &[
                pass("light0.shadow_map", 4.0),
                pass("light0.lit", 2.0),
                pass("base", 9.0),
            ],
            &[(0, Technique::ShadowMap)],
        );
        assert_eq!(m.cost(0, Technique::ShadowMap), Some(6.0));
        assert_eq!(choose(0, &o, &m, false).technique, Technique::ShadowVolume);
        m.record(
            &[pass("light0.stencil", 1.0), pass("light0.lit", 2.0)],
            &[(0, Technique::ShadowVolume)],
        );
        let c = choose(0, &o, &m, false);
        assert_eq!(c.technique, Technique::ShadowVolume, "{}", c.reason);
        // Alpha-tested casters in range: volumes' estimate (1%) misses 0.5%, maps' meets it.
        assert_eq!(choose(0, &o, &m, true).technique, Technique::ShadowMap);
        // A target nothing meets: the more accurate.
        let mut strict = o.clone();
        strict.accuracy = 0.01;
        let c = choose(0, &strict, &m, false);
        assert_eq!(c.technique, Technique::ShadowVolume);
        assert!(c.reason.contains("neither"), "{}", c.reason);
    }

    #[test]
    fn the_map_error_estimate_follows_the_measured_sizes() {
        let mut o = Options::default();
        for (size, measured) in [(64, 0.0266), (512, 0.0041), (2048, 0.0019)] {
            o.shadow_map.size = size;
            let e = estimated_error(Technique::ShadowMap, &o, false);
            let ratio = e / measured;
            assert!(
                (0.7..1.45).contains(&ratio),
                "{size}: {e} against {measured}"
            );
        }
    }
}
