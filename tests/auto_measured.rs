//! `technique = auto` from measured errors (the sampled reference) and measured pass times: each
//! light's choice checked against the full reference, against independently measured costs, and
//! for stability on a still camera.

mod common;

use common::{gl_on, load_asset, load_scene_file, options_with};
use shadowlab::frame::Frame;
use shadowlab::gl::{FrameRequest, Renderer};
use shadowlab::options::{BackendChoice, Candidate, MapBuffer, Options, Technique};
use shadowlab::report::estimate::{learn_auto, sampled_frame};
use shadowlab::scene::{Scene, path};
use shadowlab::truth::{Counts, ExactMasks, Reference};
use std::collections::BTreeMap;
use std::sync::{Mutex, MutexGuard};

/// The tests of this file compare pass times: each runs alone, so that another test's
/// rendering on the same cores does not land in the times `auto` learns or the test measures.
static ALONE: Mutex<()> = Mutex::new(());

fn alone() -> MutexGuard<'static, ()> {
    // A failed test poisons the lock; the others still run, one at a time.
    ALONE.lock().unwrap_or_else(|e| e.into_inner())
}

const AUTO: &[&str] = &["technique=auto", "accuracy=1", "width=320", "height=240"];

/// The technique each light ran with in `frame`.
fn techniques(frame: &Frame) -> BTreeMap<usize, Technique> {
    frame
        .steps
        .iter()
        .filter_map(|s| Some((s.light?, s.technique?)))
        .collect()
}

/// Each light's full-reference counts in a frame rendered with masks.
fn full_errors(scene: &Scene, frame: &Frame) -> BTreeMap<usize, Counts> {
    let mut exact = ExactMasks::new();
    let m = exact.measure(scene, frame.gbuffer.as_ref().unwrap(), &frame.masks);
    m.per_light.into_iter().collect()
}

/// A renderer that has learnt `scene` from its camera, and the frame it then keeps.
fn learnt(renderer: &mut Renderer, scene: &Scene, o: &Options, reference: &Reference) -> Frame {
    renderer.load_scene(scene).unwrap();
    learn_auto(renderer, scene, o, Some(reference)).unwrap();
    sampled_frame(renderer, scene, &scene.camera, o, reference, 99)
        .unwrap()
        .frame
}

/// The paper's volumes (front-facing casters, its edge rule) under the planner's defaults: on
/// ctf_compromise they get 27-45% of some lights' receivers wrong, which the constant estimate
/// (0.05% for volumes) cannot see.
const PAPER_VOLUMES: &[&str] = &[
    "shadow_volume.casters=front",
    "shadow_volume.edge_rule=paper",
];

/// Four views of ctf_compromise under `auto` at 1% with `extra` options: every light's
/// technique within 1% of the full reference. Returns the lights judged and how many of them
/// volumes alone would get over 1% wrong.
fn ctf_choices_within_one_percent(extra: &[&str]) -> (usize, usize) {
    let (mut scene, _, _) = load_scene_file("ctf_compromise");
    let o = options_with(&[AUTO, extra].concat());
    let reference = Reference::build(&scene);
    let (_ctx, mut renderer) = gl_on(BackendChoice::Egl, &o);
    let camera = scene.camera;
    let (mut lights, mut volume_misses) = (0, 0);
    for key in path::turn(&camera, 4) {
        scene.camera = key.apply(&camera);
        let frame = learnt(&mut renderer, &scene, &o, &reference);
        let chosen = techniques(&frame);
        let full = full_errors(&scene, &frame);
        // The volumes' own error in this view.
        let volumes = {
            let mut v = o.clone();
            v.technique = Technique::ShadowVolume;
            let f = renderer
                .render_with(
                    &scene,
                    &v,
                    FrameRequest {
                        masks: true,
                        ..Default::default()
                    },
                )
                .unwrap();
            full_errors(&scene, &f)
        };
        for (light, t) in &chosen {
            let e = full[light].rates().total;
            let sv = volumes.get(light).map_or(0.0, |c| c.rates().total);
            println!(
                "{extra:?} yaw {:.0}: light {light}: {t} full error {:.3}% (volumes {:.3}%)",
                key.yaw_deg,
                100.0 * e,
                100.0 * sv
            );
            assert!(
                e <= 0.01,
                "light {light} at yaw {}: {t} gets {:.3}% wrong ({:?})",
                key.yaw_deg,
                100.0 * e,
                frame.plan_stats.choices
            );
            lights += 1;
            volume_misses += (sv > 0.01) as usize;
        }
    }
    (lights, volume_misses)
}

#[test]
fn auto_at_one_percent_picks_for_every_light_of_ctf_compromise_a_technique_within_it() {
    let _alone = alone();
    let (lights, _) = ctf_choices_within_one_percent(&[]);
    assert!(lights >= 8, "too few lights in view to test");
    // With the paper's volumes, which the constant estimate (0.05%) cannot tell from exact.
    let (lights, volume_misses) = ctf_choices_within_one_percent(PAPER_VOLUMES);
    println!("{lights} light choices, {volume_misses} where volumes get over 1% wrong");
    assert!(
        volume_misses >= 4,
        "volumes miss 1% on too few lights: the test would not tell measurement from the estimate"
    );
}

/// Each light's milliseconds (its passes summed) in a frame of `o`.
fn light_times(renderer: &mut Renderer, scene: &Scene, o: &Options) -> BTreeMap<usize, f64> {
    let f = renderer.render(scene, o).unwrap();
    let mut sums: BTreeMap<usize, f64> = BTreeMap::new();
    for p in &f.passes {
        if let Some(l) = p.pass.light {
            *sums.entry(l).or_default() += p.ms;
        }
    }
    sums
}

/// Median milliseconds of each light's passes under each of `runs`, taken in turns (three
/// frames of each, then again) so that whatever slows the machine meanwhile slows them alike.
/// The first frame of a turn is not counted: a change of options redraws the maps and
/// rebuilds what the frames keep, which a light that stays with a technique does not pay.
fn light_costs(
    renderer: &mut Renderer,
    scene: &Scene,
    runs: &[&Options],
) -> Vec<BTreeMap<usize, f64>> {
    let mut per: Vec<BTreeMap<usize, Vec<f64>>> = vec![BTreeMap::new(); runs.len()];
    for _turn in 0..4 {
        for (o, times) in runs.iter().zip(&mut per) {
            for frame in 0..3 {
                let lights = light_times(renderer, scene, o);
                if frame > 0 {
                    for (l, ms) in lights {
                        times.entry(l).or_default().push(ms);
                    }
                }
            }
        }
    }
    per.into_iter()
        .map(|lights| {
            lights
                .into_iter()
                .map(|(l, mut v)| {
                    v.sort_by(f64::total_cmp);
                    (l, v[v.len() / 2])
                })
                .collect()
        })
        .collect()
}

#[test]
fn auto_on_oa_dm1_takes_the_cheaper_technique_that_meets_the_target_and_holds_it() {
    let _alone = alone();
    let (scene, _, _) = load_scene_file("oa_dm1");
    let o = options_with(AUTO);
    let reference = Reference::build(&scene);
    let (_ctx, mut renderer) = gl_on(BackendChoice::Egl, &o);
    let frame = learnt(&mut renderer, &scene, &o, &reference);
    let chosen = techniques(&frame);
    assert!(!chosen.is_empty());
    // Each technique forced on every light: its full error and its cost per light, measured
    // apart from `auto` on a renderer of its own.
    let forced: Vec<Options> = ["technique=shadow_map", "technique=shadow_volume"]
        .iter()
        .map(|t| options_with(&[t, "width=320", "height=240"]))
        .collect();
    // Its own context, gone before `auto`'s renderer draws again.
    let measured = {
        let (_c, mut r) = gl_on(BackendChoice::Egl, &forced[0]);
        r.load_scene(&scene).unwrap();
        let costs = light_costs(&mut r, &scene, &forced.iter().collect::<Vec<_>>());
        let mut measured = std::collections::HashMap::new();
        for (f, cost) in forced.iter().zip(costs) {
            let framed = r
                .render_with(
                    &scene,
                    f,
                    FrameRequest {
                        masks: true,
                        ..Default::default()
                    },
                )
                .unwrap();
            measured.insert(f.technique, (full_errors(&scene, &framed), cost));
        }
        measured
    };
    for (light, t) in &chosen {
        let meets = |t: Technique| measured[&t].0[light].rates().total <= 0.01;
        let cost = |t: Technique| measured[&t].1.get(light).copied().unwrap_or(0.0);
        let other = if *t == Technique::ShadowMap {
            Technique::ShadowVolume
        } else {
            Technique::ShadowMap
        };
        println!(
            "light {light}: {t} ({:.2} ms, meets: {}) against {other} ({:.2} ms, meets: {})",
            cost(*t),
            meets(*t),
            cost(other),
            meets(other)
        );
        assert!(meets(*t), "light {light}: {t} misses 1%");
        // The other is not clearly cheaper while also meeting the target. "Clearly": by more
        // than `estimate.hysteresis` (25%) and 0.5 ms, since llvmpipe's pass times on a
        // 2-core machine wander by about that much from one run to the next.
        if meets(other) {
            assert!(
                cost(other) >= 0.75 * cost(*t) - 0.5,
                "light {light}: {other} at {:.2} ms meets 1% too and is cheaper than {t} at {:.2} \
                 ms ({:?})",
                cost(other),
                cost(*t),
                frame.plan_stats.choices
            );
        }
    }
    // A still camera: 24 more frames, sampled as they run, and no light changes technique.
    for i in 0..24 {
        let f = sampled_frame(
            &mut renderer,
            &scene,
            &scene.camera,
            &o,
            &reference,
            100 + i,
        )
        .unwrap()
        .frame;
        assert_eq!(
            techniques(&f),
            chosen,
            "frame {i}: {:?}",
            f.plan_stats.choices
        );
    }
}

#[test]
fn auto_leaves_a_technique_when_its_measured_error_rises() {
    let _alone = alone();
    // ctf_compromise with the paper's volumes: facing back (yaw + 180°) light 0's volumes are
    // exact; facing the spawn's way they get about 43% of its receivers wrong.
    let (mut scene, _, _) = load_scene_file("ctf_compromise");
    let camera = scene.camera;
    let turn = path::turn(&camera, 2);
    // Hysteresis 1: a light never changes technique for cost, only for error.
    let o = options_with(&[AUTO, PAPER_VOLUMES, &["estimate.hysteresis=1"]].concat());
    let reference = Reference::build(&scene);
    let (_ctx, mut renderer) = gl_on(BackendChoice::Egl, &o);
    renderer.load_scene(&scene).unwrap();
    // Facing back, `auto` learns both techniques of every light (maps three frames, then volumes
    // three) and, never moving for cost, keeps volumes while they meet the target.
    scene.camera = turn[1].apply(&camera);
    let f = learnt(&mut renderer, &scene, &o, &reference);
    assert_eq!(
        techniques(&f)[&0],
        Technique::ShadowVolume,
        "{:?}",
        f.plan_stats.choices
    );
    let sv = renderer
        .auto_memory()
        .error(0, Technique::ShadowVolume, &o)
        .unwrap();
    assert!(sv.value < 0.01, "{sv:?}");
    // The camera turns to where they are wrong.
    scene.camera = turn[0].apply(&camera);
    let mut ran = Vec::new();
    let mut last = None;
    for i in 0..10 {
        let f = sampled_frame(&mut renderer, &scene, &scene.camera, &o, &reference, 10 + i)
            .unwrap()
            .frame;
        ran.push(techniques(&f)[&0]);
        last = Some(f);
    }
    println!("light 0 ran: {ran:?}");
    assert_eq!(
        ran[0],
        Technique::ShadowVolume,
        "auto kept the running technique at first"
    );
    let switch = ran
        .iter()
        .position(|t| *t == Technique::ShadowMap)
        .expect("light 0 never left volumes");
    assert!(switch <= 3, "{ran:?}");
    assert!(
        ran[switch..].iter().all(|t| *t == Technique::ShadowMap),
        "{ran:?}"
    );
    let f = last.unwrap();
    let e = full_errors(&scene, &f)[&0].rates().total;
    assert!(e <= 0.01, "light 0 ends {:.3}% wrong", 100.0 * e);
}

/// `auto_among` naming a map buffer: on the grazing light without polygon offset, where depth
/// maps get 46% of the receivers wrong (tests/id_buffers.rs), `auto` measures both buffers,
/// shadows with the ID buffer, and the frame errs as an ID buffer does (under 0.1% there).
#[test]
fn auto_chooses_the_id_buffer_where_depth_maps_without_offset_fail() {
    let _alone = alone();
    let (scene, _, _) = load_asset("assets/hard/grazing.toml");
    let o = options_with(
        &[
            AUTO,
            &[
                "auto_among=shadow_map,shadow_map:id",
                "shadow_map.offset=false",
            ],
        ]
        .concat(),
    );
    let reference = Reference::build(&scene);
    let (_ctx, mut renderer) = gl_on(BackendChoice::Egl, &o);
    let frame = learnt(&mut renderer, &scene, &o, &reference);
    let id = Candidate {
        technique: Technique::ShadowMap,
        buffer: MapBuffer::Id,
    };
    let full = full_errors(&scene, &frame);
    assert!(!full.is_empty(), "no light planned");
    for (light, counts) in &full {
        let memory = renderer.auto_memory();
        let depth = memory.error(*light, Technique::ShadowMap, &o).unwrap();
        let ids = memory.error(*light, id, &o).unwrap();
        let e = counts.rates().total;
        println!(
            "light {light}: sampled depth {:.3}%, id {:.3}%; frame {:.3}% ({:?})",
            100.0 * depth.value,
            100.0 * ids.value,
            100.0 * e,
            frame.plan_stats.choices
        );
        // Both were measured, and the measurements tell them apart.
        assert!(depth.low > 0.3, "depth without offset: {depth:?}");
        assert!(ids.high < 0.01, "id: {ids:?}");
        assert!(
            frame
                .plan_stats
                .choices
                .iter()
                .any(|c| c.starts_with(&format!("light {light}: shadow_map:id "))),
            "{:?}",
            frame.plan_stats.choices
        );
        assert!(e < 0.001, "light {light}: {:.3}% wrong", 100.0 * e);
    }
}
