//! Foundation: the built-in scene renders headless on every context path, deterministically.

mod common;

use common::{
    assert_colours_within_rounding, assert_masks_agree, image_difference, mean_luma, options_with,
    render, render_masks_on, stdout_of, test_options,
};
use glam::Vec3;
use shadowlab::options::BackendChoice;
use shadowlab::scene::builtin::{self, SPOT_POSITION, SPOT_TARGET};
use std::process::Command;

#[test]
fn floor_under_the_spot_light_is_brighter_than_outside_its_cone() {
    let scene = builtin::default_scene();
    let mut options = test_options();
    // Only the spot light, so the omni light cannot brighten the comparison point.
    options.set("lighting.only", "0").unwrap();
    let frame = render(&scene, &options);
    assert_eq!((frame.width(), frame.height()), (640, 480));
    // The spot aims at SPOT_TARGET on the floor; (150, -200) on the floor is > 38° off its axis.
    let axis = (SPOT_TARGET - SPOT_POSITION).normalize();
    let outside = Vec3::new(180.0, -200.0, 0.0);
    let off_axis = (outside - SPOT_POSITION)
        .normalize()
        .dot(axis)
        .acos()
        .to_degrees();
    assert!(off_axis > builtin::SPOT_CUTOFF_DEG + 5.0, "{off_axis}");
    let lit = mean_luma(&frame, frame.project(SPOT_TARGET).unwrap(), 3);
    let unlit = mean_luma(&frame, frame.project(outside).unwrap(), 3);
    assert!(lit > unlit * 2.0, "inside the cone {lit}, outside {unlit}");
    // Outside the cone only the unlit pass remains: floor texture (~112..150) x ambient 0.2.
    assert!(unlit > 15.0 && unlit < 35.0, "{unlit}");
}

#[test]
fn lights_off_leaves_only_the_ambient_level() {
    let scene = builtin::default_scene();
    let mut on = test_options();
    on.set("lighting.only", "0").unwrap();
    let mut off = on.clone();
    off.set("lighting.lights", "false").unwrap();
    let (a, b) = (render(&scene, &on), render(&scene, &off));
    let p = a.project(SPOT_TARGET).unwrap();
    assert!(mean_luma(&a, p, 2) > 3.0 * mean_luma(&b, p, 2));
}

/// One renderer draws the same frame twice bit for bit; two renderers within the rounding of
/// their additive passes (softpipe rounds two renderers apart: `assert_colours_within_rounding`).
#[test]
fn two_renders_are_bit_identical() {
    let scene = builtin::default_scene();
    let options = test_options();
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &options);
    r.load_scene(&scene).unwrap();
    let a = r.render(&scene, &options).unwrap();
    let b = r.render(&scene, &options).unwrap();
    assert_eq!(image_difference(&a, &b), (0, 0));
    let other = render(&scene, &options);
    assert_colours_within_rounding(&a, &other, "another renderer");
}

/// EGL and OSMesa give the same frame: identical masks where one rasteriser is behind both
/// (Mesa's llvmpipe, or softpipe, serves both libraries) and colours within the rounding of
/// the lights' additive passes (`assert_colours_within_rounding`: softpipe's two renderers
/// round one step apart on 25 000–28 000 lit pixels), the same decisions away from the edges
/// where they are two.
#[test]
fn osmesa_matches_egl() {
    let scene = builtin::default_scene();
    let unshadowed = render(&scene, &test_options());
    for technique in ["shadow_map", "shadow_volume"] {
        let options = options_with(&[&format!("technique={technique}")]);
        let (egl, egl_rasteriser) = render_masks_on(BackendChoice::Egl, &scene, &options);
        let (osmesa, osmesa_rasteriser) = render_masks_on(BackendChoice::Osmesa, &scene, &options);
        // The frames are shadowed: the built-in scene's shadows cover about 9% of the view (a
        // technique that drew none would change nothing); at least a twentieth must change.
        let (_, shadowed) = image_difference(&egl, &unshadowed);
        assert!(
            shadowed > 640 * 480 / 20,
            "{technique}: {shadowed} px shadowed"
        );
        let same = egl_rasteriser == osmesa_rasteriser;
        for mask in &egl.masks {
            let other = osmesa.masks.iter().find(|m| m.light == mask.light).unwrap();
            let d = assert_masks_agree(
                mask,
                other,
                same,
                &format!("{technique} light {}", mask.light),
            );
            println!(
                "{technique} light {}: EGL ({egl_rasteriser}) against OSMesa ({osmesa_rasteriser}): {d:?}",
                mask.light
            );
        }
        if same {
            assert_colours_within_rounding(&egl, &osmesa, technique);
        } else {
            let (_, differing) = image_difference(&egl, &osmesa);
            // Two rasterisers: the same decisions (above); shading may round apart.
            assert!(
                differing < 640 * 480 / 20,
                "{technique}: {differing} px differ"
            );
        }
    }
}

fn shadowlab() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shadowlab"))
}

#[test]
fn forcing_a_backend_that_cannot_start_gives_the_documented_error() {
    let out = shadowlab()
        .args(["info", "--backend", "window"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "must fail, not panic");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no OpenGL 3.3 core context could be created"),
        "{err}"
    );
    assert!(err.contains("window:") && err.contains("xvfb"), "{err}");
    assert!(!err.contains("panicked"), "{err}");

    let out = shadowlab()
        .args(["info", "--backend", "osmesa"])
        .env("SHADOWLAB_OSMESA_LIBRARY", "/nonexistent/libOSMesa.so.8")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("osmesa: libOSMesa not found"), "{err}");
    assert!(err.contains("libosmesa6"), "{err}");
}

#[test]
fn info_json_reports_the_egl_path_and_each_missing_feature_as_a_fallback() {
    let out = shadowlab().args(["info", "--json"]).output().unwrap();
    let v: serde_json::Value = serde_json::from_str(&stdout_of(out)).unwrap();
    assert_eq!(v["backend"], "egl");
    assert!(v["version"].as_str().unwrap().len() > 3);
    assert!(v["renderer"].as_str().unwrap().len() > 3);
    let fallbacks = v["fallbacks"].as_array().unwrap();
    assert!(fallbacks.iter().all(|f| f.is_string()));
    // Every missing feature appears as a fallback, and only those.
    let missing = v["features"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["supported"] == false)
        .count();
    assert_eq!(missing, fallbacks.len());
    // No options given: the defaults, which differ from the paper's frame in the planner, the
    // technique, the casters (both faces), the offset growth, the light marks, the texgen
    // space, the depth pass's space, the compared point's lift, the GPU extrusion (`auto`) and
    // the map budget only.
    assert_eq!(v["preset"], "default");
    let differs: Vec<&str> = v["differs_from_paper"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["key"].as_str().unwrap())
        .collect();
    assert_eq!(
        differs,
        [
            "lighting.light_once",
            "plan.enabled",
            "shadow_map.budget_mb",
            "shadow_map.caster_space",
            "shadow_map.cull",
            "shadow_map.normal_offset",
            "shadow_map.offset_growth",
            "shadow_map.texgen",
            "shadow_volume.casters",
            "shadow_volume.gpu_extrusion",
            "technique"
        ]
    );
    // Each feature is a fallback exactly when the probe found it missing (llvmpipe lacks
    // EXT_depth_bounds_test, softpipe has it; GPUs differ again).
    for f in v["features"].as_array().unwrap() {
        let key = f["key"].as_str().unwrap();
        let listed = fallbacks
            .iter()
            .any(|l| l.as_str().unwrap().starts_with(&format!("{key}:")));
        assert_eq!(listed, f["supported"] == false, "{key}: {f}");
    }
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let dir = std::env::temp_dir().join(format!("shadowlab-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("r.png");
    let status = shadowlab()
        .args(["render", "--size", "320x240", "--out"])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (320, 240));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn window_path_works_under_xvfb() {
    let have_xvfb = Command::new("sh")
        .args(["-c", "command -v xvfb-run"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    assert!(
        have_xvfb,
        "xvfb-run is missing: install the Debian package `xvfb` (apt-get install xvfb xauth)"
    );
    let dir = std::env::temp_dir().join(format!("shadowlab-xvfb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, e) = (dir.join("w.png"), dir.join("e.png"));
    let status = Command::new("xvfb-run")
        .args([
            "-a",
            env!("CARGO_BIN_EXE_shadowlab"),
            "render",
            "--backend",
            "window",
            "--set",
            "technique=shadow_volume",
            "--out",
        ])
        .arg(&w)
        .status()
        .unwrap();
    assert!(status.success());
    assert!(
        shadowlab()
            .args(["render", "--set", "technique=shadow_volume", "--out"])
            .arg(&e)
            .status()
            .unwrap()
            .success()
    );
    let (a, b) = (
        image::open(&w).unwrap().to_rgba8(),
        image::open(&e).unwrap().to_rgba8(),
    );
    assert_eq!(a.dimensions(), (640, 480));
    let differing = a.pixels().zip(b.pixels()).filter(|(x, y)| x != y).count();
    // Both paths render into our own framebuffer: on the same rasteriser the same image. The
    // window's GL (GLX under Xvfb) may be another rasteriser than EGL's (a GPU): then the
    // frames must agree in substance, not bit for bit.
    let renderer = |window: bool| {
        let mut c = if window {
            let mut c = Command::new("xvfb-run");
            c.args(["-a", env!("CARGO_BIN_EXE_shadowlab")]);
            c
        } else {
            shadowlab()
        };
        c.args(["info", "--json"]);
        if window {
            c.args(["--backend", "window"]);
        }
        let out = c.output().unwrap();
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_default();
        v["renderer"].as_str().unwrap_or("?").to_string()
    };
    let (rw, re) = (renderer(true), renderer(false));
    println!("window ({rw}) against egl ({re}): {differing} pixels differ");
    if rw == re {
        assert_eq!(differing, 0, "pixels differ between window and egl");
    } else {
        let luma = |i: &image::RgbaImage| i.pixels().map(|p| p[1] as f64).sum::<f64>();
        let (la, lb) = (luma(&a), luma(&b));
        assert!(
            (la - lb).abs() < 0.02 * lb,
            "mean brightness {la} against {lb}"
        );
        assert!(differing < 640 * 480 / 20, "{differing} pixels differ");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `gl.lights_per_fence`: on a software profile the frame waits for the group of lights before
/// the last (a CPU rasteriser's binned queue stays bounded), drawing the same pixels (compared
/// on volumes; see below for maps); under
/// `plan.profile = gpu` it never waits. Counted on the built-in scene's two lights, one
/// light per fence: volumes send each light once (1 wait), maps drawn first send each light's
/// maps too (3 waits). Made to fail: with `light_sent` called only for the lit passes, the
/// maps frame counts 1 wait.
#[test]
fn lights_per_fence_bounds_the_queue_on_software_only_and_changes_no_pixel() {
    let scene = builtin::default_scene();
    let base = ["width=160", "height=120", "plan.profile=software"];
    let with = |extra: &[&str]| {
        let mut keys: Vec<&str> = base.to_vec();
        keys.extend_from_slice(extra);
        options_with(&keys)
    };
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &with(&[]));
    r.load_scene(&scene).unwrap();
    let left = shadowlab::gl::FrameRequest {
        frame_only: true,
        image_on_gpu: true,
        ..Default::default()
    };
    let pixels = shadowlab::gl::FrameRequest {
        frame_only: true,
        ..Default::default()
    };
    // softpipe's shadow-map frames change with where the driver is flushed at all (a frame
    // timed pass by pass, with a glFinish between passes, differs from the same frame untimed
    // by ~2 800 bytes here, fences or not); llvmpipe's do not. The pixels are compared where
    // every driver keeps them: on volumes.
    let cases = [
        ("technique=shadow_volume", 1, true),
        ("technique=shadow_map", 3, false),
    ];
    for (technique, waits, compare_pixels) in cases {
        let one = with(&[technique, "gl.lights_per_fence=1"]);
        let f = r.render_with(&scene, &one, left).unwrap();
        assert_eq!(f.plan_stats.lights_planned, 2, "{technique}");
        assert_eq!(
            f.syncs.fence_waits,
            waits,
            "{technique}: {}",
            f.syncs.describe()
        );
        let none = with(&[technique, "gl.lights_per_fence=0"]);
        assert_eq!(r.render_with(&scene, &none, left).unwrap().syncs.total(), 0);
        let gpu = with(&[technique, "gl.lights_per_fence=1", "plan.profile=gpu"]);
        assert_eq!(r.render_with(&scene, &gpu, left).unwrap().syncs.total(), 0);
        if !compare_pixels {
            continue;
        }
        let bounded = r.render_with(&scene, &one, pixels).unwrap().image;
        let unbounded = r.render_with(&scene, &none, pixels).unwrap().image;
        assert!(
            bounded.data.iter().any(|&v| v > 0),
            "{technique}: a black frame"
        );
        assert!(
            bounded.data == unbounded.data,
            "{technique}: the fences changed pixels"
        );
    }
    r.check_errors().unwrap();
}

/// Every wait for the GPU a frame makes is counted in `Frame::syncs`: a frame whose caller wants
/// its pixels reads its image back and waits for it, asking for masks adds the masks'
/// read-backs, and a frame left on the GPU (`image_on_gpu`, as `bench` times it) under
/// `plan.profile = gpu` waits for nothing at all. Made to fail: with the counting removed from
/// the read-back path both read-back counts are 0; with the frame's final glFinish made
/// unconditional the frame left on the GPU counts 1 finish.
#[test]
fn a_frame_counts_its_waits_for_the_gpu() {
    let scene = builtin::default_scene();
    let options = options_with(&["technique=shadow_volume", "width=160", "height=120"]);
    let (_ctx, mut r) = common::gl_on(BackendChoice::Egl, &options);
    r.load_scene(&scene).unwrap();
    let request = |masks: bool| shadowlab::gl::FrameRequest {
        frame_only: !masks,
        masks,
        ..Default::default()
    };
    let plain = r.render_with(&scene, &options, request(false)).unwrap();
    let masked = r.render_with(&scene, &options, request(true)).unwrap();
    assert!(plain.syncs.read_backs >= 1, "{:?}", plain.syncs);
    assert!(plain.syncs.finishes >= 1, "{:?}", plain.syncs);
    assert!(plain.completed && plain.image.data.len() == 160 * 120 * 4);
    assert!(
        masked.syncs.read_backs > plain.syncs.read_backs,
        "masks read back nothing more: {:?} against {:?}",
        masked.syncs,
        plain.syncs
    );
    let gpu = options_with(&[
        "technique=shadow_volume",
        "width=160",
        "height=120",
        "plan.profile=gpu",
    ]);
    let left = shadowlab::gl::FrameRequest {
        frame_only: true,
        image_on_gpu: true,
        ..Default::default()
    };
    for _ in 0..3 {
        let f = r.render_with(&scene, &gpu, left).unwrap();
        assert_eq!(f.syncs.total(), 0, "{}", f.syncs.describe());
        assert!(!f.completed && f.image.data.is_empty());
        assert_eq!((f.width(), f.height()), (160, 120));
    }
    r.check_errors().unwrap();
}
