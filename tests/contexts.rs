//! The context chain: OpenGL ES 3.0 renders both techniques as desktop GL does, compatibility
//! contexts take the legacy calls, and `auto` falls to ES 3.0 when desktop EGL fails. Every
//! assertion is on the path's own properties (API, profile, masks), not on a driver's name.

mod common;

use common::{Measurer, options_with, stdout_of};
use shadowlab::gl::{GlApi, Profile, create_context};
use shadowlab::options::BackendChoice;
use shadowlab::scene::builtin;
use std::process::Command;

/// Pixels per light where the ES 3.0 mask may differ from desktop core's. GLSL ES `highp` is
/// IEEE single precision like desktop GLSL and the vertex stage is `invariant` on both, so the
/// shadow-map masks agree exactly on one driver (llvmpipe: 0). Shadow volumes differ by a few
/// pixels (llvmpipe: 1 and 3) because ES takes the clip_distances fallback: the planner's depth
/// clip is off and volume pieces are drawn whole rather than clipped, which moves pixels where
/// a clipped edge rasterizes differently. A hardware driver compiles the two languages apart
/// (fused multiply-adds may differ), moving only pixels whose depth compare is within an ulp,
/// along shadow boundaries; 150 is under 0.05% of the 307,200 pixels.
const ES_DESKTOP_DIFFERING_PIXELS: usize = 150;

/// Error against the exact reference each light's ES 3.0 mask may have at most (fraction of
/// receivers). Desktop core measures 0.31% / 0.32% (shadow maps) and 1.76% / 0.54% (shadow
/// volumes, the built-in scene's coplanar caps) on the built-in scene.
const ES_ERROR_BOUND: [(&str, [f64; 2]); 2] = [
    ("technique=shadow_map", [0.005, 0.005]),
    ("technique=shadow_volume", [0.02, 0.008]),
];

/// Each technique's frame measured on `backend` (one context at a time: a second context made
/// current on this thread would take the first one's calls).
fn measured_on(backend: BackendChoice, api: GlApi) -> Vec<common::Measured> {
    let first = options_with(&[ES_ERROR_BOUND[0].0]);
    let mut m = Measurer::on(backend, builtin::default_scene(), &first);
    assert_eq!(m.context().api, api);
    let profile = if api == GlApi::Es3 { "es" } else { "core" };
    assert_eq!(m.renderer().caps().profile, profile);
    ES_ERROR_BOUND
        .iter()
        .map(|(t, _)| m.measure(&options_with(&[t])))
        .collect()
}

#[test]
fn es3_renders_both_techniques_as_desktop_core_does() {
    let es = measured_on(BackendChoice::EglEs, GlApi::Es3);
    let desktop = measured_on(BackendChoice::Egl, GlApi::DesktopCore);
    for (((technique, bounds), on_es), on_desktop) in
        ES_ERROR_BOUND.into_iter().zip(&es).zip(&desktop)
    {
        // GLSL ES 3.00 has no gl_ClipDistance: the planner's depth clip falls back.
        assert!(
            on_es
                .frame
                .fallbacks
                .iter()
                .any(|f| f.feature == "clip_distances"),
            "{technique}: {:?}",
            on_es.frame.fallbacks
        );
        for (l, bound) in bounds.into_iter().enumerate() {
            let e = on_es.light(l).rates().total;
            let d = on_desktop.light(l).rates().total;
            let differing = on_es
                .mask(l)
                .values
                .iter()
                .zip(&on_desktop.mask(l).values)
                .filter(|(a, b)| a != b)
                .count();
            println!(
                "{technique} light {l}: ES error {:.3}%, desktop {:.3}%, {differing} pixels differ",
                100.0 * e,
                100.0 * d
            );
            assert!(e <= bound, "{technique} light {l}: error {e} > {bound}");
            assert!(
                differing <= ES_DESKTOP_DIFFERING_PIXELS,
                "{technique} light {l}: {differing} pixels differ from desktop core"
            );
        }
    }
}

#[test]
fn es3_draws_into_the_map_instead_of_copying_depth_and_reduces_depth_instead_of_reading_it() {
    let mut es = Measurer::on(
        BackendChoice::EglEs,
        builtin::default_scene(),
        &options_with(&["technique=shadow_map"]),
    );
    assert!(!es.renderer().caps().has("depth_copy"));
    let copy = es.measure(&options_with(&[
        "technique=shadow_map",
        "shadow_map.depth_source=copy",
    ]));
    let fbo = es.measure(&options_with(&[
        "technique=shadow_map",
        "shadow_map.depth_source=fbo",
    ]));
    let taken: Vec<_> = copy
        .frame
        .fallbacks
        .iter()
        .filter(|f| f.feature == "depth_copy")
        .collect();
    assert_eq!(taken.len(), 1, "{:?}", copy.frame.fallbacks);
    assert_eq!(taken[0].used, "fbo");
    for l in 0..2 {
        assert_eq!(copy.mask(l).values, fbo.mask(l).values, "light {l}");
    }
    // The planner's whole-depth read (ES reads no depth) becomes the shader-reduced one.
    assert!(!es.renderer().caps().has("depth_read"));
    let sv = "technique=shadow_volume";
    let whole = es.measure(&options_with(&[sv, "plan.reduce_depth=false"]));
    let reduced = es.measure(&options_with(&[sv, "plan.reduce_depth=true"]));
    let taken: Vec<&str> = whole
        .frame
        .fallbacks
        .iter()
        .map(|f| f.feature.as_ref())
        .collect();
    assert!(taken.contains(&"depth_read"), "{taken:?}");
    for l in 0..2 {
        assert_eq!(whole.mask(l).values, reduced.mask(l).values, "light {l}");
    }
}

#[test]
fn compatibility_contexts_take_the_legacy_calls_on_egl_and_osmesa() {
    for backend in [BackendChoice::Egl, BackendChoice::Osmesa] {
        let ctx = create_context(backend, 64, 64, Profile::Compatibility)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(ctx.api, GlApi::DesktopCompatibility, "{backend:?}");
        let caps = shadowlab::gl::caps::probe(&ctx.gl, (24, 8));
        assert_eq!(
            caps.profile, "compatibility",
            "{backend:?}: {}",
            caps.version
        );
        ctx.legacy_calls_work()
            .unwrap_or_else(|e| panic!("{backend:?}: {e}"));
        // The same check refuses a core context: it tests the profile, not the loader.
        drop(ctx);
        let core = create_context(backend, 64, 64, Profile::Core).unwrap();
        assert!(core.legacy_calls_work().is_err(), "{backend:?} core");
    }
    // ES has no compatibility profile; asked for one it says so.
    let e = create_context(BackendChoice::EglEs, 64, 64, Profile::Compatibility)
        .err()
        .expect("ES refuses the compatibility profile");
    assert!(e.to_string().contains("egl_es"), "{e}");
}

/// `shadowlab info --json` with the paths in `failing` made to fail.
fn info_with_failing(failing: &str) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["info", "--json"])
        .env(shadowlab::gl::context::FAIL_BACKENDS_ENV, failing)
        .output()
        .unwrap()
}

#[test]
fn auto_falls_to_es3_when_desktop_egl_fails() {
    let v: serde_json::Value = serde_json::from_str(&stdout_of(info_with_failing("egl"))).unwrap();
    assert_eq!(v["backend"], "egl_es", "{v}");
    assert_eq!(v["api"], "es3");
    assert_eq!(v["profile"], "es");
    let skipped = v["skipped_backends"].as_array().unwrap();
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert!(skipped[0].as_str().unwrap().starts_with("egl:"));
    // Then OSMesa, and with every step failing an error naming each one.
    let v: serde_json::Value =
        serde_json::from_str(&stdout_of(info_with_failing("egl,egl_es"))).unwrap();
    assert_eq!(v["backend"], "osmesa", "{v}");
    let out = info_with_failing("egl,egl_es,osmesa");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    for step in ["  egl: ", "  egl_es: ", "  osmesa: "] {
        assert!(err.contains(step), "{step} missing from: {err}");
    }
}
