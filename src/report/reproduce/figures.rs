//! The paper's and the thesis' figures, measured on oa_dm1 from its first spawn point. Frames
//! are drawn without the map's lightmaps (`lighting.baked=false`) so that the dynamic lights'
//! shadows are what one sees; masks and errors do not depend on it.

use super::lab::{Lab, pct};
use super::{Figure, ReproduceError, Section};
use crate::report::bench::BenchRow;
use crate::report::images::boundary_window;
use crate::report::plot;
use crate::report::table::{Align, Table, clock_name};

/// How many sections [`run`] produces (for the progress bar).
pub const SECTIONS: usize = 7;

const SM: &str = "technique=shadow_map";
const SV: &str = "technique=shadow_volume";
const UNBAKED: &str = "lighting.baked=false";

/// Error columns shared by the figure tables.
fn error_table(rows: &[BenchRow]) -> Table {
    let mut t = Table::new(&[
        ("configuration", Align::Left),
        ("error", Align::Right),
        ("false shadow", Align::Right),
        ("false lit", Align::Right),
        ("error excl. boundary", Align::Right),
        ("receiver mismatches (px)", Align::Right),
        ("frame ms", Align::Right),
        ("× shadows off", Align::Right),
    ]);
    for r in rows {
        t.push(vec![
            r.label.clone(),
            pct(r.error.total),
            pct(r.error.false_shadow),
            pct(r.error.false_lit),
            pct(r.error.total_excl_boundary),
            r.error.receiver_mismatch.to_string(),
            format!("{:.1}", r.frame_ms.median),
            format!("{:.2}", r.ratio_to_shadows_off),
        ]);
    }
    if let Some(r) = rows.first() {
        t.note = Some(format!(
            "Error: share of receiver pixels (summed over lights) whose lit/shadowed answer differs \
             from the exact reference; boundary: within 1 px of a reference shadow edge. {}x{}, \
             {} measured frame(s), {} clock.",
            r.width,
            r.height,
            r.frames,
            clock_name(&r.clock)
        ));
    }
    t
}

/// Measures `configs`, captures each, saves frame and error images, and fills the section's
/// table; returns the rows.
fn measure_with_images(
    lab: &mut Lab,
    section: &mut Section,
    configs: &[(&str, Vec<&str>)],
    slug: &str,
) -> Result<Vec<BenchRow>, ReproduceError> {
    let rows = lab.measure(configs)?;
    for (i, (name, sets)) in configs.iter().enumerate() {
        let c = lab.capture(sets)?;
        let frame = lab.save(&Lab::frame_image(&c), &format!("{slug}-{i}.png"))?;
        let errors = lab.save(&Lab::error_image(&c), &format!("{slug}-{i}-error.png"))?;
        section.figures.push(Figure {
            file: frame,
            caption: format!("{name}: frame"),
        });
        section.figures.push(Figure {
            file: errors,
            caption: format!(
                "{name}: errors (red false shadow, blue false lit, yellow receiver mismatch, grey \
                 correct), {}",
                pct(rows[i].error.total)
            ),
        });
        section.regenerate.push(lab.render_command(sets));
    }
    section.tables.push(error_table(&rows));
    Ok(rows)
}

pub fn run(lab: &mut Lab) -> Result<Vec<Section>, ReproduceError> {
    let figures: [super::SectionFn; SECTIONS] = [
        fig1_clip_planes,
        fig2_map_size,
        fig10_bias,
        fig12_pcf,
        fig13_14_stages,
        fig20_21_zpass_zfail,
        fig22_two_sided,
    ];
    figures.into_iter().map(|f| super::timed(lab, f)).collect()
}

fn done(lab: &Lab, s: Section) -> Section {
    lab.bar().inc(1);
    s
}

fn fig1_clip_planes(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "paper-fig1",
        "Paper Fig. 1: clip-plane anomalies and the missing glPolygonOffset",
        "The paper first limits each light's lit pass with the light frustum's planes as GL clip \
         planes. Clipped triangles rasterize to slightly different depths than in the unlit pass, \
         so the lit pass's depth test drops pixels along the clip lines (left image of Fig. 1). \
         Without glPolygonOffset, surfaces shadow themselves (right image). The paper's fix is \
         an offset during the lit pass.",
    );
    let configs: Vec<(&str, Vec<&str>)> = vec![
        (
            "clip planes, offset in the map only",
            vec![SM, UNBAKED, "shadow_map.outside=clip_planes"],
        ),
        (
            "clip planes, offset in the lit pass too (paper's fix)",
            vec![
                SM,
                UNBAKED,
                "shadow_map.outside=clip_planes",
                "shadow_map.offset_pass=both",
            ],
        ),
        (
            "no glPolygonOffset",
            vec![SM, UNBAKED, "shadow_map.offset=false"],
        ),
        ("defaults (clamp, offset in the map)", vec![SM, UNBAKED]),
    ];
    let rows = measure_with_images(lab, &mut s, &configs, "fig1")?;
    s.numbers.insert(
        "mismatch_clip".into(),
        rows[0].error.receiver_mismatch as f64,
    );
    s.numbers.insert(
        "mismatch_clip_fixed".into(),
        rows[1].error.receiver_mismatch as f64,
    );
    s.numbers
        .insert("false_shadow_no_offset".into(), rows[2].error.false_shadow);
    s.numbers
        .insert("false_shadow_default".into(), rows[3].error.false_shadow);
    s.findings.push(format!(
        "With clip planes, {} receiver pixels are lost by the lit pass ({} with the paper's \
         lit-pass offset).",
        rows[0].error.receiver_mismatch, rows[1].error.receiver_mismatch
    ));
    s.findings.push(format!(
        "Without any offset, {} of receiver pixels are falsely shadowed (self-shadowing acne), \
         against {} with the thesis' glPolygonOffset(1.1, 4) on the map.",
        pct(rows[2].error.false_shadow),
        pct(rows[3].error.false_shadow)
    ));
    Ok(done(lab, s))
}

/// Zoomed crops of several captures around the same shadow boundary.
fn crops(
    lab: &mut Lab,
    s: &mut Section,
    configs: &[(String, Vec<&str>)],
    slug: &str,
    window: (u32, u32),
    zoom: u32,
) -> Result<(), ReproduceError> {
    let captures = configs
        .iter()
        .map(|(_, sets)| lab.capture(sets))
        .collect::<Result<Vec<_>, _>>()?;
    let Some(last) = captures.last() else {
        return Ok(());
    };
    let exact: Vec<&crate::images::Mask> = last.exact.iter().collect();
    let (x, y) = boundary_window(&exact, window.0, window.1).unwrap_or((0, 0));
    for (i, ((name, _), c)) in configs.iter().zip(&captures).enumerate() {
        let img = Lab::frame_image(c).crop_zoom(x, y, window.0, window.1, zoom);
        let file = lab.save(&img, &format!("{slug}-crop{i}.png"))?;
        s.figures.push(Figure {
            file,
            caption: format!(
                "{name}: pixels {x}..{} x {y}..{}, {zoom}x",
                x + window.0,
                y + window.1
            ),
        });
    }
    Ok(())
}

fn crop_window(lab: &Lab) -> (u32, u32) {
    (lab.base.width / 6, lab.base.height / 6)
}

fn fig2_map_size(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "paper-fig2",
        "Paper Fig. 2: shadow-map resolution",
        "The paper shows one view with 64x64, 128x128, 256x256 and 512x512 shadow maps and \
         settles on 512x512 as sharp enough at acceptable speed.",
    );
    let mut sizes = vec![64, 128, 256, 512];
    if !lab.quick {
        sizes.extend([1024, 2048]);
    }
    let labels: Vec<String> = sizes.iter().map(|n| format!("{n}x{n}")).collect();
    let sets: Vec<String> = sizes
        .iter()
        .map(|n| format!("shadow_map.size={n}"))
        .collect();
    let configs: Vec<(&str, Vec<&str>)> = labels
        .iter()
        .zip(&sets)
        .map(|(l, a)| (l.as_str(), vec![SM, UNBAKED, a.as_str()]))
        .collect();
    let rows = lab.measure(&configs)?;
    for (n, r) in sizes.iter().zip(&rows) {
        s.numbers.insert(format!("error_{n}"), r.error.total);
        s.numbers
            .insert(format!("ratio_{n}"), r.ratio_to_shadows_off);
    }
    let paper: Vec<(String, Vec<&str>)> = configs[..4]
        .iter()
        .map(|(l, a)| (l.to_string(), a.clone()))
        .collect();
    let window = crop_window(lab);
    crops(lab, &mut s, &paper, "fig2", window, 4)?;
    let c = lab.capture(&[SM, UNBAKED])?;
    let file = lab.save(&Lab::frame_image(&c), "fig2-512.png")?;
    s.figures.push(Figure {
        file,
        caption: "512x512, the whole frame".into(),
    });
    s.tables.push(error_table(&rows));
    s.findings.push(format!(
        "Error falls with resolution: {}.",
        sizes
            .iter()
            .zip(&rows)
            .map(|(n, r)| format!("{n}: {}", pct(r.error.total)))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    s.findings.push(format!(
        "Frame time against shadows off: {:.2}x at 64x64, {:.2}x at 512x512{}.",
        rows[0].ratio_to_shadows_off,
        rows[3].ratio_to_shadows_off,
        rows.last()
            .filter(|_| rows.len() > 4)
            .map(|r| format!(", {:.2}x at 2048x2048", r.ratio_to_shadows_off))
            .unwrap_or_default()
    ));
    s.regenerate.push(lab.bench_command(
        &[SM, UNBAKED],
        &format!(
            "shadow_map.size={}",
            sizes.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(",")
        ),
    ));
    Ok(done(lab, s))
}

fn fig10_bias(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "thesis-fig10",
        "Thesis Fig. 10: no bias, too much bias, the right bias",
        "Without an offset the map's surfaces shadow themselves (a); too large an offset moves \
         shadows away from their casters, which seem to float (b); glPolygonOffset(1.1, 4), \
         after Kilgard, is right for the thesis' scenes (c).",
    );
    let configs: Vec<(&str, Vec<&str>)> = vec![
        (
            "(a) no offset",
            vec![SM, UNBAKED, "shadow_map.offset=false"],
        ),
        (
            "(b) too much: factor 1.1, units 30000",
            vec![SM, UNBAKED, "shadow_map.offset_units=30000"],
        ),
        ("(c) factor 1.1, units 4 (thesis)", vec![SM, UNBAKED]),
    ];
    let rows = measure_with_images(lab, &mut s, &configs, "fig10")?;
    s.numbers
        .insert("false_shadow_none".into(), rows[0].error.false_shadow);
    s.numbers
        .insert("false_lit_too_much".into(), rows[1].error.false_lit);
    s.numbers.insert("error_right".into(), rows[2].error.total);
    s.findings.push(format!(
        "No offset: {} falsely shadowed. Too much: {} falsely lit (detached shadows). The \
         thesis' values: {} in all.",
        pct(rows[0].error.false_shadow),
        pct(rows[1].error.false_lit),
        pct(rows[2].error.total)
    ));
    Ok(done(lab, s))
}

fn fig12_pcf(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "thesis-fig12",
        "Thesis Fig. 12: percentage-closer filtering",
        "Switching the depth texture's filter from NEAREST to LINEAR makes the hardware average \
         four depth comparisons (2x2 PCF); the edges stay jagged but look smoother, and the \
         thesis finds it free. The paper leaves PCF as future work.",
    );
    let configs: Vec<(&str, Vec<&str>)> = vec![
        (
            "nearest, alpha test (paper)",
            vec![SM, UNBAKED, "shadow_map.size=256"],
        ),
        (
            "hardware 2x2 (LINEAR)",
            vec![
                SM,
                UNBAKED,
                "shadow_map.size=256",
                "shadow_map.filter=hw2x2",
                "shadow_map.result=intensity",
            ],
        ),
        (
            "3x3 PCF in the shader",
            vec![
                SM,
                UNBAKED,
                "shadow_map.size=256",
                "shadow_map.filter=pcf3x3",
                "shadow_map.result=intensity",
            ],
        ),
        (
            "5x5 PCF in the shader",
            vec![
                SM,
                UNBAKED,
                "shadow_map.size=256",
                "shadow_map.filter=pcf",
                "shadow_map.pcf_size=5",
                "shadow_map.result=intensity",
            ],
        ),
    ];
    let rows = lab.measure(&configs)?;
    let named: Vec<(String, Vec<&str>)> = configs
        .iter()
        .map(|(l, a)| (l.to_string(), a.clone()))
        .collect();
    let window = crop_window(lab);
    crops(lab, &mut s, &named, "fig12", window, 4)?;
    for (i, (name, sets)) in configs.iter().enumerate() {
        s.regenerate.push(lab.render_command(sets));
        s.numbers.insert(format!("error_{i}"), rows[i].error.total);
        let _ = name;
    }
    s.tables.push(error_table(&rows));
    s.findings.push(format!(
        "At 256x256, against nearest sampling ({:.2} ms): hardware 2x2 costs {:.2} ms, 3x3 PCF \
         {:.2} ms, 5x5 PCF {:.2} ms a frame. Filtered results are thresholded at one half for \
         the masks, so the error counts where the soft edge's middle lies.",
        rows[0].frame_ms.median,
        rows[1].frame_ms.median,
        rows[2].frame_ms.median,
        rows[3].frame_ms.median
    ));
    Ok(done(lab, s))
}

/// Median ms of a pass total, 0 when it did not run.
fn pass(r: &BenchRow, name: &str) -> f64 {
    r.pass_ms.get(name).copied().unwrap_or(0.0)
}

fn fig13_14_stages(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "thesis-fig13-14",
        "Thesis Fig. 13-14: where a shadow-mapped frame's time goes",
        "With 1024x1024 maps, drawing the scene from the light and copying the depth buffer into \
         the texture take about 45% of the frame (Fig. 13); rendering straight into the texture \
         (a PBuffer, RenderTexture) brings creating the map down to about 35% (Fig. 14).",
    );
    let configs: Vec<(&str, Vec<&str>)> = vec![
        (
            "copy to texture (Fig. 13)",
            vec![
                SM,
                UNBAKED,
                "shadow_map.size=1024",
                "shadow_map.depth_source=copy",
            ],
        ),
        (
            "render to texture (Fig. 14; FBO)",
            vec![
                SM,
                UNBAKED,
                "shadow_map.size=1024",
                "shadow_map.depth_source=fbo",
            ],
        ),
    ];
    let rows = lab.measure(&configs)?;
    let mut t = Table::new(&[
        ("configuration", Align::Left),
        ("draw from the light ms", Align::Right),
        ("copy ms", Align::Right),
        ("final passes ms", Align::Right),
        ("frame ms", Align::Right),
        ("creating the map, share", Align::Right),
    ]);
    let mut bars = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let draw = pass(r, "lights.shadow_map");
        let copy = pass(r, "lights.depth_copy");
        let frame = r.frame_ms.median.max(1e-9);
        let rest = (frame - draw - copy).max(0.0);
        let share = (draw + copy) / frame;
        s.numbers.insert(format!("map_share_{i}"), share);
        // The two ways of filling the map store the same depths: the same error.
        s.numbers.insert(format!("error_{i}"), r.error.total);
        t.push(vec![
            r.label.clone(),
            format!("{draw:.2}"),
            format!("{copy:.2}"),
            format!("{rest:.2}"),
            format!("{frame:.2}"),
            pct(share),
        ]);
        bars.push((
            if i == 0 { "copy" } else { "render to texture" }.to_string(),
            vec![
                ("draw scene for the map".to_string(), 100.0 * draw / frame),
                ("copy to the map".to_string(), 100.0 * copy / frame),
                (
                    "final passes (rest of the frame)".to_string(),
                    100.0 * rest / frame,
                ),
            ],
        ));
    }
    t.note = rows
        .first()
        .map(|r| format!("Stage times: medians, {} clock.", clock_name(&r.clock)));
    plot::stacked_bars(
        &bars,
        "Share of the frame per stage, 1024x1024 maps (oa_dm1)",
        "% of frame time",
        &lab.out_path("fig13-14.png"),
    )
    .map_err(ReproduceError::Plot)?;
    s.figures.push(Figure {
        file: "fig13-14.png".into(),
        caption: "Stage shares of the frame: copying (left) and rendering to the texture (right)"
            .into(),
    });
    s.tables.push(t);
    s.findings.push(format!(
        "Creating the maps takes {} of the frame when copying and {} when rendering to the \
         texture (thesis: about 45% and 35%).",
        pct(s.number("map_share_0")),
        pct(s.number("map_share_1"))
    ));
    s.regenerate.push(lab.bench_command(
        &[SM, UNBAKED, "shadow_map.size=1024"],
        "shadow_map.depth_source=copy,fbo",
    ));
    Ok(done(lab, s))
}

fn fig20_21_zpass_zfail(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "thesis-fig20-21",
        "Thesis Fig. 20-21: z-pass against z-fail with the camera inside a shadow volume",
        "Counting volume faces in front of the surface (z-pass) is wrong when the camera itself \
         is inside a volume: the count starts off by one (Fig. 20a, 21a). Counting those behind \
         it (z-fail, Carmack's reverse) does not depend on where the camera is (Fig. 20b, 21b), \
         at the price of capping the volumes.",
    );
    let configs: Vec<(&str, Vec<&str>)> = vec![
        ("z-pass", vec![SV, UNBAKED, "shadow_volume.counting=zpass"]),
        (
            "z-fail (paper)",
            vec![SV, UNBAKED, "shadow_volume.counting=zfail"],
        ),
    ];
    let rows = measure_with_images(lab, &mut s, &configs, "fig20")?;
    s.numbers.insert("error_zpass".into(), rows[0].error.total);
    s.numbers.insert("error_zfail".into(), rows[1].error.total);
    s.findings.push(format!(
        "From oa_dm1's first spawn point the camera sits inside volumes: z-pass gets {} of \
         receiver pixels wrong ({} falsely lit, {} falsely shadowed), z-fail {}.",
        pct(rows[0].error.total),
        pct(rows[0].error.false_lit),
        pct(rows[0].error.false_shadow),
        pct(rows[1].error.total)
    ));
    Ok(done(lab, s))
}

fn fig22_two_sided(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "thesis-fig22",
        "Thesis Fig. 22: one-sided against two-sided stencil",
        "EXT_stencil_two_side draws the volumes once with different stencil operations for front \
         and back faces instead of twice; the thesis reports a noticeable speed-up (its chart's \
         labels read TwoSide 24 fps, OneSide 28 fps).",
    );
    let configs: Vec<(&str, Vec<&str>)> = vec![
        (
            "one-sided: two passes (paper)",
            vec![SV, UNBAKED, "shadow_volume.stencil=two_pass"],
        ),
        (
            "two-sided: one pass, separate front/back operations",
            vec![SV, UNBAKED, "shadow_volume.stencil=separate"],
        ),
    ];
    let rows = lab.measure(&configs)?;
    let mut t = Table::new(&[
        ("configuration", Align::Left),
        ("volumes (stencil) ms", Align::Right),
        ("final shading ms", Align::Right),
        ("frame ms", Align::Right),
        ("fps", Align::Right),
        ("error", Align::Right),
    ]);
    let mut bars = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let volumes = pass(r, "lights.stencil") + pass(r, "lights.volume_build");
        let frame = r.frame_ms.median.max(1e-9);
        let shading = (frame - volumes).max(0.0);
        s.numbers.insert(format!("frame_ms_{i}"), frame);
        s.numbers.insert(format!("volumes_ms_{i}"), volumes);
        // One pass or two count the same volumes: the same error.
        s.numbers.insert(format!("error_{i}"), r.error.total);
        t.push(vec![
            r.label.clone(),
            format!("{volumes:.2}"),
            format!("{shading:.2}"),
            format!("{frame:.2}"),
            format!("{:.1}", 1000.0 / frame),
            pct(r.error.total),
        ]);
        bars.push((
            if i == 0 { "one-sided" } else { "two-sided" }.to_string(),
            vec![
                ("render shadow volumes".to_string(), volumes),
                ("final shading".to_string(), shading),
            ],
        ));
    }
    t.note = rows.first().map(|r| {
        format!(
            "Volumes: building and drawing them into the stencil buffer; medians, {} clock.",
            clock_name(&r.clock)
        )
    });
    plot::stacked_bars(
        &bars,
        "Frame time, one-sided and two-sided stencil (oa_dm1)",
        "ms per frame",
        &lab.out_path("fig22.png"),
    )
    .map_err(ReproduceError::Plot)?;
    s.figures.push(Figure {
        file: "fig22.png".into(),
        caption: "Volume and shading time per frame".into(),
    });
    s.tables.push(t);
    s.findings.push(format!(
        "Two-sided stencil takes the volume passes from {:.2} ms to {:.2} ms ({:.2}x); the \
         frame from {:.2} ms to {:.2} ms.",
        s.number("volumes_ms_0"),
        s.number("volumes_ms_1"),
        s.number("volumes_ms_0") / s.number("volumes_ms_1").max(1e-9),
        s.number("frame_ms_0"),
        s.number("frame_ms_1")
    ));
    s.regenerate
        .push(lab.bench_command(&[SV, UNBAKED], "shadow_volume.stencil=two_pass,separate"));
    Ok(done(lab, s))
}
