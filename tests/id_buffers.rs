//! ID and priority buffers (`shadow_map.buffer`, Forsyth's slides) against the exact
//! reference: no bias needed where depth maps need it most, the edge filter's cure and its
//! shrink, and the priority buffer's sort. `cargo test --release --test id_buffers --
//! --nocapture` prints the figures.

mod common;

use common::{
    Measured, Measurer, differing, id_buffers_run_or_fall_back, load_asset, load_scene_file,
    options_with,
};
use shadowlab::truth::Counts;

const SM: &str = "technique=shadow_map";

fn pct(x: f64) -> String {
    format!("{:.3}%", 100.0 * x)
}

fn report(case: &str, what: &str, m: &Measured) -> Counts {
    let r = m.total.rates();
    println!(
        "{case} {what}: error {} (false shadow {}, false lit {}), {} outside the band",
        pct(r.total),
        pct(r.false_shadow),
        pct(r.false_lit),
        pct(r.total_excl_boundary)
    );
    m.total
}

#[test]
fn id_and_priority_buffers_need_no_bias_on_the_grazing_light() {
    let case = "grazing";
    let mut m = Measurer::new(
        load_asset("assets/hard/grazing.toml").0,
        &options_with(&[SM]),
    );
    if !id_buffers_run_or_fall_back(&mut m, case) {
        return;
    }
    let depth_bare = m.measure(&options_with(&[SM, "shadow_map.offset=false"]));
    let id = m.measure(&options_with(&[
        SM,
        "shadow_map.buffer=id",
        "shadow_map.offset=false",
    ]));
    let id_offset = m.measure(&options_with(&[SM, "shadow_map.buffer=id"]));
    let priority = m.measure(&options_with(&[
        SM,
        "shadow_map.buffer=priority",
        "shadow_map.offset=false",
    ]));
    let bare = report(case, "depth, no offset", &depth_bare).rates().total;
    let id_error = report(case, "id, no offset", &id).rates().total;
    let priority_error = report(case, "priority, no offset", &priority).rates().total;
    // The case is what makes bias necessary: depth without offset is mostly acne.
    assert!(bare > 0.40, "depth without offset: {}", pct(bare));
    // No bias: an ID compares equal to itself. What is left is where the post meets the floor
    // (a texel of the post's ID over floor fragments) and the edge band: under 0.1%, a
    // five-hundredth of the acne.
    assert!(id_error < 0.001, "id: {}", pct(id_error));
    assert!(priority_error < 0.001, "priority: {}", pct(priority_error));
    // The offset does not touch what an ID buffer stores.
    assert_eq!(differing(id.mask(0), id_offset.mask(0)), 0);
}

/// The edge filter (lit where any of the nine texels holds the fragment's ID) against plain
/// compares on oa_dm1, whose convex parts meet everywhere: false shadow away from edges (the
/// edge acne) falls, false lit (the shrink) rises, and the shrink is a texel's: doubling the
/// map's resolution shrinks it.
#[test]
fn the_edge_filter_cures_edge_acne_and_shrinks_shadows_by_about_a_texel() {
    let case = "oa_dm1";
    let (scene, _, _) = load_scene_file("oa_dm1");
    let mut m = Measurer::new(scene, &options_with(&[SM]));
    if !id_buffers_run_or_fall_back(&mut m, "edge filter") {
        return;
    }
    let mut shrink = Vec::new();
    for size in [512, 1024] {
        let sz = format!("shadow_map.size={size}");
        let plain = m.measure(&options_with(&[SM, "shadow_map.buffer=id", &sz]));
        let filtered = m.measure(&options_with(&[
            SM,
            "shadow_map.buffer=id",
            "shadow_map.id_edge_filter=true",
            &sz,
        ]));
        let p = report(case, &format!("id {size}"), &plain);
        let f = report(case, &format!("id {size}, edge filter"), &filtered);
        assert!(
            2 * f.false_shadow_excl_boundary <= p.false_shadow_excl_boundary,
            "{size}: the filter leaves {} of {} acne pixels",
            f.false_shadow_excl_boundary,
            p.false_shadow_excl_boundary
        );
        assert!(
            f.false_lit >= p.false_lit,
            "{size}: the filter cannot light less"
        );
        shrink.push(f.false_lit - p.false_lit);
    }
    println!(
        "shrink (extra false-lit pixels): 512: {}, 1024: {}",
        shrink[0], shrink[1]
    );
    // A texel-sized effect halves with the texel; allow for the edges' pixel rounding.
    assert!(
        4 * shrink[1] < 3 * shrink[0],
        "shrink {} at 1024 against {} at 512",
        shrink[1],
        shrink[0]
    );
}

/// IDs per triangle in 8 bits collide (Forsyth: per-triangle IDs need more than 8 bits): a
/// triangle 256 IDs away is taken for the fragment's own, and its shadow is lost.
#[test]
fn eight_bit_triangle_ids_collide() {
    let (scene, _, _) = load_scene_file("oa_dm1");
    let mut m = Measurer::new(scene, &options_with(&[SM]));
    if !id_buffers_run_or_fall_back(&mut m, "8-bit ids") {
        return;
    }
    let full = m.measure(&options_with(&[
        SM,
        "shadow_map.buffer=id",
        "shadow_map.id_unit=triangle",
    ]));
    let narrow = m.measure(&options_with(&[
        SM,
        "shadow_map.buffer=id",
        "shadow_map.id_unit=triangle",
        "shadow_map.id_bits=8",
    ]));
    let f = report("oa_dm1", "triangle ids, 32 bits", &full);
    let n = report("oa_dm1", "triangle ids, 8 bits", &narrow);
    assert!(n.false_lit > f.false_lit, "8 bits lose no shadow: {n:?}");
}

/// Priority buffers under minification (`shadow_map.priority_mipmap`): a 2048² map seen in a
/// 160×120 frame, so that a pixel covers many texels. The reference is what most of each
/// pixel's area sees (the exact masks at 1280×960, by majority over 8×8 blocks): one texel at
/// the pixel's centre says only what the centre sees. The chain must change nothing where the
/// map is magnified, and where shadows are finer than a pixel (hard case 14) it must err far
/// less than the unfiltered buffer; on the cases with shadow edges only, both are printed
/// (docs/id-buffers.md: there the chain errs a little more).
#[test]
fn mipmapped_priority_buffers_under_minification() {
    let priority = |size: &'static str, w: &'static str, h: &'static str, mipmap: bool| {
        let mut sets = vec![SM, "shadow_map.buffer=priority", size, w, h];
        sets.push(if mipmap {
            "shadow_map.priority_mipmap=true"
        } else {
            "shadow_map.priority_mipmap=false"
        });
        options_with(&sets)
    };
    // Magnified (a 256² map over 640×480): level 0 everywhere, the same decisions.
    let mut m = Measurer::new(
        load_asset("assets/hard/thin_casters.toml").0,
        &options_with(&[SM]),
    );
    if !id_buffers_run_or_fall_back(&mut m, "priority mips") {
        return;
    }
    let (size, w, h) = ("shadow_map.size=256", "width=640", "height=480");
    let flat = m.measure(&priority(size, w, h, false));
    let chain = m.measure(&priority(size, w, h, true));
    assert_eq!(differing(flat.mask(0), chain.mask(0)), 0);

    let mut changed = 0;
    for (case, file) in [
        ("thin_casters", "assets/hard/thin_casters.toml"),
        ("grazing", "assets/hard/grazing.toml"),
        ("builtin", ""),
        ("minified_grate", "assets/hard/minified_grate.toml"),
    ] {
        let scene = if file.is_empty() {
            shadowlab::scene::builtin::default_scene()
        } else {
            load_asset(file).0
        };
        let lights = scene.lights.len();
        let mut m = Measurer::new(scene, &options_with(&[SM]));
        // The exact masks at eight times the frame's size (the G-buffer comes with any frame):
        // fine enough that the 64 samples of a pixel spread over the minified grate's stripes
        // (at four times, whole rows of samples fell on one stripe's phase).
        m.measure(&options_with(&[SM, "width=1280", "height=960"]));
        let fine: Vec<shadowlab::images::Mask> =
            (0..lights).map(|l| m.exact(1280, 960, l).clone()).collect();
        let (size, w, h) = ("shadow_map.size=2048", "width=160", "height=120");
        let runs = [false, true].map(|mipmap| m.measure(&priority(size, w, h, mipmap)));
        let errors = runs.each_ref().map(|r| {
            let mut all = Counts::default();
            for (l, f) in fine.iter().enumerate() {
                all.add(&shadowlab::truth::compare_majority(r.mask(l), f, 8));
            }
            all.rates().total
        });
        println!(
            "{case}, priority 2048 at 160x120 against the majority: unfiltered {}, mipmapped {} \
             (against the pixel centres: {}, {})",
            pct(errors[0]),
            pct(errors[1]),
            pct(runs[0].total.rates().total),
            pct(runs[1].total.rates().total),
        );
        if case == "minified_grate" {
            // Forsyth's claim where it applies: a quarter of each pixel's area lies under a
            // stripe, so a map read at the pixel's centre lands on one about one pixel in four,
            // while a vote over the footprint calls nearly all of them lit (the reference's ties
            // are left out; what remains wrong is the cone's rim and the zone's edges).
            assert!(
                errors[0] > 0.15,
                "point sampling should alias: {}",
                pct(errors[0])
            );
            assert!(
                errors[1] < errors[0] / 10.0,
                "the chain should vote the stripes away: {} against {}",
                pct(errors[1]),
                pct(errors[0])
            );
        }
        changed += (0..lights)
            .map(|l| differing(runs[0].mask(l), runs[1].mask(l)))
            .sum::<usize>();
    }
    // The chain is read: some pixel decides otherwise (on the grazing case no level above 0
    // changes a decision: its shadow edges are long straight lines).
    assert!(changed > 0, "the mip chain changed no pixel");
}
