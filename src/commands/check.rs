//! `shadowlab check`: every map of a data set (or one) loaded, rendered from its first spawn
//! point under shadow maps and shadow volumes, planner on and off, and measured against the
//! exact reference; one JSON line per map on stdout, progress on stderr.

use super::{CommonArgs, scene_options, start_gl};
use anyhow::{Result, bail};
use shadowlab::options::{OptionValue, Technique};
use shadowlab::q3::pk3::Vfs;
use shadowlab::report::check::{MapCheck, check_map};
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
    /// A map name (`oa_dm1`) or a bsp path inside the pk3s.
    map: Option<String>,
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
    let maps = match (&args.map, args.all) {
        (Some(m), false) => vec![super::inspect::bsp_path(m)],
        (None, true) => vfs.list("maps/", ".bsp"),
        _ => bail!("give a MAP name, or --all"),
    };
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
    let (_ctx, mut renderer) = start_gl(&options)?;
    let mut failed = 0;
    let out = std::io::stdout();
    for (i, map) in maps.iter().enumerate() {
        eprintln!("[{}/{}] {map}", i + 1, maps.len());
        let line = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            check_map(&mut renderer, &args.data, map, &options, &techniques)
        }))
        .unwrap_or_else(|panic| MapCheck {
            map: map.clone(),
            error: Some(format!("panicked: {}", panic_text(&panic))),
            ..MapCheck::default()
        });
        failed += line.error.is_some() as usize;
        let mut out = out.lock();
        writeln!(out, "{}", serde_json::to_string(&line)?)?;
        out.flush()?;
    }
    if failed > 0 {
        bail!("{failed} of {} maps could not be checked", maps.len());
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
