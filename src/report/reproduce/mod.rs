//! `reproduce`: every figure and claim of the paper (Arneson) and the thesis (Sindholt) that
//! the pipeline can answer, set beside our own measurement of it on the OpenArena benchmark
//! scenes, all measured in one run.
//!
//! The run is organised by scene (each scene is loaded once and its exact reference masks are
//! reused by every configuration); the sections are then put in the paper's order. Every
//! number in the report comes from this run; the paper's numbers are quoted as such.
//!
//! Everything is measured on the paper's frame (`plan.enabled = false`: every light, every
//! caster, the counting it asks for), except the sweeps' rows named "planner".

mod claims;
mod figures;
mod forsyth;
mod lab;
mod page;
mod pareto;
mod thesis;
mod units;
pub use pareto::fixed_sweep;
pub use units::names as unit_names;

pub use lab::{Lab, pct};

/// What the paper's figures and claims are measured with: its frame, without the planner.
const PAPER_FRAME: &[&str] = &["plan.enabled=false"];

use super::bench::BenchRow;
use super::table::Table;
use crate::options::{OptionError, Options};
use crate::report::shard::Shard;
use crate::run::{RenderError, Renderer};
use crate::scene::Scene;
use crate::scene_file::SceneFileError;
use crate::scene_file::load::{LoadError, Loaded, load_file};
use indicatif::ProgressBar;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("scene {name}: {source}")]
    Scene {
        name: String,
        source: Box<SceneFileError>,
    },
    #[error(transparent)]
    Option(#[from] OptionError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("writing an image: {0}")]
    Image(#[from] image::ImageError),
    #[error("drawing a plot: {0}")]
    Plot(String),
    #[error("{0}")]
    Json(#[from] serde_json::Error),
    #[error(transparent)]
    Tune(#[from] crate::report::tune::TuneError),
    #[error(transparent)]
    Shard(#[from] crate::report::shard::ShardError),
}

/// What a run measures and how much.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Where the benchmark scene files are (`assets/scenes`).
    pub scenes_dir: PathBuf,
    /// A small run for tests: 320x240, one scene for the sweeps, one frame per configuration.
    pub quick: bool,
    pub width: u32,
    pub height: u32,
    pub warmup: usize,
    pub frames: usize,
    /// Configurations whose measured frames add up to this many seconds stop there (one frame
    /// at least; `BenchSettings::enough_seconds`): the paper's frame on the large maps takes
    /// seconds a frame. None: every configuration `frames`.
    pub enough_seconds: Option<f64>,
    /// `KEY=VALUE` settings applied to every configuration (after each scene's `[options]`).
    pub sets: Vec<String>,
    pub progress: bool,
    /// Where measured rows are kept by content (code, GL, scene, options, frame settings), so
    /// that a run interrupted or run again measures only what it lacks; None keeps them for
    /// this run only (a configuration met twice is still measured once).
    pub keep: Option<PathBuf>,
    /// The run's units this process measures (`units::names`): all, or one shard's.
    pub shard: Shard,
}

impl Settings {
    /// The full report at the paper's 640x480: one warm-up and three measured frames each.
    pub fn full(scenes_dir: &Path) -> Settings {
        Settings {
            scenes_dir: scenes_dir.to_path_buf(),
            quick: false,
            width: 640,
            height: 480,
            warmup: 1,
            frames: 3,
            enough_seconds: Some(crate::report::bench::ENOUGH_SECONDS),
            sets: Vec::new(),
            progress: true,
            keep: None,
            shard: Shard::WHOLE,
        }
    }

    /// A small run that still measures every section (for tests).
    pub fn quick(scenes_dir: &Path) -> Settings {
        Settings {
            quick: true,
            width: 320,
            height: 240,
            warmup: 0,
            frames: 1,
            progress: false,
            ..Settings::full(scenes_dir)
        }
    }

    /// The scenes whose accuracy-against-time is plotted.
    fn sweep_scenes(&self) -> &'static [&'static str] {
        if self.quick {
            &["oa_dm1"]
        } else {
            &[
                "oa_dm1",
                "q3dm6ish",
                "wrackdm17",
                "ctf_compromise",
                "oa_dm3",
            ]
        }
    }
}

/// An image of a section, as a file in the output folder.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Figure {
    pub file: String,
    pub caption: String,
}

/// One figure or claim of the paper, with our measurement.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Section {
    pub id: String,
    pub title: String,
    /// What the paper or thesis shows or says (paraphrased, its numbers quoted).
    pub source: String,
    /// What this run measured, as sentences built from the numbers.
    pub findings: Vec<String>,
    pub figures: Vec<Figure>,
    pub tables: Vec<Table>,
    /// Commands that regenerate the section's numbers and images.
    pub regenerate: Vec<String>,
    /// The key numbers, by name (for the summary and for tests).
    pub numbers: BTreeMap<String, f64>,
    /// Seconds this run spent measuring the section (a claim's scenes added together; the
    /// first section on a scene also pays for its exact reference).
    pub seconds: f64,
}

impl Section {
    fn new(id: &str, title: &str, source: &str) -> Section {
        Section {
            id: id.to_string(),
            title: title.to_string(),
            source: source.to_string(),
            ..Section::default()
        }
    }

    /// A key number (0 when the section did not measure it).
    pub fn number(&self, key: &str) -> f64 {
        self.numbers.get(key).copied().unwrap_or(0.0)
    }
}

/// The whole report.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Sentences that sum the run up.
    pub summary: Vec<String>,
    /// Machine, GL, settings and scene warnings.
    pub environment: Vec<String>,
    pub sections: Vec<Section>,
    /// Every measured configuration.
    pub rows: Vec<BenchRow>,
    /// How many configurations were measured, and how many taken from rows kept before.
    pub reuse: String,
    pub elapsed_s: f64,
    /// Seconds spent loading scenes and uploading them (outside every section).
    pub loading_s: f64,
}

impl Report {
    pub fn section(&self, id: &str) -> Option<&Section> {
        self.sections.iter().find(|s| s.id == id)
    }
}

/// Loads one benchmark scene and the options that apply to it.
fn load_scene(
    settings: &Settings,
    name: &str,
) -> Result<(Scene, Options, Vec<String>), ReproduceError> {
    let path = settings.scenes_dir.join(format!("{name}.toml"));
    let wrap = |e: SceneFileError| ReproduceError::Scene {
        name: name.to_string(),
        source: Box::new(e),
    };
    let overrides = |mut options: Options| -> Result<Options, OptionError> {
        for s in &settings.sets {
            options.set_assignment(s)?;
        }
        options.set("width", &settings.width.to_string())?;
        options.set("height", &settings.height.to_string())?;
        options.validate()?;
        Ok(options)
    };
    let Loaded {
        scene,
        options,
        report,
    } = load_file(&path, overrides).map_err(|e| match e {
        LoadError::File(e) => wrap(e),
        LoadError::Options(e) | LoadError::Overrides(e) => ReproduceError::Option(e),
    })?;
    let mut warnings = report.warnings;
    warnings.extend(crate::truth::enclosure::scene_warnings(&scene));
    Ok((scene, options, warnings))
}

/// A section measured on one lab.
type SectionFn = fn(&mut Lab) -> Result<Section, ReproduceError>;

/// The order sections appear in, whatever order they were measured in.
const ORDER: &[&str] = &[
    "paper-fig1",
    "paper-fig2",
    "thesis-fig10",
    "thesis-fig12",
    "thesis-fig13-14",
    "thesis-fig20-21",
    "thesis-fig22",
    "thesis-ch4",
    "thesis-ch5",
    "claim-sm-lights",
    "claim-sv-lights",
    "forsyth-buffers",
    "forsyth-ids",
    "forsyth-shootout",
    "vector-subdivision",
];

/// The bar over the run's sections, hidden unless `settings.progress`.
fn progress_bar(settings: &Settings) -> ProgressBar {
    if !settings.progress {
        return ProgressBar::hidden();
    }
    // The length is set once the units are known (`units::measure`).
    let b = ProgressBar::with_draw_target(Some(0), crate::report::progress::draw_target());
    b.set_style(crate::report::progress::style(
        "reproduce [{elapsed_precise}] {bar:30} {pos}/{len} sections, {left} left, {peak}  {msg}",
    ));
    b
}

/// The report's lines on where it ran: the GL, the frame settings, the machine, the options
/// set for every configuration.
fn environment(renderer: &Renderer, settings: &Settings) -> Vec<String> {
    let mut lines = vec![
        format!(
            "Renderer: {} ({}), {}",
            renderer.caps().renderer,
            renderer.caps().version,
            renderer.caps().vendor
        ),
        format!(
            "{}x{}, {} warm-up and {} measured frames per configuration; times are medians; \
             error is measured on the first frame against the exact ray-cast reference.",
            settings.width, settings.height, settings.warmup, settings.frames
        ),
        format!(
            "Machine: {} CPU threads; shadowlab {}.",
            std::thread::available_parallelism().map_or(0, |n| n.get()),
            env!("CARGO_PKG_VERSION")
        ),
    ];
    if !settings.sets.is_empty() {
        lines.push(format!(
            "Options set for every configuration: {}",
            settings.sets.join(" ")
        ));
    }
    lines
}

/// Claims measured on two scenes merged into one section each, the sections in `ORDER`.
fn merged_in_order(sections: Vec<Section>) -> Vec<Section> {
    let mut merged: Vec<Section> = Vec::new();
    for s in sections {
        match merged.iter_mut().find(|m| m.id == s.id) {
            Some(m) => m.absorb(s),
            None => merged.push(s),
        }
    }
    merged.sort_by_key(|s| ORDER.iter().position(|o| *o == s.id).unwrap_or(ORDER.len()));
    merged
}

/// Runs one section, recording how long it took.
fn timed<'a>(
    lab: &mut Lab<'a>,
    section: impl FnOnce(&mut Lab<'a>) -> Result<Section, ReproduceError>,
) -> Result<Section, ReproduceError> {
    let start = Instant::now();
    let mut s = section(lab)?;
    s.seconds = start.elapsed().as_secs_f64();
    Ok(s)
}

/// The error of an I/O failure on `path`.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReproduceError {
    let path = path.to_path_buf();
    move |source| ReproduceError::Io { path, source }
}

/// Runs every section (or a shard's units) and writes `out/index.html`, `out/index.md`,
/// `out/results.json` and the images; a shard also writes its part (`units::PART`) for
/// [`merge`].
pub fn run(
    renderer: &mut Renderer,
    settings: &Settings,
    out: &Path,
) -> Result<Report, ReproduceError> {
    std::fs::create_dir_all(out).map_err(io(out))?;
    let bar = progress_bar(settings);
    let part = units::measure(renderer, settings, out, &bar)?;
    bar.finish_and_clear();
    if settings.shard != Shard::WHOLE {
        let path = out.join(units::PART);
        std::fs::write(&path, serde_json::to_string(&part)?).map_err(io(&path))?;
    }
    let report = part.report();
    page::write(&report, out)?;
    Ok(report)
}

/// Joins the parts of a sharded run (`dirs`, every unit of `units` once) into `out`: the
/// report one run writes, with every part's images. The run's time is the parts' times added.
pub fn merge(units: &[String], dirs: &[PathBuf], out: &Path) -> Result<Report, ReproduceError> {
    std::fs::create_dir_all(out).map_err(io(out))?;
    let mut parts = Vec::with_capacity(dirs.len());
    for dir in dirs {
        let path = dir.join(units::PART);
        let text = std::fs::read_to_string(&path).map_err(io(&path))?;
        parts.push(serde_json::from_str::<units::Part>(&text)?);
        for entry in std::fs::read_dir(dir).map_err(io(dir))? {
            let from = entry.map_err(io(dir))?.path();
            if from.extension().is_some_and(|e| e == "png") {
                let to = out.join(from.file_name().unwrap_or_default());
                std::fs::copy(&from, &to).map_err(io(&to))?;
            }
        }
    }
    let report = units::Part::join(units, parts)?.report();
    page::write(&report, out)?;
    Ok(report)
}

impl Section {
    /// Appends another scene's measurement of the same claim.
    fn absorb(&mut self, other: Section) {
        self.findings.extend(other.findings);
        self.figures.extend(other.figures);
        self.tables.extend(other.tables);
        self.regenerate.extend(other.regenerate);
        self.numbers.extend(other.numbers);
        self.seconds += other.seconds;
    }
}

/// A few sentences over the whole run, each from measured numbers.
fn summary(sections: &[Section], sweeps: &[Section]) -> Vec<String> {
    let mut out = Vec::new();
    let get = |id: &str| sections.iter().find(|s| s.id == id);
    if let Some(s) = get("paper-fig2") {
        out.push(format!(
            "Shadow-map resolution (paper Fig. 2): error falls from {} at 64x64 to {} at 512x512 \
             on oa_dm1.",
            pct(s.number("error_64")),
            pct(s.number("error_512"))
        ));
    }
    if let Some(s) = get("thesis-fig20-21") {
        out.push(format!(
            "Camera inside a shadow volume (thesis Fig. 20-21): z-pass gets {} of receiver pixels \
             wrong, z-fail {}.",
            pct(s.number("error_zpass")),
            pct(s.number("error_zfail"))
        ));
    }
    for s in sweeps {
        let (sm, sv) = (s.number("sm_ratio"), s.number("sv_ratio"));
        if sm > 0.0 && sv > 0.0 {
            out.push(format!(
                "{}: the paper's shadow mapping costs {:.1}x the frame time of shadows off at {} \
                 error, its shadow volumes {:.1}x at {}; most accurate: {}.",
                s.title.trim_start_matches("Accuracy against time: "),
                sm,
                pct(s.number("sm_error")),
                sv,
                pct(s.number("sv_error")),
                s.findings.first().cloned().unwrap_or_default()
            ));
        }
    }
    out
}
