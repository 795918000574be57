//! `EXT_depth_bounds_test` where the GL has it, its emulation (clip planes behind the depth
//! buffer, `plan.depth_clip`) where it does not: the same masks, and the frame says which ran.

mod common;

use common::{Measured, Measurer, options_with};
use shadowlab::images::MaskValue;
use shadowlab::scene::builtin;

const SV: &str = "technique=shadow_volume";

fn sum(m: &Measured, f: impl Fn(&shadowlab::plan::volume_draws::VolumeStats) -> usize) -> usize {
    m.frame.volumes.iter().map(f).sum()
}

/// Every shadowed pixel's stored depth (its surface's window depth) lies within the light's
/// planned range: the bound a depth bounds test is fed drops no count that is read. Returns
/// how many shadowed pixels were checked.
fn shadowed_pixels_lie_within_the_range(m: &Measured) -> usize {
    let g = m.frame.gbuffer.as_ref().expect("masks asked for");
    let mut checked = 0;
    for v in &m.frame.volumes {
        let range = v.depth_range.expect("receivers known: a range per light");
        let mask = m.mask(v.light);
        for (i, p) in g.position.iter().enumerate() {
            if mask.values[i] != MaskValue::Shadowed as u8 {
                continue;
            }
            let c = m.frame.view_proj * glam::Vec3::from_array(*p).extend(1.0);
            let depth = 0.5 * c.z / c.w + 0.5;
            assert!(
                depth >= range[0] && depth <= range[1],
                "light {}: pixel {i} at depth {depth} outside {range:?}",
                v.light
            );
            checked += 1;
        }
    }
    checked
}

#[test]
fn the_extension_where_present_and_its_emulation_give_the_same_masks() {
    let asked = options_with(&[SV]);
    let mut m = Measurer::new(builtin::default_scene(), &asked);
    let has = m.renderer().caps_for(&asked).unwrap().has("depth_bounds");
    let with = m.measure(&asked);
    let emulated = m.measure(&options_with(&[SV, "gl.disable=depth_bounds"]));

    // Hidden: the fallback is listed and the plan clips instead of bounding.
    let listed = |f: &Measured| {
        f.frame
            .fallbacks
            .iter()
            .filter(|f| f.feature == "depth_bounds")
            .map(|f| (f.option, f.asked.clone(), f.used.clone()))
            .collect::<Vec<_>>()
    };
    let fallback = vec![("plan.depth_bounds_test", "true".into(), "false".into())];
    assert_eq!(listed(&emulated), fallback);
    assert_eq!(sum(&emulated, |v| v.parts_depth_bounded), 0);
    assert!(sum(&emulated, |v| v.parts_depth_clipped) > 0);
    // The range the test is (or would be) given is sound on every GL.
    let checked = shadowed_pixels_lie_within_the_range(&emulated);
    assert!(checked > 1000, "{checked} shadowed pixels");

    if has {
        // The test ran in place of the clip planes, and changed no mask pixel.
        assert_eq!(listed(&with), vec![]);
        assert!(sum(&with, |v| v.parts_depth_bounded) > 0);
        assert_eq!(sum(&with, |v| v.parts_depth_clipped), 0);
        shadowed_pixels_lie_within_the_range(&with);
    } else {
        // Missing: the default frame takes the same fallback and says so.
        assert_eq!(listed(&with), fallback);
        assert_eq!(sum(&with, |v| v.parts_depth_bounded), 0);
        assert!(sum(&with, |v| v.parts_depth_clipped) > 0);
    }
    let lights: Vec<usize> = with.frame.masks.iter().map(|k| k.light).collect();
    assert_eq!(lights.len(), 2);
    for l in lights {
        let differ = with
            .mask(l)
            .values
            .iter()
            .zip(&emulated.mask(l).values)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(differ, 0, "light {l}: {differ} mask pixels differ");
    }
    println!(
        "EXT_depth_bounds_test {}: {} parts bounded, {} clipped under the emulation, {checked} shadowed pixels within range",
        if has { "used" } else { "absent (emulated)" },
        sum(&with, |v| v.parts_depth_bounded),
        sum(&emulated, |v| v.parts_depth_clipped),
    );
}
