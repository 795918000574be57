//! `shadow_map.budget_mb`: a frame whose maps would hold more than the budget draws each
//! light's maps just before its own pass, into textures the lights share. It must draw the
//! same image and masks as the frame that draws every map first, and hold no more than one
//! light's maps when the budget is smaller than any light's.

mod common;

use common::{image_difference, load_scene_file};
use shadowlab::frame::Frame;
use shadowlab::options::{BackendChoice, Options};
use shadowlab::plan::Plan;
use shadowlab::plan::map_memory::light_map_bytes;
use shadowlab::run::{FrameRequest, Renderer};
use shadowlab::scene::Scene;

/// The frame with masks, and the bytes of map textures the renderer holds after it.
fn frame_and_held(r: &mut Renderer, scene: &Scene, o: &Options) -> (Frame, u64) {
    let request = FrameRequest {
        masks: true,
        ..FrameRequest::default()
    };
    let frame = r
        .render_with(scene, o, request)
        .unwrap_or_else(|e| panic!("{e}"));
    (frame, r.held().map_bytes)
}

#[test]
fn maps_drawn_per_light_within_the_budget_draw_the_frame_of_every_map_first() {
    let (scene, _, base) = load_scene_file("oa_dm1");
    let cases: [&[&str]; 5] = [
        // The paper's copies from the frame's depth (here from a scratch framebuffer).
        &["technique=shadow_map"],
        &["technique=shadow_map", "shadow_map.depth_source=fbo"],
        &[
            "technique=shadow_map",
            "shadow_map.omni=cube",
            "shadow_map.size=1024",
        ],
        &["technique=hybrid", "shadow_map.depth_source=fbo"],
        &[
            "technique=shadow_map",
            "shadow_map.buffer=id",
            "shadow_map.depth_source=fbo",
        ],
    ];
    for sets in cases {
        let mut o = base.clone();
        for s in sets {
            o.set_assignment(s).unwrap_or_else(|e| panic!("{e}"));
        }
        o.width = 320;
        o.height = 240;
        let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &o);
        r.load_scene(&scene).unwrap();
        let mut all_first = o.clone();
        all_first.shadow_map.budget_mb = 0.0;
        let (a, _) = frame_and_held(&mut r, &scene, &all_first);
        assert!(
            !a.plan_stats.maps_per_light,
            "{sets:?}: no budget, every map first"
        );
        // A budget below any one light's maps: every light takes the textures over.
        let mut budget = o.clone();
        budget.shadow_map.budget_mb = 0.01;
        let (_ctx2, mut r2) = common::gl_on(BackendChoice::Egl, &o);
        r2.load_scene(&scene).unwrap();
        // Twice: the second frame finds the textures the first left to another light.
        for frame in 0..2 {
            let (b, held) = frame_and_held(&mut r2, &scene, &budget);
            assert!(b.plan_stats.maps_per_light, "{sets:?}: over the budget");
            // Two renderers: their colours within rounding, their masks (below) identical.
            common::assert_colours_within_rounding(&a, &b, &format!("{sets:?} frame {frame}"));
            assert_eq!(a.masks.len(), b.masks.len());
            for (ma, mb) in a.masks.iter().zip(&b.masks) {
                let d = common::differing(ma, mb);
                assert_eq!(d, 0, "{sets:?} frame {frame}: light {}'s mask", ma.light);
            }
            let plan = Plan::build(&scene, &budget);
            let largest = plan
                .lights
                .iter()
                .map(|lp| light_map_bytes(lp, &budget.shadow_map))
                .max()
                .unwrap_or(0);
            assert!(largest > 0, "{sets:?}: some light has maps");
            assert!(
                held <= largest,
                "{sets:?} frame {frame}: {held} bytes of maps held, one light's largest {largest}"
            );
        }
        assert!(
            r.held().map_bytes > r2.held().map_bytes,
            "{sets:?}: every map first holds more"
        );
        // Masks drawn within the frame leave its image as a frame without masks draws it.
        // (With the frame's target left unbound after a mask, the hybrid's frames above
        // differed by 71 393 pixels.)
        let (_ctx3, mut r3) = common::gl_on(BackendChoice::Egl, &o);
        r3.load_scene(&scene).unwrap();
        let plain = r3
            .render_with(&scene, &budget, FrameRequest::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let masked = frame_and_held(&mut r3, &scene, &budget);
        let (max, differing) = image_difference(&plain, &masked.0);
        assert_eq!(
            differing, 0,
            "{sets:?}: masks within the frame change {differing} pixels (by up to {max})"
        );
    }
}

#[test]
fn a_renderer_released_between_configurations_holds_nothing_and_draws_the_same() {
    let (scene, _, mut o) = load_scene_file("oa_dm1");
    o.width = 320;
    o.height = 240;
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &o);
    r.load_scene(&scene).unwrap();
    let mut maps = o.clone();
    maps.set_assignment("technique=shadow_map").unwrap();
    let mut volumes = o.clone();
    volumes.set_assignment("technique=shadow_volume").unwrap();
    let first = r.render(&scene, &maps).unwrap();
    r.render(&scene, &volumes).unwrap();
    let held = r.held();
    assert!(held.map_textures > 0 && held.map_bytes > 0, "{held:?}");
    assert!(held.volume_parts > 0, "{held:?}");
    r.release_kept();
    assert_eq!(r.held(), shadowlab::run::Held::default());
    let again = r.render(&scene, &maps).unwrap();
    let (max, differing) = image_difference(&first, &again);
    assert_eq!(differing, 0, "{differing} pixels differ by up to {max}");
}

/// Bytes of each planned light's maps, in the plan's order.
fn lights_bytes(scene: &Scene, o: &Options) -> Vec<u64> {
    let plan = Plan::build(scene, o);
    plan.lights
        .iter()
        .map(|lp| light_map_bytes(lp, &o.shadow_map))
        .filter(|&b| b > 0)
        .collect()
}

#[test]
fn the_papers_frame_drawing_maps_per_light_holds_one_lights_maps() {
    // The paper's frame draws every map each frame: a map of a light already lit is never
    // read again, so however large the budget, the textures held are one light's.
    let (scene, _, mut o) = load_scene_file("oa_dm1");
    o.width = 320;
    o.height = 240;
    o.set_assignment("plan.enabled=false").unwrap();
    o.set_assignment("technique=hybrid").unwrap();
    let bytes = lights_bytes(&scene, &o);
    assert!(bytes.len() > 1, "{bytes:?}");
    let all: u64 = bytes.iter().sum();
    let largest = *bytes.iter().max().unwrap();
    assert!(
        u64::from(o.shadow_map.budget_mb as u32) * 1048576 > all,
        "the budget holds every light's maps ({all} bytes)"
    );
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &o);
    r.load_scene(&scene).unwrap();
    let mut all_first = o.clone();
    all_first.shadow_map.budget_mb = 0.0;
    let (a, held_all) = frame_and_held(&mut r, &scene, &all_first);
    assert!(!a.plan_stats.maps_per_light);
    assert_eq!(held_all, all, "every map first holds every light's");
    let (_ctx2, mut r2) = common::gl_on(BackendChoice::Egl, &o);
    r2.load_scene(&scene).unwrap();
    for frame in 0..2 {
        let (b, held) = frame_and_held(&mut r2, &scene, &o);
        assert!(b.plan_stats.maps_per_light, "beside the volumes: per light");
        assert!(
            held <= largest,
            "frame {frame}: {held} bytes held, one light's largest {largest} (all {all})"
        );
        let (max, differing) = image_difference(&a, &b);
        assert_eq!(differing, 0, "frame {frame}: by up to {max}");
        for (ma, mb) in a.masks.iter().zip(&b.masks) {
            assert_eq!(common::differing(ma, mb), 0, "light {}'s mask", ma.light);
        }
    }
}

#[test]
fn a_still_camera_over_the_budget_draws_again_only_the_maps_that_did_not_fit() {
    // Lights draw their maps in the same order every frame: giving up the least recently
    // used map over the budget gives up the one the next light needs next frame, so a still
    // camera drew every map every frame (q3dm6ish: 15 of 15 drawn again, none reused).
    let (scene, _, mut o) = load_scene_file("q3dm6ish");
    o.width = 320;
    o.height = 240;
    o.set_assignment("technique=shadow_map").unwrap();
    o.set_assignment("shadow_map.size=1024").unwrap();
    // Every light's maps of one kind (a cube each), so that each light's textures can take
    // over another's.
    o.set_assignment("shadow_map.omni=cube").unwrap();
    let bytes = lights_bytes(&scene, &o);
    assert!(bytes.len() > 2, "{bytes:?}");
    let all: u64 = bytes.iter().sum();
    // Room for every light's maps but the smallest's.
    let budget = all - bytes.iter().min().unwrap();
    o.shadow_map.budget_mb = (budget as f64 / 1048576.0) as f32;
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &o);
    r.load_scene(&scene).unwrap();
    let (first, _) = frame_and_held(&mut r, &scene, &o);
    assert!(first.plan_stats.maps_per_light);
    let drawn = first.cache.maps_rendered;
    let (second, held) = frame_and_held(&mut r, &scene, &o);
    let (again, reused) = (second.cache.maps_rendered, second.cache.maps_reused);
    assert!(held <= budget, "{held} bytes held, budget {budget}");
    // The budget leaves out only the smallest light's maps: one light's maps, or two where
    // the one that does not fit is larger, are drawn again.
    assert!(
        again <= 2 && reused + again == drawn,
        "second frame: {again} maps drawn again, {reused} reused, of {drawn} ({bytes:?})"
    );
    let (max, differing) = image_difference(&first, &second);
    assert_eq!(differing, 0, "by up to {max}");
    for (ma, mb) in first.masks.iter().zip(&second.masks) {
        assert_eq!(common::differing(ma, mb), 0, "light {}'s mask", ma.light);
    }
}

#[test]
fn a_round_robin_bench_draws_each_error_frame_from_the_scene_alone() {
    // Round-robin timing draws each configuration's error frame on the bench's own renderer,
    // one configuration after another. A frame without maps keeps the last frame's maps, so
    // a volumes configuration after a maps one held both (oa_dm3: a planned PSM's 512 MiB of
    // maps beside the subdivision's fragment buffers).
    use shadowlab::report::bench::Bench;
    let (scene, o) = small_oa_dm1();
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &o);
    r.load_scene(&scene).unwrap();
    let configs = technique_configs(&o, &["shadow_map", "shadow_volume"]);
    let rows = Bench::new(&mut r, &scene, one_frame(&scene, true, None))
        .run(&configs)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rows.len(), 2);
    assert!(rows[0].error.total < 0.01, "{}", rows[0].error.total);
    let held = r.held();
    assert_eq!(
        held,
        shadowlab::run::Held::default(),
        "after the volumes' error frame"
    );
}

#[test]
fn a_round_robin_bench_groups_its_renderers_by_what_each_held_before() {
    // `tune`'s final round times its finalists round-robin, a group of renderers at a time
    // within `--memory-mb`. The groups counted each renderer's planned maps only, so volumes
    // and the subdivision's fragments (no maps) all went into one group whatever they held;
    // now they count what the same options held in the rungs before.
    use shadowlab::report::bench::{Bench, BenchRow};
    let (scene, o) = small_oa_dm1();
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &o);
    r.load_scene(&scene).unwrap();
    let configs = technique_configs(&o, &["shadow_volume", "subdivision"]);
    let settings =
        |interleave: bool, memory_mb: Option<f32>| one_frame(&scene, interleave, memory_mb);
    let groups = |rows: &[BenchRow]| -> Vec<Option<usize>> {
        rows.iter().map(|row| row.round_robin_group).collect()
    };
    // One after another, as the rungs measure.
    let mut rungs = Bench::new(&mut r, &scene, settings(false, None));
    let measured = rungs.run(&configs).unwrap_or_else(|e| panic!("{e}"));
    let kept = rungs.take_kept();
    let held: Vec<u64> = measured.iter().map(|row| row.held_bytes).collect();
    assert_eq!(groups(&measured), [None, None]);
    assert!(held.iter().all(|&b| b > 0), "held {held:?}");
    // A limit below what either held: each needs a group of its own.
    let limit = Some((*held.iter().min().unwrap() as f64 / 2.0 / 1048576.0) as f32);
    let fresh = Bench::new(&mut r, &scene, settings(true, limit))
        .run(&configs)
        .unwrap_or_else(|e| panic!("{e}"));
    // Without an earlier bench only the planned maps count, and neither plans any.
    assert_eq!(groups(&fresh), [Some(0), Some(0)]);
    let after_rungs = Bench::new(&mut r, &scene, settings(true, limit))
        .with_kept(kept)
        .run(&configs)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(groups(&after_rungs), [Some(0), Some(1)], "held {held:?}");
}

/// oa_dm1 at 160x120, unsampled: the round-robin cases' scene.
fn small_oa_dm1() -> (Scene, Options) {
    let (scene, _, mut o) = load_scene_file("oa_dm1");
    o.width = 160;
    o.height = 120;
    o.estimate.samples = 0;
    (scene, o)
}

/// `o` with each of `techniques`, named by it.
fn technique_configs(
    o: &Options,
    techniques: &[&str],
) -> Vec<shadowlab::report::bench::BenchConfig> {
    techniques
        .iter()
        .map(|t| {
            let mut c = o.clone();
            c.set_assignment(&format!("technique={t}")).unwrap();
            shadowlab::report::bench::BenchConfig::named(t, c)
        })
        .collect()
}

/// One warm-up and one measured frame of the scene's camera, nothing broken down.
fn one_frame(
    scene: &Scene,
    interleave: bool,
    memory_mb: Option<f32>,
) -> shadowlab::report::bench::BenchSettings {
    shadowlab::report::bench::BenchSettings {
        warmup: 1,
        frames: 1,
        path: vec![shadowlab::scene::path::PathKey::of(&scene.camera)],
        progress: false,
        interleave,
        breakdown: false,
        pipelined: false,
        motion: false,
        sample_every: 1,
        memory_mb,
        enough_seconds: None,
    }
}
