//! `shadowlab info`: the context path taken, the capability probe, the fallbacks chosen, and
//! which preset the options equal or how they differ from the paper's frame.

use super::{CommonArgs, start_gl};
use anyhow::Result;
use serde_json::json;
use shadowlab::plan::{fixed_function, profile};
use shadowlab::presets::Preset;

#[derive(clap::Args)]
pub struct Args {
    /// Print JSON (keys: backend, renderer, version, fallbacks, ...).
    #[arg(long)]
    json: bool,
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let options = common.options_for(&shadowlab::scene::builtin::default_scene())?;
    let (ctx, renderer) = start_gl(&options)?;
    let caps = &renderer.caps_for(&options)?;
    // What these options would run with: each option the GL cannot run, and its replacement.
    let (_, replaced) = fixed_function::resolve_all(&options, |f| caps.has(f));
    // The machine the planner weighs its decisions for here (`plan.profile`).
    let cost_profile = profile::effective(options.plan.profile, caps.is_software());
    let skipped: Vec<String> = ctx
        .skipped
        .iter()
        .map(|(b, why)| format!("{b}: {why}"))
        .collect();
    if args.json {
        let v = json!({
            "backend": ctx.backend.as_str(),
            "api": ctx.api,
            "device": ctx.device,
            "renderer": caps.renderer,
            "vendor": caps.vendor,
            "version": caps.version,
            "glsl_version": caps.glsl_version,
            "gl_version": [caps.major, caps.minor],
            "profile": caps.profile,
            "software": caps.is_software(),
            "cost_profile": cost_profile.to_string(),
            "depth_bits": caps.depth_bits,
            "stencil_bits": caps.stencil_bits,
            "max_texture_size": caps.max_texture_size,
            "max_cube_map_size": caps.max_cube_map_size,
            "max_renderbuffer_size": caps.max_renderbuffer_size,
            "max_clip_distances": caps.max_clip_distances,
            "extension_count": caps.extension_count,
            "features": caps.features,
            "fallbacks": caps.fallbacks(),
            "options_replaced": replaced,
            "preset": Preset::matching(&options),
            "differs_from_paper": Preset::Paper.differences(&options),
            "skipped_backends": skipped,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("backend:        {} ({})", ctx.backend, ctx.device);
    println!("API:            {}", ctx.api);
    println!("renderer:       {}", caps.renderer);
    println!("vendor:         {}", caps.vendor);
    println!(
        "version:        {} ({} profile)",
        caps.version, caps.profile
    );
    println!("GLSL:           {}", caps.glsl_version);
    println!(
        "plan.profile:   {cost_profile} ({})",
        match cost_profile {
            shadowlab::options::Profile::Software => "decisions may read the frame back",
            _ => "no decision reads the frame back",
        }
    );
    println!(
        "depth/stencil:  {}/{} bits (our framebuffer)",
        caps.depth_bits, caps.stencil_bits
    );
    println!(
        "max sizes:      texture {}, cube map {}, renderbuffer {}",
        caps.max_texture_size, caps.max_cube_map_size, caps.max_renderbuffer_size
    );
    println!("clip distances: {}", caps.max_clip_distances);
    println!("extensions:     {}", caps.extension_count);
    println!("features:");
    for f in &caps.features {
        println!(
            "  {:24} {:3}  {}",
            f.key,
            if f.supported { "yes" } else { "no" },
            f.detail
        );
    }
    let fallbacks = caps.fallbacks();
    println!(
        "fallbacks:{}",
        if fallbacks.is_empty() { " none" } else { "" }
    );
    for f in fallbacks {
        println!("  {f}");
    }
    for r in &replaced {
        println!(
            "  these options: {} = {} -> {} ({})",
            r.option,
            r.asked,
            r.used,
            match r.feature.as_ref() {
                "fixed_function" => "the fixed-function pipeline cannot draw it".to_string(),
                f => format!("no {f}"),
            }
        );
    }
    for s in skipped {
        println!("skipped path:   {s}");
    }
    let differs: Vec<String> = Preset::Paper
        .differences(&options)
        .into_iter()
        .map(|d| format!("{} = {} (paper: {})", d.key, d.value, d.preset))
        .collect();
    println!(
        "preset:         {}",
        Preset::matching(&options).map_or("none", |p| p.name())
    );
    println!(
        "against the paper: {}",
        if differs.is_empty() {
            "the paper's frame".to_string()
        } else {
            differs.join(", ")
        }
    );
    Ok(())
}
