//! `shadowlab subdivide`: the light-volume subdivision (Vector; the shadow-volume BSP tree of
//! Chin & Feiner) of a scene's lights, kept on disk by map and light, with its build time and
//! fragment counts, and, with `--check`, its agreement with the ray-cast reference on the
//! scene camera's frame.

use super::{CommonArgs, load};
use anyhow::{Context, Result};
use shadowlab::truth::subdivision::{
    self, CacheWrite, Geometry, default_cache_dir, subdivision_mask,
};
use shadowlab::truth::{Reference, Tracing, compare, reference_mask};
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML); the built-in scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Where subdivisions are kept (default: ~/.cache/shadowlab/subdivision).
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Compare each light's subdivision with the ray caster on the scene camera's frame (the
    /// frame is rendered for its surface positions).
    #[arg(long)]
    check: bool,
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let loaded = load(common, args.scene.as_deref())?;
    let scene = loaded.scene;
    let dir = match &args.cache {
        Some(d) => d.clone(),
        None => {
            default_cache_dir().context("no cache folder: set --cache, HOME or XDG_CACHE_HOME")?
        }
    };
    let gbuffer = if args.check {
        let mut options = loaded.options.clone();
        options.technique = shadowlab::options::Technique::None;
        let (_ctx, mut renderer) = super::start_gl(&options)?;
        renderer.load_scene(&scene)?;
        let frame = renderer.render_with(
            &scene,
            &options,
            shadowlab::gl::FrameRequest {
                masks: true,
                ..shadowlab::gl::FrameRequest::default()
            },
        )?;
        frame.gbuffer
    } else {
        None
    };
    let reference = gbuffer
        .as_ref()
        .map(|_| Reference::build_with(&scene, false));
    eprintln!(
        "subdivide: {} lights of {} (cache {})",
        scene.lights.len(),
        scene.name,
        dir.display()
    );
    for (l, light) in scene.lights.iter().enumerate() {
        let start = Instant::now();
        let sub = subdivision::subdivide_cached(
            &scene,
            l,
            Geometry::Everything,
            (&dir, CacheWrite::Write),
        )?;
        let s = sub.stats;
        let how = if s.cached {
            format!("read in {:.1} ms", start.elapsed().as_secs_f64() * 1e3)
        } else {
            format!(
                "built in {:.1} ms ({} receivers, {} casters, {} clips)",
                s.build.as_secs_f64() * 1e3,
                s.receivers,
                s.casters,
                s.clips
            )
        };
        let mut line = format!(
            "light{l} ({}): {} lit + {} shadowed fragments, {how}",
            light.name, s.lit_fragments, s.shadowed_fragments
        );
        if let (Some(g), Some(r)) = (&gbuffer, &reference) {
            let c = compare(
                &subdivision_mask(&sub, g, light),
                &reference_mask(r, g, light, l, Tracing::Bvh),
            );
            line.push_str(&format!(
                "; against the ray caster: {} of {} receiver pixels differ, {} outside the boundary band",
                c.false_shadow + c.false_lit,
                c.receiver_pixels,
                c.false_shadow_excl_boundary + c.false_lit_excl_boundary
            ));
        }
        println!("{line}");
    }
    Ok(())
}
