//! The sampled reference against the full one: along a turning camera on the five benchmark scenes
//! and on every hard case, both techniques, the sampled error of each frame (over every light's
//! receivers) holds the full reference's error within its stated 95% interval in at least 95% of
//! the frames. Sampling is seeded; the figures print with `--nocapture`.

mod common;

use common::{Measurer, load_asset, openarena_data, options_with};
use shadowlab::scene::path;
use shadowlab::truth::Reference;
use shadowlab::truth::sampled::sample_frame;

const SCENES: &[&str] = &[
    "assets/scenes/oa_dm1.toml",
    "assets/scenes/oa_dm3.toml",
    "assets/scenes/q3dm6ish.toml",
    "assets/scenes/wrackdm17.toml",
    "assets/scenes/ctf_compromise.toml",
];

/// Frames along the turn per scene (evenly spaced over the 360°).
const FRAMES: usize = 8;
/// Pixels per light and frame: fewer than the default 512, so that most lights are sampled
/// rather than traced whole and the intervals are really put to the test.
const SAMPLES: usize = 128;

/// One frame's comparison.
struct Outcome {
    full: f64,
    /// Whether the sampled interval holds the full error.
    held: bool,
    exact: bool,
}

fn run_scene(file: &str, outcomes: &mut Vec<(String, Outcome)>) {
    let (scene, _, _) = load_asset(file);
    let camera = scene.camera;
    let reference = Reference::build(&scene);
    for technique in ["technique=shadow_map", "technique=shadow_volume"] {
        let o = options_with(&[technique, "width=320", "height=240"]);
        let mut m = Measurer::new(scene.clone(), &o);
        for (i, key) in path::turn(&camera, FRAMES).iter().enumerate() {
            m.set_camera(key.apply(&camera));
            let measured = m.measure(&o);
            let g = measured.frame.gbuffer.as_ref().unwrap();
            let s = sample_frame(
                &reference,
                g,
                &scene.lights,
                &measured.frame.masks,
                SAMPLES,
                7,
                i as u64,
            );
            let full = measured.total.rates().total;
            let label = format!("{} {technique} frame {i}", scene.name);
            println!(
                "{label}: full {:.4}% sampled {:.4}% [{:.4}, {:.4}]{}",
                100.0 * full,
                100.0 * s.total.value,
                100.0 * s.total.low,
                100.0 * s.total.high,
                if s.total.holds(full) { "" } else { "  MISSED" }
            );
            outcomes.push((
                label,
                Outcome {
                    full,
                    held: s.total.holds(full),
                    exact: s.per_light.iter().all(|l| l.exact),
                },
            ));
        }
    }
}

#[test]
fn sampled_intervals_hold_the_full_error_in_95_percent_of_frames() {
    openarena_data();
    let mut outcomes = Vec::new();
    for file in SCENES {
        run_scene(file, &mut outcomes);
    }
    let hard = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/hard");
    let mut cases: Vec<_> = std::fs::read_dir(&hard)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    cases.sort();
    assert!(
        cases.len() >= 11,
        "hard cases missing under {}",
        hard.display()
    );
    for case in &cases {
        let rel = format!(
            "assets/hard/{}",
            case.file_name().unwrap().to_string_lossy()
        );
        run_scene(&rel, &mut outcomes);
    }
    let held = outcomes.iter().filter(|(_, o)| o.held).count();
    let sampled: Vec<_> = outcomes.iter().filter(|(_, o)| !o.exact).collect();
    let wrong: Vec<_> = sampled.iter().filter(|(_, o)| o.full > 0.002).collect();
    let missed: Vec<&str> = outcomes
        .iter()
        .filter(|(_, o)| !o.held)
        .map(|(l, _)| l.as_str())
        .collect();
    println!(
        "{held} of {} frames held ({} sampled rather than traced whole, {} of them over 0.2% wrong); missed: {missed:?}",
        outcomes.len(),
        sampled.len(),
        wrong.len()
    );
    // The test means something only if most frames were sampled and some had errors to find.
    assert!(sampled.len() * 2 > outcomes.len(), "too few sampled frames");
    assert!(wrong.len() >= 10, "too few frames with errors to test");
    assert!(
        held as f64 >= 0.95 * outcomes.len() as f64,
        "{held} of {} frames held the full error: {missed:?}",
        outcomes.len()
    );
}

#[test]
fn every_pixel_traced_gives_the_full_error_exactly() {
    // With more samples than receivers the sampled reference is the full one.
    let (scene, _, _) = load_asset("assets/hard/grazing.toml");
    let reference = Reference::build(&scene);
    let o = options_with(&["technique=shadow_map", "width=160", "height=120"]);
    let mut m = Measurer::new(scene.clone(), &o);
    let measured = m.measure(&o);
    let g = measured.frame.gbuffer.as_ref().unwrap();
    let s = sample_frame(
        &reference,
        g,
        &scene.lights,
        &measured.frame.masks,
        1 << 20,
        1,
        0,
    );
    assert!(s.per_light.iter().all(|l| l.exact));
    let full = measured.total.rates().total;
    assert!(full > 0.0, "the grazing case should have errors to count");
    assert!(
        (s.total.value - full).abs() < 1e-9,
        "sampled {} full {full}",
        s.total.value
    );
}
