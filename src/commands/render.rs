//! `shadowlab render`: one frame, headless, to a PNG.

use super::{CommonArgs, load, start_gl};
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
    let super::Loaded {
        scene,
        options,
        report,
    } = load(common, args.scene.as_deref())?;
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
    // Per-light passes are summed so that 64 lights still give one readable line.
    let mut totals: Vec<(String, f64, usize)> = Vec::new();
    for p in &frame.passes {
        let stage = match p.name.split_once('.') {
            Some((light, stage)) if light.starts_with("light") => format!("lights.{stage}"),
            _ => p.name.clone(),
        };
        match totals.iter_mut().find(|(n, _, _)| *n == stage) {
            Some(t) => {
                t.1 += p.ms;
                t.2 += 1;
            }
            None => totals.push((stage, p.ms, 1)),
        }
    }
    let passes: Vec<String> = totals
        .iter()
        .map(|(n, ms, count)| match count {
            1 => format!("{n} {ms:.1} ms"),
            _ => format!("{n} {ms:.1} ms over {count}"),
        })
        .collect();
    eprintln!(
        "wrote {} ({}x{}, {} path, scene {} loaded in {:.0} ms, frame {:.1} ms: {})",
        args.out.display(),
        frame.width,
        frame.height,
        ctx.backend,
        scene.name,
        report.load_ms,
        frame.frame_ms,
        passes.join(", ")
    );
    Ok(())
}
