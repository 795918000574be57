//! Quake 3 content on the real OpenArena data: every map loads and renders, counts agree with an
//! independent implementation, the benchmark scenes hold what they promise.
//! Needs `scripts/fetch-openarena.sh` (the tests say so when the data is missing).

mod common;

use common::{
    load_asset, load_scene_file, openarena_data, options_with, render, stdout_of, test_options,
};
use shadowlab::gl::{Profile, create_context};
use shadowlab::options::BackendChoice;
use shadowlab::q3::builder::SceneBuilder;
use shadowlab::q3::pk3::Vfs;
use shadowlab::q3::world;
use shadowlab::run::Renderer;
use shadowlab::scene::{Camera, SurfaceOwner};
use shadowlab::scene_file::load_shader_library;
use std::process::Command;

#[test]
fn every_map_in_the_data_set_loads_and_renders_a_frame() {
    let vfs = Vfs::open_data_dir(&openarena_data()).unwrap();
    let maps = vfs.list("maps/", ".bsp");
    // 62 bsp entries in the packages, 58 distinct names (later paks override earlier ones).
    assert!(maps.len() >= 58, "only {} maps in the data set", maps.len());
    let mut warnings = Vec::new();
    let shaders = load_shader_library(&vfs, &mut warnings);
    let mut options = test_options();
    options.set("width", "160").unwrap();
    options.set("height", "120").unwrap();
    let ctx = create_context(BackendChoice::Egl, 160, 120, Profile::Core).unwrap();
    let mut renderer = Renderer::new(ctx.gl.clone(), 160, 120).unwrap();
    for map in &maps {
        let mut builder = SceneBuilder::new(map, &shaders);
        let info = world::load_map(&mut builder, &vfs, map, &options.q3)
            .unwrap_or_else(|e| panic!("{map}: {e}"));
        let (mut scene, _missing) = builder.finish(&vfs, false);
        assert!(info.counts.triangles.total > 0, "{map}: no triangles");
        // From the first spawn point when there is one, else from the middle of the map.
        scene.camera = match info.spawns.first() {
            Some(s) => Camera {
                position: s.origin + glam::Vec3::Z * 26.0,
                yaw_deg: s.yaw_deg,
                ..Camera::default()
            },
            None => Camera {
                position: scene.bounds().center(),
                ..Camera::default()
            },
        };
        renderer
            .load_scene(&scene)
            .unwrap_or_else(|e| panic!("{map}: {e}"));
        renderer
            .render(&scene, &options)
            .unwrap_or_else(|e| panic!("{map}: {e}"));
        // Some maps are nearly black in their lightmaps where they start (czest2ctf: ~7/255), so
        // coverage is checked with flat ambient light; the clear colour is black, sky undrawn.
        let mut flat = options.clone();
        flat.set("lighting.baked", "false").unwrap();
        flat.set("lighting.ambient", "1").unwrap();
        let frame = renderer.render(&scene, &flat).unwrap();
        let drawn = frame
            .image
            .data
            .chunks_exact(4)
            .filter(|p| p[0] | p[1] | p[2] > 0)
            .count();
        assert!(
            drawn * 20 > (frame.width() * frame.height()) as usize,
            "{map}: only {drawn} drawn pixels from the first spawn point"
        );
    }
}

fn inspect(map: &str) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["inspect", "--data"])
        .arg(openarena_data())
        .arg(map)
        .output()
        .unwrap();
    serde_json::from_str(&stdout_of(out)).unwrap()
}

#[test]
fn inspect_matches_an_independent_count() {
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/count-bsp.py");
    for map in ["oa_dm1", "oa_dm3", "wrackdm17"] {
        let ours = inspect(map);
        let out = Command::new("python3")
            .arg(&script)
            .arg(openarena_data())
            .arg(map)
            .output()
            .expect("python3 is needed for the independent count (Debian: python3)");
        let theirs: serde_json::Value = serde_json::from_str(&stdout_of(out)).unwrap();
        for key in ["faces", "triangles", "lightmaps", "leaves", "clusters"] {
            assert_eq!(ours[key], theirs[key], "{map}: {key}");
        }
        let count = |v: &serde_json::Value, key: &str| {
            v["vertices"][key]
                .as_u64()
                .unwrap_or_else(|| panic!("{map}: vertices.{key} missing in {v}"))
        };
        assert_eq!(count(&ours, "raw"), count(&theirs, "raw"), "{map}");
        // Welding can only merge vertices.
        assert!(count(&ours, "welded") <= count(&ours, "raw"), "{map}");
    }
    // The figures the benchmark set is known by (world triangles after tessellation).
    assert_eq!(inspect("oa_dm1")["triangles"]["total"], 7460);
    assert_eq!(inspect("oa_dm3")["triangles"]["total"], 68352);
    assert_eq!(inspect("wrackdm17")["triangles"]["total"], 25359);
}

#[test]
fn inspect_all_prints_one_line_per_map() {
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["inspect", "--all", "--data"])
        .arg(openarena_data())
        .output()
        .unwrap();
    let lines: Vec<serde_json::Value> = stdout_of(out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(lines.len() >= 58);
    for l in &lines {
        let e = &l["edges"];
        assert!(e["manifold"].as_u64().unwrap() > 0, "{}", l["map"]);
        assert!(l["triangles"]["total"].as_u64().unwrap() > 0);
    }
    // Quake 3 worlds are not 2-manifold: the benchmark maps have open and non-manifold edges.
    let dm1 = lines.iter().find(|l| l["map"] == "oa_dm1").unwrap();
    assert!(dm1["edges"]["open"].as_u64().unwrap() > 100);
    assert!(dm1["edges"]["non_manifold"].as_u64().unwrap() > 100);
}

#[test]
fn benchmark_scenes_hold_their_lights_and_a_player() {
    for (name, lights) in [
        ("q3dm6ish", 26),
        ("oa_dm1", 4),
        ("oa_dm3", 64),
        ("ctf_compromise", 4),
        ("wrackdm17", 4),
    ] {
        let (scene, report, _) = load_scene_file(name);
        assert_eq!(scene.lights.len(), lights, "{name}");
        // No light sees the backs of faces (q3dm6ish's four fill lights above the hull, which
        // do, are excluded by its scene file).
        let warnings = shadowlab::truth::enclosure::scene_warnings(&scene);
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        assert!(
            scene
                .models
                .iter()
                .any(|m| m.name.contains("players/sarge")),
            "{name}"
        );
        let model_tris: usize = scene
            .surfaces
            .iter()
            .filter(|s| matches!(s.owner, SurfaceOwner::Model(_)))
            .map(|s| s.index_count as usize / 3)
            .sum();
        assert!(
            model_tris > 500,
            "{name}: the player has {model_tris} triangles"
        );
        assert!(report.counts.is_some());
        // The camera stands 26 units above the first spawn point, inside the map.
        let world = scene.world.as_ref().unwrap();
        assert!(
            world.cluster_at(scene.camera.position) >= 0,
            "{name}: camera outside the map"
        );
    }
}

#[test]
fn q3dm6ish_lights_come_from_its_entities() {
    let (scene, _, _) = load_scene_file("q3dm6ish");
    // Its 30 `light` entities have no targets, so all are omni lights; the radius is the
    // entity's light value (DarkPlaces' convention), and all lie inside the map.
    assert!(scene.lights.iter().all(|l| !l.is_spot()));
    let world = scene.world.as_ref().unwrap();
    for l in &scene.lights {
        assert!(
            l.radius >= 50.0 && l.radius <= 2000.0,
            "{}: radius {}",
            l.name,
            l.radius
        );
        assert!(
            world.cluster_at(l.position) >= 0,
            "{} is outside the map",
            l.name
        );
    }
}

#[test]
fn pvs_and_frustum_culling_cut_the_world_and_keep_the_view() {
    let (scene, _, mut options) = load_scene_file("oa_dm3");
    let plan = shadowlab::plan::Plan::build(&scene, &options);
    let vis = plan.stats.vis.clone().unwrap();
    assert!(vis.camera_cluster >= 0);
    assert!(vis.leaves_outside_pvs > 0 && vis.leaves_outside_frustum > 0);
    assert!(plan.stats.triangles_visible < scene.triangle_count() / 2);
    // Culling changes what is drawn, not what is seen: the images match.
    options.set("lighting.lights", "false").unwrap();
    let culled = common::render(&scene, &options);
    options.set("culling.pvs", "false").unwrap();
    options.set("culling.frustum", "false").unwrap();
    let all = common::render(&scene, &options);
    let (max, differing) = common::image_difference(&culled, &all);
    assert_eq!((max, differing), (0, 0));
}

/// oa_dm1's corridor floor (surface 521, one of the map's 62 planar surfaces whose own
/// triangles overlap): the lit pass adds a light there once (`lighting.light_once`), where the
/// paper's unmarked additive pass adds it twice in bands.
#[test]
fn a_light_is_added_once_where_a_surfaces_own_triangles_overlap() {
    let (scene, _, _) = load_asset("assets/scenes/oa_dm1.toml");
    let image = |extra: &[&str]| {
        let mut sets = vec![
            "lighting.baked=false",
            "technique=none",
            "lighting.only=1",
            "width=640",
            "height=400",
        ];
        sets.extend_from_slice(extra);
        render(&scene, &options_with(&sets)).image
    };
    let unlit = image(&["lighting.lights=false"]);
    let marked = image(&[]);
    let unmarked = image(&["lighting.light_once=false"]);
    let added = |img: &shadowlab::images::Rgba, i: usize| img.data[i] as i32 - unlit.data[i] as i32;
    let (mut more, mut doubled) = (0, 0);
    for i in (0..unlit.data.len()).step_by(4) {
        let (once, twice) = (added(&marked, i), added(&unmarked, i));
        // Marks only ever take a second addition away (1 level of rounding allowed).
        more += (once > twice + 1) as usize;
        // Twice the light, where the light is bright enough to tell (8 levels).
        doubled += (once >= 8 && twice as f64 >= 1.7 * once as f64) as usize;
    }
    assert_eq!(more, 0);
    // 4 022 such pixels at 1280x800, a quarter of that here.
    assert!(doubled > 200, "{doubled}");
}
