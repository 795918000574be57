//! `shadowlab flythrough`: records a walk through a scene's map as a camera path file (the
//! benchmark paths of `assets/paths/` were made with it).

use super::{CommonArgs, load};
use anyhow::{Context, Result};
use shadowlab::report::flythrough::{WalkSettings, walk};
use shadowlab::scene::path;
use shadowlab::truth::Reference;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML); the built-in scene when absent. The walk starts at its camera.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Seconds of walking (20 path frames per second).
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Walking speed, units per second.
    #[arg(long, default_value_t = 250.0)]
    speed: f32,
    /// Seed of the walker's wandering: the same seed walks the same path.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Where to write the path (`x y z yaw pitch` per line).
    #[arg(long)]
    out: PathBuf,
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    anyhow::ensure!(
        args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= 3600.0,
        "--seconds must be within (0, 3600]"
    );
    anyhow::ensure!(
        args.speed.is_finite() && args.speed > 0.0,
        "--speed must be a positive number"
    );
    let loaded = load(common, args.scene.as_deref())?;
    let scene = loaded.scene;
    eprintln!(
        "flythrough: {} s through {} from its camera",
        args.seconds, scene.name
    );
    let reference = Reference::build(&scene);
    let settings = WalkSettings {
        seconds: args.seconds,
        speed: args.speed,
        seed: args.seed,
        ..WalkSettings::default()
    };
    let keys = walk(&scene, &reference, &scene.camera, &settings)?;
    let travelled: f32 = keys
        .windows(2)
        .map(|w| w[0].position.distance(w[1].position))
        .sum();
    let mut text = format!(
        "# {}: {} s walked from the scene's camera ({} frames at {} Hz, {:.0} units), \
         seed {}\n# made by `shadowlab flythrough --scene ... --seconds {} --seed {}`\n",
        scene.name,
        args.seconds,
        keys.len(),
        path::FRAME_RATE_HZ,
        travelled,
        args.seed,
        args.seconds,
        args.seed
    );
    text.push_str(&path::to_text(&keys));
    std::fs::write(&args.out, text)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    eprintln!(
        "wrote {} ({} frames, {travelled:.0} units)",
        args.out.display(),
        keys.len()
    );
    Ok(())
}
