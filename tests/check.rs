//! `shadowlab check`: one JSON line per map with both techniques, planner on and off, measured
//! against the exact reference; a map that cannot be loaded is a line saying why.

mod common;

use std::process::Command;

fn shadowlab() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shadowlab"))
}

/// `shadowlab check` of one map of the OpenArena data with `args` after it: its JSON line.
fn check_line(args: &[&str]) -> serde_json::Value {
    let out = shadowlab()
        .args(["check", "--data"])
        .arg(common::openarena_data())
        .args(args)
        .output()
        .unwrap();
    serde_json::from_str(common::stdout_of(out).trim()).unwrap()
}

#[test]
fn check_measures_oa_dm1_under_both_techniques_with_the_planner_on_and_off() {
    let line = check_line(&["oa_dm1"]);
    assert_eq!(line["map"], "maps/oa_dm1.bsp");
    assert!(line.get("error").is_none(), "{line}");
    // oa_dm1's light entities were compiled away: one light above each spawn point and item.
    assert_eq!(line["light_source"], "placed");
    assert!(line["lights"].as_u64().unwrap() > 10, "{line}");
    assert!(line["open_edges"].as_u64().unwrap() > 0, "{line}");
    let runs = line["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    for run in runs {
        let error = run["error_percent"].as_f64().unwrap();
        assert!(run["receiver_pixels"].as_u64().unwrap() > 10_000, "{run}");
        // Measured 0.56% (shadow maps, 512²) and 0.007% / 0.11% (volumes, planner on / off);
        // a lost shadow or a broken reference gives several percent.
        let bound = if run["technique"] == "shadow_map" {
            1.5
        } else {
            0.5
        };
        assert!(error < bound, "{run}");
    }
    assert_eq!(line["planner"].as_array().unwrap().len(), 2);
}

/// Placed lights are lowered out of low ceilings: on oa_bases5 the usual 64 units put 13 of
/// them inside solid geometry, and volumes then got 4.8% of the receivers wrong (0.05% now).
#[test]
fn placed_lights_stay_out_of_solid_geometry() {
    let line = check_line(&["oa_bases5"]);
    let warnings = line["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .all(|w| !w.as_str().unwrap().contains("inside solid")),
        "{warnings:?}"
    );
    for run in line["runs"].as_array().unwrap() {
        if run["technique"] == "shadow_volume" {
            assert!(run["error_percent"].as_f64().unwrap() < 0.5, "{run}");
        }
    }
}

#[test]
fn a_map_that_cannot_be_loaded_is_a_line_saying_why() {
    use std::io::Write;
    let dir = std::env::temp_dir().join(format!("shadowlab-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut z = zip::ZipWriter::new(std::fs::File::create(dir.join("broken.pk3")).unwrap());
    z.start_file("maps/broken.bsp", zip::write::SimpleFileOptions::default())
        .unwrap();
    // The header of a Quake 3 map, then nothing where its lumps should be.
    z.write_all(b"IBSP\x2e\x00\x00\x00").unwrap();
    z.write_all(&[0xff; 64]).unwrap();
    z.finish().unwrap();
    let out = shadowlab()
        .args(["check", "--all", "--data"])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    let line: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let error = line["error"].as_str().unwrap();
    assert!(error.starts_with("cannot load"), "{error}");
    assert!(!error.contains("panicked"), "{error}");
    assert!(
        stderr.contains("1 of 1 maps could not be checked"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// ctf_inyard from its first spawn shows parts of a ceiling over leaves outside the camera's
/// PVS (the ceiling is drawn whole, one of its leaves being visible). Seven lights whose range
/// meets only those leaves were culled by a test of the visible leaves, and their 172 lit
/// pixels went dark under both techniques; the planner's decisions that claim to change no
/// pixel now change none there.
#[test]
fn the_planner_keeps_lights_that_reach_a_receiver_over_leaves_outside_the_pvs() {
    let line = check_line(&["ctf_inyard"]);
    let planner = line["planner"].as_array().unwrap();
    assert_eq!(planner.len(), 2, "{line}");
    for p in planner {
        assert_eq!(p["conservative_beyond_edge_band"], 0, "{p}");
    }
}

/// oa_koth2's volumes err 0.131% from its first spawn, above the 0.1% volumes are held to:
/// light 29 shadows 5.4% of its receivers falsely, and shadow maps drawing the same casters
/// solid (`shadow_map.alpha_casters=ignore`) err there the same way. The pixels are holes of
/// alpha-tested casters, which a volume extruded from triangles cannot follow; beside them the
/// volumes err 0.005%. A count that leaves out too little keeps the whole error.
#[test]
fn check_tells_the_volumes_error_in_alpha_tested_holes_from_the_rest() {
    let line = check_line(&["oa_koth2", "--techniques", "shadow_volume"]);
    let runs = line["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2, "{line}");
    for run in runs {
        let all = run["error_percent"].as_f64().unwrap();
        let beside = run["error_beside_alpha_percent"].as_f64().unwrap();
        assert!(all > 0.1, "{run}");
        assert!(beside < 0.02, "{run}");
    }
}
