//! `tune` on the built-in scene: what it keeps and calls its frontier follows from what it
//! measured, and the errors it reports are the frames' against the exact reference. Which
//! configurations are faster is a timing, and timings are `bench`'s and `reproduce`'s to report
//! (reproduce's section frontier-oa_dm1 sets tune's frontier beside its fixed sweep); nothing
//! here depends on how fast this machine draws.

mod common;

use common::{Measurer, options_with};
use indicatif::ProgressBar;
use shadowlab::report::tune::{TuneSettings, point, tune};
use shadowlab::scene::builtin;
use shadowlab::scene::path::PathKey;

#[test]
fn the_frontier_is_what_tune_measured_and_its_errors_are_the_frames() {
    let scene = builtin::default_scene();
    let base = options_with(&["width=320", "height=240", "estimate.samples=0"]);
    let mut m = Measurer::new(scene.clone(), &base);
    let path = vec![PathKey::of(&scene.camera)];
    let mut settings = TuneSettings::new(24, path);
    settings.rung_frames = vec![2, 3];
    settings.finalists = 6;
    settings.final_frames = 5;
    settings.per_light = false;
    let hidden = ProgressBar::hidden();
    let result = tune(m.renderer(), &scene, &base, &settings, &hidden).unwrap();

    // The rungs halve the candidates down to the finalists, which the final round measures.
    let stages: Vec<(&str, usize, usize)> = result
        .rungs
        .iter()
        .map(|r| (r.stage, r.configurations, r.kept))
        .collect();
    println!("rungs (stage, measured, kept): {stages:?}");
    assert_eq!(stages.first().map(|s| s.1), Some(24), "{stages:?}");
    for pair in stages.windows(2) {
        assert_eq!(
            pair[0].2, pair[1].1,
            "a rung measures what the last kept: {stages:?}"
        );
    }
    assert_eq!(stages.last().map(|s| (s.0, s.1)), Some(("final", 6)));
    assert_eq!(result.rows.len(), 6);

    // The frontier: exactly the finalists no other finalist dominates on (error, time) as
    // measured, whatever those times were.
    let points: Vec<(f64, f64)> = result.rows.iter().map(point).collect();
    let dominated = |i: usize| {
        points.iter().any(|&(e, t)| {
            let (ei, ti) = points[i];
            e <= ei && t <= ti && (e < ei || t < ti)
        })
    };
    for (i, r) in result.rows.iter().enumerate() {
        println!(
            "{:60} {:8.2} ms {:8.3}% {}",
            r.label,
            r.frame_ms.median,
            100.0 * r.error.total,
            if result.frontier[i] { "frontier" } else { "" }
        );
        assert_eq!(result.frontier[i], !dominated(i), "{}", r.label);
    }
    let frontier = result.frontier_rows();
    assert!(!frontier.is_empty());

    // Each frontier configuration's error is its frame's against the exact reference: drawn
    // again here, the same pixels decide the same way.
    for r in &frontier {
        let again = m.measure(&r.options).total.rates().total;
        assert!(
            (again - r.error.total).abs() < 1e-12,
            "{}: tune reported {:.4}%, the frame measures {:.4}%",
            r.label,
            100.0 * r.error.total,
            100.0 * again
        );
    }
    // The fastest within the target meets it.
    let pick = result
        .cheapest_meeting(settings.accuracy)
        .expect("a frontier configuration within the target");
    assert!(
        100.0 * pick.error.total <= settings.accuracy,
        "{}",
        pick.label
    );
}

/// A configuration whose frames stopped at `enough_seconds` in one rung is not measured
/// again in the next (it would take as many frames of the same still view): with a bound
/// every frame passes, the second rung carries every configuration it ranks; without one,
/// none. Made to fail: with nothing carried, the second rung measured all 4 again.
#[test]
fn a_rung_carries_the_rows_that_stopped_at_enough_seconds() {
    let scene = builtin::default_scene();
    let base = options_with(&["width=160", "height=120", "estimate.samples=0"]);
    let mut m = Measurer::new(scene.clone(), &base);
    let path = vec![PathKey::of(&scene.camera)];
    for (enough, carried) in [(Some(1e-9), 4), (None, 0)] {
        let mut settings = TuneSettings::new(8, path.clone());
        settings.rung_frames = vec![2, 3];
        settings.finalists = 2;
        settings.final_frames = 2;
        settings.per_light = false;
        settings.enough_seconds = enough;
        let hidden = ProgressBar::hidden();
        let result = tune(m.renderer(), &scene, &base, &settings, &hidden).unwrap();
        let second = &result.rungs[1];
        assert_eq!(second.stage, "halving");
        assert_eq!(second.configurations, 4, "{:?}", result.rungs);
        assert_eq!(second.carried, carried, "{enough:?}: {:?}", result.rungs);
        assert_eq!(result.rungs[0].carried, 0);
        assert_eq!(result.rows.len(), 2);
    }
}

/// On one still view the rungs sample the masks of the error frames they draw, so the final
/// round draws no finalist's error frame again (on oa_dm3 a paper's-frame finalist's takes
/// seconds). Made to fail: with the rungs' samples zeroed, the final round drew one per
/// finalist.
#[test]
fn the_final_round_on_one_view_draws_no_error_frame_again() {
    let scene = builtin::default_scene();
    let base = options_with(&["width=160", "height=120", "estimate.samples=256"]);
    let mut m = Measurer::new(scene.clone(), &base);
    let mut settings = TuneSettings::new(6, vec![PathKey::of(&scene.camera)]);
    settings.rung_frames = vec![1];
    settings.finalists = 2;
    settings.final_frames = 1;
    settings.per_light = false;
    let hidden = ProgressBar::hidden();
    let result = tune(m.renderer(), &scene, &base, &settings, &hidden).unwrap();
    let (first, last) = (&result.rungs[0], result.rungs.last().unwrap());
    assert_eq!(
        first.error_frames, first.configurations,
        "{:?}",
        result.rungs
    );
    assert_eq!((last.stage, last.configurations), ("final", 2));
    assert_eq!(last.error_frames, 0, "{:?}", result.rungs);
    for r in &result.rows {
        let sampled = r.sampled.as_ref().expect("a finalist's sampled error");
        assert_eq!(sampled.frames.len(), 1, "{}", r.label);
        assert_eq!(sampled.samples_per_light, 256, "{}", r.label);
    }
}
