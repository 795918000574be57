//! `tune`: the price of accuracy on one scene. A budgeted search of the option space (technique,
//! map size, depth bits, filter, offsets, caster faces, omni views, what the map stores
//! (depth, IDs, priorities); counting, stencil passes, edge rule, casters; the planner) by successive halving: many random configurations measured
//! cheaply (few frames), the better half by Pareto rank (error, then time) measured again with
//! more frames, until a few remain, which are measured in full (round-robin timing, the exact
//! reference on the first frame, the sampled one along the path). Their Pareto frontier says, for
//! each step of error, what it costs in time.

use super::bench::{Bench, BenchConfig, BenchRow, BenchSettings, Kept};
use crate::options::{Candidate, OptionError, Options, Technique};
use crate::run::{RenderError, Renderer};
use crate::scene::Scene;
use crate::scene::path::PathKey;
use indicatif::ProgressBar;
use serde::Serialize;
use std::collections::{BTreeMap, HashSet};
use std::time::Instant;

/// One searched option: its key, its values, and the techniques it matters to.
#[derive(Debug, Clone)]
pub struct Dimension {
    pub key: &'static str,
    pub values: &'static [&'static str],
    pub scope: Scope,
}

/// The techniques an option matters to: a draw sets it only for those, so that two
/// configurations never differ in an option their technique ignores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    Every,
    /// Every technique that draws maps (the map options).
    Maps,
    /// Every technique that counts volumes (the volume options).
    Volumes,
    Only(Technique),
}

impl Scope {
    fn applies(self, t: Technique) -> bool {
        match self {
            Scope::Every => true,
            Scope::Maps => t.uses_maps(),
            Scope::Volumes => t.uses_volumes(),
            Scope::Only(own) => own == t,
        }
    }
}

const fn dim(key: &'static str, values: &'static [&'static str], scope: Scope) -> Dimension {
    Dimension { key, values, scope }
}

const SM: Scope = Scope::Maps;
const SV: Scope = Scope::Volumes;

/// The option space searched: the choices the reports show to matter for time or error.
pub fn space() -> Vec<Dimension> {
    vec![
        dim("shadow_map.size", &["256", "512", "1024", "2048"], SM),
        dim("shadow_map.depth_bits", &["16", "24", "32f"], SM),
        dim("shadow_map.filter", &["nearest", "hw2x2", "pcf3x3"], SM),
        dim("shadow_map.offset_factor", &["0", "1.1", "2", "4"], SM),
        dim("shadow_map.offset_units", &["0", "4", "16", "64"], SM),
        dim("shadow_map.cull", &["both", "front", "back"], SM),
        dim("shadow_map.omni", &["six_spots", "cube", "frusta"], SM),
        // What the map stores: standard maps only (`Options::map_buffer`).
        dim(
            "shadow_map.buffer",
            &["depth", "id", "priority", "priority_depth"],
            Scope::Only(Technique::ShadowMap),
        ),
        dim("shadow_volume.counting", &["zfail", "zpass", "auto"], SV),
        dim("shadow_volume.stencil", &["two_pass", "separate"], SV),
        dim("shadow_volume.edge_rule", &["paper", "signed"], SV),
        dim("shadow_volume.casters", &["front", "both"], SV),
        dim(
            "psm.min_near",
            &["0.01", "0.05", "0.2"],
            Scope::Only(Technique::Psm),
        ),
        dim(
            "psm.tsm_focus",
            &["0.1", "0.2", "0.5"],
            Scope::Only(Technique::Tsm),
        ),
        dim("hybrid.radius", &["1", "2"], Scope::Only(Technique::Hybrid)),
        dim("plan.enabled", &["true", "false"], Scope::Every),
    ]
}

/// The techniques searched: the thesis's four, trapezoidal maps and Vector's subdivision.
pub const TECHNIQUES: [Technique; 6] = [
    Technique::ShadowMap,
    Technique::ShadowVolume,
    Technique::Psm,
    Technique::Tsm,
    Technique::Hybrid,
    Technique::Subdivision,
];

/// A configuration of the space: `base` with the values set; its label names the technique and
/// the values that differ from `base`.
fn config_of(base: &Options, sets: &BTreeMap<String, String>) -> Result<BenchConfig, OptionError> {
    let mut options = base.clone();
    let mut swept = BTreeMap::new();
    for (k, v) in sets {
        options.set(k, v)?;
        let value = options.get(k)?;
        if k == "technique" || value != base.get(k)? {
            swept.insert(k.clone(), value);
        }
    }
    Ok(BenchConfig {
        name: None,
        swept,
        options,
    })
}

/// `count` distinct configurations drawn from `space` over `base` (seeded), the first of each
/// technique its defaults in `base`.
pub fn candidates(
    base: &Options,
    space: &[Dimension],
    count: usize,
    seed: u64,
) -> Result<Vec<BenchConfig>, OptionError> {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    // Distinct by the options they give (two draws may differ only where `base` agrees).
    let key = |c: &BenchConfig| serde_json::to_string(&c.options).unwrap_or_default();
    for t in TECHNIQUES {
        let sets = BTreeMap::from([("technique".to_string(), t.to_string())]);
        let c = config_of(base, &sets)?;
        seen.insert(key(&c));
        out.push(c);
    }
    // Stops when the space is exhausted, however large `count` is.
    let mut tries = 0;
    while out.len() < count && tries < count * 50 {
        tries += 1;
        let t = TECHNIQUES[rng.usize(..TECHNIQUES.len())];
        let mut sets = BTreeMap::from([("technique".to_string(), t.to_string())]);
        for d in space.iter().filter(|d| d.scope.applies(t)) {
            sets.insert(
                d.key.to_string(),
                d.values[rng.usize(..d.values.len())].to_string(),
            );
        }
        let c = config_of(base, &sets)?;
        if seen.insert(key(&c)) {
            out.push(c);
        }
    }
    Ok(out)
}

/// Each point's Pareto rank on (error, time), both lower better: 0 for the points no other
/// dominates, 1 for those only rank-0 points dominate, and so on.
pub fn pareto_ranks(points: &[(f64, f64)]) -> Vec<usize> {
    let dominates =
        |a: (f64, f64), b: (f64, f64)| a.0 <= b.0 && a.1 <= b.1 && (a.0 < b.0 || a.1 < b.1);
    let mut rank = vec![usize::MAX; points.len()];
    let mut r = 0;
    while rank.contains(&usize::MAX) {
        let open: Vec<usize> = (0..points.len())
            .filter(|&i| rank[i] == usize::MAX)
            .collect();
        let front: Vec<usize> = open
            .iter()
            .copied()
            .filter(|&i| !open.iter().any(|&j| dominates(points[j], points[i])))
            .collect();
        for i in front {
            rank[i] = r;
        }
        r += 1;
    }
    rank
}

/// The indices of the `keep` best points: by Pareto rank, then by error (the nearer the
/// accuracy end of a front, the later a configuration is dropped), then by time.
pub fn best(points: &[(f64, f64)], keep: usize) -> Vec<usize> {
    let rank = pareto_ranks(points);
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        rank[a]
            .cmp(&rank[b])
            .then(points[a].0.total_cmp(&points[b].0))
            .then(points[a].1.total_cmp(&points[b].1))
    });
    order.truncate(keep);
    order.sort();
    order
}

/// Who goes on after a rung: the better half (never fewer than `finalists`), or after the last
/// rung the `finalists` best. Chosen by rank here: `best` returns them in draw order, so cutting
/// its list afterwards would keep the first drawn, not the best.
pub fn survivors(points: &[(f64, f64)], last: bool, finalists: usize) -> Vec<usize> {
    let keep = if last {
        finalists
    } else {
        (points.len() / 2).max(finalists)
    };
    best(points, keep)
}

/// (error, median frame ms) of a measured row: the exact reference's error on the first frame.
pub fn point(r: &BenchRow) -> (f64, f64) {
    (r.error.total, r.frame_ms.median)
}

/// How the search spends its time.
#[derive(Debug, Clone, Serialize)]
pub struct TuneSettings {
    /// Configurations drawn for the first rung.
    pub candidates: usize,
    /// Measured frames per configuration on each rung; the halving stops at the last rung or
    /// when `finalists` or fewer remain.
    pub rung_frames: Vec<usize>,
    /// How many are measured in full at the end.
    pub finalists: usize,
    /// Measured frames of the final round (round-robin).
    pub final_frames: usize,
    /// Time the finalists pass by pass too (`pass_ms`, one frame per measured frame, each
    /// pass between two glFinish calls where timer queries do not work) and with frames in
    /// flight (`pipelined_ms`). `reproduce`'s frontier shows neither, so it sets this off.
    pub breakdown: bool,
    pub seed: u64,
    /// Also measure, per light, the map sizes and filters of `per_light_configs` and name each
    /// light's cheapest within `accuracy`.
    pub per_light: bool,
    /// The target, in percent of receiver pixels (for the per-light choice).
    pub accuracy: f64,
    /// Camera poses, cycled through.
    #[serde(skip)]
    pub path: Vec<PathKey>,
    /// MiB the final round's renderers may hold together (maps, volumes and fragments, as
    /// the rungs measured each finalist): past it the finalists are timed a group at a time
    /// (`BenchSettings::memory_mb`). Each renderer's own maps stay within
    /// `shadow_map.budget_mb`.
    pub memory_mb: Option<f32>,
    /// A candidate's frames stop once they add up to this many seconds, on a still camera
    /// (`BenchSettings::enough_seconds`).
    pub enough_seconds: Option<f64>,
}

/// `TuneSettings::memory_mb` unless told otherwise: with a renderer's maps within
/// `shadow_map.budget_mb` (512 by default) and the scene's images shared, aiming at a
/// search of oa_dm3 within 2 GiB (docs/reproduce.md, "Memory", says what it reached).
pub const DEFAULT_MEMORY_MB: f32 = 512.0;

impl TuneSettings {
    /// A search of `candidates` configurations along `path`.
    pub fn new(candidates: usize, path: Vec<PathKey>) -> TuneSettings {
        TuneSettings {
            candidates,
            rung_frames: vec![2, 4],
            finalists: 8,
            final_frames: 8,
            breakdown: true,
            seed: 1,
            per_light: true,
            accuracy: 0.5,
            path,
            memory_mb: Some(DEFAULT_MEMORY_MB),
            enough_seconds: Some(crate::report::bench::ENOUGH_SECONDS),
        }
    }
}

/// What one rung measured.
#[derive(Debug, Clone, Serialize)]
pub struct Rung {
    /// `halving`, `final` or `per light`.
    pub stage: &'static str,
    pub configurations: usize,
    pub frames: usize,
    /// Configurations kept for the next stage (per light: lights answered).
    pub kept: usize,
    /// Configurations whose row the rung before stands for, not measured again: their frames
    /// stopped short of that rung's at `enough_seconds`, so this rung would take as many
    /// frames of the same still view.
    pub carried: usize,
    /// Error frames it drew (configurations whose error an earlier rung took drew none).
    pub error_frames: usize,
    pub seconds: f64,
}

/// The search's outcome: the finalists measured in full and which of them are on the frontier.
#[derive(Debug, Clone, Serialize)]
pub struct TuneResult {
    pub scene: String,
    pub settings: TuneSettings,
    pub rungs: Vec<Rung>,
    pub rows: Vec<BenchRow>,
    /// Per row, whether it is on the Pareto frontier of the finalists.
    pub frontier: Vec<bool>,
    /// Per light, the cheapest of `per_light_configs` within the target (when asked for).
    pub per_light: Vec<LightChoice>,
    /// The same among the configurations a frame can give each light its own of: the
    /// scene's filter (one for every light) at any map size, or volumes. Their `entry`s,
    /// joined, are the `lighting.techniques` that draws them ([`lighting_techniques`]).
    pub per_light_drawable: Vec<LightChoice>,
}

/// One light's cheapest configuration within the target, by its own error and pass times.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LightChoice {
    pub light: usize,
    pub label: String,
    /// The light's error against the exact reference on the first frame (a fraction).
    pub error: f64,
    /// Median milliseconds of the light's own passes.
    pub ms: f64,
    /// False where nothing met the target: then the most accurate.
    pub meets: bool,
    /// Its `lighting.techniques` entry: `3:shadow_map@1024`, `5:shadow_volume`.
    pub entry: String,
}

/// The `lighting.techniques` value that gives each light of `choices` its own.
pub fn lighting_techniques(choices: &[LightChoice]) -> String {
    choices
        .iter()
        .map(|c| c.entry.as_str())
        .collect::<Vec<_>>()
        .join(",")
}

/// Light `light`'s `lighting.techniques` entry for a row's options: its candidate as
/// `auto_among` writes it, with the map size for standard maps.
fn entry_of(light: usize, options: &Options) -> String {
    let candidate = Candidate::of(options.technique, options);
    match options.technique {
        Technique::ShadowMap => format!("{light}:{}", candidate.sized(options.shadow_map.size)),
        _ => format!("{light}:{candidate}"),
    }
}

/// Map sizes and filters measured per light.
const PER_LIGHT_SIZES: [&str; 4] = ["256", "512", "1024", "2048"];
const PER_LIGHT_FILTERS: [&str; 3] = ["nearest", "hw2x2", "pcf3x3"];

/// The configurations measured per light: shadow volumes as `base` has them, and shadow maps at
/// every size and filter of the grid.
pub fn per_light_configs(base: &Options) -> Result<Vec<BenchConfig>, OptionError> {
    let mut out = vec![config_of(
        base,
        &BTreeMap::from([("technique".into(), "shadow_volume".into())]),
    )?];
    for size in PER_LIGHT_SIZES {
        for filter in PER_LIGHT_FILTERS {
            out.push(config_of(
                base,
                &BTreeMap::from([
                    ("technique".into(), "shadow_map".into()),
                    ("shadow_map.size".into(), size.into()),
                    ("shadow_map.filter".into(), filter.into()),
                ]),
            )?);
        }
    }
    Ok(out)
}

/// Milliseconds of light `light`'s own passes in a row (its `light<i>.*` entries).
pub fn light_ms(row: &BenchRow, light: usize) -> f64 {
    let prefix = format!("light{light}.");
    row.pass_ms
        .iter()
        .filter(|(k, _)| k.starts_with(&prefix))
        .map(|(_, ms)| ms)
        .sum()
}

/// Per light, among `rows`, the cheapest whose error for that light is at most `target` (a
/// fraction); the most accurate where none is.
pub fn per_light_choices(rows: &[BenchRow], target: f64) -> Vec<LightChoice> {
    let mut lights: Vec<usize> = rows
        .iter()
        .flat_map(|r| r.error_per_light.iter().map(|(l, _)| *l))
        .collect();
    lights.sort_unstable();
    lights.dedup();
    lights
        .into_iter()
        .filter_map(|light| {
            let options: Vec<LightChoice> = rows
                .iter()
                .filter_map(|r| {
                    let (_, e) = r.error_per_light.iter().find(|(l, _)| *l == light)?;
                    // A light with no receiver in view has nothing to choose.
                    (e.receiver_pixels > 0).then(|| LightChoice {
                        light,
                        label: r.label.clone(),
                        error: e.total,
                        ms: light_ms(r, light),
                        meets: e.total <= target,
                        entry: entry_of(light, &r.options),
                    })
                })
                .collect();
            let meeting = options
                .iter()
                .filter(|c| c.meets)
                .min_by(|a, b| a.ms.total_cmp(&b.ms));
            meeting
                .or_else(|| options.iter().min_by(|a, b| a.error.total_cmp(&b.error)))
                .cloned()
        })
        .collect()
}

impl TuneResult {
    /// The frontier's rows, fastest first.
    pub fn frontier_rows(&self) -> Vec<&BenchRow> {
        let mut f: Vec<&BenchRow> = self
            .rows
            .iter()
            .zip(&self.frontier)
            .filter(|(_, on)| **on)
            .map(|(r, _)| r)
            .collect();
        f.sort_by(|a, b| a.frame_ms.median.total_cmp(&b.frame_ms.median));
        f
    }

    /// The fastest frontier configuration whose error is at most `accuracy` percent.
    pub fn cheapest_meeting(&self, accuracy: f64) -> Option<&BenchRow> {
        self.frontier_rows()
            .into_iter()
            .find(|r| 100.0 * r.error.total <= accuracy)
    }
}

/// How one stage of the search measures.
struct Stage {
    name: &'static str,
    /// Shown on the progress bar.
    prefix: String,
    frames: usize,
    /// Round-robin timing, each configuration on a renderer of its own.
    interleave: bool,
    /// The per-pass frames (`pass_ms`).
    breakdown: bool,
}

/// Measures `configs` for one stage, but for those `carried` holds a row of (one entry per
/// configuration, or none at all); the stage's record says how many it kept as all of them
/// (the caller sets it where it keeps fewer).
fn measure_stage(
    renderer: &mut Renderer,
    scene: &Scene,
    settings: &TuneSettings,
    (configs, carried): (&[BenchConfig], &[Option<BenchRow>]),
    stage: Stage,
    bar: &ProgressBar,
    kept: &mut Kept,
) -> Result<(Vec<BenchRow>, Rung), RenderError> {
    let start = Instant::now();
    let is_carried = |i: usize| carried.get(i).is_some_and(Option::is_some);
    let todo: Vec<BenchConfig> = (0..configs.len())
        .filter(|&i| !is_carried(i))
        .map(|i| configs[i].clone())
        .collect();
    bar.set_length(todo.len() as u64);
    bar.set_position(0);
    bar.set_prefix(stage.prefix);
    let bench = BenchSettings {
        warmup: 1,
        frames: stage.frames,
        path: settings.path.clone(),
        progress: false,
        interleave: stage.interleave,
        breakdown: stage.breakdown,
        // Throughput ranks nothing: the rows that report it are the final round's.
        pipelined: stage.breakdown,
        // The scene as loaded: tune compares techniques, the path moves the camera.
        motion: false,
        sample_every: 1,
        memory_mb: settings.memory_mb,
        enough_seconds: settings.enough_seconds,
    };
    let mut bench = Bench::new(renderer, scene, bench).with_kept(std::mem::take(kept));
    let measured = bench.run_with(&todo, bar);
    let error_frames = bench.error_frames();
    *kept = bench.take_kept();
    let rows = fill_gaps(carried, configs.len(), measured?);
    let rung = Rung {
        stage: stage.name,
        configurations: configs.len(),
        frames: stage.frames,
        kept: configs.len(),
        carried: configs.len() - todo.len(),
        error_frames,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((rows, rung))
}

/// The rows of `count` configurations: each carried row where `carried` has one, the next of
/// `measured` (in order) elsewhere.
fn fill_gaps(carried: &[Option<BenchRow>], count: usize, measured: Vec<BenchRow>) -> Vec<BenchRow> {
    let mut measured = measured.into_iter();
    (0..count)
        .filter_map(|i| match carried.get(i) {
            Some(Some(row)) => Some(row.clone()),
            _ => measured.next(),
        })
        .collect()
}

/// Of `rows` (measured over `frames` frames each), those whose frames stopped short at
/// `enough_seconds`, for the configurations `kept` (their indices) in the next rung.
fn carry(rows: &[BenchRow], frames: usize, kept: &[usize]) -> Vec<Option<BenchRow>> {
    kept.iter()
        .map(|&i| rows.get(i).filter(|r| r.frames < frames).cloned())
        .collect()
}

/// Runs the search on `scene` over `base`.
pub fn tune(
    renderer: &mut Renderer,
    scene: &Scene,
    base: &Options,
    settings: &TuneSettings,
    bar: &ProgressBar,
) -> Result<TuneResult, TuneError> {
    tune_keeping(renderer, scene, base, settings, bar, &mut Kept::default())
}

/// [`tune`], reusing and adding to what `kept` holds (rows kept by content, and the exact
/// masks and errors of the same scene's view): each candidate's error frame is drawn once,
/// not once per rung, and a configuration kept before is not measured again.
pub fn tune_keeping(
    renderer: &mut Renderer,
    scene: &Scene,
    base: &Options,
    settings: &TuneSettings,
    bar: &ProgressBar,
    kept: &mut Kept,
) -> Result<TuneResult, TuneError> {
    let mut base = base.clone();
    // The halving ranks by the exact error of the first frame; sampling the path is for the
    // final round only. On one still view the path is that frame: its masks, sampled as the
    // rungs draw them (tracing takes milliseconds), are the final round's sample, so no
    // finalist's error frame is drawn again (on oa_dm3 a paper's-frame finalist's takes 3-40 s).
    let samples = base.estimate.samples;
    if settings.path.len() > 1 {
        base.estimate.samples = 0;
    }
    let mut configs = candidates(&base, &space(), settings.candidates, settings.seed)?;
    let mut rungs = Vec::new();
    let mut carried = Vec::new();
    for (k, &frames) in settings.rung_frames.iter().enumerate() {
        if configs.len() <= settings.finalists {
            break;
        }
        // The rungs rank by frame time and error only: no pass breakdown.
        let stage = Stage {
            name: "halving",
            prefix: format!("rung {}: {frames} frames", rungs.len() + 1),
            frames,
            interleave: false,
            breakdown: false,
        };
        let (rows, mut rung) = measure_stage(
            renderer,
            scene,
            settings,
            (&configs, &carried),
            stage,
            bar,
            kept,
        )?;
        let points: Vec<(f64, f64)> = rows.iter().map(point).collect();
        let last = k + 1 == settings.rung_frames.len();
        let kept = survivors(&points, last, settings.finalists);
        rung.kept = kept.len();
        rungs.push(rung);
        carried = carry(&rows, frames, &kept);
        configs = kept.into_iter().map(|i| configs[i].clone()).collect();
    }
    if configs.len() > settings.finalists {
        // No rung measured them (`rung_frames` is empty): the first drawn.
        configs.truncate(settings.finalists);
    }
    for c in &mut configs {
        c.options.estimate.samples = samples;
    }
    let stage = Stage {
        name: "final",
        prefix: "final, round-robin".into(),
        frames: settings.final_frames,
        interleave: true,
        breakdown: settings.breakdown,
    };
    let (rows, rung) = measure_stage(renderer, scene, settings, (&configs, &[]), stage, bar, kept)?;
    rungs.push(rung);
    let ranks = pareto_ranks(&rows.iter().map(point).collect::<Vec<_>>());
    let (per_light, per_light_drawable) = if settings.per_light {
        let configs = per_light_configs(&base)?;
        // One after another on one renderer: the passes are timed one by one anyway.
        let stage = Stage {
            name: "per light",
            prefix: "per light: map sizes and filters".into(),
            frames: settings.final_frames,
            interleave: false,
            breakdown: true,
        };
        let (light_rows, mut rung) =
            measure_stage(renderer, scene, settings, (&configs, &[]), stage, bar, kept)?;
        let target = settings.accuracy / 100.0;
        let choices = per_light_choices(&light_rows, target);
        let filter = base.shadow_map.filter;
        let drawable: Vec<BenchRow> = light_rows
            .into_iter()
            .filter(|r| {
                r.options.technique != Technique::ShadowMap || r.options.shadow_map.filter == filter
            })
            .collect();
        rung.kept = choices.len();
        rungs.push(rung);
        (choices, per_light_choices(&drawable, target))
    } else {
        (Vec::new(), Vec::new())
    };
    Ok(TuneResult {
        scene: scene.name.clone(),
        settings: settings.clone(),
        rungs,
        frontier: ranks.iter().map(|r| *r == 0).collect(),
        rows,
        per_light,
        per_light_drawable,
    })
}

#[derive(Debug, thiserror::Error)]
pub enum TuneError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Option(#[from] OptionError),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranks_peel_fronts_in_order() {
        // (error, time): a and b trade off, c is dominated by a only, d by all.
        let pts = [(0.1, 5.0), (0.5, 1.0), (0.2, 6.0), (0.6, 7.0)];
        assert_eq!(pareto_ranks(&pts), vec![0, 0, 1, 2]);
        // Equal points dominate neither.
        assert_eq!(pareto_ranks(&[(1.0, 1.0), (1.0, 1.0)]), vec![0, 0]);
        assert_eq!(best(&pts, 3), vec![0, 1, 2]);
        assert_eq!(best(&pts, 1), vec![0]);
    }

    #[test]
    fn each_light_takes_its_cheapest_configuration_within_the_target() {
        use crate::report::bench::{ErrorRow, test_row};
        // (light, error, ms) per light of a row.
        let row = |label: &str, lights: &[(usize, f64, f64)]| {
            let mut r = test_row("shadow_map", label, 1.0, 0.0);
            for &(l, e, ms) in lights {
                let err = ErrorRow {
                    receiver_pixels: 100,
                    total: e,
                    ..ErrorRow::default()
                };
                r.error_per_light.push((l, err));
                r.pass_ms.insert(format!("light{l}.lit"), ms / 2.0);
                r.pass_ms.insert(format!("light{l}.shadow_map"), ms / 2.0);
                // Sums over lights must not count as a light's own.
                r.pass_ms.insert("lights.lit".into(), 99.0);
            }
            r
        };
        let mut rows = [
            row("small", &[(0, 0.02, 1.0), (1, 0.004, 1.0)]),
            row("large", &[(0, 0.008, 3.0), (1, 0.001, 3.0)]),
            row("volumes", &[(0, 0.0001, 5.0), (1, 0.0, 2.0)]),
        ];
        for (r, (technique, size)) in rows.iter_mut().zip([
            (Technique::ShadowMap, 256),
            (Technique::ShadowMap, 2048),
            (Technique::ShadowVolume, 512),
        ]) {
            r.options.technique = technique;
            r.options.shadow_map.size = size;
        }
        let c = per_light_choices(&rows, 0.01);
        let picks: Vec<(usize, &str, bool)> = c
            .iter()
            .map(|c| (c.light, c.label.as_str(), c.meets))
            .collect();
        assert_eq!(picks, vec![(0, "large", true), (1, "small", true)]);
        assert_eq!(c[0].ms, 3.0);
        // What draws them: each light's own map size.
        assert_eq!(
            lighting_techniques(&c),
            "0:shadow_map@2048,1:shadow_map@256"
        );
        // Nothing within 0.001% for light 0: the most accurate.
        let strict = per_light_choices(&rows, 0.00001);
        assert_eq!(strict[0].label, "volumes");
        assert_eq!(strict[0].entry, "0:shadow_volume");
        assert!(!strict[0].meets);
    }

    #[test]
    fn the_last_rung_keeps_the_best_finalists_not_the_first_drawn() {
        // The two best points were drawn last.
        let pts = [
            (0.5, 9.0),
            (0.6, 8.0),
            (0.7, 7.0),
            (0.8, 6.0),
            (0.01, 1.0),
            (0.02, 0.5),
        ];
        assert_eq!(survivors(&pts, true, 2), vec![4, 5]);
        // Before the last: the better half (the front, then the most accurate of the next).
        assert_eq!(survivors(&pts, false, 2), vec![0, 4, 5]);
    }

    #[test]
    fn candidates_are_distinct_and_set_only_their_techniques_options() {
        let base = Options::default();
        let c = candidates(&base, &space(), 40, 3).unwrap();
        assert_eq!(c.len(), 40);
        assert_eq!(c[0].options.technique, Technique::ShadowMap);
        assert_eq!(c[0].swept.len(), 1);
        let mut seen = HashSet::new();
        for k in &c {
            let options = serde_json::to_string(&k.options).unwrap();
            assert!(seen.insert(options), "{:?} twice", k.swept);
            let t = k.options.technique;
            for key in k.swept.keys() {
                let forbidden = [
                    ("shadow_map.", !t.uses_maps()),
                    ("shadow_volume.", !t.uses_volumes()),
                    ("shadow_map.buffer", t != Technique::ShadowMap),
                    ("psm.min_near", t != Technique::Psm),
                    ("psm.tsm_focus", t != Technique::Tsm),
                    ("hybrid.", t != Technique::Hybrid),
                ];
                for (prefix, no) in forbidden {
                    assert!(!(no && key.starts_with(prefix)), "{t} sets {key}");
                }
            }
        }
        // The same seed, the same draw.
        let again = candidates(&base, &space(), 40, 3).unwrap();
        assert!(c.iter().zip(&again).all(|(a, b)| a.swept == b.swept));
    }
}
