//! The lit pass records each light's decision as it shades (`gl::record`): the masks read
//! from that record must be the masks drawn again after the frame (`masks_drawn_again`).

mod common;

use shadowlab::images::{Mask, MaskValue};
use shadowlab::options::{BackendChoice, Options};
use shadowlab::presets::Preset;
use shadowlab::run::FrameRequest;
use shadowlab::scene::Scene;
use shadowlab::truth::metrics::near_boundary;

/// How a recorded mask differs from the mask drawn again.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
struct Differences {
    /// Receiver pixels of both.
    receivers: usize,
    /// Lit in one, shadowed in the other, beyond the drawn mask's edge band.
    flipped: usize,
    /// Lit in one, shadowed in the other, on the edge band (within 1 px of a lit/shadowed
    /// boundary).
    flipped_on_edges: usize,
    /// A receiver in one only.
    reach: usize,
}

impl Differences {
    fn add(self, o: Differences) -> Differences {
        Differences {
            receivers: self.receivers + o.receivers,
            flipped: self.flipped + o.flipped,
            flipped_on_edges: self.flipped_on_edges + o.flipped_on_edges,
            reach: self.reach + o.reach,
        }
    }
}

fn differences(recorded: &Mask, drawn: &Mask) -> Differences {
    let mut d = Differences::default();
    let w = drawn.width as usize;
    for (i, (&a, &b)) in recorded.values.iter().zip(&drawn.values).enumerate() {
        match (MaskValue::from_u8(a), MaskValue::from_u8(b)) {
            (MaskValue::NotReceiver, MaskValue::NotReceiver) => {}
            (MaskValue::NotReceiver, _) | (_, MaskValue::NotReceiver) => d.reach += 1,
            (a, b) => {
                d.receivers += 1;
                if a != b {
                    match near_boundary(drawn, (i % w) as u32, (i / w) as u32) {
                        true => d.flipped_on_edges += 1,
                        false => d.flipped += 1,
                    }
                }
            }
        }
    }
    d
}

/// Renders `scene` with masks drawn again, then recorded; how they differ over every light,
/// and how many lights recorded (the frame's masks drawn within it or after it are the
/// others).
fn compare(scene: &Scene, o: &Options, what: &str) -> Differences {
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, o);
    r.load_scene(scene).unwrap();
    let mut frame = |again: bool| {
        r.render_with(
            scene,
            o,
            FrameRequest {
                masks: true,
                masks_drawn_again: again,
                ..FrameRequest::default()
            },
        )
        .unwrap_or_else(|e| panic!("{what}: {e}"))
    };
    let recorded = frame(false);
    let drawn = frame(true);
    assert_eq!(drawn.masks_recorded, 0, "{what}");
    assert!(
        recorded.masks_recorded > 0 && recorded.masks_recorded <= recorded.masks.len(),
        "{what}: {} of {} masks recorded",
        recorded.masks_recorded,
        recorded.masks.len()
    );
    assert_eq!(
        recorded.masks.iter().map(|m| m.light).collect::<Vec<_>>(),
        drawn.masks.iter().map(|m| m.light).collect::<Vec<_>>(),
        "{what}: the same lights"
    );
    let d = recorded
        .masks
        .iter()
        .zip(&drawn.masks)
        .map(|(a, b)| differences(a, b))
        .fold(Differences::default(), Differences::add);
    println!(
        "{what}: {d:?}, {} of {} masks recorded",
        recorded.masks_recorded,
        recorded.masks.len()
    );
    d
}

/// What the record must hold to: no decision that differs away from a shadow's edge, and at
/// most one pixel in 20 000 receivers either differing on an edge or a receiver in one mask
/// only. Why any at all: the lit program and the mask program are compiled from different
/// defines, and where a map's compare or the light's reach test is a tie a rasteriser's
/// compiler may round the two differently (llvmpipe: oa_dm1's light 1, one pixel of 252 257
/// receivers, on an edge; softpipe: one pixel of suspended's 63 871 a receiver in one only).
fn assert_same(d: Differences, what: &str) {
    assert!(
        d.receivers > 1000,
        "{what}: too few receivers to judge ({d:?})"
    );
    assert_eq!(d.flipped, 0, "{what}: {d:?}");
    assert!(
        d.flipped_on_edges + d.reach <= d.receivers / 20_000,
        "{what}: {} decisions on edges and {} receivers differ ({d:?})",
        d.flipped_on_edges,
        d.reach
    );
}

fn options_for(base: &Options, sets: &[&str]) -> Options {
    let mut o = base.clone();
    o.width = 320;
    o.height = 240;
    for s in sets {
        o.set_assignment(s).unwrap_or_else(|e| panic!("{s}: {e}"));
    }
    o
}

const TECHNIQUES: [&str; 4] = ["shadow_map", "shadow_volume", "psm", "tsm"];

#[test]
fn recorded_masks_are_the_masks_drawn_again_on_the_five_scenes() {
    for name in [
        "oa_dm1",
        "q3dm6ish",
        "wrackdm17",
        "ctf_compromise",
        "oa_dm3",
    ] {
        let (scene, _, base) = common::load_scene_file(name);
        for t in TECHNIQUES {
            let what = format!("{name} {t}");
            let o = options_for(&base, &[&format!("technique={t}")]);
            assert_same(compare(&scene, &o, &what), &what);
        }
    }
}

#[test]
fn recorded_masks_are_the_masks_drawn_again_on_the_hard_cases() {
    // oa_koth2's light facing a wall head-on, oa_ctf2's floor rows, suspended's alpha-tested
    // grate, ctf_inyard's ceiling over leaves outside the PVS.
    for (bsp, light) in [
        ("maps/oa_koth2.bsp", "placed41"),
        ("maps/oa_ctf2.bsp", "placed15"),
        ("maps/suspended.bsp", "placed0"),
        ("maps/ctf_inyard.bsp", "placed0"),
    ] {
        let (scene, _) = common::check_scene(bsp, light);
        for t in TECHNIQUES {
            let what = format!("{bsp} {t}");
            let o = options_for(&common::test_options(), &[&format!("technique={t}")]);
            assert_same(compare(&scene, &o, &what), &what);
        }
    }
}

#[test]
fn recorded_masks_hold_where_the_shader_decides_and_on_the_papers_frame() {
    // `shadow_map.result = intensity`: the lit pass keeps shadowed fragments, scaled (under
    // the default `alpha` the alpha test rejects them, kept while recording to add nothing).
    // The paper's frame too (the preset), and the subdivision's stencil (which drops them, as
    // volumes' does: the G-buffer's reach bits find them).
    let (scene, _, base) = common::load_scene_file("q3dm6ish");
    let mut paper = base.clone();
    Preset::Paper.apply(&mut paper).unwrap();
    let cases: [(&Options, &[&str]); 4] = [
        (
            &base,
            &["technique=shadow_map", "shadow_map.result=intensity"],
        ),
        (&paper, &[]),
        (&paper, &["technique=shadow_map"]),
        (&base, &["technique=subdivision"]),
    ];
    for (from, sets) in cases {
        let what = format!("q3dm6ish {sets:?}");
        assert_same(compare(&scene, &options_for(from, sets), &what), &what);
    }
}

#[test]
fn the_g_buffer_read_where_the_sample_picks_samples_as_the_whole_one_does() {
    use shadowlab::truth::Reference;
    use shadowlab::truth::sampled::{frame_picks, picked_pixels, sample_frame};
    let (scene, _, base) = common::load_scene_file("oa_dm1");
    let reference = Reference::build(&scene);
    for t in ["shadow_map", "shadow_volume"] {
        let o = options_for(&base, &[&format!("technique={t}")]);
        let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &o);
        r.load_scene(&scene).unwrap();
        let frame = |kept: bool, r: &mut shadowlab::run::Renderer| {
            r.render_with(
                &scene,
                &o,
                FrameRequest {
                    masks: true,
                    gbuffer_kept: kept,
                    ..FrameRequest::default()
                },
            )
            .unwrap_or_else(|e| panic!("{t}: {e}"))
        };
        let whole = frame(false, &mut r);
        let kept = frame(true, &mut r);
        assert!(kept.gbuffer.is_none(), "{t}: the G-buffer stays on the GPU");
        let gbuffer = whole.gbuffer.as_ref().unwrap();
        let (n, seed) = (64, 7);
        let pixels = picked_pixels(&frame_picks(&scene.lights, &kept.masks, n, seed, 3));
        assert!(pixels.len() > 100, "{t}: {} pixels picked", pixels.len());
        let picks = r.gbuffer_at(pixels.clone()).unwrap();
        assert_eq!(picks.pixels, pixels);
        for (k, &i) in pixels.iter().enumerate() {
            let i = i as usize;
            assert_eq!(
                (picks.position[k], picks.normal[k], picks.kind[k]),
                (gbuffer.position[i], gbuffer.normal[i], gbuffer.kind[i]),
                "{t}: pixel {i}"
            );
        }
        let lights = &scene.lights;
        let over_whole = sample_frame(&reference, gbuffer, lights, &whole.masks, n, seed, 3);
        let over_picks = sample_frame(&reference, &picks, lights, &kept.masks, n, seed, 3);
        assert!(over_whole.rays > 100, "{t}: {} rays", over_whole.rays);
        assert_eq!(over_whole, over_picks, "{t}");
    }
}
