//! The scene in motion: MD3 players animated between key frames, lights that move, and the
//! caches that must redo exactly what motion touches (OpenArena data:
//! `scripts/fetch-openarena.sh`).

mod common;

use common::{Footprint, Measurer, differing, load_scene_file, options_with};
use shadowlab::frame::CacheStats;
use shadowlab::gl::FrameRequest;
use shadowlab::options::Options;
use shadowlab::q3::md3;
use shadowlab::q3::pk3::{self, Vfs};
use shadowlab::scene::Scene;
use shadowlab::scene::motion::Rig;
use shadowlab::scene::path::{self, FRAME_RATE_HZ, PathKey};
use shadowlab::shadow::views::ViewKind;

const SM: &str = "technique=shadow_map";
const SV: &str = "technique=shadow_volume";

fn read_md3(vfs: &Vfs, path: &str) -> md3::Md3 {
    md3::parse(&vfs.read(path).unwrap()).unwrap()
}

/// oa_dm1 with its rig (sarge running).
fn oa_dm1_rig() -> (Scene, Rig, Options) {
    let (scene, _, options) = load_scene_file("oa_dm1");
    let rig = scene
        .motion
        .rigs
        .first()
        .expect("oa_dm1's sarge runs")
        .clone();
    (scene, rig, options)
}

/// One rig mesh as the scene holds it: part, mesh name, positions and normals (model space).
type MeshVertices = (String, String, Vec<[f32; 3]>, Vec<[f32; 3]>);

/// The model-space vertices of every rig mesh, as the scene holds them.
fn rig_vertices(scene: &Scene, rig: &Rig) -> Vec<MeshVertices> {
    rig.parts
        .iter()
        .flat_map(|part| {
            part.meshes.iter().map(|m| {
                let v = &scene.vertices[m.first_vertex..m.first_vertex + m.verts];
                (
                    part.name.clone(),
                    m.name.clone(),
                    v.iter().map(|v| v.position).collect(),
                    v.iter().map(|v| v.normal).collect(),
                )
            })
        })
        .collect()
}

#[test]
fn an_animated_player_equals_its_key_frames_exactly_and_its_parts_follow_the_tags() {
    let (mut scene, rig, _) = oa_dm1_rig();
    let vfs = Vfs::open_data_dir(&pk3::data_dir()).unwrap();
    let dir = "models/players/sarge";
    let lower = read_md3(&vfs, &format!("{dir}/lower.md3"));
    let upper = read_md3(&vfs, &format!("{dir}/upper.md3"));
    let head = read_md3(&vfs, &format!("{dir}/head.md3"));
    let legs = rig.parts[0].clip;
    assert!(legs.frames > 1, "the run has frames to play");
    let mut checked = 0;
    // Every key frame of the run and one past its loop: t = k / fps.
    for k in 0..=legs.frames {
        let t = f64::from(k) / f64::from(legs.fps);
        let poses = rig.part_poses(t);
        let (l, u) = (poses[0].keys, poses[1].keys);
        assert_eq!(
            (l.fraction, u.fraction),
            (0.0, 0.0),
            "t = {t} is a key frame"
        );
        scene.pose_at(t);
        let expected = md3::assemble_player(&lower, &upper, &head, l.from, u.from).unwrap();
        for (part, name, positions, normals) in rig_vertices(&scene, &rig) {
            let e = expected
                .iter()
                .find(|p| p.part == part && p.surface_name == name)
                .unwrap_or_else(|| panic!("{part} {name} is assembled"));
            let e_pos: Vec<[f32; 3]> = e.vertices.iter().map(|v| v.position).collect();
            let e_nrm: Vec<[f32; 3]> = e.vertices.iter().map(|v| v.normal).collect();
            // Bit for bit: at a key frame nothing is mixed, and the upper and head models
            // hang on the stored tags exactly as the still assembly hangs them.
            assert_eq!(positions, e_pos, "{part} {name} at key frame {k}");
            assert_eq!(normals, e_nrm, "{part} {name} normals at key frame {k}");
            checked += 1;
        }
    }
    assert!(
        checked > 3 * legs.frames as usize,
        "{checked} meshes checked"
    );

    // Halfway between two key frames, each lower vertex is halfway between its keys, and the
    // head sits on the torso's mixed tag: its vertices move with it, not with the key frames.
    let t = 0.5 / f64::from(legs.fps);
    let keys = rig.part_poses(t)[0].keys;
    assert!((keys.fraction - 0.5).abs() < 1e-6);
    scene.pose_at(t);
    let a = md3::assemble_player(&lower, &upper, &head, keys.from, 0).unwrap();
    let b = md3::assemble_player(&lower, &upper, &head, keys.to, 0).unwrap();
    let mut worst: f32 = 0.0;
    let torso_stand = rig.parts[1].clip.first as usize;
    let a_upper = md3::assemble_player(&lower, &upper, &head, keys.from, torso_stand).unwrap();
    let b_upper = md3::assemble_player(&lower, &upper, &head, keys.to, torso_stand).unwrap();
    let mut head_between = 0;
    for (part, name, positions, _) in rig_vertices(&scene, &rig) {
        let find = |set: &[md3::PlacedSurface]| {
            set.iter()
                .find(|p| p.part == part && p.surface_name == name)
                .unwrap()
                .vertices
                .iter()
                .map(|v| glam::Vec3::from_array(v.position))
                .collect::<Vec<_>>()
        };
        if part == "lower" {
            for ((p, pa), pb) in positions.iter().zip(find(&a)).zip(find(&b)) {
                worst = worst.max(glam::Vec3::from_array(*p).distance((pa + pb) * 0.5));
            }
        } else {
            // Upper and head: between the two still assemblies (the tag mixed), not on either.
            let (pa, pb) = (find(&a_upper), find(&b_upper));
            let moved = pa.iter().zip(&pb).any(|(x, y)| x.distance(*y) > 0.5);
            if moved {
                let p0 = glam::Vec3::from_array(positions[0]);
                assert!(p0.distance(pa[0]) > 1e-3 && p0.distance(pb[0]) > 1e-3);
                head_between += 1;
            }
        }
    }
    assert!(worst < 1e-3, "lower vertices {worst} units off halfway");
    assert!(head_between > 0, "the torso's tag moves during the run");
}

/// Frames `0..n` of the scene's motion seen from its camera, measured against the exact
/// reference of each frame's pose: per frame, the error outside the boundary band (pixels).
fn errors_along(m: &mut Measurer, options: &Options, n: usize) -> Vec<(usize, f64, usize)> {
    (0..n)
        .map(|i| {
            m.pose(i as f64 / FRAME_RATE_HZ);
            let r = m.measure(options);
            let t = r.total;
            let built = r.frame.cache.caster_groups_built + r.frame.cache.models_uploaded;
            (i, t.rates().total_excl_boundary, built)
        })
        .collect()
}

#[test]
fn an_animated_player_shadow_matches_the_exact_reference_on_every_frame() {
    let (scene, _, _) = oa_dm1_rig();
    let options = options_with(&["width=320", "height=240"]);
    let mut m = Measurer::new(scene, &options);
    // A second of running (the route turns back at 130 units: 0.9 s at 150 units/s).
    let frames = 20;
    let sv = errors_along(
        &mut m,
        &options_with(&[SV, "width=320", "height=240"]),
        frames,
    );
    let sm = errors_along(
        &mut m,
        &options_with(&[SM, "width=320", "height=240"]),
        frames,
    );
    println!("SV (frame, error excl. boundary, groups + uploads): {sv:?}");
    println!("SM: {sm:?}");
    // Shadow volumes are exact up to the boundary band on the still oa_dm1 frame (the
    // planner tests and `check` hold them there); a volume left from an earlier pose would
    // put a running player's shadow where he no longer is.
    for (i, e, _) in &sv {
        assert!(*e < 0.0005, "SV frame {i}: {:.4}% wrong", 100.0 * e);
    }
    // Shadow maps: under the bound their still oa_dm1 frame holds (0.5% outside the band,
    // `shadowlab check`): a stale map shows a whole player's shadow, which is more.
    for (i, e, _) in &sm {
        assert!(*e < 0.005, "SM frame {i}: {:.4}% wrong", 100.0 * e);
    }
    // The player's vertices went up, and his caster group was built again, as he ran.
    assert!(sv.iter().skip(1).all(|(_, _, built)| *built >= 1), "{sv:?}");
}

#[test]
fn volumes_hold_with_the_camera_inside_the_running_player() {
    // oa_dm3's flythrough walks through sarge at frame 448: the eye inside a closed caster,
    // whose inner faces are culled. The planner's near-plane split counted the rest of him
    // depth-pass and lost light rt2's shadow of him: 16.8% of rt2's receivers wrong.
    let (mut scene, _, _) = load_scene_file("oa_dm3");
    let keys = path::read(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/paths/oa_dm3.path"),
    )
    .unwrap();
    scene.camera = keys[448].apply(&scene.camera);
    scene.pose_at(448.0 / FRAME_RATE_HZ);
    let rt2 = scene.lights.iter().position(|l| l.name == "rt2").unwrap();
    let options = options_with(&[
        SV,
        "width=320",
        "height=240",
        &format!("lighting.only={rt2}"),
    ]);
    let mut m = Measurer::new(scene, &options);
    let r = m.measure(&options);
    let rates = r.light(rt2).rates();
    println!("rt2 inside sarge: {:.4}% wrong", 100.0 * rates.total);
    assert!(rates.receiver_pixels > 1000, "rt2 lights the view");
    assert!(
        rates.total_excl_boundary < 0.0005,
        "{:.3}% wrong",
        100.0 * rates.total_excl_boundary
    );
}

/// Options with every cache the renderer keeps across frames off.
fn caches_off(options: &Options) -> Options {
    let mut o = options.clone();
    for set in [
        "plan.cache_maps=false",
        "plan.reuse_depth=false",
        "plan.reuse_depth_fits=false",
        "plan.reuse_volume_draws=false",
        "shadow_volume.caching=false",
    ] {
        o.set_assignment(set).unwrap();
    }
    o
}

#[test]
fn in_motion_the_masks_equal_those_of_a_renderer_with_every_cache_off() {
    let (scene, _, _) = load_scene_file("oa_dm1");
    assert!(!scene.motion.lights.is_empty(), "oa_dm1 has a light moving");
    masks_equal_with_caches_off(scene.clone());
    // Running in place: only the vertices move, not the model's transform.
    let mut in_place = scene;
    in_place.motion.walks.clear();
    masks_equal_with_caches_off(in_place);
}

/// oa_dm1's benchmark flythrough.
fn oa_dm1_path() -> Vec<PathKey> {
    path::read(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/paths/oa_dm1.path"))
        .unwrap()
}

#[test]
fn volumes_laid_out_again_on_the_gpu_equal_those_built_afresh_in_motion() {
    let (mut scene, _, _) = load_scene_file("oa_dm1");
    let keys = oa_dm1_path();
    // Without the clip test nothing reads an uploaded part's triangles: the CPU gives up every
    // copy, and each new layout copies the parts it keeps from the light's old buffer.
    let cached = options_with(&[SV, "width=320", "height=240", "plan.cull_clipped=false"]);
    let fresh = caches_off(&cached);
    let (_ctx, mut a) = common::gl_on(shadowlab::options::BackendChoice::Egl, &cached);
    let mut b = a.sibling(cached.width, cached.height).unwrap();
    a.load_scene(&scene).unwrap();
    let (mut compared, mut moved) = (0, 0);
    for i in (0..8).chain((8..60).step_by(4)) {
        scene.pose_at(i as f64 / FRAME_RATE_HZ);
        let camera = keys[i].apply(&scene.camera);
        let (fa, n) = common::cached_against_fresh(
            (&mut a, &mut b),
            (&scene, &camera),
            (&cached, &fresh),
            &format!("frame {i}"),
        );
        compared += n;
        moved += fa.volumes.iter().map(|v| v.parts_moved).sum::<usize>();
    }
    println!("{compared} masks compared, {moved} parts moved on the GPU");
    assert!(compared > 40, "{compared} masks compared");
    assert!(moved > 100, "{moved} parts moved on the GPU");
}

fn masks_equal_with_caches_off(mut scene: Scene) {
    let keys = oa_dm1_path();
    for technique in [SM, SV] {
        let cached = options_with(&[technique, "width=320", "height=240"]);
        let fresh = caches_off(&cached);
        let (_ctx, mut a) = common::gl_on(shadowlab::options::BackendChoice::Egl, &cached);
        let mut b = a.sibling(cached.width, cached.height).unwrap();
        a.load_scene(&scene).unwrap();
        let mut compared = 0;
        let mut redone = 0;
        let (mut static_drawn, mut models_only) = (0, 0);
        // The light circles (side_room, 6 s a turn) and sarge runs while the camera walks:
        // every few frames for three seconds, and the first frames each in turn.
        for i in (0..8).chain((8..60).step_by(4)) {
            let posed = scene.pose_at(i as f64 / FRAME_RATE_HZ);
            let camera = keys[i].apply(&scene.camera);
            // The reference renderer forgets everything before each frame.
            let (fa, n) = common::cached_against_fresh(
                (&mut a, &mut b),
                (&scene, &camera),
                (&cached, &fresh),
                &format!("{technique}, frame {i} ({posed:?})"),
            );
            compared += n;
            redone += fa.cache.maps_rendered + fa.cache.volume_parts_built;
            static_drawn += fa.cache.maps_static_drawn;
            models_only += fa.cache.maps_models_only;
        }
        assert!(compared > 40, "{compared} masks compared");
        assert!(
            redone > 0,
            "{technique}: the cached renderer redid work in motion"
        );
        if technique == SM {
            // The static lights' maps were made from their kept static maps with sarge drawn
            // over the copy: the path the masks above hold to the cache-off frame's.
            println!(
                "static maps drawn {static_drawn}, maps made with the models only {models_only}"
            );
            assert!(
                static_drawn > 0 && models_only > static_drawn,
                "{static_drawn}, {models_only}"
            );
        }
    }
}

/// Per frame, the map counters along 100 frames of oa_dm1's flythrough with sarge running
/// (`standing`: without his run) and only light `light` drawn.
fn map_counts_along_the_path(light: usize, standing: bool) -> Vec<CacheStats> {
    let (mut scene, _, _) = load_scene_file("oa_dm1");
    if standing {
        scene.motion.rigs.clear();
        scene.motion.walks.clear();
    }
    let keys: Vec<PathKey> = path::read(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/paths/oa_dm1.path"),
    )
    .unwrap();
    let only = format!("lighting.only={light}");
    let options = options_with(&[SM, "width=320", "height=240", only.as_str()]);
    let (_ctx, mut r) = common::gl_on(shadowlab::options::BackendChoice::Egl, &options);
    r.load_scene(&scene).unwrap();
    (0..100)
        .map(|i| {
            scene.pose_at(i as f64 / FRAME_RATE_HZ);
            let camera = keys[i].apply(&scene.camera);
            let f = r
                .render_at(&scene, &camera, &options, FrameRequest::default())
                .unwrap();
            f.cache
        })
        .collect()
}

#[test]
fn a_static_light_keeps_its_static_map_and_redraws_only_the_running_player_over_it() {
    // corridor_spot (a spot) and corridor_far (an omni light: one cube) reach sarge's route
    // from every frame of the path's first 100 while the camera walks and turns.
    for light in [0, 1] {
        let running = map_counts_along_the_path(light, false);
        let sum = |f: fn(&CacheStats) -> usize| running.iter().map(f).sum::<usize>();
        let (drawn, static_drawn, models_only, reused) = (
            sum(|c| c.maps_rendered),
            sum(|c| c.maps_static_drawn),
            sum(|c| c.maps_models_only),
            sum(|c| c.maps_reused),
        );
        println!(
            "light {light}, sarge running: {drawn} maps made, {static_drawn} static maps drawn, {models_only} from the kept static map, {reused} reused"
        );
        // The static map is drawn on the first frame and kept; every other frame copies it
        // and draws sarge alone (he moves every frame, so the map itself is never reused).
        assert_eq!(static_drawn, 1, "light {light}");
        assert_eq!(models_only, 99, "light {light}");
        assert_eq!((drawn, reused), (100, 0), "light {light}");
        // Sarge standing: nothing moves in the light's range, so its map is drawn once and
        // kept whole, without a static map.
        let standing = map_counts_along_the_path(light, true);
        let made: Vec<usize> = standing.iter().map(|c| c.maps_rendered).collect();
        let split: usize = standing
            .iter()
            .map(|c| c.maps_static_drawn + c.maps_models_only)
            .sum();
        assert_eq!(made.iter().sum::<usize>(), 1, "light {light}: {made:?}");
        assert_eq!(split, 0, "light {light}");
    }
}

#[test]
fn a_cube_face_draws_only_the_casters_in_its_frustum() {
    let (scene, _, _) = load_scene_file("oa_dm1");
    let options = options_with(&[SM, "width=320", "height=240"]);
    let plan = shadowlab::plan::Plan::build(&scene, &options);
    let mut cubes = 0;
    for lp in &plan.lights {
        for (vi, view) in lp.views.iter().enumerate() {
            if view.kind != ViewKind::Cube {
                continue;
            }
            cubes += 1;
            let eye = scene.lights[lp.light].position;
            let images = &lp.view_images[vi];
            let all = &lp.view_casters[vi];
            assert_eq!(images.len(), 6);
            let mut listed = 0;
            for (face, view_proj) in view.face_view_projs(eye, None) {
                let image = &images[face.unwrap()];
                let on_face: Vec<u32> = image.base.iter().chain(&image.moving).copied().collect();
                listed += on_face.len();
                // A caster left off a face lies wholly beyond one side of its frustum: its
                // box's corners all outside the same clip plane.
                for &c in all.iter().filter(|c| !on_face.contains(c)) {
                    let corners = scene.surfaces[c as usize].bounds.corners();
                    let clip: Vec<glam::Vec4> =
                        corners.iter().map(|p| view_proj * p.extend(1.0)).collect();
                    let outside = (0..3).any(|axis| {
                        clip.iter().all(|q| q[axis] > q.w) || clip.iter().all(|q| q[axis] < -q.w)
                    });
                    assert!(
                        outside,
                        "light {} face {face:?}: caster {c} left off",
                        lp.light
                    );
                }
            }
            // Each caster is drawn on the faces it reaches, not on all six.
            println!(
                "light {}: {} casters in range, {listed} drawn over six faces",
                lp.light,
                all.len()
            );
            assert!(listed < 3 * all.len(), "{listed} of {}", all.len());
            assert!(listed >= all.len());
        }
    }
    assert_eq!(cubes, 2, "corridor_far and side_room are cubes");
}

#[test]
fn a_static_light_keeps_its_map_and_volumes_while_a_moving_one_redoes_only_its_own() {
    let (mut scene, _, _) = load_scene_file("oa_dm1");
    // Only the orbiting light moves: the player stands.
    scene.motion.rigs.clear();
    scene.motion.walks.clear();
    let moving = scene.motion.lights[0].light;
    for technique in [SM, SV] {
        let options = options_with(&[technique, "width=320", "height=240"]);
        let (_ctx, mut r) = common::gl_on(shadowlab::options::BackendChoice::Egl, &options);
        r.load_scene(&scene).unwrap();
        let mut frames = Vec::new();
        for i in 0..6 {
            scene.pose_at(i as f64 / FRAME_RATE_HZ);
            frames.push(r.render(&scene, &options).unwrap());
        }
        for f in &frames[2..] {
            let c = f.cache;
            if technique == SM {
                // Spot maps: one per static spot, six faces (or one cube) per omni; only the
                // moving light's are drawn again.
                assert!(c.maps_reused > 0, "{c:?}");
                assert!(c.maps_rendered >= 1, "{c:?}");
                assert_eq!(
                    c.maps_rendered,
                    r.shadow_map_views(moving).min(c.maps_rendered),
                    "{c:?}"
                );
            } else {
                assert!(c.volume_parts_reused > 0, "{c:?}");
                assert_eq!(c.caster_groups_built, 0, "{c:?}");
            }
        }
    }
}

#[test]
fn ten_thousand_frames_in_motion_stay_flat() {
    let (scene, _, _) = load_scene_file("oa_dm1");
    let keys: Vec<PathKey> = path::read(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/paths/oa_dm1.path"),
    )
    .unwrap();
    let small = ["width=64", "height=48", "shadow_map.size=256"];
    let options = options_with(&small);
    let sm = options_with(&[&small[..], &[SM]].concat());
    let sv = options_with(&[&small[..], &[SV]].concat());
    let mut m = Measurer::new(scene, &options);
    let first = |m: &mut Measurer| {
        m.pose(0.0);
        m.set_camera(keys[0].apply(&m.scene.camera));
        (m.measure(&sm), m.measure(&sv))
    };
    let (first_sm, first_sv) = first(&mut m);
    let held_first = m.renderer().held();
    let gl = m.renderer().gl_handle();
    let frame = |m: &mut Measurer, i: usize| {
        let scene = std::mem::take(&mut m.scene);
        let mut scene = scene;
        scene.pose_at(i as f64 / FRAME_RATE_HZ);
        let camera = keys[i % keys.len()].apply(&scene.camera);
        let o = if i.is_multiple_of(2) { &sm } else { &sv };
        m.renderer()
            .render_at(&scene, &camera, o, FrameRequest::default())
            .unwrap();
        m.scene = scene;
    };
    for i in 0..200 {
        frame(&mut m, i);
    }
    let before = Footprint::take(&gl);
    const FRAMES: usize = 10_000;
    // The most held over the first lap of the path, and over the laps after it.
    let (mut held_lap, mut held_max) = (shadowlab::run::Held::default(), Default::default());
    for i in 200..200 + FRAMES {
        frame(&mut m, i);
        let h = m.renderer().held();
        let most: &mut shadowlab::run::Held = if i < 200 + keys.len() {
            &mut held_lap
        } else {
            &mut held_max
        };
        most.map_textures = most.map_textures.max(h.map_textures);
        most.volume_parts = most.volume_parts.max(h.volume_parts);
        most.depth_fits = most.depth_fits.max(h.depth_fits);
    }
    let after = Footprint::take(&gl);
    // The fixed frame (t = 0, the path's first pose) after it all: what the renderer keeps
    // after it is what it kept after the same frame at the start.
    let (last_sm, last_sv) = first(&mut m);
    let held_last = m.renderer().held();
    println!(
        "{FRAMES} frames in motion: held after the fixed frame {held_first:?} at first, \
         {held_last:?} at last, at most {held_max:?}; GL names grew by {:?}; {}",
        after.names_since(&before),
        after.memory_since(&before)
    );
    for (a, b, what) in [(&first_sm, &last_sm, "SM"), (&first_sv, &last_sv, "SV")] {
        for mask in &a.frame.masks {
            assert_eq!(
                differing(mask, b.mask(mask.light)),
                0,
                "{what} light {} drifted",
                mask.light
            );
        }
    }
    // The same tolerances as the still long run (hard case 10).
    after.assert_flat_since(&before);
    // Flat caches: after the same frame the renderer keeps the maps it kept at the start (a
    // cache that grows per frame keeps more), and once the path was walked the volume parts
    // kept (a still light's pieces stay while out of view) and depth fits grow no more. How
    // long frames take is bench's to measure.
    assert_eq!(
        held_last.map_textures, held_first.map_textures,
        "maps kept after the fixed frame"
    );
    // What can be kept is bounded by the scene: per light, a part per piece kept, and at
    // most a split pair per piece of the frame's; a cache keyed by anything per frame would
    // pass that over 10 000 frames.
    let groups = shadowlab::shadow::volume::CasterGroups::build(&m.scene);
    let pieces: usize = groups
        .groups
        .iter()
        .map(|g| g.chunks.len() + g.components.len())
        .sum();
    let bound = m.scene.lights.len() * 3 * pieces;
    for held in [held_lap, held_max, held_last] {
        assert!(
            held.volume_parts <= bound && held.depth_fits <= bound,
            "{held:?} against {bound} ({pieces} pieces)"
        );
    }
}

/// A running player reposed builds its own caster group again and shares every other: the
/// world's (the scene's largest) is not copied frame after frame.
#[test]
fn reposing_a_player_builds_its_group_and_shares_the_worlds() {
    let (mut scene, _, _) = load_scene_file("oa_dm1");
    let mut planner = shadowlab::plan::planner::Planner::default();
    scene.pose_at(0.0);
    let before = planner.casters(&scene);
    scene.pose_at(0.25);
    let after = planner.casters(&scene);
    assert_eq!(planner.take_groups_rebuilt(), before.groups.len() + 1);
    let (mut shared, mut rebuilt) = (0, 0);
    for (a, b) in before.groups.iter().zip(&after.groups) {
        match a.owner {
            shadowlab::scene::SurfaceOwner::World => {
                assert!(std::sync::Arc::ptr_eq(a, b), "the world's group was copied");
                shared += 1;
            }
            shadowlab::scene::SurfaceOwner::Model(_) => {
                assert_ne!(a.pose, b.pose);
                rebuilt += 1;
            }
        }
    }
    assert_eq!((shared, rebuilt), (1, 1));
}
