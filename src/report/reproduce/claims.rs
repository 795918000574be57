//! The paper's speed claims, as ratios to shadows off. The paper gives frame rates on a 2004
//! machine (Radeon 9800 Pro, 640x480): 120-250 fps typical, about 30 fps and sometimes over 100
//! with shadow maps and 2-10 lights, 30-40 fps with shadow volumes and 3-4 visible lights.
//! Absolute rates do not carry over; ratios to the same scene without shadows do, roughly.

use super::lab::{Lab, pct};
use super::{ReproduceError, Section};
use crate::images::MaskValue;
use crate::report::table::{Align, Table, clock_name};

/// Sections [`run`] produces per scene (for the progress bar).
pub const SECTIONS: usize = 2;

/// The scene's lights ordered by how many pixels of the view they reach (the exact masks),
/// the most first: the lights that matter for a claim about "lights in view".
fn lights_by_reach(lab: &mut Lab) -> Result<Vec<usize>, ReproduceError> {
    let c = lab.capture(&["technique=none"])?;
    let mut reach: Vec<(usize, usize)> = c
        .exact
        .iter()
        .map(|m| {
            let receivers = m.values.len() - m.count(MaskValue::NotReceiver);
            (m.light, receivers)
        })
        .collect();
    reach.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    Ok(reach.into_iter().map(|(l, _)| l).collect())
}

/// Measures `technique` with the first n lights of `order`, for each n.
fn claim(
    lab: &mut Lab,
    id: &str,
    title: &str,
    source: &str,
    technique: &str,
    counts: &[usize],
    order: &[usize],
) -> Result<Section, ReproduceError> {
    let mut s = Section::new(id, title, source);
    let counts: Vec<usize> = counts
        .iter()
        .copied()
        .filter(|&n| n <= order.len())
        .collect();
    let labels: Vec<String> = counts
        .iter()
        .map(|n| format!("{}, {n} lights", lab.name))
        .collect();
    let only: Vec<String> = counts
        .iter()
        .map(|&n| {
            let mut l: Vec<usize> = order[..n].to_vec();
            l.sort_unstable();
            format!(
                "lighting.only={}",
                l.iter()
                    .map(|i| i.to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            )
        })
        .collect();
    let assignment = format!("technique={technique}");
    let configs: Vec<(&str, Vec<&str>)> = labels
        .iter()
        .zip(&only)
        .map(|(l, o)| (l.as_str(), vec![assignment.as_str(), o.as_str()]))
        .collect();
    let rows = lab.measure(&configs)?;
    let mut t = Table::new(&[
        ("scene, lights", Align::Left),
        ("shadows off ms (fps)", Align::Right),
        ("with shadows ms (fps)", Align::Right),
        ("× shadows off", Align::Right),
        ("error", Align::Right),
    ]);
    for ((n, r), o) in counts.iter().zip(&rows).zip(&only) {
        let off = r.shadows_off_frame_ms.median;
        let on = r.frame_ms.median;
        t.push(vec![
            r.label.clone(),
            format!("{off:.1} ({:.0})", 1000.0 / off.max(1e-9)),
            format!("{on:.1} ({:.0})", 1000.0 / on.max(1e-9)),
            format!("{:.2}", r.ratio_to_shadows_off),
            pct(r.error.total),
        ]);
        s.numbers
            .insert(format!("{}_ratio_{n}", lab.name), r.ratio_to_shadows_off);
        s.numbers
            .insert(format!("{}_error_{n}", lab.name), r.error.total);
        s.regenerate
            .push(lab.bench_command(&[o.as_str()], &format!("technique=none,{technique}")));
    }
    t.note = rows.first().map(|r| {
        format!(
            "{}: the lights reaching the most pixels of the view. {}x{}, medians of {} frame(s), {} clock.",
            lab.name,
            r.width,
            r.height,
            r.frames,
            clock_name(&r.clock)
        )
    });
    s.tables.push(t);
    if let (Some(first), Some(last)) = (rows.first(), rows.last()) {
        s.findings.push(format!(
            "{}: {:.1}x the frame time of shadows off with {} lights, {:.1}x with {}.",
            lab.name,
            first.ratio_to_shadows_off,
            counts[0],
            last.ratio_to_shadows_off,
            counts[counts.len() - 1]
        ));
    }
    lab.bar().inc(1);
    Ok(s)
}

pub fn run(lab: &mut Lab) -> Result<Vec<Section>, ReproduceError> {
    let order = lights_by_reach(lab)?;
    let sm_counts: &[usize] = if lab.quick {
        &[2, 4]
    } else {
        &[2, 4, 6, 8, 10]
    };
    let sm = super::timed(lab, |lab| {
        claim(
            lab,
            "claim-sm-lights",
            "Paper: shadow maps with 2 to 10 lights",
            "\"With 2 to 10 lights in a scene\" the paper's shadow maps run at around 30 fps and \
         sometimes above 100 fps, against 120-250 fps typical for its renderer: roughly 1.2x to \
         8x the frame time, if those rates are taken as shadows off. It names the area of the \
         screen a light reaches as the dominant cost.",
            "shadow_map",
            sm_counts,
            &order,
        )
    })?;
    let sv = super::timed(lab, |lab| {
        claim(
            lab,
            "claim-sv-lights",
            "Paper: shadow volumes with 3 to 4 lights",
            "With around 3-4 lights visible, the paper's shadow volumes run at 30-40 fps (about 20 \
         fps with more lights potentially visible), against 120-250 fps typical: roughly 3x to \
         8x the frame time. The two stencil passes per light dominate.",
            "shadow_volume",
            &[3, 4],
            &order,
        )
    })?;
    Ok(vec![sm, sv])
}
