//! Accuracy against time on one scene: every technique with its main toggles on the paper's
//! frame, the same with the planner, a plot, and the configurations no other beats in both time
//! and error (the Pareto front).

use super::lab::{Lab, pct};
use super::{Figure, ReproduceError, Section};
use crate::options::Options;
use crate::report::bench::{BenchConfig, BenchRow};
use crate::report::plot;
use crate::report::table::{Align, Table, bench_table};
use crate::report::tune::{TuneSettings, tune_keeping};
use crate::scene::path::PathKey;

/// The configurations: the paper's choices first, then the toggles that matter most.
fn configs(quick: bool) -> Vec<(&'static str, Vec<&'static str>)> {
    const SM: &str = "technique=shadow_map";
    const SV: &str = "technique=shadow_volume";
    // The lab measures the paper's frame; these rows switch the planner back on.
    const PLANNER: &str = "plan.enabled=true";
    if quick {
        let mut quick = vec![
            ("shadows off", vec!["technique=none"]),
            ("SM 512 (paper)", vec![SM]),
            (
                "SM 256 pcf3x3",
                vec![
                    SM,
                    "shadow_map.size=256",
                    "shadow_map.filter=pcf3x3",
                    "shadow_map.result=intensity",
                ],
            ),
            ("SV z-fail (paper)", vec![SV]),
            ("SV z-pass", vec![SV, "shadow_volume.counting=zpass"]),
            ("SM 512 planner", vec![SM, PLANNER]),
            ("SV planner", vec![SV, PLANNER]),
        ];
        quick.extend(super::thesis::sweep_configs());
        return quick;
    }
    let mut full = vec![
        ("shadows off", vec!["technique=none"]),
        ("SM 512 (paper)", vec![SM]),
        ("SM 256", vec![SM, "shadow_map.size=256"]),
        ("SM 1024", vec![SM, "shadow_map.size=1024"]),
        ("SM 2048", vec![SM, "shadow_map.size=2048"]),
        (
            "SM 512 pcf3x3",
            vec![
                SM,
                "shadow_map.filter=pcf3x3",
                "shadow_map.result=intensity",
            ],
        ),
        ("SM 512 fbo", vec![SM, "shadow_map.depth_source=fbo"]),
        ("SM 512 back faces", vec![SM, "shadow_map.cull=back"]),
        ("SV z-fail (paper)", vec![SV]),
        ("SV z-pass", vec![SV, "shadow_volume.counting=zpass"]),
        ("SV auto", vec![SV, "shadow_volume.counting=auto"]),
        ("SV two-sided", vec![SV, "shadow_volume.stencil=separate"]),
        (
            "SV signed edges",
            vec![SV, "shadow_volume.edge_rule=signed"],
        ),
        ("SM 512 planner", vec![SM, PLANNER]),
        ("SV planner", vec![SV, PLANNER]),
        (
            "SV planner signed edges",
            vec![SV, PLANNER, "shadow_volume.edge_rule=signed"],
        ),
        ("auto planner", vec!["technique=auto", PLANNER]),
    ];
    // The thesis's other two algorithms and trapezoidal maps (its final comparison).
    full.extend(super::thesis::sweep_configs());
    full
}

/// The fixed sweep of this section over a scene's options `base`, as the lab measures it (the
/// paper's frame with each configuration's assignments): for comparing other searches with it.
pub fn fixed_sweep(base: &Options, quick: bool) -> Result<Vec<BenchConfig>, ReproduceError> {
    configs(quick)
        .into_iter()
        .map(|(name, sets)| {
            let mut o = base.clone();
            for s in super::PAPER_FRAME.iter().chain(&sets) {
                o.set_assignment(s)?;
            }
            o.validate()?;
            Ok(BenchConfig::named(name, o))
        })
        .collect()
}

/// For each row, whether no other row with shadows is at least as fast and as accurate and
/// strictly better in one of the two.
pub fn pareto_front(rows: &[BenchRow]) -> Vec<bool> {
    let shadows = |r: &BenchRow| r.technique != "none";
    rows.iter()
        .map(|a| {
            shadows(a)
                && !rows.iter().any(|b| {
                    shadows(b)
                        && b.frame_ms.median <= a.frame_ms.median
                        && b.error.total <= a.error.total
                        && (b.frame_ms.median < a.frame_ms.median || b.error.total < a.error.total)
                })
        })
        .collect()
}

pub fn run(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let name = lab.name.clone();
    let mut s = Section::new(
        &format!("sweep-{name}"),
        &format!("Accuracy against time: {name}"),
        "Not a figure of the paper: what each choice costs in time and buys in accuracy on this \
         scene, measured in this run.",
    );
    let configs = configs(lab.quick);
    let rows = lab.measure(&configs)?;
    let front = pareto_front(&rows);
    let file = format!("sweep-{name}.png");
    plot::error_vs_time_marked(
        &rows,
        &front,
        &format!(
            "{name}: error against frame time ({} lights, ringed: Pareto front)",
            lab.scene.lights.len()
        ),
        &lab.out_path(&file),
    )
    .map_err(ReproduceError::Plot)?;
    s.figures.push(Figure {
        file,
        caption: format!(
            "{name}: error against median frame time; ringed points are on the Pareto front"
        ),
    });
    let mut best = Table::new(&[
        ("Pareto-best configuration", Align::Left),
        ("frame ms", Align::Right),
        ("× shadows off", Align::Right),
        ("error", Align::Right),
        ("error excl. boundary", Align::Right),
    ]);
    let mut on_front: Vec<&BenchRow> = rows
        .iter()
        .zip(&front)
        .filter(|(_, f)| **f)
        .map(|(r, _)| r)
        .collect();
    on_front.sort_by(|a, b| a.frame_ms.median.total_cmp(&b.frame_ms.median));
    for r in &on_front {
        best.push(vec![
            r.label.clone(),
            format!("{:.1}", r.frame_ms.median),
            format!("{:.2}", r.ratio_to_shadows_off),
            pct(r.error.total),
            pct(r.error.total_excl_boundary),
        ]);
    }
    // The first finding names the most accurate configuration (the summary quotes it).
    if let Some(r) = rows
        .iter()
        .filter(|r| r.technique != "none")
        .min_by(|a, b| a.error.total.total_cmp(&b.error.total))
    {
        s.findings.push(format!(
            "{} ({} error, {:.1}x shadows off)",
            r.label,
            pct(r.error.total),
            r.ratio_to_shadows_off
        ));
    }
    for (label, key) in [("SM 512 (paper)", "sm"), ("SV z-fail (paper)", "sv")] {
        if let Some(r) = rows.iter().find(|r| r.label == label) {
            s.numbers
                .insert(format!("{key}_ratio"), r.ratio_to_shadows_off);
            s.numbers.insert(format!("{key}_error"), r.error.total);
        }
    }
    s.findings.push(format!(
        "On the Pareto front, fastest first: {}.",
        on_front
            .iter()
            .map(|r| r.label.clone())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    s.tables.push(best);
    s.tables.push(bench_table(&rows));
    for (_, sets) in &configs {
        s.regenerate.push(lab.render_command(sets));
    }
    Ok(s)
}

/// The frontier `tune` finds from the scene's own options (the library's defaults, not the
/// paper's frame): what each step of accuracy costs on this scene.
pub fn frontier(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let name = lab.name.clone();
    let mut s = Section::new(
        &format!("frontier-{name}"),
        &format!("The price of accuracy: {name}"),
        "Not a figure of the paper: `shadowlab tune`'s budgeted search (successive halving over \
         technique, map size, depth bits, filter, offsets, caster faces, omni views, counting, \
         stencil passes, edge rule, casters and the planner), its finalists measured in full \
         in this run; the frontier says what each step of error costs in time.",
    );
    let (candidates, finalists) = if lab.quick { (6, 3) } else { (32, 6) };
    let scene = lab.scene;
    let base = lab.base.clone();
    let mut settings = TuneSettings::new(candidates, vec![PathKey::of(&scene.camera)]);
    settings.finalists = finalists;
    settings.per_light = false;
    // The finalists as many frames as every other configuration of the report.
    settings.final_frames = lab.frames;
    // The frontier is time against error: no per-pass or pipelined frames (a paper's-frame
    // finalist's per-pass frame on oa_dm3 takes tens of seconds).
    settings.breakdown = false;
    settings.enough_seconds = lab.enough_seconds;
    if lab.quick {
        settings.rung_frames = vec![1];
    }
    lab.bar()
        .set_message(format!("{name}: tune, {candidates} configurations"));
    let hidden = indicatif::ProgressBar::hidden();
    let mut kept = lab.take_kept();
    let result = tune_keeping(lab.renderer(), scene, &base, &settings, &hidden, &mut kept);
    lab.put_kept(kept);
    let result = result?;
    let file = format!("frontier-{name}.png");
    plot::error_vs_time_marked(
        &result.rows,
        &result.frontier,
        &format!("{name}: tune finalists (ringed: frontier)"),
        &lab.out_path(&file),
    )
    .map_err(ReproduceError::Plot)?;
    s.figures.push(Figure {
        file,
        caption: format!("{name}: tune's finalists, error against median frame time"),
    });
    let mut t = Table::new(&[
        ("frontier configuration", Align::Left),
        ("frame ms", Align::Right),
        ("× shadows off", Align::Right),
        ("error", Align::Right),
    ]);
    for r in result.frontier_rows() {
        t.push(vec![
            r.label.clone(),
            format!("{:.1}", r.frame_ms.median),
            format!("{:.2}", r.ratio_to_shadows_off),
            pct(r.error.total),
        ]);
    }
    for target in [1.0, 0.1] {
        if let Some(r) = result.cheapest_meeting(target) {
            s.findings.push(format!(
                "The fastest found within {target}%: {} ({}, {:.2}x shadows off).",
                r.label,
                pct(r.error.total),
                r.ratio_to_shadows_off
            ));
        }
    }
    s.tables.push(t);
    s.regenerate.push(format!(
        "shadowlab tune --scene assets/scenes/{name}.toml --candidates {candidates} --finalists \
         {finalists} --final-frames {} --enough-seconds {} --no-per-light",
        settings.final_frames,
        settings.enough_seconds.unwrap_or(0.0)
    ));
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(technique: &str, ms: f64, error: f64) -> BenchRow {
        crate::report::bench::test_row(technique, &format!("{technique} {ms} {error}"), ms, error)
    }

    #[test]
    fn the_front_keeps_only_undominated_rows_with_shadows() {
        let rows = [
            row("none", 1.0, 0.5),
            row("shadow_map", 2.0, 0.1),
            row("shadow_map", 3.0, 0.2),
            row("shadow_volume", 4.0, 0.01),
            row("shadow_volume", 4.0, 0.01),
            row("shadow_volume", 5.0, 0.01),
        ];
        assert_eq!(pareto_front(&rows), [false, true, false, true, true, false]);
    }
}
