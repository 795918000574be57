//! `tune` against the fixed sweep of `reproduce`: on the built-in scene, the search's frontier
//! holds a configuration that no point of the sweep dominates, both measured in one round-robin
//! run.

mod common;

use common::{gl_on, options_with};
use indicatif::ProgressBar;
use shadowlab::options::BackendChoice;
use shadowlab::report::bench::{Bench, BenchSettings};
use shadowlab::report::reproduce::fixed_sweep;
use shadowlab::report::tune::{TuneSettings, point, tune};
use shadowlab::scene::builtin;
use shadowlab::scene::path::PathKey;

#[test]
fn the_frontier_holds_a_configuration_no_point_of_the_fixed_sweep_dominates() {
    let scene = builtin::default_scene();
    let base = options_with(&["width=320", "height=240", "estimate.samples=0"]);
    let (_ctx, mut renderer) = gl_on(BackendChoice::Egl, &base);
    renderer.load_scene(&scene).unwrap();
    let path = vec![PathKey::of(&scene.camera)];
    let mut settings = TuneSettings::new(24, path.clone());
    settings.rung_frames = vec![2, 3];
    settings.finalists = 6;
    settings.final_frames = 5;
    settings.per_light = false;
    let hidden = ProgressBar::hidden();
    let result = tune(&mut renderer, &scene, &base, &settings, &hidden).unwrap();
    let frontier: Vec<_> = result.frontier_rows().into_iter().cloned().collect();
    assert!(!frontier.is_empty());
    // The frontier and the sweep measured again together, round-robin, so that the machine's
    // speed drifts on both alike.
    let sweep = fixed_sweep(&base, false).unwrap();
    let tuned: Vec<_> = frontier
        .iter()
        .map(|r| {
            shadowlab::report::bench::BenchConfig::named(
                &format!("tuned {}", r.label),
                r.options.clone(),
            )
        })
        .collect();
    let all: Vec<_> = tuned.iter().chain(&sweep).cloned().collect();
    let rows = Bench::new(
        &mut renderer,
        &scene,
        BenchSettings {
            warmup: 1,
            frames: 7,
            path,
            progress: false,
            interleave: true,
            breakdown: true,
            // The scene as loaded: these measure techniques, not motion.
            motion: false,
            sample_every: 1,
        },
    )
    .run_with(&all, &hidden)
    .unwrap();
    let (tuned_rows, sweep_rows) = rows.split_at(tuned.len());
    let sweep_rows: Vec<_> = sweep_rows
        .iter()
        .filter(|r| r.technique != "none")
        .collect();
    let dominated = |t: (f64, f64)| {
        sweep_rows.iter().any(|s| {
            let s = point(s);
            s.0 <= t.0 && s.1 <= t.1 && (s.0 < t.0 || s.1 < t.1)
        })
    };
    for r in tuned_rows.iter().chain(sweep_rows.iter().copied()) {
        println!(
            "{:60} {:8.2} ms {:8.3}%",
            r.label,
            r.frame_ms.median,
            100.0 * r.error.total
        );
    }
    let undominated: Vec<_> = tuned_rows.iter().filter(|r| !dominated(point(r))).collect();
    assert!(
        !undominated.is_empty(),
        "every frontier configuration is dominated by a point of the fixed sweep"
    );
    println!(
        "not dominated by the sweep: {:?}",
        undominated.iter().map(|r| &r.label).collect::<Vec<_>>()
    );
}
