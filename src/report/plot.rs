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
    register_font();
    let root = BitMapBackend::new(path, (960, 640)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let max_x = rows.iter().map(|r| r.frame_ms.median).fold(1e-3, f64::max) * 1.15;
    let max_y = rows
        .iter()
        .map(|r| 100.0 * r.error.total)
        .fold(0.1, f64::max)
        * 1.15;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..max_x, 0.0..max_y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("frame time, median ms")
        .y_desc("error, % of receiver pixels")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    let palette = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK];
    for (i, r) in rows.iter().enumerate() {
        let colour = palette[i % palette.len()];
        let p = (r.frame_ms.median, 100.0 * r.error.total);
        // The label sits beside its point, in pixels, so it never covers it.
        let point = EmptyElement::at(p)
            + Circle::new((0, 0), 5, colour.filled())
            + Text::new(
                r.label.clone(),
                (9, -7),
                ("sans-serif", 13).into_font().color(&colour),
            );
        chart.draw_series(std::iter::once(point)).map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
