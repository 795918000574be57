//! The thesis's own comparison (Sindholt, chapters 4, 5 and 7): perspective shadow maps beside
//! the standard map where the camera looks along a receiver, Chan & Durand's hybrid beside
//! shadow volumes, and error against time for all four (and trapezoidal maps) on every
//! benchmark scene.

use super::lab::{Lab, pct};
use super::{Figure, ReproduceError, Section};
use crate::frame::StepKind;
use crate::gl::FrameRequest;
use crate::report::bench::BenchRow;
use crate::report::plot;
use crate::report::table::{Align, Table};

/// The four algorithms (and trapezoidal maps) as the scene sweeps measure them: the label of
/// each one's row there and its technique.
pub const FOUR: [(&str, &str); 5] = [
    ("SM 512 (paper)", "shadow_map"),
    ("PSM 512", "psm"),
    ("TSM 512", "tsm"),
    ("SV z-fail (paper)", "shadow_volume"),
    ("hybrid", "hybrid"),
];

/// The sweep rows of the four algorithms, for the scene sweeps' configuration lists.
pub fn sweep_configs() -> Vec<(&'static str, Vec<&'static str>)> {
    vec![
        ("PSM 512", vec!["technique=psm"]),
        ("TSM 512", vec!["technique=tsm"]),
        ("hybrid", vec!["technique=hybrid"]),
    ]
}

/// The final comparison on one scene, from its sweep's rows (`rows`, measured in this run).
pub fn comparison(lab: &Lab, rows: &[BenchRow]) -> Result<Section, ReproduceError> {
    let name = &lab.name;
    let mut s = Section::new(
        &format!("thesis-four-{name}"),
        &format!("The thesis's four algorithms: {name}"),
        "Thesis chapter 7 compares shadow maps, shadow volumes, perspective shadow maps and \
         Chan's hybrid on its test scenes and concludes that the choice depends on the scene. \
         Here: the four (and trapezoidal maps, after Forsyth) on this OpenArena scene, on the \
         paper's frame, maps 512x512.",
    );
    let picked: Vec<(&str, &BenchRow)> = FOUR
        .iter()
        .filter_map(|(label, t)| rows.iter().find(|r| r.label == *label).map(|r| (*t, r)))
        .collect();
    let mut t = Table::new(&[
        ("technique", Align::Left),
        ("frame ms", Align::Right),
        ("× shadows off", Align::Right),
        ("error", Align::Right),
        ("error excl. boundary", Align::Right),
    ]);
    for (technique, r) in &picked {
        t.push(vec![
            technique.to_string(),
            format!("{:.1}", r.frame_ms.median),
            format!("{:.2}", r.ratio_to_shadows_off),
            pct(r.error.total),
            pct(r.error.total_excl_boundary),
        ]);
        s.numbers
            .insert(format!("{technique}_error"), r.error.total);
        s.numbers
            .insert(format!("{technique}_ratio"), r.ratio_to_shadows_off);
    }
    if let Some((t, r)) = picked
        .iter()
        .min_by(|a, b| a.1.error.total.total_cmp(&b.1.error.total))
    {
        s.findings.push(format!(
            "Most accurate: {t} ({} error at {:.2}x shadows off).",
            pct(r.error.total),
            r.ratio_to_shadows_off
        ));
    }
    if let Some((t, r)) = picked
        .iter()
        .min_by(|a, b| a.1.frame_ms.median.total_cmp(&b.1.frame_ms.median))
    {
        s.findings.push(format!(
            "Fastest: {t} ({:.2}x shadows off, {} error).",
            r.ratio_to_shadows_off,
            pct(r.error.total)
        ));
    }
    let plotted: Vec<BenchRow> = picked.iter().map(|(_, r)| (*r).clone()).collect();
    let file = format!("thesis-four-{name}.png");
    plot::error_vs_time_marked(
        &plotted,
        &vec![false; plotted.len()],
        &format!("{name}: the four algorithms, error against frame time"),
        &lab.out_path(&file),
    )
    .map_err(ReproduceError::Plot)?;
    s.figures.push(Figure {
        file,
        caption: format!("{name}: error against median frame time, one point per algorithm"),
    });
    s.tables.push(t);
    s.regenerate
        .push(lab.bench_command(&[], "technique=shadow_map,psm,tsm,shadow_volume,hybrid"));
    Ok(s)
}

/// Thesis chapter 4 on the near-receiver hard case: the standard map, PSM and TSM at three
/// sizes, and the frames at 512.
pub fn chapter4(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "thesis-ch4",
        "Perspective shadow maps (thesis chapter 4)",
        "The thesis (after Stamminger & Drettakis): drawing the map in the camera's \
         post-perspective space gives objects near the camera more texels, so shadows near the \
         viewer are sharper than with a standard map of the same size (its Fig. 'Comparing \
         Perspective Shadow Maps to ordinary Shadow Maps'). Forsyth: special cases (light \
         behind, duelling frusta) and shimmering. Here: the hard case `near_receiver` (camera a \
         few units above a large floor, looking along it; a spot high above), only its first \
         light.",
    );
    let sizes: &[&str] = if lab.quick {
        &["256"]
    } else {
        &["256", "512", "1024"]
    };
    let mut t = Table::new(&[
        ("map size", Align::Right),
        ("shadow map error", Align::Right),
        ("psm error", Align::Right),
        ("tsm error", Align::Right),
        ("psm gain", Align::Right),
    ]);
    for size in sizes {
        let set = format!("shadow_map.size={size}");
        let mut errors = Vec::new();
        for technique in ["shadow_map", "psm", "tsm"] {
            let sets = [
                format!("technique={technique}"),
                set.clone(),
                "lighting.only=0".into(),
            ];
            let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
            let c = lab.capture(&sets)?;
            let e = c.total.rates().total;
            errors.push(e);
            s.numbers.insert(format!("{technique}_{size}"), e);
            if *size == "512" || lab.quick {
                let file = lab.save(&Lab::frame_image(&c), &format!("ch4-{technique}.png"))?;
                let errors_file =
                    lab.save(&Lab::error_image(&c), &format!("ch4-{technique}-error.png"))?;
                s.figures.push(Figure {
                    file,
                    caption: format!("{technique} {size}x{size}: frame"),
                });
                s.figures.push(Figure {
                    file: errors_file,
                    caption: format!("{technique} {size}x{size}: errors, {}", pct(e)),
                });
                s.regenerate.push(lab.render_command(&sets));
            }
        }
        t.push(vec![
            format!("{size}²"),
            pct(errors[0]),
            pct(errors[1]),
            pct(errors[2]),
            format!("{:.1}x", errors[0] / errors[1].max(1e-9)),
        ]);
    }
    s.findings.push(format!(
        "At {0}x{0} the standard map gets {1} of the receivers wrong, PSM {2}, TSM {3}.",
        sizes[sizes.len().min(2) - 1],
        pct(s.number(&format!("shadow_map_{}", sizes[sizes.len().min(2) - 1]))),
        pct(s.number(&format!("psm_{}", sizes[sizes.len().min(2) - 1]))),
        pct(s.number(&format!("tsm_{}", sizes[sizes.len().min(2) - 1]))),
    ));
    s.tables.push(t);
    Ok(s)
}

/// Thesis chapter 5 on the scene of `lab`: the hybrid's silhouette pixels, what its mask saves
/// and its error beside shadow volumes, with the computation mask as an image.
pub fn chapter5(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "thesis-ch5",
        "Chan's hybrid (thesis chapter 5)",
        "The thesis (after Chan & Durand 2004): a shadow map classifies the pixels; only near \
         shadow edges (silhouette pixels, where the 2x2 compares disagree) are shadow volumes \
         rasterised, through a computation mask, so the result is as exact as shadow volumes \
         at a fraction of their fill rate. Here: the mask is the stencil's top bit (the depth \
         bounds test Chan & Durand used is absent on llvmpipe), the fragments counted with \
         GL_SAMPLES_PASSED.",
    );
    let sv = lab.capture(&["technique=shadow_volume"])?;
    let hybrid = lab.capture(&["technique=hybrid"])?;
    let mut t = Table::new(&[
        ("light", Align::Right),
        ("receiver pixels", Align::Right),
        ("silhouette pixels", Align::Right),
        ("volume fragments, masked", Align::Right),
        ("volume fragments, plain", Align::Right),
        ("share", Align::Right),
    ]);
    let (mut masked, mut plain) = (0u64, 0u64);
    for h in &hybrid.frame.hybrid {
        masked += h.volume_fragments.unwrap_or(0);
        plain += h.volume_fragments_unmasked.unwrap_or(0);
        t.push(vec![
            h.light.to_string(),
            h.receiver_pixels.to_string(),
            format!("{} ({})", h.silhouette_pixels, pct(h.silhouette_share())),
            h.volume_fragments.map_or("-".into(), |n| n.to_string()),
            h.volume_fragments_unmasked
                .map_or("-".into(), |n| n.to_string()),
            h.fragment_share().map_or("-".into(), pct),
        ]);
    }
    let share = masked as f64 / plain.max(1) as f64;
    s.numbers.insert("fragment_share".into(), share);
    s.numbers.insert("sv_error".into(), sv.total.rates().total);
    s.numbers
        .insert("hybrid_error".into(), hybrid.total.rates().total);
    s.findings.push(format!(
        "Shadow volumes get {} of the receivers wrong, the hybrid {}, rasterising {} of the \
         volumes' fragments ({masked} of {plain}).",
        pct(sv.total.rates().total),
        pct(hybrid.total.rates().total),
        pct(share)
    ));
    s.tables.push(t);
    // The walkthrough's computation-mask step of the first hybrid light, as an image.
    let options = lab.options(&["technique=hybrid"])?;
    let scene = lab.scene;
    let steps = lab
        .renderer()
        .render_with(scene, &options, FrameRequest::default())?;
    if let Some(i) = steps
        .steps
        .iter()
        .position(|st| st.kind == StepKind::ComputationMask)
    {
        let request = FrameRequest {
            stop_after: Some(i),
            ..FrameRequest::default()
        };
        let f = lab.renderer().render_with(scene, &options, request)?;
        if let Some(image) = &f.step_image {
            let file = lab.save(image, "ch5-mask.png")?;
            s.figures.push(Figure {
                file,
                caption: "The computation mask of the first light: bright where the map decides \
                          (the stencil's top bit), dark at silhouette pixels, where the volumes \
                          were counted"
                    .into(),
            });
        }
    }
    for (technique, c) in [("shadow_volume", &sv), ("hybrid", &hybrid)] {
        let file = lab.save(&Lab::error_image(c), &format!("ch5-{technique}-error.png"))?;
        s.figures.push(Figure {
            file,
            caption: format!("{technique}: errors, {}", pct(c.total.rates().total)),
        });
        s.regenerate
            .push(lab.render_command(&[&format!("technique={technique}")]));
    }
    Ok(s)
}
