//! `shadowlab view`: the walkthrough viewer in a window.

use super::{CommonArgs, load, parse_size};
use anyhow::{Context, Result};
use shadowlab::viewer::{self, ViewerSettings, script};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML); the built-in scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Drive the viewer from a script (one command per line; see `src/viewer/script.rs`).
    #[arg(long)]
    script: Option<PathBuf>,
    /// Play a camera path (`x y z yaw pitch` per line) once the window is up.
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Window size.
    #[arg(long, default_value = "1280x800", value_name = "WxH")]
    window: String,
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let loaded = load(common, args.scene.as_deref())?;
    let mut commands = match &args.script {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read {}", p.display()))?;
            script::parse(&text).with_context(|| format!("in {}", p.display()))?
        }
        None => Vec::new(),
    };
    if let Some(p) = &args.replay {
        commands.insert(0, script::Command::Replay(p.clone()));
    }
    let (w, h) = parse_size(&args.window)?;
    viewer::run(ViewerSettings {
        scene: loaded.scene,
        options: loaded.options,
        script: commands,
        window: (w.clamp(320, 16384), h.clamp(240, 16384)),
    })?;
    Ok(())
}
