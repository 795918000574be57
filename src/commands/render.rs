//! `shadowlab render`: one frame, headless, to a PNG.

use super::{CommonArgs, load, start_gl};
use anyhow::{Context, Result};
use glam::Vec3;
use shadowlab::frame::Frame;
use shadowlab::gl::FrameRequest;
use shadowlab::options::{Options, Technique};
use shadowlab::plan::auto::learning_frames;
use shadowlab::presets::Preset;
use shadowlab::report::estimate::{GBufferRead, learn_auto, sampled_frame};
use shadowlab::scene::Scene;
use shadowlab::truth::sampled::FrameSample;
use shadowlab::truth::{self, Reference, reference};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Masks, reference masks and error images of every light, with the error rates.
fn write_masks(scene: &Scene, frame: &Frame, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let gbuffer = frame
        .gbuffer
        .as_ref()
        .context("the frame has no G-buffer")?;
    let start = Instant::now();
    let reference = Reference::build(scene);
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let mut trace_ms = 0.0;
    let measured = truth::measure_with(&frame.masks, |mask| {
        let t = Instant::now();
        let exact = truth::exact_mask(scene, &reference, gbuffer, mask);
        trace_ms += t.elapsed().as_secs_f64() * 1e3;
        exact
    });
    for ((mask, exact), (_, counts)) in frame
        .masks
        .iter()
        .zip(&measured.exact)
        .zip(&measured.per_light)
    {
        let r = counts.rates();
        println!(
            "light{} ({}): {} receivers, {:.3}% reference-shadowed, error {:.3}% (false shadow {:.3}%, false lit {:.3}%), {:.3}% excluding the boundary band, {} receiver mismatches",
            mask.light,
            scene.lights[mask.light].name,
            r.receiver_pixels,
            100.0 * counts.reference_shadowed as f64 / r.receiver_pixels.max(1) as f64,
            100.0 * r.total,
            100.0 * r.false_shadow,
            100.0 * r.false_lit,
            100.0 * r.total_excl_boundary,
            counts.receiver_mismatch
        );
        let name = |kind: &str| dir.join(format!("light{}.{kind}.png", mask.light));
        mask.save_png(&name("mask"))?;
        exact.save_png(&name("reference"))?;
        image::save_buffer(
            name("error"),
            &truth::error_image(mask, exact),
            mask.width,
            mask.height,
            image::ExtendedColorType::Rgba8,
        )?;
    }
    let r = measured.total.rates();
    println!(
        "all lights: {} receivers, error {:.3}%, {:.3}% excluding the boundary band; reference: {} triangles, BVH {:.0} ms, rays {:.0} ms",
        r.receiver_pixels,
        100.0 * r.total,
        100.0 * r.total_excl_boundary,
        reference.triangle_count(),
        build_ms,
        trace_ms
    );
    Ok(())
}

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML); the built-in scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Where to write the PNG.
    #[arg(long, default_value = "shadowlab.png")]
    out: PathBuf,
    /// Also write each light's mask, the exact reference mask and the error image into DIR
    /// (light<i>.mask.png, light<i>.reference.png, light<i>.error.png) and print the errors.
    #[arg(long, value_name = "DIR")]
    mask: Option<PathBuf>,
    /// Explain one pixel (repeatable): its surface, and per light what the technique and the
    /// exact reference say and which triangle blocks the shadow ray.
    #[arg(long, value_name = "X,Y")]
    probe: Vec<String>,
    /// Print what the planner decided, what the frame reused and, per light, its error against
    /// the sampled reference (`estimate.samples` pixels traced; JSON on stdout).
    #[arg(long)]
    stats: bool,
    /// Render the scene's motion (animated players, moving lights) at this many seconds
    /// (default: 0, or the time of `--frame` on a path).
    #[arg(long)]
    time: Option<f64>,
    /// A camera path file (`x y z yaw pitch` per line): render its frame `--frame`.
    #[arg(long, requires = "frame")]
    path: Option<PathBuf>,
    /// The frame of `--path` to render, posed at its time (frame / 20 s).
    #[arg(long, requires = "path")]
    frame: Option<usize>,
}

fn parse_probe(s: &str) -> Result<(u32, u32)> {
    let (x, y) = s
        .split_once(',')
        .with_context(|| format!("--probe `{s}` is not X,Y"))?;
    Ok((x.trim().parse()?, y.trim().parse()?))
}

/// Prints what decides pixel (x, y)'s shadows, light by light.
fn probe(scene: &Scene, frame: &Frame, (x, y): (u32, u32)) -> Result<()> {
    let g = frame
        .gbuffer
        .as_ref()
        .context("the frame has no G-buffer")?;
    if x >= g.width || y >= g.height {
        anyhow::bail!(
            "--probe {x},{y} is outside the {}x{} frame",
            g.width,
            g.height
        );
    }
    let i = (y * g.width + x) as usize;
    let (p, n) = (
        Vec3::from_array(g.position[i]),
        Vec3::from_array(g.normal[i]),
    );
    println!(
        "pixel {x},{y}: position {p:?}, normal {n:?}, G-buffer kind {}",
        g.kind[i]
    );
    let reference = Reference::build(scene);
    for mask in &frame.masks {
        let light = &scene.lights[mask.light];
        let from = reference::shadow_ray_origin(p, n);
        let blockers = reference.blockers(from, light.position.as_dvec3());
        let what = if blockers.is_empty() {
            "nothing blocks the ray".to_string()
        } else {
            let list: Vec<String> = blockers
                .iter()
                .take(6)
                .map(|b| {
                    let m = &scene.materials[scene.surfaces[b.surface].material];
                    format!(
                        "\n    at {:.2}: surface {} (`{}`, cull {:?}), {} the light, triangle {:?}",
                        b.distance,
                        b.surface,
                        m.name,
                        m.cull,
                        if b.faces_light { "facing" } else { "back to" },
                        b.triangle.map(|v| v.to_array().map(|c| c as f32))
                    )
                })
                .collect();
            format!(
                "{} triangles block the ray:{}",
                blockers.len(),
                list.concat()
            )
        };
        println!(
            "  light{} ({}, at {:?}): technique {:?}, {what}",
            mask.light,
            light.name,
            light.position.to_array(),
            mask.get(x, y)
        );
    }
    Ok(())
}

/// Moves the camera to `--path`'s frame `--frame` and poses the scene's motion at `--time`
/// (else at that frame's time).
fn pose(scene: &mut Scene, args: &Args) -> Result<()> {
    if let (Some(path), Some(frame)) = (&args.path, args.frame) {
        let keys = shadowlab::scene::path::read(path)?;
        let key = keys.get(frame).with_context(|| {
            format!(
                "{} has {} frames, not {}",
                path.display(),
                keys.len(),
                frame + 1
            )
        })?;
        scene.camera = key.apply(&scene.camera);
    }
    let time = args
        .time
        .unwrap_or_else(|| args.frame.unwrap_or(0) as f64 / shadowlab::scene::path::FRAME_RATE_HZ);
    anyhow::ensure!(
        time.is_finite() && time >= 0.0,
        "--time must be a finite number of seconds >= 0"
    );
    scene.pose_at(time);
    Ok(())
}

/// `--stats`: what the frame decided, reused and waited on, and the sampled error.
fn stats_json(
    frame: &Frame,
    options: &Options,
    sampled: Option<&(FrameSample, f64)>,
) -> serde_json::Value {
    let volumes: Vec<_> = frame.volumes.iter().collect();
    serde_json::json!({
        "preset": Preset::matching(options),
        "fallbacks": frame.fallbacks,
        "differs_from_paper": Preset::Paper.differences(options),
        "plan": frame.plan_stats,
        "cache": frame.cache,
        "syncs": frame.syncs,
        "volumes": volumes,
        "hybrid": frame.hybrid.iter().map(|h| serde_json::json!({
            "light": h.light,
            "receiver_pixels": h.receiver_pixels,
            "silhouette_pixels": h.silhouette_pixels,
            "silhouette_share": h.silhouette_share(),
            "volume_fragments": h.volume_fragments,
            "volume_fragments_unmasked": h.volume_fragments_unmasked,
            "fragment_share": h.fragment_share(),
        })).collect::<Vec<_>>(),
        "sampled": sampled.map(|(s, ms)| serde_json::json!({
            "samples_per_light": options.estimate.samples,
            "trace_ms": ms,
            "total": s.total,
            "per_light": s.per_light,
        })),
    })
}

/// Each hybrid light's classification, a line each.
fn print_hybrid(frame: &Frame) {
    for h in &frame.hybrid {
        let fragments = match (h.volume_fragments, h.volume_fragments_unmasked) {
            (Some(m), Some(all)) => format!(
                "; volume fragments past the computation mask {m} of {all} ({:.1}%)",
                100.0 * h.fragment_share().unwrap_or(0.0)
            ),
            _ => String::new(),
        };
        eprintln!(
            "light{} hybrid: {} silhouette pixels of {} receivers ({:.2}%){fragments}",
            h.light,
            h.silhouette_pixels,
            h.receiver_pixels,
            100.0 * h.silhouette_share()
        );
    }
}

/// The frame's passes in a line, per-light passes summed so that 64 lights still give one
/// readable line.
fn pass_summary(frame: &Frame) -> String {
    let mut totals: Vec<(String, f64, usize)> = Vec::new();
    for p in &frame.passes {
        let stage = p.pass.summed_name();
        match totals.iter_mut().find(|(n, _, _)| *n == stage) {
            Some(t) => {
                t.1 += p.ms;
                t.2 += 1;
            }
            None => totals.push((stage, p.ms, 1)),
        }
    }
    totals
        .iter()
        .map(|(n, ms, count)| match count {
            1 => format!("{n} {ms:.1} ms"),
            _ => format!("{n} {ms:.1} ms over {count}"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let super::Loaded {
        mut scene,
        options,
        report,
    } = load(common, args.scene.as_deref())?;
    pose(&mut scene, args)?;
    // `ctx` is borrowed mutably only to show the frame in a window.
    #[cfg_attr(not(feature = "window"), allow(unused_mut))]
    let (mut ctx, mut renderer) = start_gl(&options)?;
    renderer.load_scene(&scene)?;
    let probes: Vec<(u32, u32)> = args
        .probe
        .iter()
        .map(|s| parse_probe(s))
        .collect::<Result<_>>()?;
    let sampling = options.estimate.samples > 0;
    let wants_reference =
        sampling && (args.stats || options.uses(scene.lights.len(), Technique::Auto));
    let reference = wants_reference.then(|| Reference::build(&scene));
    // `auto` picks from measured costs and errors: measure before the frame that is kept.
    learn_auto(&mut renderer, &scene, &options, reference.as_ref())?;
    let (frame, sampled) = match reference.as_ref().filter(|_| args.stats) {
        Some(r) => {
            // Masks and probes read the frame's G-buffer whole.
            let read = match args.mask.is_some() || !probes.is_empty() {
                true => GBufferRead::Whole,
                false => GBufferRead::Picks,
            };
            let s = sampled_frame(
                &mut renderer,
                &scene,
                &scene.camera,
                &options,
                r,
                (learning_frames(&options) as u64, read),
            )?;
            (s.frame, Some((s.sample, s.trace_ms)))
        }
        None => {
            let request = FrameRequest {
                masks: args.mask.is_some() || !probes.is_empty(),
                ..FrameRequest::default()
            };
            (renderer.render_with(&scene, &options, request)?, None)
        }
    };
    #[cfg(feature = "window")]
    if let Some(window) = ctx.window() {
        // Show the frame too, proving the window path presents what it rendered.
        renderer.present_to_default(options.width, options.height);
        window.window.swap().map_err(anyhow::Error::msg)?;
        window.pump();
    }
    frame
        .save_png(&args.out)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    if let Some(dir) = &args.mask {
        write_masks(&scene, &frame, dir)?;
    }
    for &p in &probes {
        probe(&scene, &frame, p)?;
    }
    if args.stats {
        let stats = stats_json(&frame, &options, sampled.as_ref());
        println!("{}", serde_json::to_string_pretty(&stats)?);
    }
    print_hybrid(&frame);
    eprintln!(
        "wrote {} ({}x{}, {} path, scene {} loaded in {:.0} ms, frame {:.1} ms: {})",
        args.out.display(),
        frame.width(),
        frame.height(),
        ctx.backend,
        scene.name,
        report.load_ms,
        frame.frame_ms,
        pass_summary(&frame)
    );
    Ok(())
}
