//! `technique = auto`: per light, the cheapest technique whose error meets the `accuracy`
//! target. Costs come from a [`CostSource`]: measured (each light's own pass times, averaged
//! over frames) in use, supplied by the caller where the choice must not depend on the
//! machine's speed (tests, a cost model of another GPU). Errors are
//! measured too where the caller samples the frames (`truth::sampled`, recorded with
//! [`AutoMemory::record_errors`]: `render`'s learning frames, `bench`, the viewer); until a
//! technique has been sampled for a light, its error is estimated from what this project
//! measured against the exact reference:
//!
//! - shadow volumes are exact up to rasterization at shadow edges (0.005-0.055% of receivers
//!   on the benchmark maps: 0.05% is assumed), but cannot follow alpha-tested casters (the
//!   built-in grate: 0.75%; 1% is assumed when such casters are in range, until a sampled
//!   frame, under any technique, has counted the light's receivers lit through those casters'
//!   holes: then that share, over the light's last `estimate.window` sampled frames, is added
//!   to the 0.05%);
//! - shadow maps alias: 0.41% at 512x512 on oa_dm1, 2.66% at 64x64 and 0.19% at 2048x2048,
//!   which `0.41% × (512 / size)^0.75` follows within a factor 1.4; 16-bit depth multiplies it
//!   by 19 (7.75% against 0.41% on the built-in scene).
//!
//! The estimates are the same everywhere; the measurements are per light and view, and they
//! differ by far: the paper's edge rule gets 8-38% of some ctf_compromise lights' receivers wrong.
//!
//! `auto_among` may name a map buffer (`shadow_map:id`): each such entry is a candidate of
//! its own, measured and judged apart from `shadow_map` with depth.
//!
//! So that the choice does not flicker: a light keeps the technique it ran with while that
//! one's measured error (the estimate) meets the target, and a technique it did not run with
//! meets the target only when the whole 95% interval does; it moves to a cheaper technique only
//! when that one is cheaper by more than `estimate.hysteresis`.
//!
//! A measurement is of the views it was sampled in: one the light has not added to for
//! `estimate.window` of its sampled frames, while the camera moved, is forgotten, and the
//! technique is judged by its constant again until it runs. Kept, a moment of error along a
//! flythrough sent a light to the dearer technique for the rest of the path (wrackdm17: lights 1
//! and 3 to volumes for 85% of it, the frame 17% over shadow maps alone, whose error over the
//! whole path was 0.21% and 0.04%); on a still camera nothing is forgotten.

use super::pass::PassTime;
use crate::options::{Candidate, DepthBits, MapBuffer, Options, Technique};
use crate::truth::sampled::{Interval, LightSample, Running};
use std::collections::HashMap;

/// Weight of the newest frame in the cost average.
const NEWEST: f64 = 0.3;

/// Frames a one-frame command renders first so that `auto` has measured every technique it
/// chooses among (`auto_among`) for every light, [`WARM_FRAMES`] each, and then the cheapest
/// again with its caches warm: 8 for the default pair.
pub fn learning_frames(options: &Options) -> usize {
    WARM_FRAMES as usize * options.auto_choices().len() + 2
}

/// Frames of a technique before its cost counts. A light's first frame under a technique
/// compiles its programs and draws its maps afresh (kept while the light and its casters stay:
/// `plan.cache_maps`), which later frames do not: the second frame's time replaces the first's.
/// The cost is then the least of the frames after the first: a frame's time only grows with
/// what else the machine runs meanwhile, and one frame taken in such a moment (one in eight on
/// a busy 2-core machine) would otherwise stand for a technique the light no longer runs.
pub const WARM_FRAMES: u32 = 3;

/// A light's sampled error under one technique, and the options it was measured with.
#[derive(Debug, Clone)]
struct MeasuredError {
    /// The technique's option group as measured (a change forgets the measurement).
    options: String,
    running: Running,
    /// The light's sampled frames and the camera's views counted when it was last added to.
    at: (u64, u64),
}

/// Where `auto` takes each light's cost per candidate from.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum CostSource {
    /// The light's own pass times, summed per frame and averaged over frames (the default).
    #[default]
    Measured,
    /// Milliseconds the caller gives per candidate, for every light, and per light where
    /// `per_light` names it; a candidate given no cost is the dearest. Frame times are not
    /// learnt, so the choice depends on the errors and these costs alone, whatever the machine.
    Supplied {
        per_candidate: HashMap<Candidate, f64>,
        per_light: HashMap<(usize, Candidate), f64>,
    },
}

impl CostSource {
    /// The same cost for every light: `(candidate, ms)` pairs.
    pub fn supplied(costs: impl IntoIterator<Item = (Candidate, f64)>) -> CostSource {
        CostSource::Supplied {
            per_candidate: costs.into_iter().collect(),
            per_light: HashMap::new(),
        }
    }

    /// The supplied cost of `candidate` for `light`, if this source supplies costs.
    fn supplied_cost(&self, light: usize, candidate: Candidate) -> Option<Option<f64>> {
        match self {
            CostSource::Measured => None,
            CostSource::Supplied {
                per_candidate,
                per_light,
            } => Some(
                per_light
                    .get(&(light, candidate))
                    .or_else(|| per_candidate.get(&candidate))
                    .copied(),
            ),
        }
    }
}

/// What `auto` has learnt: each light's measured milliseconds per candidate (an exponential
/// moving average), its sampled error per candidate, and the candidate it last ran with.
#[derive(Debug, Clone, Default)]
pub struct AutoMemory {
    source: CostSource,
    costs: HashMap<(usize, Candidate), f64>,
    /// Frames timed per light and candidate.
    frames: HashMap<(usize, Candidate), u32>,
    errors: HashMap<(usize, Candidate), MeasuredError>,
    last: HashMap<usize, Candidate>,
    /// Choices a caller dictates for this frame ([`AutoMemory::follow`]), by light.
    followed: HashMap<usize, Candidate>,
    /// Each light's frames sampled so far.
    sampled: HashMap<usize, u64>,
    /// Each light's last sampled frames, whatever it ran: the share it lights through
    /// alpha-tested casters' holes ([`AutoMemory::alpha_holes`]).
    holes: HashMap<usize, Running>,
    /// Camera poses seen so far (a pose unlike the last counts one), and the last one.
    views: u64,
    camera: Option<[u32; 5]>,
}

/// The volume options an error is measured under, less where the volumes are built and how
/// many are kept (`gpu_extrusion`, `kept_mb`): those change no more than tie pixels at a
/// volume's edge, and `plan.profile` resolves `gpu_extrusion = auto` inside the frame, after
/// the caller who records the error chose its options.
fn volume_options(options: &Options) -> crate::options::ShadowVolumeOptions {
    let mut o = options.shadow_volume.clone();
    o.gpu_extrusion = crate::options::GpuExtrusion::Auto;
    o.kept_mb = 0.0;
    o
}

/// The option group a candidate's error depends on, as text.
fn technique_options(candidate: Candidate, options: &Options) -> String {
    match candidate.technique {
        Technique::ShadowMap => {
            let mut maps = options.shadow_map.clone();
            maps.buffer = candidate.buffer;
            maps.size = candidate.size.unwrap_or(maps.size);
            serde_json::to_string(&maps)
        }
        Technique::ShadowVolume => serde_json::to_string(&volume_options(options)),
        Technique::Psm | Technique::Tsm => {
            serde_json::to_string(&(&options.shadow_map, &options.psm))
        }
        Technique::Hybrid => serde_json::to_string(&(
            &options.shadow_map,
            &volume_options(options),
            &options.hybrid,
        )),
        // The subdivision is exact: no option changes its error.
        Technique::Subdivision | Technique::None | Technique::Auto => Ok(String::new()),
    }
    .unwrap_or_default()
}

impl AutoMemory {
    /// Takes costs from `source` from now on; the costs measured so far are forgotten.
    pub fn set_cost_source(&mut self, source: CostSource) {
        self.source = source;
        self.costs.clear();
    }

    /// Where the costs come from.
    pub fn cost_source(&self) -> &CostSource {
        &self.source
    }

    /// `candidate`'s cost for `light` (a bare technique: its maps store depth): supplied, or
    /// measured.
    pub fn cost(&self, light: usize, candidate: impl Into<Candidate>) -> Option<f64> {
        let candidate = candidate.into();
        match self.source.supplied_cost(light, candidate) {
            Some(supplied) => supplied,
            None => self.costs.get(&(light, candidate)).copied(),
        }
    }

    /// Whether `light` has run [`WARM_FRAMES`] frames with `candidate`: its measured cost is
    /// past its first frames, and its error sampled as often as the others' (a light tries
    /// every candidate in turn until each is warm, whichever source its costs come from).
    pub fn warm(&self, light: usize, candidate: impl Into<Candidate>) -> bool {
        self.frames
            .get(&(light, candidate.into()))
            .is_some_and(|n| *n >= WARM_FRAMES)
    }

    /// The sampled error of `candidate` for `light` under `options`, pooled over the frames
    /// kept; None before it was sampled, after its options changed, or once it is of views
    /// the camera left ([`AutoMemory::stale`]).
    pub fn error(
        &self,
        light: usize,
        candidate: impl Into<Candidate>,
        options: &Options,
    ) -> Option<Interval> {
        let candidate = candidate.into();
        let m = self.errors.get(&(light, candidate))?;
        if m.options != technique_options(candidate, options) || self.stale(light, m, options) {
            return None;
        }
        m.running.estimate()
    }

    /// The share of `light`'s receivers lit through alpha-tested casters' holes over its last
    /// `estimate.window` sampled frames, whatever technique ran: what volumes, which draw
    /// those casters solid, get wrong besides their edges. None before it was sampled.
    pub fn alpha_holes(&self, light: usize) -> Option<Interval> {
        self.holes.get(&light)?.alpha_holes()
    }

    /// Counts the camera's pose: a pose unlike the last one is another view.
    pub fn note_view(&mut self, camera: &crate::scene::Camera) {
        let p = camera.position;
        let key = [p.x, p.y, p.z, camera.yaw_deg, camera.pitch_deg].map(f32::to_bits);
        if self.camera != Some(key) {
            self.camera = Some(key);
            self.views += 1;
        }
    }

    /// Whether `m`, a measurement of `light`, was last added to `estimate.window` or more of
    /// the light's sampled frames ago, with the camera moved since.
    fn stale(&self, light: usize, m: &MeasuredError, options: &Options) -> bool {
        let sampled = self.sampled.get(&light).copied().unwrap_or(0);
        sampled >= m.at.0 + u64::from(options.estimate.window) && self.views != m.at.1
    }

    /// Makes `choices` (light, candidate) this frame's choices for those lights, in place of
    /// judging them (empty: judge every light again). `bench` times a path's frames with the
    /// choices `auto` made when it ran the same frames sampled, so that the times and the
    /// error of its row are of the same choices.
    pub fn follow(&mut self, choices: &[(usize, Candidate)]) {
        self.followed = choices.iter().copied().collect();
    }

    /// The candidate `light` last ran with.
    pub fn last(&self, light: usize) -> Option<Candidate> {
        self.last.get(&light).copied()
    }

    /// Notes the candidate each light of a frame timed whole ran with: no cost to learn, but
    /// the light's current candidate (which the hysteresis keeps) is that one.
    pub fn note_ran(&mut self, ran: &[(usize, Candidate)]) {
        for &(light, candidate) in ran {
            if !matches!(candidate.technique, Technique::None | Technique::Auto) {
                self.last.insert(light, candidate);
            }
        }
    }

    /// Adds a frame's passes: each light's pass times summed, under the candidate the light
    /// ran with.
    pub fn record(&mut self, passes: &[PassTime], ran: &[(usize, Candidate)]) {
        let mut per_light: HashMap<usize, f64> = HashMap::new();
        for p in passes {
            if let Some(i) = p.pass.light {
                *per_light.entry(i).or_default() += p.ms;
            }
        }
        for &(light, candidate) in ran {
            if matches!(candidate.technique, Technique::None | Technique::Auto) {
                continue;
            }
            self.last.insert(light, candidate);
            let frames = self.frames.entry((light, candidate)).or_insert(0);
            *frames += 1;
            let n = *frames;
            if self.source != CostSource::Measured {
                continue;
            }
            let ms = per_light.get(&light).copied().unwrap_or(0.0);
            self.costs
                .entry((light, candidate))
                .and_modify(|e| {
                    *e = match n {
                        0..=2 => ms,
                        _ if n <= WARM_FRAMES => e.min(ms),
                        _ => (1.0 - NEWEST) * *e + NEWEST * ms,
                    }
                })
                .or_insert(ms);
        }
    }

    /// Adds a frame's sampled errors, each light's under the candidate it ran with (`ran`),
    /// pooled over the last `options.estimate.window` frames.
    pub fn record_errors(
        &mut self,
        samples: &[LightSample],
        ran: &[(usize, Candidate)],
        options: &Options,
    ) {
        let window = options.estimate.window as usize;
        for s in samples {
            if s.samples > 0 {
                let holes = self
                    .holes
                    .entry(s.light)
                    .or_insert_with(|| Running::new(window));
                holes.push(*s);
            }
            let Some(&(_, candidate)) = ran.iter().find(|(l, _)| *l == s.light) else {
                continue;
            };
            if matches!(candidate.technique, Technique::None | Technique::Auto) {
                continue;
            }
            let sampled = {
                let n = self.sampled.entry(s.light).or_insert(0);
                *n += u64::from(s.samples > 0);
                *n
            };
            let text = technique_options(candidate, options);
            let fresh = MeasuredError {
                options: text.clone(),
                running: Running::new(window),
                at: (sampled, self.views),
            };
            let forget = match self.errors.get(&(s.light, candidate)) {
                Some(m) => m.options != text || self.stale(s.light, m, options),
                None => true,
            };
            if forget {
                self.errors.insert((s.light, candidate), fresh);
            }
            let views = self.views;
            let m = self
                .errors
                .get_mut(&(s.light, candidate))
                .expect("inserted above");
            m.running.push(*s);
            m.at = (sampled, views);
        }
    }
}

/// The expected error, as a fraction of receiver pixels, of `candidate` for a light.
pub fn estimated_error(
    candidate: impl Into<Candidate>,
    options: &Options,
    alpha_casters: bool,
) -> f64 {
    let candidate = candidate.into();
    match candidate.technique {
        // The subdivision's casters are solid, as the volumes' are.
        Technique::ShadowVolume | Technique::Hybrid | Technique::Subdivision => {
            if alpha_casters {
                0.01
            } else {
                0.0005
            }
        }
        Technique::ShadowMap | Technique::Psm | Technique::Tsm => {
            let o = &options.shadow_map;
            let side = candidate.size.unwrap_or(o.size);
            let size = (512.0 / side.max(1) as f64).powf(0.75);
            let depth = if o.depth_bits == DepthBits::D16 {
                19.0
            } else {
                1.0
            };
            let aliasing = 0.0041 * size * depth;
            match candidate.buffer {
                MapBuffer::Depth => aliasing,
                // Frame 0 of the five benchmark scenes at 512 (docs/id-buffers.md): ID buffers
                // err 1.7-10.7 times as much as depth maps (geometric mean 3.9); ...
                MapBuffer::Id => 4.0 * aliasing,
                // ... priority buffers 3.6-36%, by sorting, not resolution (geometric mean 12.6%).
                MapBuffer::Priority | MapBuffer::PriorityDepth => 0.12,
            }
        }
        Technique::None | Technique::Auto => 1.0,
    }
}

/// Whether `technique` draws alpha-tested casters solid (they cannot follow texture alpha).
fn solid_casters(technique: Technique) -> bool {
    matches!(
        technique,
        Technique::ShadowVolume | Technique::Hybrid | Technique::Subdivision
    )
}

/// What `auto` picked for a light, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Choice {
    pub candidate: Candidate,
    pub reason: String,
}

/// A candidate's error for the choice: measured (with its interval) or estimated.
#[derive(Debug, Clone, Copy)]
struct Judged {
    candidate: Candidate,
    error: Interval,
    measured: bool,
    /// Estimated from the light's sampled share lit through alpha-tested casters' holes.
    holes: bool,
    cost: Option<f64>,
    warm: bool,
}

impl Judged {
    /// Whether it meets `target`: by its estimate when the light runs with it now, by its
    /// whole interval otherwise (the hysteresis on error).
    fn meets(&self, target: f64, current: bool) -> bool {
        if current {
            self.error.value <= target
        } else {
            self.error.high <= target
        }
    }

    fn describe(&self) -> String {
        let e = self.error;
        let err = if self.measured {
            format!(
                "{:.2}% ± {:.2}%",
                100.0 * e.value,
                100.0 * (e.high - e.low) / 2.0
            )
        } else if self.holes {
            format!(
                "~{:.2}% (up to {:.2}%: alpha-tested casters' holes sampled)",
                100.0 * e.value,
                100.0 * e.high
            )
        } else {
            format!("~{:.2}% (estimated)", 100.0 * e.value)
        };
        match self.cost {
            Some(ms) => format!("{} {err} at {ms:.2} ms", self.candidate),
            None => format!("{} {err}", self.candidate),
        }
    }
}

/// Picks a candidate for `light`: one whose cost is not yet measured first; else among those
/// that meet `options.accuracy` (percent) the cheapest, keeping the current one unless another
/// is cheaper by more than `estimate.hysteresis`; if none meets it, the most accurate.
/// A choice the caller dictates ([`AutoMemory::follow`]) stands in place of the judgement.
pub fn choose(light: usize, options: &Options, memory: &AutoMemory, alpha_casters: bool) -> Choice {
    match memory.followed.get(&light) {
        Some(&candidate) => Choice {
            candidate,
            reason: "as told: the choice `auto` made at this frame of a sampled run".into(),
        },
        None => judge(light, options, memory, alpha_casters),
    }
}

/// `t`'s error for `light` as measured, else from the holes sampled (volumes with
/// alpha-tested casters in range), else its constant, with its cost.
fn judge_candidate(
    t: Candidate,
    light: usize,
    options: &Options,
    memory: &AutoMemory,
    alpha_casters: bool,
) -> Judged {
    let measured = memory.error(light, t, options);
    let estimate = estimated_error(t, options, alpha_casters);
    let holes = alpha_casters
        .then(|| solid_casters(t.technique))
        .filter(|solid| *solid)
        .and_then(|_| memory.alpha_holes(light));
    let error = match (measured, holes) {
        (Some(m), _) => m,
        // Solid casters err where the light shines through their holes, as sampled,
        // besides what they err without alpha-tested casters.
        (None, Some(h)) => {
            let base = estimated_error(t, options, false);
            Interval {
                value: base + h.value,
                low: h.low,
                high: base + h.high,
            }
        }
        (None, None) => Interval {
            value: estimate,
            low: estimate,
            high: estimate,
        },
    };
    Judged {
        candidate: t,
        error,
        measured: measured.is_some(),
        holes: measured.is_none() && holes.is_some(),
        cost: memory.cost(light, t),
        warm: memory.warm(light, t),
    }
}

/// [`choose`] by the light's measured (or estimated) errors and costs.
fn judge(light: usize, options: &Options, memory: &AutoMemory, alpha_casters: bool) -> Choice {
    let target = options.accuracy as f64 / 100.0;
    let current = memory.last(light);
    let judged: Vec<Judged> = options
        .auto_choices()
        .iter()
        .map(|&t| judge_candidate(t, light, options, memory, alpha_casters))
        .collect();
    let pct = |x: f64| format!("{:.2}%", 100.0 * x);
    let all = || {
        judged
            .iter()
            .map(Judged::describe)
            .collect::<Vec<_>>()
            .join("; ")
    };
    let meeting: Vec<&Judged> = judged
        .iter()
        .filter(|j| j.meets(target, current == Some(j.candidate)))
        .collect();
    if meeting.is_empty() {
        // A candidate known only by its constant is tried before the measured ones are
        // compared with it: a light with alpha-tested casters in range has volumes estimated
        // at 1%, so that one whose maps measured above the target never ran volumes and kept
        // its maps (q3dm6ish's light 10: 0.84% along the flythrough, 0.001% under volumes).
        if let Some(j) = judged.iter().find(|j| !j.measured && !j.holes && !j.warm) {
            return Choice {
                candidate: j.candidate,
                reason: format!(
                    "none meets {}: {} tried, its error not measured yet ({})",
                    pct(target),
                    j.candidate,
                    all()
                ),
            };
        }
        // The most accurate; the current one unless another is surely better.
        let best = judged
            .iter()
            .min_by(|a, b| a.error.value.total_cmp(&b.error.value))
            .expect("at least one choice");
        let keep = judged
            .iter()
            .find(|j| Some(j.candidate) == current)
            .filter(|c| c.error.low <= best.error.high);
        let t = keep.unwrap_or(best).candidate;
        return Choice {
            candidate: t,
            reason: format!("none meets {}: the most accurate ({})", pct(target), all()),
        };
    }
    if let Some(j) = meeting.iter().find(|j| !j.warm) {
        return Choice {
            candidate: j.candidate,
            reason: format!(
                "{} meets {}; cost not measured yet",
                j.describe(),
                pct(target)
            ),
        };
    }
    let cost = |j: &Judged| j.cost.unwrap_or(f64::MAX);
    let cheapest = meeting
        .iter()
        .copied()
        .min_by(|a, b| cost(a).total_cmp(&cost(b)))
        .expect("some technique meets the target");
    let margin = 1.0 - options.estimate.hysteresis as f64;
    let kept = meeting
        .iter()
        .copied()
        .find(|j| Some(j.candidate) == current)
        .filter(|c| cost(cheapest) >= margin * cost(c));
    let chosen = kept.unwrap_or(cheapest);
    let others: Vec<String> = judged
        .iter()
        .filter(|j| j.candidate != chosen.candidate)
        .map(|j| {
            if meeting.iter().any(|m| m.candidate == j.candidate) {
                return format!("; {} meets it too", j.describe());
            }
            let volumes = j.candidate.technique == Technique::ShadowVolume;
            let why = if volumes && alpha_casters && !j.measured {
                " (alpha-tested casters)"
            } else {
                ""
            };
            format!("; {} misses it{why}", j.describe())
        })
        .collect();
    let how = if kept.is_some() && cheapest.candidate != chosen.candidate {
        "kept (the other is not cheaper by the hysteresis)"
    } else {
        "the cheapest"
    };
    Choice {
        candidate: chosen.candidate,
        reason: format!(
            "{} meets {}: {how}{}",
            chosen.describe(),
            pct(target),
            others.concat()
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
        let mut m = AutoMemory::default();
        let first = choose(0, &o, &m, false);
        assert_eq!(first.candidate.technique, Technique::ShadowMap);
        // The first frame (programs compiled, maps drawn afresh) is replaced by the second.
        m.record(
            &[pass("light0.shadow_map", 40.0)],
            &[(0, Technique::ShadowMap.into())],
        );
        assert_eq!(
            choose(0, &o, &m, false).candidate.technique,
            Technique::ShadowMap
        );
        m.record(
            &[
                pass("light0.shadow_map", 4.0),
                pass("light0.lit", 2.0),
                pass("base", 9.0),
            ],
            &[(0, Technique::ShadowMap.into())],
        );
        assert_eq!(m.cost(0, Technique::ShadowMap), Some(6.0));
        assert_eq!(
            choose(0, &o, &m, false).candidate.technique,
            Technique::ShadowMap
        );
        // A third frame slowed by something else on the machine: the least warm frame stays.
        m.record(
            &[pass("light0.shadow_map", 12.0), pass("light0.lit", 3.0)],
            &[(0, Technique::ShadowMap.into())],
        );
        assert_eq!(m.cost(0, Technique::ShadowMap), Some(6.0));
        assert_eq!(
            choose(0, &o, &m, false).candidate.technique,
            Technique::ShadowVolume
        );
        for _ in 0..WARM_FRAMES {
            m.record(
                &[pass("light0.stencil", 1.0), pass("light0.lit", 2.0)],
                &[(0, Technique::ShadowVolume.into())],
            );
        }
        let c = choose(0, &o, &m, false);
        assert_eq!(
            c.candidate.technique,
            Technique::ShadowVolume,
            "{}",
            c.reason
        );
        // Alpha-tested casters in range: volumes' estimate (1%) misses 0.5%, maps' meets it.
        assert_eq!(
            choose(0, &o, &m, true).candidate.technique,
            Technique::ShadowMap
        );
        // A target nothing meets: the more accurate.
        let mut strict = o.clone();
        strict.accuracy = 0.01;
        let c = choose(0, &strict, &m, false);
        assert_eq!(c.candidate.technique, Technique::ShadowVolume);
        assert!(c.reason.contains("none meets"), "{}", c.reason);
    }

    /// A light's sampled error of `share` over `n` pixels.
    fn sample(share: f64, n: usize) -> LightSample {
        LightSample {
            light: 0,
            receivers: 10_000.0,
            samples: n,
            effective: n as f64,
            exact: false,
            error: Interval::wilson(share, n as f64, false),
            alpha_holes: Interval::default(),
        }
    }

    /// One frame of light 0 under `t` costing `ms`, sampled at `share`.
    fn frame(m: &mut AutoMemory, o: &Options, t: Technique, ms: f64, share: f64) {
        let stage = if t == Technique::ShadowMap {
            "light0.shadow_map"
        } else {
            "light0.stencil"
        };
        m.record(&[pass(stage, ms)], &[(0, t.into())]);
        m.record_errors(&[sample(share, 512)], &[(0, t.into())], o);
    }

    /// A technique's measured miss is forgotten once the light has run another for a window
    /// of sampled frames while the camera moved, and the cheaper one is tried again; on a
    /// still camera it is kept. Made to fail by never forgetting: volumes throughout.
    #[test]
    fn a_miss_measured_in_a_view_the_camera_left_is_forgotten() {
        let o = Options::default();
        let window = o.estimate.window;
        let (still, mut moving) = (AutoMemory::default(), AutoMemory::default());
        let mut memories = [still, std::mem::take(&mut moving)];
        for (k, m) in memories.iter_mut().enumerate() {
            let mut camera = crate::scene::Camera::default();
            m.note_view(&camera);
            // Maps miss at first (2%), volumes meet; maps are the cheaper.
            for _ in 0..WARM_FRAMES {
                frame(m, &o, Technique::ShadowMap, 2.0, 0.02);
                frame(m, &o, Technique::ShadowVolume, 3.0, 0.0);
            }
            let c = choose(0, &o, m, false);
            assert_eq!(
                c.candidate.technique,
                Technique::ShadowVolume,
                "{}",
                c.reason
            );
            // Volumes run until the maps' last sample is a window old.
            for i in 1..window {
                if k == 1 {
                    camera.yaw_deg = i as f32;
                    m.note_view(&camera);
                }
                frame(m, &o, Technique::ShadowVolume, 3.0, 0.0);
            }
        }
        let [still, moving] = memories;
        let kept = choose(0, &o, &still, false);
        assert_eq!(
            kept.candidate.technique,
            Technique::ShadowVolume,
            "{}",
            kept.reason
        );
        assert!(still.error(0, Technique::ShadowMap, &o).is_some());
        let retried = choose(0, &o, &moving, false);
        assert_eq!(
            retried.candidate.technique,
            Technique::ShadowMap,
            "{}",
            retried.reason
        );
        assert!(moving.error(0, Technique::ShadowMap, &o).is_none());
    }

    /// Choices a caller dictates stand in place of the judgement, light by light, until it
    /// dictates none.
    #[test]
    fn followed_choices_stand_until_none_are_given() {
        let o = Options::default();
        let mut m = AutoMemory::default();
        for _ in 0..WARM_FRAMES {
            frame(&mut m, &o, Technique::ShadowMap, 2.0, 0.02);
            frame(&mut m, &o, Technique::ShadowVolume, 3.0, 0.0);
        }
        let judged = choose(0, &o, &m, false);
        assert_eq!(judged.candidate.technique, Technique::ShadowVolume);
        m.follow(&[(0, Technique::ShadowMap.into())]);
        let told = choose(0, &o, &m, false);
        assert_eq!(told.candidate.technique, Technique::ShadowMap);
        assert!(told.reason.contains("as told"), "{}", told.reason);
        // Another light is judged as ever.
        assert!(!choose(1, &o, &m, false).reason.contains("as told"));
        m.follow(&[]);
        assert_eq!(choose(0, &o, &m, false), judged);
    }

    /// With alpha-tested casters in range volumes are estimated at 1%: a light whose maps
    /// measure above the target tries them once its maps are known to miss, and takes them
    /// when their measured error meets it; without samples it keeps the more accurate.
    #[test]
    fn a_candidate_known_only_by_its_constant_is_tried_when_the_measured_one_misses() {
        let o = Options::default();
        let mut m = AutoMemory::default();
        for _ in 0..WARM_FRAMES {
            frame(&mut m, &o, Technique::ShadowMap, 2.0, 0.008);
        }
        let c = choose(0, &o, &m, true);
        assert_eq!(
            c.candidate.technique,
            Technique::ShadowVolume,
            "{}",
            c.reason
        );
        assert!(c.reason.contains("not measured yet"), "{}", c.reason);
        for _ in 0..WARM_FRAMES {
            frame(&mut m, &o, Technique::ShadowVolume, 3.0, 0.0);
        }
        let c = choose(0, &o, &m, true);
        assert_eq!(
            c.candidate.technique,
            Technique::ShadowVolume,
            "{}",
            c.reason
        );
        assert!(c.reason.contains("the cheapest"), "{}", c.reason);
        // Volumes run unsampled, maps sampled: the light's share lit through alpha-tested
        // casters' holes, sampled under maps, stands for the volumes' error. At 2% the maps
        // (0.8%) are the more accurate; at none the volumes meet the target without a try.
        // Made to fail by judging volumes by their constant (1%): maps both times.
        for (holes, expected) in [(0.02, Technique::ShadowMap), (0.0, Technique::ShadowVolume)] {
            let mut only_maps = AutoMemory::default();
            for _ in 0..WARM_FRAMES {
                only_maps.record(
                    &[pass("light0.stencil", 3.0)],
                    &[(0, Technique::ShadowVolume.into())],
                );
                only_maps.record(
                    &[pass("light0.shadow_map", 2.0)],
                    &[(0, Technique::ShadowMap.into())],
                );
                let s = LightSample {
                    alpha_holes: Interval::wilson(holes, 512.0, false),
                    ..sample(0.008, 512)
                };
                only_maps.record_errors(&[s], &[(0, Technique::ShadowMap.into())], &o);
            }
            let c = choose(0, &o, &only_maps, true);
            assert_eq!(c.candidate.technique, expected, "{}", c.reason);
            assert!(c.reason.contains("holes sampled"), "{}", c.reason);
        }
    }

    #[test]
    fn measured_errors_decide_and_the_choice_holds_still_then_follows_them() {
        let o = Options {
            accuracy: 1.0,
            ..Options::default()
        };
        let mut m = AutoMemory::default();
        // Maps cost 2 ms and get 0.2% wrong (four frames: one frame's interval reaches past
        // 1%); volumes 3 ms and nothing wrong.
        for _ in 0..4 {
            frame(&mut m, &o, Technique::ShadowMap, 2.0, 0.002);
        }
        for _ in 0..WARM_FRAMES {
            frame(&mut m, &o, Technique::ShadowVolume, 3.0, 0.0);
        }
        let mut picks = Vec::new();
        for k in 0..20 {
            let c = choose(0, &o, &m, false);
            picks.push(c.candidate.technique);
            // Pass times that wobble by 20% must not flip the choice.
            let wobble = if k % 2 == 0 { 1.2 } else { 0.8 };
            let ms = if c.candidate.technique == Technique::ShadowMap {
                2.0
            } else {
                3.0
            };
            frame(&mut m, &o, c.candidate.technique, ms * wobble, 0.002);
        }
        assert!(
            picks.iter().all(|t| *t == Technique::ShadowMap),
            "{picks:?}"
        );
        // The light moves: its map now gets 6% wrong. The measured error sends it to volumes,
        // and it stays there although the map's last measurement is cheaper.
        for _ in 0..8 {
            frame(&mut m, &o, Technique::ShadowMap, 2.0, 0.06);
        }
        let c = choose(0, &o, &m, false);
        assert_eq!(
            c.candidate.technique,
            Technique::ShadowVolume,
            "{}",
            c.reason
        );
        assert!(c.reason.contains("shadow_map 6.00%"), "{}", c.reason);
        frame(&mut m, &o, Technique::ShadowVolume, 3.0, 0.0);
        assert_eq!(
            choose(0, &o, &m, false).candidate.technique,
            Technique::ShadowVolume
        );
        // A measurement under other map options no longer counts: the estimate does again.
        let mut larger = o.clone();
        larger.shadow_map.size = 2048;
        assert!(m.error(0, Technique::ShadowMap, &larger).is_none());
        assert!(m.error(0, Technique::ShadowMap, &o).is_some());
    }

    #[test]
    fn a_technique_not_running_needs_its_whole_interval_under_the_target() {
        let o = Options {
            accuracy: 1.0,
            ..Options::default()
        };
        let mut m = AutoMemory::default();
        // Volumes run, cost 4 ms. The map costs 1 ms; one frame measured 0.8% on 128 pixels:
        // its interval reaches past 1%, so it does not replace the running volumes.
        for _ in 0..WARM_FRAMES {
            m.record(
                &[pass("light0.shadow_map", 1.0)],
                &[(0, Technique::ShadowMap.into())],
            );
        }
        m.record_errors(
            &[sample(0.008, 128)],
            &[(0, Technique::ShadowMap.into())],
            &o,
        );
        for _ in 0..WARM_FRAMES {
            frame(&mut m, &o, Technique::ShadowVolume, 4.0, 0.0);
        }
        let c = choose(0, &o, &m, false);
        assert_eq!(
            c.candidate.technique,
            Technique::ShadowVolume,
            "{}",
            c.reason
        );
        assert!(c.reason.contains("misses it"), "{}", c.reason);
        // Running, the same 0.8% would meet it: the estimate decides for the current one.
        m.record(
            &[pass("light0.shadow_map", 1.0)],
            &[(0, Technique::ShadowMap.into())],
        );
        assert_eq!(
            choose(0, &o, &m, false).candidate.technique,
            Technique::ShadowMap
        );
    }

    #[test]
    fn a_map_buffer_is_a_candidate_of_its_own() {
        let o = Options {
            accuracy: 1.0,
            auto_among: "shadow_map,shadow_map:id".into(),
            ..Options::default()
        };
        let id = Candidate::maps(MapBuffer::Id);
        let depth = Candidate::from(Technique::ShadowMap);
        // Unmeasured, each is tried in turn: depth maps first, as `auto_among` lists them.
        assert_eq!(
            choose(0, &o, &AutoMemory::default(), false).candidate,
            depth
        );
        // Depth maps without bias on a grazing light: cheaper, but 46% wrong; the ID buffer
        // 0.05%. Each kept apart in the memory.
        let mut m = AutoMemory::default();
        for _ in 0..WARM_FRAMES {
            m.record(&[pass("light0.shadow_map", 2.0)], &[(0, depth)]);
            m.record_errors(&[sample(0.46, 512)], &[(0, depth)], &o);
            m.record(&[pass("light0.shadow_map", 3.0)], &[(0, id)]);
            m.record_errors(&[sample(0.0005, 512)], &[(0, id)], &o);
        }
        assert_eq!(m.cost(0, depth), Some(2.0));
        assert_eq!(m.cost(0, id), Some(3.0));
        let c = choose(0, &o, &m, false);
        assert_eq!(c.candidate, id, "{}", c.reason);
        assert!(c.reason.starts_with("shadow_map:id 0.05%"), "{}", c.reason);
        assert!(c.reason.contains("shadow_map 46.00%"), "{}", c.reason);
        // Unmeasured, an ID buffer is expected to err four times as much as a depth map.
        let ratio = estimated_error(id, &o, false) / estimated_error(depth, &o, false);
        assert_eq!(ratio, 4.0);
    }

    #[test]
    fn supplied_costs_decide_whatever_the_frames_took() {
        let o = Options {
            accuracy: 1.0,
            ..Options::default()
        };
        let maps = Candidate::from(Technique::ShadowMap);
        let volumes = Candidate::from(Technique::ShadowVolume);
        let mut m = AutoMemory::default();
        m.set_cost_source(CostSource::supplied([(maps, 5.0), (volumes, 1.0)]));
        assert_eq!(m.cost(7, volumes), Some(1.0));
        // Each candidate still runs its first frames (its error is sampled meanwhile); frames
        // that took the opposite of the supplied costs are not learnt.
        assert_eq!(choose(0, &o, &m, false).candidate, maps);
        for _ in 0..WARM_FRAMES {
            m.record(&[pass("light0.stencil", 50.0)], &[(0, volumes)]);
            m.record(&[pass("light0.shadow_map", 0.1)], &[(0, maps)]);
        }
        assert!(m.warm(0, maps) && m.warm(0, volumes) && !m.warm(3, maps));
        assert_eq!(m.cost(0, volumes), Some(1.0));
        assert_eq!(m.last(0), Some(maps));
        // Running maps now, volumes are cheaper by more than the hysteresis: volumes.
        assert_eq!(choose(0, &o, &m, false).candidate, volumes);
        for _ in 0..WARM_FRAMES {
            m.record(&[pass("light3.shadow_map", 9.0)], &[(3, maps)]);
            m.record(&[pass("light3.stencil", 0.1)], &[(3, volumes)]);
        }
        // A light of its own: its cost overrides the shared one.
        m.set_cost_source(CostSource::Supplied {
            per_candidate: [(maps, 5.0), (volumes, 1.0)].into(),
            per_light: [((3, maps), 0.5)].into(),
        });
        assert_eq!(choose(3, &o, &m, false).candidate, maps);
        assert_eq!(choose(0, &o, &m, false).candidate, volumes);
        // Back to measuring: nothing supplied is kept as a measurement.
        m.set_cost_source(CostSource::Measured);
        assert_eq!(m.cost(0, volumes), None);
    }

    #[test]
    fn the_map_error_estimate_follows_the_measured_sizes() {
        let mut o = Options::default();
        for (size, measured) in [(64, 0.0266), (512, 0.0041), (2048, 0.0019)] {
            // A candidate's own size (`shadow_map@N`) is estimated as the option's would be.
            let sized = Candidate::from(Technique::ShadowMap).sized(size);
            assert_eq!(
                estimated_error(sized, &o, false).to_bits(),
                {
                    let mut at = o.clone();
                    at.shadow_map.size = size;
                    estimated_error(Technique::ShadowMap, &at, false).to_bits()
                },
                "{size}"
            );
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
