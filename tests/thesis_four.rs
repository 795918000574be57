//! The thesis's four algorithms against the exact reference: perspective (and trapezoidal)
//! shadow maps where the camera looks along a large receiver, their degenerate cases falling
//! back to a standard map, and Chan & Durand's hybrid matching shadow volumes while rasterising
//! a fraction of their fragments. `cargo test --release --test thesis_four -- --nocapture`
//! prints the figures.

mod common;

use common::{Measured, Measurer, load_asset, options_with};
use shadowlab::options::Options;

fn error(m: &Measured, light: usize) -> f64 {
    m.light(light).rates().total
}

fn pct(x: f64) -> String {
    format!("{:.3}%", 100.0 * x)
}

/// The near-receiver case (`assets/hard/near_receiver.toml`) with `sets`.
fn near_receiver(m: &mut Measurer, sets: &[&str]) -> Measured {
    m.measure(&options_with(sets))
}

#[test]
fn perspective_maps_beat_the_standard_map_where_the_camera_looks_along_a_receiver() {
    let (scene, _, _) = load_asset("assets/hard/near_receiver.toml");
    let mut m = Measurer::new(scene, &Options::default());
    for size in ["256", "512"] {
        let sm = near_receiver(
            &mut m,
            &[
                "technique=shadow_map",
                "lighting.only=0",
                &format!("shadow_map.size={size}"),
            ],
        );
        let psm = near_receiver(
            &mut m,
            &[
                "technique=psm",
                "lighting.only=0",
                &format!("shadow_map.size={size}"),
            ],
        );
        let (e_sm, e_psm) = (error(&sm, 0), error(&psm, 0));
        println!("size {size}: shadow map {}, psm {}", pct(e_sm), pct(e_psm));
        // Measured 2.12% against 1.08% at 256 and 1.14% against 0.38% at 512 (llvmpipe): the
        // near field's texels are what PSM is for; 1.5× leaves room for rasteriser rounding.
        assert!(
            e_psm * 1.5 < e_sm,
            "size {size}: psm {} is not 1.5× better than the standard map's {}",
            pct(e_psm),
            pct(e_sm)
        );
        assert!(
            psm.frame.plan_stats.warp_fallbacks == 0,
            "{:?}",
            psm.frame.plan_stats.warps
        );
        // Never a receiver lost: the mask's receivers are the reference's.
        assert_eq!(psm.light(0).receiver_mismatch, 0);
    }
    // Trapezoidal maps share the code; their default focus (half the view's depth onto 80%
    // of the map) warps less: measured 1.65% against 2.12% at 256, 0.48% against 0.64% at 1024.
    for size in ["256", "1024"] {
        let sm = near_receiver(
            &mut m,
            &[
                "technique=shadow_map",
                "lighting.only=0",
                &format!("shadow_map.size={size}"),
            ],
        );
        let tsm = near_receiver(
            &mut m,
            &[
                "technique=tsm",
                "lighting.only=0",
                &format!("shadow_map.size={size}"),
            ],
        );
        let (e_sm, e_tsm) = (error(&sm, 0), error(&tsm, 0));
        println!("size {size}: shadow map {}, tsm {}", pct(e_sm), pct(e_tsm));
        assert!(e_tsm * 1.2 < e_sm, "size {size}: tsm {}", pct(e_tsm));
        assert_eq!(tsm.light(0).receiver_mismatch, 0);
    }
}

/// The options of `sets` at the slope factor `warped`'s frame ran with where the GL took a
/// fallback for it (`offset_per_fragment`: a warped map's offset is raised where the GL adds
/// it per vertex, and a degenerate one falls back to a standard map at that offset).
fn standard_map_as_run(warped: &Measured, sets: &[&str]) -> Options {
    let mut o = options_with(sets);
    for f in &warped.frame.fallbacks {
        if f.option == "shadow_map.offset_factor" {
            o.set(&f.option, &f.used).unwrap_or_else(|e| panic!("{e}"));
        }
    }
    o
}

#[test]
fn degenerate_perspective_maps_fall_back_with_the_standard_maps_error() {
    // Duelling frusta: the camera faces a light that shines back at it.
    let (scene, _, _) = load_asset("assets/hard/duelling.toml");
    let mut m = Measurer::new(scene, &Options::default());
    let psm = m.measure(&options_with(&["technique=psm", "lighting.only=0"]));
    let sm = m.measure(&standard_map_as_run(
        &psm,
        &["technique=shadow_map", "lighting.only=0"],
    ));
    let warps = &psm.frame.plan_stats.warps;
    println!("{warps:?}");
    assert!(
        warps
            .iter()
            .any(|w| w.contains("fell back") && w.contains("duelling")),
        "{warps:?}"
    );
    // The fallback is the standard map itself: the same decisions, pixel for pixel.
    assert_eq!(psm.mask(0).values, sm.mask(0).values);
    assert_eq!(error(&psm, 0), error(&sm, 0));

    // A light behind the camera: with `psm.invert` off it falls back (the standard map's
    // error); inverted, its depth order is reversed and its shadows stay right.
    let (scene, _, _) = load_asset("assets/hard/near_receiver.toml");
    let mut m = Measurer::new(scene, &Options::default());
    let only = "lighting.only=1";
    let off = m.measure(&options_with(&["technique=psm", only, "psm.invert=false"]));
    let sm = m.measure(&standard_map_as_run(&off, &["technique=shadow_map", only]));
    let inverted = m.measure(&options_with(&["technique=psm", only]));
    let warps = &off.frame.plan_stats.warps;
    assert!(
        warps.iter().any(|w| w.contains("behind the camera")),
        "{warps:?}"
    );
    assert_eq!(off.mask(1).values, sm.mask(1).values);
    let warps = &inverted.frame.plan_stats.warps;
    assert!(
        warps.iter().any(|w| w.contains("depth reversed")),
        "{warps:?}"
    );
    let shadowed = inverted.light(1).reference_shadowed as f64
        / inverted.light(1).receiver_pixels.max(1) as f64;
    println!(
        "behind the camera: {} shadowed; standard {}, inverted psm {}",
        pct(shadowed),
        pct(error(&sm, 1)),
        pct(error(&inverted, 1))
    );
    // Measured 0.70% (standard 0.77%) with 3.6% of the receivers in shadow: a map drawn
    // without the reversal loses them (about 3.5% wrong).
    assert!(shadowed > 0.02, "the case must have shadows to lose");
    assert!(
        error(&inverted, 1) < 1.0e-2,
        "inverted psm {}",
        pct(error(&inverted, 1))
    );
}

/// The hybrid against plain shadow volumes on `scene`: its error within `tolerance` above
/// theirs (both ways when `both_ways`), with fewer than `max_share` of their fragments.
fn hybrid_against_volumes(
    (path, scene, base): (&str, shadowlab::scene::Scene, Options),
    both_ways: bool,
    max_share: f64,
) {
    let mut m = Measurer::new(scene, &base);
    let with = |t: &str| {
        let mut o = base.clone();
        o.set("technique", t).unwrap();
        o
    };
    let sv = m.measure(&with("shadow_volume"));
    let hybrid = m.measure(&with("hybrid"));
    let (e_sv, e_h) = (sv.total.rates().total, hybrid.total.rates().total);
    println!("{path}: shadow volumes {}, hybrid {}", pct(e_sv), pct(e_h));
    assert!(
        e_h <= e_sv + 0.0005,
        "{path}: hybrid {} against volumes {}",
        pct(e_h),
        pct(e_sv)
    );
    if both_ways {
        assert!((e_h - e_sv).abs() <= 0.0005);
    }
    assert!(!hybrid.frame.hybrid.is_empty());
    for h in &hybrid.frame.hybrid {
        let share = h.fragment_share().expect("desktop GL counts samples");
        println!(
            "  light {}: silhouette pixels {} of {} ({}); volume fragments {} of {} ({})",
            h.light,
            h.silhouette_pixels,
            h.receiver_pixels,
            pct(h.silhouette_share()),
            h.volume_fragments.unwrap_or(0),
            h.volume_fragments_unmasked.unwrap_or(0),
            pct(share)
        );
        assert!(h.receiver_pixels > 0 && h.volume_fragments_unmasked.unwrap_or(0) > 0);
        assert!(share < max_share, "light {}: {}", h.light, pct(share));
        assert!(h.silhouette_share() < 0.15);
    }
}

#[test]
fn the_hybrid_matches_shadow_volumes_with_a_fraction_of_their_fragments() {
    // Built-in scene: measured volumes 0.855%, hybrid 0.275% (the volumes' error there is
    // away from shadow edges, where the hybrid takes the map's answer), fragments 8.2% and
    // 3.7%. oa_dm1: 0.013% and 0.019%, fragments 2.0–7.4%. The bounds leave room for
    // rasteriser rounding: a quarter of the volumes' fragments at most.
    let builtin = shadowlab::scene::builtin::default_scene();
    hybrid_against_volumes(("built-in", builtin, Options::default()), false, 0.25);
    let (oa_dm1, _, options) = load_asset("assets/scenes/oa_dm1.toml");
    hybrid_against_volumes(("oa_dm1", oa_dm1, options), true, 0.25);
}
