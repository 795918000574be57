//! `shadowlab render`: one frame, headless, to a PNG.

use super::{CommonArgs, load_scene, start_gl};
use anyhow::{Context, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML); the built-in scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Where to write the PNG.
    #[arg(long, default_value = "shadowlab.png")]
    out: PathBuf,
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let scene = load_scene(args.scene.as_deref())?;
    let options = common.options_for(&scene)?;
    let (mut ctx, mut renderer) = start_gl(&options)?;
    renderer.load_scene(&scene)?;
    let frame = renderer.render(&scene, &options)?;
    if let Some(window) = ctx.window() {
        // Show the frame too, proving the window path presents what it rendered.
        renderer.present_to_default(options.width, options.height);
        window.window.swap().map_err(anyhow::Error::msg)?;
        window.pump();
    }
    frame
        .save_png(&args.out)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    let passes: Vec<String> = frame
        .passes
        .iter()
        .map(|p| format!("{} {:.2} ms", p.name, p.ms))
        .collect();
    eprintln!(
        "wrote {} ({}x{}, {} path, frame {:.1} ms: {})",
        args.out.display(),
        frame.width,
        frame.height,
        ctx.backend,
        frame.frame_ms,
        passes.join(", ")
    );
    Ok(())
}
