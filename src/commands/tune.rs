//! `shadowlab tune`: the Pareto frontier of error against time on one scene, found by a budgeted
//! search of the option space (successive halving), and the cheapest configuration that meets
//! an accuracy target.

use super::{CommonArgs, camera_path, load, start_gl};
use anyhow::{Context, Result};
use indicatif::ProgressBar;
use shadowlab::options::Options;
use shadowlab::report::bench::BenchRow;
use shadowlab::report::plot;
use shadowlab::report::progress;
use shadowlab::report::table::{Align, Table, bench_table};
use shadowlab::report::tune::{TuneResult, TuneSettings, lighting_techniques, space, tune};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML); the built-in scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// The error target in percent of receiver pixels: the answer is the fastest frontier
    /// configuration within it.
    #[arg(long, default_value_t = 0.5)]
    accuracy: f64,
    /// Configurations drawn at random (seeded) for the first rung; each rung keeps the better
    /// half by Pareto rank.
    #[arg(long, default_value_t = 48)]
    candidates: usize,
    /// Configurations measured in full at the end.
    #[arg(long, default_value_t = 8)]
    finalists: usize,
    /// Measured frames of each finalist (round-robin).
    #[arg(long, default_value_t = 8)]
    final_frames: usize,
    /// Seed of the draw.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Camera path, as for `bench`: `turn` or a recorded path file; the scene's camera when
    /// absent.
    #[arg(long)]
    path: Option<String>,
    /// Skip the per-light measurement (each light's cheapest map size and filter, or volumes,
    /// within the target).
    #[arg(long)]
    no_per_light: bool,
    /// MiB the final round's renderers may hold together (maps, volume buffers and their CPU
    /// copies, subdivision fragments: what each finalist held after its frames in the
    /// rungs): past it the finalists are timed a group at a time, each with its baseline (0:
    /// all at once, whatever they hold). Each renderer's own maps stay within
    /// `shadow_map.budget_mb`.
    #[arg(long, value_name = "MIB", default_value_t = shadowlab::report::tune::DEFAULT_MEMORY_MB)]
    memory_mb: f32,
    /// On a still camera, a candidate's measured frames stop once they add up to this many
    /// seconds, one frame at least (a frame of seconds is its own long sample). 0: every
    /// candidate all its frames.
    #[arg(long, value_name = "S", default_value_t = shadowlab::report::bench::ENOUGH_SECONDS)]
    enough_seconds: f64,
    /// Folder for tune.md, tune.json and tune.png (default: tune-<scene>).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The frontier as a table: fastest first, with whether each meets the target.
fn frontier_table(result: &TuneResult, accuracy: f64) -> Table {
    let mut t = Table::new(&[
        ("configuration", Align::Left),
        ("frame ms", Align::Right),
        ("× shadows off", Align::Right),
        ("error % (exact, first frame)", Align::Right),
        ("path error % (sampled median)", Align::Right),
        ("meets target", Align::Left),
    ]);
    for r in result.frontier_rows() {
        t.push(vec![
            r.label.clone(),
            format!("{:.2}", r.frame_ms.median),
            format!("{:.2}", r.ratio_to_shadows_off),
            format!("{:.3}", 100.0 * r.error.total),
            r.sampled
                .as_ref()
                .map_or("–".into(), |p| format!("{:.3}", 100.0 * p.median)),
            if 100.0 * r.error.total <= accuracy {
                "yes"
            } else {
                "no"
            }
            .into(),
        ]);
    }
    t.note = Some(format!(
        "Pareto frontier of {} finalists ({} configurations drawn, {} dimensions searched); \
         target {accuracy}%.",
        result.rows.len(),
        result.settings.candidates,
        space().len()
    ));
    t
}

/// Each light's cheapest configuration of the per-light grid within the target.
fn per_light_table(result: &TuneResult) -> Table {
    let mut t = Table::new(&[
        ("light", Align::Right),
        ("cheapest within the target", Align::Left),
        ("its error %", Align::Right),
        ("its passes ms", Align::Right),
    ]);
    for c in &result.per_light {
        t.push(vec![
            c.light.to_string(),
            if c.meets {
                c.label.clone()
            } else {
                format!("none meets it; the most accurate: {}", c.label)
            },
            format!("{:.3}", 100.0 * c.error),
            format!("{:.2}", c.ms),
        ]);
    }
    t.note = Some(
        "Per light: shadow volumes, and shadow maps at 256–2048 with nearest, hw2x2 and pcf3x3 \
         filters, each light judged by its own error (exact, first frame) and its own passes."
            .into(),
    );
    t
}

/// What draws each light with its own size: the filter is one for every light, so among the
/// scene's filter's sizes and volumes.
fn per_light_sets(result: &TuneResult, base: &Options) -> String {
    format!(
        "Each light its own map size, at the scene's filter ({}): `--set lighting.techniques={}`\n",
        base.shadow_map.filter,
        lighting_techniques(&result.per_light_drawable)
    )
}

fn answer(result: &TuneResult, accuracy: f64) -> String {
    match result.cheapest_meeting(accuracy) {
        Some(r) => format!(
            "cheapest within {accuracy}%: {} ({:.3}% wrong, {:.2} ms, {:.2}× shadows off)",
            r.label,
            100.0 * r.error.total,
            r.frame_ms.median,
            r.ratio_to_shadows_off
        ),
        None => {
            let best: Option<&BenchRow> = result
                .rows
                .iter()
                .min_by(|a, b| a.error.total.total_cmp(&b.error.total));
            format!(
                "no configuration found meets {accuracy}%; the most accurate: {}",
                best.map_or("none".into(), |r| format!(
                    "{} ({:.3}%)",
                    r.label,
                    100.0 * r.error.total
                ))
            )
        }
    }
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let loaded = load(common, args.scene.as_deref())?;
    let (scene, options) = (loaded.scene, loaded.options);
    let path = camera_path(&scene.camera, args.path.as_deref())?;
    let mut settings = TuneSettings::new(args.candidates.max(2), path);
    settings.finalists = args.finalists.max(1);
    settings.final_frames = args.final_frames.max(1);
    settings.seed = args.seed;
    settings.per_light = !args.no_per_light;
    settings.accuracy = args.accuracy;
    settings.memory_mb = (args.memory_mb > 0.0).then_some(args.memory_mb);
    settings.enough_seconds = (args.enough_seconds > 0.0).then_some(args.enough_seconds);
    let (_ctx, mut renderer) = start_gl(&options)?;
    renderer.load_scene(&scene)?;
    eprintln!(
        "tune: {} on {}, {} configurations drawn, halving over {:?} frames to {}, {}",
        scene.name,
        renderer.caps().renderer,
        settings.candidates,
        settings.rung_frames,
        settings.finalists,
        if settings.path.len() > 1 {
            format!("{} poses", settings.path.len())
        } else {
            "still camera".into()
        }
    );
    let bar = ProgressBar::with_draw_target(Some(0), progress::draw_target());
    bar.set_style(progress::style(
        "{prefix}: [{elapsed_precise}] {bar:30} {pos}/{len}, {left} left, {peak}  {msg}",
    ));
    let result = tune(&mut renderer, &scene, &options, &settings, &bar)?;
    bar.finish_and_clear();
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("tune-{}", scene.name)));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let frontier = frontier_table(&result, args.accuracy);
    let all = bench_table(&result.rows);
    let rungs: Vec<String> = result
        .rungs
        .iter()
        .map(|r| {
            let outcome = if r.stage == "per light" {
                format!("{} lights answered", r.kept)
            } else {
                format!("{} kept", r.kept)
            };
            let carried = if r.carried > 0 {
                format!(", {} carried from the rung before", r.carried)
            } else {
                String::new()
            };
            format!(
                "{}: {} configurations × {} frames{carried}, {} error frames → {outcome} ({:.0} s)",
                r.stage, r.configurations, r.frames, r.error_frames, r.seconds
            )
        })
        .collect();
    // The command as a person would type it (the binary by its name, not its path).
    let command = std::iter::once("shadowlab".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    let lights = if result.per_light.is_empty() {
        String::new()
    } else {
        format!(
            "## Per light\n\n{}\n{}\n",
            per_light_table(&result).to_markdown(),
            per_light_sets(&result, &options)
        )
    };
    let md = format!(
        "# tune: {}\n\n{}\n\n## Frontier\n\n{}\n{lights}## Finalists\n\n{}\n## Search\n\n- {}\n\nRegenerate: `{command}`\n",
        scene.name,
        answer(&result, args.accuracy),
        frontier.to_markdown(),
        all.to_markdown(),
        rungs.join("\n- ")
    );
    std::fs::write(out.join("tune.md"), &md)?;
    std::fs::write(
        out.join("tune.json"),
        serde_json::to_string_pretty(&result)?,
    )?;
    plot::error_vs_time_marked(
        &result.rows,
        &result.frontier,
        &format!("{}: tune finalists (ringed: frontier)", scene.name),
        &out.join("tune.png"),
    )
    .map_err(anyhow::Error::msg)?;
    println!("{}", frontier.to_markdown());
    if !result.per_light.is_empty() {
        println!("{}", per_light_table(&result).to_markdown());
        println!("{}", per_light_sets(&result, &options));
    }
    println!("{}", answer(&result, args.accuracy));
    eprintln!("wrote {}/tune.md, tune.json, tune.png", out.display());
    Ok(())
}
