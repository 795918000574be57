//! `shadowlab check`: every map of a data set (or one) loaded, rendered from its first spawn
//! point under shadow maps and shadow volumes, planner on and off, and measured against the
//! exact reference; one JSON line per map on stdout, progress on stderr. `--shard K/N` checks
//! every N-th map from the K-th, and `--out DIR` keeps the lines with a manifest for
//! `shadowlab merge` (docs/shards.md).

use super::{CommonArgs, scene_options, start_gl};
use anyhow::{Result, bail};
use shadowlab::options::{OptionValue, Technique};
use shadowlab::q3::pk3::Vfs;
use shadowlab::report::check::{MapCheck, check_map};
use shadowlab::report::progress::Lines;
use shadowlab::report::shard::{Manifest, Shard};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A folder holding pk3 files (or a data folder with baseoa/ in it).
    #[arg(long)]
    data: PathBuf,
    /// Every map in the data set.
    #[arg(long)]
    all: bool,
    /// Map names (`oa_dm1`) or bsp paths inside the pk3s.
    maps: Vec<String>,
    /// Check only shard K of N of the maps (`K/N`: every N-th map of the list from the K-th),
    /// for runs spread over processes or machines; `shadowlab merge` joins the parts.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Also write the JSON lines to DIR/check.jsonl, with the manifest `shadowlab merge` reads
    /// (DIR/shard.json).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// The techniques measured, each with the planner on and off, comma separated (any of
    /// shadow_map, psm, tsm, shadow_volume, hybrid).
    #[arg(long, default_value = "shadow_map,shadow_volume")]
    techniques: String,
}

/// Frames are this size unless `--size` says otherwise: every map with every light twice per
/// technique is long work on a software rasterizer.
const DEFAULT_SIZE: &str = "320x240";

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let vfs = Vfs::open_data_dir(&args.data)?;
    let units = match (args.maps.is_empty(), args.all) {
        (false, false) => args
            .maps
            .iter()
            .map(|m| super::inspect::bsp_path(m))
            .collect(),
        (true, true) => vfs.list("maps/", ".bsp"),
        _ => bail!("give MAP names, or --all"),
    };
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::WHOLE,
    };
    let maps: Vec<&String> = (0..units.len())
        .filter(|&i| shard.takes(i))
        .map(|i| &units[i])
        .collect();
    let mut common = common.clone();
    common.size.get_or_insert_with(|| DEFAULT_SIZE.to_string());
    let techniques = args
        .techniques
        .split(',')
        .map(|t| Technique::parse_value(t).map_err(|e| anyhow::anyhow!("--techniques: {e}")))
        .collect::<Result<Vec<_>>>()?;
    if techniques
        .iter()
        .any(|t| matches!(t, Technique::None | Technique::Auto))
    {
        bail!("--techniques: name shadow techniques (not none or auto)");
    }
    let mut options = scene_options(&common, &toml::Table::new())?;
    options.q3.progress = false;
    let manifest = Manifest {
        command: "check".into(),
        shard,
        settings: format!("{options} techniques={}", args.techniques),
        units: units.clone(),
        version: env!("CARGO_PKG_VERSION").into(),
    };
    let mut part = match &args.out {
        Some(dir) => {
            manifest.write(dir)?;
            Some(std::fs::File::create(dir.join(LINES))?)
        }
        None => None,
    };
    let (_ctx, mut renderer) = start_gl(&options)?;
    let mut failed = 0;
    let out = std::io::stdout();
    let mut progress = Lines::new(maps.len(), "maps");
    for map in &maps {
        eprintln!("{}", progress.next(map));
        let line = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            check_map(&mut renderer, &args.data, map, &options, &techniques)
        }))
        .unwrap_or_else(|panic| MapCheck {
            map: map.to_string(),
            error: Some(format!("panicked: {}", panic_text(&panic))),
            ..MapCheck::default()
        });
        failed += line.error.is_some() as usize;
        let text = serde_json::to_string(&line)?;
        if let Some(f) = &mut part {
            writeln!(f, "{text}")?;
            f.flush()?;
        }
        let mut out = out.lock();
        writeln!(out, "{text}")?;
        out.flush()?;
    }
    eprintln!("{}", progress.finish());
    failures(failed, maps.len())
}

/// The JSON lines' file name in `--out`'s folder.
pub const LINES: &str = "check.jsonl";

/// An error when any of `of` maps could not be checked.
pub fn failures(failed: usize, of: usize) -> Result<()> {
    if failed > 0 {
        bail!("{failed} of {of} maps could not be checked");
    }
    Ok(())
}

fn panic_text(panic: &Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_string())
}
