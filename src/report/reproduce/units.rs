//! The run's independent units (a scene's figures and claims, a hard case, a scene's sweep),
//! each measured on its own: all of them in one run, or every N-th in a shard (`--shard K/N`),
//! whose part `merge` joins with the others into the one run's report.

use super::lab::Lab;
use super::{
    Report, ReproduceError, Section, SectionFn, Settings, claims, environment, figures, forsyth,
    io, load_scene, merged_in_order, pareto, summary, thesis, timed,
};
use crate::options::Options;
use crate::report::bench::{BenchRow, Kept, View};
use crate::report::store::RowStore;
use crate::run::Renderer;
use crate::scene::Scene;
use indicatif::ProgressBar;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

/// The part's file name in a shard's `--out` folder.
pub const PART: &str = "part.json";

/// What a unit measures.
#[derive(Clone, Copy)]
enum Kind {
    /// The figures (oa_dm1 only) and the claims measured on this scene.
    Figures(&'static str),
    /// One section on a hard case.
    Hard(&'static str, SectionFn),
    /// The accuracy-against-time sweep, the thesis's comparison and `tune`'s frontier.
    Sweep(&'static str),
}

impl Kind {
    fn name(&self) -> String {
        match self {
            Kind::Figures(scene) => scene.to_string(),
            Kind::Hard(case, _) => case.to_string(),
            Kind::Sweep(scene) => format!("sweep-{scene}"),
        }
    }

    /// Sections the progress bar counts for the unit.
    fn sections(&self) -> usize {
        match self {
            Kind::Figures("oa_dm1") => {
                figures::SECTIONS + 1 + forsyth::SECTIONS / 2 + claims::SECTIONS
            }
            Kind::Figures(_) => claims::SECTIONS,
            Kind::Hard(..) | Kind::Sweep(_) => 1,
        }
    }
}

/// Every unit of a run, in its order.
fn kinds(settings: &Settings) -> Vec<Kind> {
    let mut kinds = vec![Kind::Figures("oa_dm1")];
    if !settings.quick {
        kinds.push(Kind::Figures("q3dm6ish"));
    }
    // ID and priority buffers on the grazing light, where depth maps need their bias most;
    // multiple frusta where the camera faces an omni light; mipmapped priority buffers where
    // shadow stripes are finer than a pixel; perspective shadow maps on the hard case made
    // for them.
    kinds.extend([
        Kind::Hard("grazing", forsyth::buffers as SectionFn),
        Kind::Hard("duelling_omni", forsyth::frusta),
        Kind::Hard("minified_grate", forsyth::priority_mips),
        Kind::Hard("near_receiver", thesis::chapter4),
    ]);
    kinds.extend(settings.sweep_scenes().iter().map(|s| Kind::Sweep(s)));
    kinds
}

/// The names of a run's units, in its order (a sharded run's manifest lists them).
pub fn names(settings: &Settings) -> Vec<String> {
    kinds(settings).iter().map(Kind::name).collect()
}

/// What one unit measured.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct UnitResult {
    pub unit: String,
    /// Figure and claim sections, before a claim's scenes are merged into one section.
    pub sections: Vec<Section>,
    pub sweeps: Vec<Section>,
    pub rows: Vec<BenchRow>,
    /// Scene warnings.
    pub environment: Vec<String>,
    pub loading_s: f64,
}

/// The units one process measured: a whole run's, or a shard's.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Part {
    /// The GL, the frame settings and the machine.
    pub environment: Vec<String>,
    pub results: Vec<UnitResult>,
    pub elapsed_s: f64,
    /// How many configurations were measured and how many reused.
    pub reuse: String,
}

impl Part {
    /// The report of these units: claims merged, sections in the paper's order, the summary.
    pub fn report(self) -> Report {
        let mut environment = self.environment;
        let (mut sections, mut sweeps, mut rows) = (Vec::new(), Vec::new(), Vec::new());
        let mut loading_s = 0.0;
        for r in self.results {
            environment.extend(r.environment);
            sections.extend(r.sections);
            sweeps.extend(r.sweeps);
            rows.extend(r.rows);
            loading_s += r.loading_s;
        }
        environment.sort();
        environment.dedup();
        let mut merged = merged_in_order(sections);
        let summary = summary(&merged, &sweeps);
        merged.extend(sweeps);
        Report {
            summary,
            environment,
            sections: merged,
            rows,
            reuse: self.reuse,
            elapsed_s: self.elapsed_s,
            loading_s,
        }
    }

    /// The parts of one run (each unit once, checked by the caller), as one part: the units in
    /// the run's order, their times added.
    pub fn join(settings_units: &[String], parts: Vec<Part>) -> Result<Part, ReproduceError> {
        let mut environment = Vec::new();
        let (mut results, mut elapsed_s, mut reuse) = (Vec::new(), 0.0, Vec::new());
        for p in parts {
            environment.extend(p.environment);
            results.extend(p.results);
            elapsed_s += p.elapsed_s;
            reuse.push(p.reuse);
        }
        let results =
            crate::report::shard::in_run_order(settings_units, results, |r| r.unit.clone())?;
        Ok(Part {
            environment,
            results,
            elapsed_s,
            reuse: reuse.join("; "),
        })
    }
}

/// Measures the units `settings.shard` takes, advancing `bar` by section.
pub fn measure(
    renderer: &mut Renderer,
    settings: &Settings,
    out: &Path,
    bar: &ProgressBar,
) -> Result<Part, ReproduceError> {
    let start = Instant::now();
    let taken: Vec<Kind> = kinds(settings)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| settings.shard.takes(*i))
        .map(|(_, k)| k)
        .collect();
    bar.set_length(taken.iter().map(Kind::sections).sum::<usize>() as u64);
    let store = match &settings.keep {
        Some(dir) => RowStore::on_disk(dir).map_err(io(dir))?,
        None => RowStore::in_memory(),
    };
    let environment = environment(renderer, settings);
    let mut runner = Runner {
        renderer,
        settings,
        out,
        bar,
        store,
        views: HashMap::new(),
    };
    let mut results = Vec::with_capacity(taken.len());
    for kind in taken {
        results.push(runner.unit(kind)?);
    }
    Ok(Part {
        environment,
        results,
        elapsed_s: start.elapsed().as_secs_f64(),
        reuse: runner.store.summary(),
    })
}

/// What the units of one process share: the renderer, the rows kept, and each scene's view
/// for its next unit.
struct Runner<'r> {
    renderer: &'r mut Renderer,
    settings: &'r Settings,
    out: &'r Path,
    bar: &'r ProgressBar,
    store: RowStore,
    /// Exact masks and errors by scene, for the scene's next unit.
    views: HashMap<String, View>,
}

impl Runner<'_> {
    fn unit(&mut self, kind: Kind) -> Result<UnitResult, ReproduceError> {
        let mut result = UnitResult {
            unit: kind.name(),
            sections: Vec::new(),
            sweeps: Vec::new(),
            rows: Vec::new(),
            environment: Vec::new(),
            loading_s: 0.0,
        };
        let (file, label) = match kind {
            Kind::Figures(s) | Kind::Sweep(s) => (s.to_string(), s),
            Kind::Hard(case, _) => (format!("../hard/{case}"), case),
        };
        let (scene, options) = self.upload(&file, label, &mut result)?;
        let view = match kind {
            Kind::Hard(..) => View::default(),
            _ => self.views.remove(label).unwrap_or_default(),
        };
        let kept = Kept {
            store: std::mem::take(&mut self.store),
            view,
            ..Kept::default()
        };
        let (settings, out, bar) = (self.settings, self.out, self.bar);
        let mut lab =
            Lab::new(self.renderer, &scene, label, options, settings, out, bar).with_kept(kept);
        if let Kind::Hard(case, _) = kind {
            lab = lab.with_scene_file(&format!("assets/hard/{case}.toml"));
        }
        let measured = measure_unit(&mut lab, kind, &mut result);
        let (rows, kept) = lab.into_parts();
        self.store = kept.store;
        // A sweep is its scene's last unit: its view (the reference's BVH with it) goes.
        if let Kind::Figures(_) = kind {
            self.views.insert(label.to_string(), kept.view);
        }
        measured?;
        result.rows = rows;
        Ok(result)
    }

    /// Loads a scene file and uploads it, adding the time and its warnings to `result`.
    fn upload(
        &mut self,
        file: &str,
        label: &str,
        result: &mut UnitResult,
    ) -> Result<(Scene, Options), ReproduceError> {
        let start = Instant::now();
        let (scene, options, warnings) = load_scene(self.settings, file)?;
        self.renderer.load_scene(&scene)?;
        result.loading_s += start.elapsed().as_secs_f64();
        if !file.starts_with("../hard/") {
            result
                .environment
                .extend(warnings.iter().map(|w| format!("{label}: {w}")));
        }
        Ok((scene, options))
    }
}

/// The unit's sections, measured on its lab.
fn measure_unit(lab: &mut Lab, kind: Kind, result: &mut UnitResult) -> Result<(), ReproduceError> {
    match kind {
        Kind::Figures(scene) => {
            if scene == "oa_dm1" {
                result.sections.extend(figures::run(lab)?);
                result.sections.push(timed(lab, thesis::chapter5)?);
                lab.bar().inc(1);
                for section in [forsyth::ids, forsyth::shootout, forsyth::subdivision] {
                    result.sections.push(timed(lab, section)?);
                    lab.bar().inc(1);
                }
            }
            result.sections.extend(claims::run(lab)?);
        }
        Kind::Hard(_, section) => {
            result.sections.push(timed(lab, section)?);
            lab.bar().inc(1);
        }
        Kind::Sweep(_) => {
            result.sweeps.push(timed(lab, pareto::run)?);
            result
                .sweeps
                .push(timed(lab, |lab| thesis::comparison(lab, lab.rows()))?);
            result.sweeps.push(timed(lab, pareto::frontier)?);
            lab.bar().inc(1);
        }
    }
    Ok(())
}
