//! `shadowlab reproduce`: the paper's figures and claims beside our measurements, as a report.

use super::{CommonArgs, start_gl};
use anyhow::{Context, Result, bail};
use shadowlab::options::Options;
use shadowlab::report::reproduce::{self, Settings};
use shadowlab::report::shard::{Manifest, Shard};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Folder for index.html, index.md, results.json and the images (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Folder holding the benchmark scene files.
    #[arg(long, default_value = "assets/scenes")]
    scenes: PathBuf,
    /// A small run (320x240, oa_dm1 only, one frame per configuration) to check the pipeline.
    #[arg(long)]
    quick: bool,
    /// Measured frames per configuration (default 3, 1 with --quick).
    #[arg(long)]
    frames: Option<usize>,
    /// Unmeasured frames before each configuration (default 1, 0 with --quick).
    #[arg(long)]
    warmup: Option<usize>,
    /// A configuration's measured frames (and its pipelined and per-pass frames) stop once
    /// they add up to this many seconds, one frame at least: the paper's frame on the large
    /// maps takes seconds a frame. 0: every configuration all its frames.
    #[arg(long, value_name = "S", default_value_t = shadowlab::report::bench::ENOUGH_SECONDS)]
    enough_seconds: f64,
    /// Where measured configurations are kept by content (the code, GL, scene, options and
    /// frame settings), so that a run interrupted or run again measures only what it lacks
    /// (default: OUT/rows). A rebuilt binary measures everything anew.
    #[arg(long, value_name = "DIR")]
    keep: Option<PathBuf>,
    /// Measure everything anew and keep nothing on disk.
    #[arg(long, conflicts_with = "keep")]
    fresh: bool,
    /// Measure only shard K of N of the run's units (`K/N`: every N-th of the list from the
    /// K-th; a unit is a scene's figures and claims, a hard case, or a scene's sweep), writing
    /// OUT/part.json and OUT/shard.json for `shadowlab merge`, which writes the whole report.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
}

/// What a shard's results depend on besides its units (a manifest's settings).
pub fn manifest_settings(settings: &Settings) -> String {
    format!(
        "{} {}x{} warmup={} frames={} enough={:?} quick={} sets={:?}",
        settings.scenes_dir.display(),
        settings.width,
        settings.height,
        settings.warmup,
        settings.frames,
        settings.enough_seconds,
        settings.quick,
        settings.sets
    )
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    if !args.scenes.join("oa_dm1.toml").is_file() {
        bail!(
            "{} holds no oa_dm1.toml: run from the repository root or give --scenes",
            args.scenes.display()
        );
    }
    let mut settings = if args.quick {
        Settings::quick(&args.scenes)
    } else {
        Settings::full(&args.scenes)
    };
    if let Some(size) = &common.size {
        let (w, h) = super::parse_size(size)?;
        (settings.width, settings.height) = (w, h);
    }
    settings.frames = args.frames.unwrap_or(settings.frames).max(1);
    settings.warmup = args.warmup.unwrap_or(settings.warmup);
    settings.enough_seconds = (args.enough_seconds > 0.0).then_some(args.enough_seconds);
    settings.sets = common.sets.clone();
    settings.progress = true;
    settings.keep =
        (!args.fresh).then(|| args.keep.clone().unwrap_or_else(|| args.out.join("rows")));
    if let Some(s) = &args.shard {
        settings.shard = Shard::parse(s)?;
        Manifest {
            command: "reproduce".into(),
            shard: settings.shard,
            units: reproduce::unit_names(&settings),
            settings: manifest_settings(&settings),
            version: env!("CARGO_PKG_VERSION").into(),
        }
        .write(&args.out)
        .with_context(|| format!("cannot write the manifest in {}", args.out.display()))?;
    }
    // The context is made once for the whole run, on the chosen path.
    let mut options = Options::default();
    if let Some(b) = &common.backend {
        options.set("backend", b).context("--backend")?;
    }
    options.set("width", &settings.width.to_string())?;
    options.set("height", &settings.height.to_string())?;
    let (_ctx, mut renderer) = start_gl(&options)?;
    eprintln!(
        "reproduce: {} into {} on {}",
        if settings.quick {
            "quick run"
        } else {
            "full run"
        },
        args.out.display(),
        renderer.caps().renderer
    );
    let report = reproduce::run(&mut renderer, &settings, &args.out)?;
    for s in &report.summary {
        println!("{s}");
    }
    eprintln!(
        "wrote {} ({} sections, {} configurations, {:.1} minutes)",
        args.out.join("index.html").display(),
        report.sections.len(),
        report.rows.len(),
        report.elapsed_s / 60.0
    );
    eprintln!("{}", report.reuse);
    Ok(())
}
