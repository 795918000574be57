//! `reproduce` in its quick form: every section is measured and written, and the numbers that
//! the paper's figures are about go the way the figures say (on oa_dm1 at 320x240). The same
//! run split into two shards and merged gives the same sections and error figures.

mod common;

use common::{gl_on, openarena_data};
use shadowlab::options::{BackendChoice, Options};
use shadowlab::report::reproduce::{self, Section, Settings};
use shadowlab::report::shard::Shard;
use std::path::Path;

/// A number the section recorded; a missing one fails, naming what the section has.
fn n(s: &Section, key: &str) -> f64 {
    *s.numbers.get(key).unwrap_or_else(|| {
        panic!(
            "section {}: no number `{key}` (it has {:?})",
            s.id,
            s.numbers.keys().collect::<Vec<_>>()
        )
    })
}

#[test]
fn quick_report_measures_every_section_and_writes_it() {
    openarena_data();
    let out = std::env::temp_dir().join(format!("shadowlab-reproduce-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let settings = Settings::quick(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes"));
    let options = Options {
        width: settings.width,
        height: settings.height,
        ..Options::default()
    };
    let (_ctx, mut renderer) = gl_on(BackendChoice::Egl, &options);
    // ID and priority buffers need gl_PrimitiveID in fragment shaders (the probe draws it).
    let ids = renderer.caps_for(&options).unwrap().has("primitive_id");
    let report = reproduce::run(&mut renderer, &settings, &out).unwrap_or_else(|e| panic!("{e}"));
    for s in &report.summary {
        println!("{s}");
    }
    for s in &report.sections {
        println!("{}: {:?}", s.id, s.numbers);
    }
    let section = |id: &str| {
        report
            .section(id)
            .unwrap_or_else(|| panic!("no section {id}"))
    };

    // Every section of the issue is there, with an image or a table and a way to regenerate.
    for id in [
        "paper-fig1",
        "paper-fig2",
        "thesis-fig10",
        "thesis-fig12",
        "thesis-fig13-14",
        "thesis-fig20-21",
        "thesis-fig22",
        "thesis-ch4",
        "thesis-ch5",
        "thesis-four-oa_dm1",
        "claim-sm-lights",
        "claim-sv-lights",
        "sweep-oa_dm1",
        "frontier-oa_dm1",
        "forsyth-buffers",
        "forsyth-ids",
        "forsyth-shootout",
        "forsyth-frusta",
        "forsyth-priority-mips",
        "vector-subdivision",
    ] {
        let s = report
            .section(id)
            .unwrap_or_else(|| panic!("no section {id}"));
        assert!(!s.tables.is_empty() && !s.regenerate.is_empty(), "{id}");
        for f in &s.figures {
            let size = std::fs::metadata(out.join(&f.file))
                .map(|m| m.len())
                .unwrap_or(0);
            assert!(size > 1000, "{id}: {} missing or empty", f.file);
        }
    }
    // The frontier: at least one configuration, fastest first, none dominating another.
    let frontier = &report.section("frontier-oa_dm1").unwrap().tables[0];
    assert!(!frontier.rows.is_empty());
    let cell = |r: &Vec<String>, i: usize| -> f64 {
        r[i].trim_end_matches('%').parse().unwrap_or(f64::NAN)
    };
    for pair in frontier.rows.windows(2) {
        // Slower but less accurate would be dominated (the cells are rounded: ties pass).
        assert!(cell(&pair[0], 1) <= cell(&pair[1], 1), "{pair:?}");
        assert!(cell(&pair[0], 3) >= cell(&pair[1], 3), "{pair:?}");
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let md = std::fs::read_to_string(out.join("index.md")).unwrap();
    assert!(html.contains("Paper Fig. 2") && md.contains("## Paper Fig. 2"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json.as_array().unwrap().len(), report.rows.len());

    // Every section holds at least one number a wrong result would move past its bound
    // (`n` fails naming a number the section no longer records). Errors are fractions of the
    // receiver pixels, against the exact reference; no bound is on a time.
    // Fig. 1: clip planes lose receivers; no offset means acne.
    let f1 = section("paper-fig1");
    assert!(n(f1, "mismatch_clip") > 100.0);
    assert!(n(f1, "false_shadow_no_offset") > 10.0 * n(f1, "false_shadow_default"));
    // Fig. 2: a 64x64 map is several times worse than 512x512.
    let f2 = section("paper-fig2");
    assert!(n(f2, "error_64") > 3.0 * n(f2, "error_512"));
    assert!(n(f2, "error_128") > n(f2, "error_512"));
    // Fig. 10: no offset shadows falsely, too much lights falsely, the thesis' values do neither.
    let f10 = section("thesis-fig10");
    assert!(n(f10, "false_shadow_none") > 10.0 * n(f10, "error_right"));
    assert!(n(f10, "false_lit_too_much") > 2.0 * n(f10, "error_right"));
    // Fig. 12: filtering at 256² (nearest under the alpha test, then hardware 2x2, 3x3 and 5x5
    // PCF with the intensity result): the wider the kernel, the wider the band of edge pixels
    // it moves (measured 0.52%, 0.46%, 0.73%, 1.50% at 320x240), all within 2%.
    let f12 = section("thesis-fig12");
    let e12: Vec<f64> = (0..4).map(|i| n(f12, &format!("error_{i}"))).collect();
    assert!(e12[1] < e12[2] && e12[2] < e12[3], "fig 12: {e12:?}");
    assert!(e12.iter().all(|e| *e < 0.02), "fig 12: {e12:?}");
    // Fig. 13-14: copying the depth buffer and rendering into the texture store the same
    // depths (which share of the frame each takes is the section's timing, not a check).
    let f13 = section("thesis-fig13-14");
    assert_eq!(n(f13, "error_0"), n(f13, "error_1"));
    assert!(n(f13, "error_0") < 0.02);
    // Fig. 20-21: z-pass fails with the camera in a volume, z-fail does not.
    let f20 = section("thesis-fig20-21");
    assert!(n(f20, "error_zpass") > 0.01);
    assert!(n(f20, "error_zfail") < 0.002);
    // Fig. 22: one pass with two-sided stencil counts what two passes count (within the
    // slivers a rasteriser may face apart: SLIVER_SPECKS in tests/common).
    let f22 = section("thesis-fig22");
    assert!((n(f22, "error_0") - n(f22, "error_1")).abs() < 0.0005);
    assert!(n(f22, "error_0") < 0.002);
    // Ch. 4: perspective maps alias less than standard maps of the same size.
    let ch4 = section("thesis-ch4");
    assert!(n(ch4, "psm_256") < n(ch4, "shadow_map_256"));
    // Ch. 5: the hybrid rasterises a small share of the volumes' fragments and stays nearly as
    // exact (3.4% of the fragments, 0.015% against 0.010%).
    let ch5 = section("thesis-ch5");
    assert!(n(ch5, "fragment_share") < 0.2);
    assert!(n(ch5, "hybrid_error") < 0.002 && n(ch5, "sv_error") < 0.001);
    // The lights claims: every light count shadowed within the techniques' usual error on
    // oa_dm1 (maps under 1%, volumes under 0.1%).
    for (id, bound) in [("claim-sm-lights", 0.01), ("claim-sv-lights", 0.001)] {
        let c = section(id);
        let errors: Vec<(&String, &f64)> = c
            .numbers
            .iter()
            .filter(|(k, _)| k.contains("_error_"))
            .collect();
        assert!(
            !errors.is_empty(),
            "{id}: no errors recorded: {:?}",
            c.numbers
        );
        for (k, e) in errors {
            assert!(*e < bound, "{id}: {k} = {e}");
        }
    }
    // The sweep and the four techniques on oa_dm1: volumes near exact, maps within 1%.
    let sweep = section("sweep-oa_dm1");
    assert!(n(sweep, "sv_error") < 0.001 && n(sweep, "sm_error") < 0.01);
    let four = section("thesis-four-oa_dm1");
    for t in ["shadow_map", "psm", "tsm", "hybrid"] {
        assert!(n(four, &format!("{t}_error")) < 0.01, "{t}");
    }
    assert!(n(four, "shadow_volume_error") < 0.001);
    // The shootout: the exact techniques exact.
    let fs = section("forsyth-shootout");
    assert!(n(fs, "shadow_volumes_error") < 0.001);
    assert!(n(fs, "light-volume_subdivision_error") < 0.001);
    if ids {
        // Forsyth: the ID buffer needs no bias where the depth map without one is mostly acne.
        let fb = section("forsyth-buffers");
        assert!(n(fb, "depth_no_offset") > 0.3);
        assert!(n(fb, "id") < n(fb, "depth_no_offset") / 100.0);
        // Forsyth: one ID per convex part errs less than one per triangle (0.73% against 4.78%).
        let fi = section("forsyth-ids");
        assert!(n(fi, "part__32_bits") < n(fi, "triangle__32_bits") / 2.0);
        // The shootout: priority buffers far behind the depth map.
        let fs = section("forsyth-shootout");
        assert!(n(fs, "priority_buffer_error") > 10.0 * n(fs, "depth_map_error"));
    } else {
        // Without it they fall back to depth maps (listed with the frame's fallbacks) that keep
        // the row's own offset, the default: every ID and priority row is the depth map's with
        // its offset, and far from the acne of the one without.
        let fb = section("forsyth-buffers");
        for row in ["id", "id_filtered", "priority", "priority_depth"] {
            assert_eq!(n(fb, row), n(fb, "depth_offset"), "{row}");
        }
        assert!(n(fb, "depth_no_offset") > 10.0 * n(fb, "depth_offset"));
        println!("this GL lacks gl_PrimitiveID in fragment shaders: ID buffers fell back");
    }
    // Forsyth: multiple frusta beat six faces of the same texels where the camera faces the
    // light (tests/frusta.rs measures it at 640x480; here at the quick report's size).
    let ff = section("forsyth-frusta");
    assert!(n(ff, "frusta_256") < n(ff, "faces_256"));
    assert!(n(ff, "frusta_512") < n(ff, "faces_512"));
    if ids {
        // Forsyth: the mip chain votes away stripes finer than a pixel (tests/id_buffers.rs gives
        // the reasons for the bounds).
        let fp = section("forsyth-priority-mips");
        assert!(n(fp, "unfiltered") > 0.15);
        assert!(n(fp, "mipmapped") < n(fp, "unfiltered") / 10.0);
    }
    // Vector: the two exact references agree outside the boundary band (tests/subdivision.rs
    // says which pixels may differ and why).
    let v = section("vector-subdivision");
    assert!(n(v, "disagreement_excl_boundary") < 0.0005);

    // The same run as two shards, merged: the same sections in the same order, the same
    // configurations with the same error figures (times aside), every image.
    let parts: Vec<_> = (1..=2).map(|k| out.join(format!("part{k}"))).collect();
    for (k, part) in parts.iter().enumerate() {
        let shard = Settings {
            shard: Shard {
                index: k + 1,
                count: 2,
            },
            ..settings.clone()
        };
        reproduce::run(&mut renderer, &shard, part).unwrap_or_else(|e| panic!("{e}"));
    }
    let merged_dir = out.join("merged");
    let merged = reproduce::merge(&reproduce::unit_names(&settings), &parts, &merged_dir)
        .unwrap_or_else(|e| panic!("{e}"));
    let ids = |r: &reproduce::Report| r.sections.iter().map(|s| s.id.clone()).collect::<Vec<_>>();
    assert_eq!(ids(&merged), ids(&report));
    let errors = |r: &reproduce::Report| {
        r.rows
            .iter()
            .map(|row| {
                (
                    row.label.clone(),
                    row.error.total,
                    row.error_per_light.clone(),
                )
            })
            .collect::<Vec<_>>()
    };
    let (merged_errors, single_errors) = (errors(&merged), errors(&report));
    assert_eq!(merged_errors.len(), single_errors.len());
    let differ: Vec<_> = merged_errors
        .iter()
        .zip(&single_errors)
        .filter(|(m, s)| m != s)
        .map(|(m, s)| format!("{}: merged {} against {}", s.0, m.1, s.1))
        .collect();
    assert!(differ.is_empty(), "{differ:#?}");
    for f in report.sections.iter().flat_map(|s| &s.figures) {
        assert!(merged_dir.join(&f.file).is_file(), "{} missing", f.file);
    }
    // Each shard measured only its own units.
    let part_rows = |p: &Path| {
        let text = std::fs::read_to_string(p.join("part.json")).unwrap();
        let part: serde_json::Value = serde_json::from_str(&text).unwrap();
        part["results"].as_array().unwrap().len()
    };
    let units = reproduce::unit_names(&settings).len();
    assert_eq!(part_rows(&parts[0]) + part_rows(&parts[1]), units);
    let _ = std::fs::remove_dir_all(&out);
}
