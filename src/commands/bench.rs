//! `shadowlab bench`: frame time and accuracy of a sweep of options, as a table, JSON and a plot.

use super::{CommonArgs, camera_path, load, start_gl};
use anyhow::{Context, Result, bail};
use shadowlab::options::Technique;
use shadowlab::report::bench::{Bench, BenchConfig, BenchRow, BenchSettings, sweep_configs};
use shadowlab::report::shard::{Manifest, Shard};
use shadowlab::report::store::RowStore;
use shadowlab::report::{plot, table};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML); the built-in scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// A swept option, `key=v1,v2,...` (repeatable; every combination is measured).
    #[arg(long = "sweep", value_name = "KEY=V1,V2,...")]
    sweeps: Vec<String>,
    /// Unmeasured frames before each configuration.
    #[arg(long, default_value_t = 3)]
    warmup: usize,
    /// Measured frames per configuration (default: 10, or one lap of --path). Each is also
    /// sampled against the exact reference afterwards, untimed (`estimate.samples` pixels per
    /// light; `--set estimate.samples=0` skips it); on a still camera with the scene standing
    /// the frames are all the first, whose masks are sampled once.
    #[arg(long)]
    frames: Option<usize>,
    /// Camera path: `turn` (360° in place over 128 frames, DarkPlaces' timerefresh), `still`
    /// (the scene's camera) or a recorded path file (`x y z yaw pitch` per line). Default: the
    /// scene file's `flythrough`, else still.
    #[arg(long)]
    path: Option<String>,
    /// Hold the scene as loaded instead of playing its motion (animated players, moving
    /// lights) along the path, one path frame per 1/20 s.
    #[arg(long)]
    no_motion: bool,
    /// Sample every n-th measured frame against the sampled reference (default: 4 on a
    /// recorded path, else 1). The frames between are drawn too, plain, so that each sampled
    /// frame moves one step as the timed frames do and the plain frame after it shows what
    /// sampling added to the frame.
    #[arg(long)]
    sample_every: Option<usize>,
    /// MiB the round-robin renderers may hold together (their shadow maps as planned for the
    /// first frame): past it the configurations are timed a group at a time, each with its
    /// baseline (default: all at once). Each renderer's own maps stay within
    /// `shadow_map.budget_mb`.
    #[arg(long, value_name = "MIB")]
    memory_mb: Option<f32>,
    /// On a still camera with the scene standing, a configuration's measured frames (and its
    /// pipelined and per-pass frames) stop once they add up to this many seconds, one frame
    /// at least: for sweeps whose frames take seconds (default: all of --frames).
    #[arg(long, value_name = "S")]
    enough_seconds: Option<f64>,
    /// Time one configuration after another on one renderer, instead of round-robin (one frame
    /// of each configuration and baseline in turn, each on its own renderer), which keeps the
    /// ratios steady when the machine's speed drifts.
    #[arg(long)]
    sequential: bool,
    /// Measure only shard K of N of the configurations (`K/N`: every N-th of the sweep's
    /// order from the K-th), for sweeps spread over processes or machines; with `--out`,
    /// `shadowlab merge` joins the parts.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Write the rows to DIR/rows.json and the plot to DIR/bench.png, with the manifest
    /// `shadowlab merge` reads (DIR/shard.json).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Keep each measured configuration in DIR by content (the code, GL, scene, options and
    /// frame settings): a sweep run again, or resumed after an interruption, measures only
    /// what DIR lacks. A rebuilt binary measures everything anew.
    #[arg(long, value_name = "DIR")]
    keep: Option<PathBuf>,
    /// Write the rows as a JSON array.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the error-against-time plot (default: the JSON file's name with .png, else
    /// bench.png).
    #[arg(long)]
    plot: Option<PathBuf>,
}

fn parse_sweep(s: &str) -> Result<(String, Vec<String>)> {
    let (key, values) = s
        .split_once('=')
        .with_context(|| format!("--sweep `{s}` is not KEY=V1,V2,..."))?;
    let values: Vec<String> = values
        .split(',')
        .map(|v| v.trim().to_string())
        .filter(|v| !v.is_empty())
        .collect();
    if values.is_empty() {
        bail!("--sweep `{s}` has no values");
    }
    Ok((key.trim().to_string(), values))
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let sweeps: Vec<(String, Vec<String>)> = args
        .sweeps
        .iter()
        .map(|s| parse_sweep(s))
        .collect::<Result<_>>()?;
    let loaded = load(common, args.scene.as_deref())?;
    let flythrough = loaded.report.flythrough;
    let (scene, mut options) = (loaded.scene, loaded.options);
    // Sweeping one technique's options without choosing it would measure nothing: pick it.
    if options.technique == Technique::None && !sweeps.iter().any(|(k, _)| k == "technique") {
        let implied = Technique::ALL.iter().copied().find(|t| {
            *t != Technique::None && sweeps.iter().any(|(k, _)| k.starts_with(&format!("{t}.")))
        });
        if let Some(t) = implied {
            eprintln!(
                "note: the sweep sets {t}.* options, so technique = {t} (set technique to override)"
            );
            options.technique = t;
        }
    }
    let all = sweep_configs(&options, &sweeps)?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::WHOLE,
    };
    let configs: Vec<BenchConfig> = (0..all.len())
        .filter(|&i| shard.takes(i))
        .map(|i| all[i].clone())
        .collect();
    let path = match args.path.as_deref() {
        Some("still") => None,
        Some(p) => Some(p.to_string()),
        None => flythrough.map(|f| f.display().to_string()),
    };
    let keys = camera_path(&scene.camera, path.as_deref())?;
    let recorded = path.as_deref().is_some_and(|p| p != "turn");
    let frames = args
        .frames
        .unwrap_or(if path.is_some() { keys.len() } else { 10 });
    let (_ctx, mut renderer) = start_gl(&options)?;
    renderer.load_scene(&scene)?;
    eprintln!(
        "bench: {} configuration(s) on {} ({} triangles, {} lights), {} warm-up + {} measured frames each along {}{}, {}",
        configs.len(),
        scene.name,
        scene.triangle_count(),
        scene.lights.len(),
        args.warmup,
        frames,
        path.as_deref().unwrap_or("the still camera"),
        if args.no_motion || scene.motion.is_still() {
            ""
        } else {
            " with the scene moving"
        },
        renderer.caps().renderer
    );
    let settings = BenchSettings {
        warmup: args.warmup,
        frames,
        path: keys,
        progress: true,
        interleave: !args.sequential,
        breakdown: true,
        pipelined: true,
        motion: !args.no_motion,
        sample_every: args.sample_every.unwrap_or(if recorded { 4 } else { 1 }),
        memory_mb: args.memory_mb,
        enough_seconds: args.enough_seconds.filter(|s| *s > 0.0),
    };
    let manifest = Manifest {
        command: "bench".into(),
        shard,
        units: all.iter().map(BenchConfig::label).collect(),
        settings: format!(
            "{} {options} {:?} {}",
            scene.name,
            settings,
            renderer.caps().renderer
        ),
        version: env!("CARGO_PKG_VERSION").into(),
    };
    let mut bench = Bench::new(&mut renderer, &scene, settings);
    if let Some(dir) = &args.keep {
        let store = RowStore::on_disk(dir)
            .with_context(|| format!("cannot keep rows in {}", dir.display()))?;
        bench = bench.with_store(store);
    }
    let rows = bench.run(&configs)?;
    if args.keep.is_some() {
        eprintln!("{}", bench.store().summary());
    }
    if let Some(dir) = &args.out {
        manifest.write(dir)?;
        std::fs::write(dir.join(ROWS), serde_json::to_string_pretty(&rows)?)
            .with_context(|| format!("cannot write {}", dir.join(ROWS).display()))?;
    }
    let title = format!(
        "{}: error against frame time ({}x{})",
        scene.name, options.width, options.height
    );
    let plot_path = args
        .plot
        .clone()
        .unwrap_or_else(|| match (&args.out, &args.json) {
            (Some(dir), _) => dir.join("bench.png"),
            (None, Some(j)) => j.with_extension("png"),
            (None, None) => PathBuf::from("bench.png"),
        });
    write_outputs(&rows, args.json.as_deref(), &title, &plot_path)
}

/// The rows' file name in `--out`'s folder.
pub const ROWS: &str = "rows.json";

/// What a bench run writes: the table (and the per-frame errors where they fit) on stdout,
/// the rows as JSON where asked, and the plot.
pub fn write_outputs(
    rows: &[BenchRow],
    json: Option<&Path>,
    title: &str,
    plot_path: &Path,
) -> Result<()> {
    println!("{}", table::markdown(rows));
    // Frame by frame only where it fits on a screen; the JSON holds every frame.
    if rows
        .iter()
        .any(|r| r.sampled.as_ref().is_some_and(|p| p.frames.len() <= 32))
    {
        println!("{}", table::path_error_table(rows).to_markdown());
    }
    if let Some(json) = json {
        std::fs::write(json, serde_json::to_string_pretty(rows)?)
            .with_context(|| format!("cannot write {}", json.display()))?;
        eprintln!("wrote {}", json.display());
    }
    plot::error_vs_time(rows, title, plot_path).map_err(anyhow::Error::msg)?;
    eprintln!("wrote {}", plot_path.display());
    Ok(())
}
