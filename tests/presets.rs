//! `--preset paper`: the paper's frame (no planner, two saturating depth-fail stencil passes)
//! on a real map, and the command line that reports it.

mod common;

use common::{Measurer, load_scene_file, options_with, stdout_of};
use shadowlab::presets::Preset;
use std::process::Command;

#[test]
fn the_paper_preset_runs_the_papers_frame_on_oa_dm1() {
    let (scene, _, loaded) = load_scene_file("oa_dm1");
    let mut paper = loaded.clone();
    Preset::Paper.apply(&mut paper).unwrap();
    let mut m = Measurer::new(scene, &paper);
    let preset = m.measure(&paper);
    let p = &preset.frame.plan_stats;
    // The paper's frame: every light drawn (nothing culled), every volume counted depth-fail in
    // two passes. The planned default counts depth-pass where it can, in one pass, so each of
    // these fails if the preset does not reach the renderer.
    assert_eq!(p.stencil_passes, 2, "{p:?}");
    assert_eq!(p.zpass_parts, 0, "{p:?}");
    assert!(p.zfail_parts > 0, "{p:?}");
    assert_eq!(p.lights_culled_frustum + p.lights_culled_pvs, 0, "{p:?}");
    let planned = m.measure(&options_with(&["technique=shadow_volume"]));
    let q = &planned.frame.plan_stats;
    assert!(q.stencil_passes == 1 && q.zpass_parts > 0, "{q:?}");
    // The same frame as the planner switched off by hand with the paper's technique and
    // casters (the defaults cast from both sides).
    let by_hand = m.measure(&options_with(&[
        "plan.enabled=false",
        "technique=shadow_volume",
        "shadow_volume.casters=front",
        "shadow_map.cull=front",
        "shadow_map.offset_growth=1",
    ]));
    for mask in &preset.frame.masks {
        assert_eq!(
            &mask.values,
            &by_hand.mask(mask.light).values,
            "light {}",
            mask.light
        );
    }
    println!(
        "oa_dm1, paper preset: error {:.3}% of {} receiver pixels",
        100.0 * preset.total.rates().total,
        preset.total.receiver_pixels
    );
}

#[test]
fn render_stats_say_which_preset_ran_and_what_differs_from_the_paper() {
    common::openarena_data();
    let out_png = std::env::temp_dir().join(format!("shadowlab-preset-{}.png", std::process::id()));
    let run = |size: &str, extra: &[&str]| -> serde_json::Value {
        let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
            .args(["render", "--scene", "assets/scenes/oa_dm1.toml", "--stats"])
            .args(["--size", size, "--out"])
            .arg(&out_png)
            .args(extra)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let text = stdout_of(out);
        let start = text.find("\n{").map_or(0, |i| i + 1);
        let end = text.find("\n}").expect("the stats JSON") + 2;
        serde_json::from_str(&text[start..end]).unwrap_or_else(|e| panic!("{e}: {text}"))
    };
    // --size differs from the paper's 640x480: the one difference reported.
    let paper = run("160x120", &["--preset", "paper"]);
    let keys: Vec<&str> = paper["differs_from_paper"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["key"].as_str().unwrap())
        .collect();
    assert_eq!(keys, ["height", "width"], "{paper}");
    assert_eq!(paper["plan"]["stencil_passes"], 2);
    let tweaked = run(
        "160x120",
        &["--preset", "paper", "--set", "shadow_map.size=1024"],
    );
    assert_eq!(tweaked["differs_from_paper"].as_array().unwrap().len(), 3);
    let default = run("640x480", &[]);
    assert_eq!(default["preset"], "default", "{default}");
    let _ = std::fs::remove_file(&out_png);
}
