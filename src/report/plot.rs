//! Figures with plotters (bitmap backend), using the fonts egui ships.

use super::bench::BenchRow;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// Error rate against median frame time, one labelled point per configuration.
pub fn error_vs_time(rows: &[BenchRow], title: &str, path: &Path) -> Result<(), String> {
    error_vs_time_marked(rows, &[], title, path)
}

/// The same, with a ring around the rows whose `marked` flag is set (e.g. the Pareto front).
pub fn error_vs_time_marked(
    rows: &[BenchRow],
    marked: &[bool],
    title: &str,
    path: &Path,
) -> Result<(), String> {
    register_font();
    let root = BitMapBackend::new(path, (960, 640)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let max_x = rows.iter().map(|r| r.frame_ms.median).fold(1e-3, f64::max) * 1.15;
    // Errors span four decades (shadows off against exact volumes): a log axis, with exact
    // zeros drawn on its floor.
    let floor = 1e-3;
    let max_y = rows
        .iter()
        .map(|r| 100.0 * r.error.total)
        .fold(0.1, f64::max)
        * 2.0;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..max_x, (floor..max_y).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("frame time, median ms")
        .y_desc("error, % of receiver pixels (log)")
        .y_label_formatter(&|v| format!("{v}"))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    let palette = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK];
    for (i, r) in rows.iter().enumerate() {
        let colour = palette[i % palette.len()];
        let p = (r.frame_ms.median, (100.0 * r.error.total).max(floor));
        // The label sits beside its point, in pixels, so it never covers it.
        let ring = if marked.get(i).copied().unwrap_or(false) {
            9
        } else {
            0
        };
        let point = EmptyElement::at(p)
            + Circle::new((0, 0), 5, colour.filled())
            + Circle::new((0, 0), ring, colour.stroke_width(2))
            + Text::new(
                r.label.clone(),
                (11, -7),
                ("sans-serif", 13).into_font().color(&colour),
            );
        chart.draw_series(std::iter::once(point)).map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// One stacked bar per entry: its segments (name, value) bottom to top, one colour per segment
/// name across bars, with a legend.
pub fn stacked_bars(
    bars: &[(String, Vec<(String, f64)>)],
    title: &str,
    y_desc: &str,
    path: &Path,
) -> Result<(), String> {
    register_font();
    let root = BitMapBackend::new(path, (800, 560)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let max_y = bars
        .iter()
        .map(|(_, segs)| segs.iter().map(|(_, v)| v.max(0.0)).sum::<f64>())
        .fold(1e-6, f64::max)
        * 1.35;
    let mut names: Vec<&str> = Vec::new();
    for (_, segs) in bars {
        for (n, _) in segs {
            if !names.contains(&n.as_str()) {
                names.push(n);
            }
        }
    }
    let n = bars.len().max(1) as i32;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((0..n - 1).into_segmented(), 0.0..max_y)
        .map_err(err)?;
    let labels: Vec<String> = bars.iter().map(|(l, _)| l.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_label_formatter(&|x| match x {
            SegmentValue::CenterOf(i) => labels.get(*i as usize).cloned().unwrap_or_default(),
            _ => String::new(),
        })
        .y_desc(y_desc)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    let palette = [
        RGBColor(70, 110, 190),
        RGBColor(230, 140, 50),
        RGBColor(90, 170, 90),
        RGBColor(190, 70, 70),
        RGBColor(140, 100, 180),
        RGBColor(120, 120, 120),
    ];
    for (k, name) in names.iter().enumerate() {
        let colour = palette[k % palette.len()];
        let rects: Vec<Rectangle<(SegmentValue<i32>, f64)>> = bars
            .iter()
            .enumerate()
            .filter_map(|(i, (_, segs))| {
                let pos = segs.iter().position(|(s, _)| s == name)?;
                let below: f64 = segs[..pos].iter().map(|(_, v)| v.max(0.0)).sum();
                let v = segs[pos].1.max(0.0);
                let mut r = Rectangle::new(
                    [
                        (SegmentValue::Exact(i as i32), below),
                        (SegmentValue::Exact(i as i32 + 1), below + v),
                    ],
                    colour.filled(),
                );
                r.set_margin(0, 0, 40, 40);
                Some(r)
            })
            .collect();
        chart
            .draw_series(rects)
            .map_err(err)?
            .label(name.to_string())
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 12, y + 6)], colour.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}
