//! Tables: built once, written as Markdown or HTML.

use super::bench::BenchRow;

/// How a column's cells line up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Align {
    Left,
    Right,
}

/// A table of text cells with a header row.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Table {
    pub header: Vec<(String, Align)>,
    pub rows: Vec<Vec<String>>,
    /// A line under the table (units, clocks).
    pub note: Option<String>,
}

impl Table {
    pub fn new(header: &[(&str, Align)]) -> Table {
        Table {
            header: header.iter().map(|(h, a)| (h.to_string(), *a)).collect(),
            ..Table::default()
        }
    }

    pub fn push(&mut self, row: Vec<String>) {
        self.rows.push(row);
    }

    pub fn to_markdown(&self) -> String {
        let cell = |s: &str| s.replace('|', "\\|");
        let mut s = String::from("|");
        for (h, _) in &self.header {
            s.push_str(&format!(" {} |", cell(h)));
        }
        s.push_str("\n|");
        for (_, a) in &self.header {
            s.push_str(match a {
                Align::Left => "---|",
                Align::Right => "---:|",
            });
        }
        s.push('\n');
        for r in &self.rows {
            s.push('|');
            for c in r {
                s.push_str(&format!(" {} |", cell(c)));
            }
            s.push('\n');
        }
        if let Some(n) = &self.note {
            s.push_str(&format!("\n{n}\n"));
        }
        s
    }

    pub fn to_html(&self) -> String {
        let align = |a: Align| match a {
            Align::Left => "left",
            Align::Right => "right",
        };
        let mut s = String::from("<table>\n<tr>");
        for (h, a) in &self.header {
            s.push_str(&format!(
                "<th style=\"text-align:{}\">{}</th>",
                align(*a),
                escape_html(h)
            ));
        }
        s.push_str("</tr>\n");
        for r in &self.rows {
            s.push_str("<tr>");
            for (i, c) in r.iter().enumerate() {
                let a = self.header.get(i).map_or(Align::Left, |h| h.1);
                s.push_str(&format!(
                    "<td style=\"text-align:{}\">{}</td>",
                    align(a),
                    escape_html(c)
                ));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</table>\n");
        if let Some(n) = &self.note {
            s.push_str(&format!("<p class=\"note\">{}</p>\n", escape_html(n)));
        }
        s
    }
}

pub fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The stages worth a column: every `lights.<stage>` sum, plus the base pass.
fn stage_names(rows: &[BenchRow]) -> Vec<String> {
    let mut names: Vec<String> = rows
        .iter()
        .flat_map(|r| r.pass_ms.keys())
        .filter(|k| k.starts_with("lights.") || *k == "base")
        .cloned()
        .collect();
    names.sort();
    names.dedup();
    names
}

/// One line per configuration: frame time, its CPU part, ratios to shadows off (of the medians,
/// and frame by frame), error, and per-stage medians.
pub fn bench_table(rows: &[BenchRow]) -> Table {
    let stages = stage_names(rows);
    let mut header = vec![
        ("scene".to_string(), Align::Left),
        ("configuration".to_string(), Align::Left),
        ("lights".to_string(), Align::Right),
        ("frame ms (median)".to_string(), Align::Right),
        ("CPU ms median".to_string(), Align::Right),
        ("CPU ms p99".to_string(), Align::Right),
        ("own CPU ms median, p99".to_string(), Align::Right),
        ("ms, 2 in flight".to_string(), Align::Right),
        ("waits per frame".to_string(), Align::Right),
        ("p95, p99 ms".to_string(), Align::Right),
        ("p99 / median".to_string(), Align::Right),
        ("× shadows off".to_string(), Align::Right),
        ("× off median".to_string(), Align::Right),
        ("× off p99".to_string(), Align::Right),
        (
            "redone per frame (maps, of which models only, volume parts, caster groups)"
                .to_string(),
            Align::Right,
        ),
        ("error %".to_string(), Align::Right),
        ("error % excl. boundary".to_string(), Align::Right),
    ];
    let sampled = rows.iter().any(|r| r.sampled.is_some());
    if sampled {
        header.push((
            "path error % (sampled median, max)".to_string(),
            Align::Right,
        ));
        header.push((
            "sampling ms (frame + masks + rays)".to_string(),
            Align::Right,
        ));
        header.push((
            "worst light on the path % (pooled, 95%)".to_string(),
            Align::Right,
        ));
    }
    header.extend(stages.iter().map(|s| (format!("{s} ms"), Align::Right)));
    let mut t = Table {
        header,
        ..Table::default()
    };
    for r in rows {
        let mut row = vec![
            r.scene.clone(),
            r.label.clone(),
            r.lights.to_string(),
            format!("{:.2}", r.frame_ms.median),
            format!("{:.2}", r.cpu_ms.median),
            format!("{:.2}", r.cpu_ms.p99),
            format!("{:.2}, {:.2}", r.own_ms.median, r.own_ms.p99),
            if r.pipelined_ms > 0.0 {
                format!("{:.2}", r.pipelined_ms)
            } else {
                "–".to_string()
            },
            format!("{:.1}", r.syncs_per_frame.total),
            format!("{:.2}, {:.2}", r.frame_ms.p95, r.frame_ms.p99),
            format!("{:.2}", r.frame_ms.p99_over_median()),
            format!("{:.2}", r.ratio_to_shadows_off),
            format!("{:.2}", r.ratio_median),
            format!("{:.2}", r.ratio_p99),
            format!(
                "{:.1}, {:.1}, {:.1}, {:.1}",
                r.redone.maps_rendered,
                r.redone.maps_models_only,
                r.redone.volume_parts_built,
                r.redone.caster_groups_built
            ),
            format!("{:.3}", 100.0 * r.error.total),
            format!("{:.3}", 100.0 * r.error.total_excl_boundary),
        ];
        if sampled {
            match &r.sampled {
                Some(p) => {
                    row.push(format!("{:.3}, {:.3}", 100.0 * p.median, 100.0 * p.max));
                    row.push(format!(
                        "{:.1} + {:.1} + {:.1}",
                        p.frame_extra_ms, p.masks_ms, p.trace_ms
                    ));
                    row.push(match p.lights.first() {
                        Some(l) => format!(
                            "{:.3} [{:.3}, {:.3}] (light {})",
                            100.0 * l.error.value,
                            100.0 * l.error.low,
                            100.0 * l.error.high,
                            l.light
                        ),
                        None => "–".to_string(),
                    });
                }
                None => row.extend(["–", "–", "–"].map(String::from)),
            }
        }
        row.extend(stages.iter().map(|st| match r.pass_ms.get(st) {
            Some(ms) => format!("{ms:.2}"),
            None => "–".to_string(),
        }));
        t.push(row);
    }
    t.note = rows.first().map(|r| {
        format!(
            "{}x{}, {} measured frames per configuration, pass times from the {} clock.",
            r.width,
            r.height,
            r.frames,
            clock_name(&r.clock)
        )
    });
    t
}

/// The sampled error of every configuration on every frame of the path: the estimate and its
/// 95% interval, in percent.
pub fn path_error_table(rows: &[BenchRow]) -> Table {
    let sampled: Vec<&BenchRow> = rows.iter().filter(|r| r.sampled.is_some()).collect();
    let mut header = vec![("frame".to_string(), Align::Right)];
    header.extend(
        sampled
            .iter()
            .map(|r| (format!("{} error %", r.label), Align::Right)),
    );
    let mut t = Table {
        header,
        ..Table::default()
    };
    let frames = sampled
        .iter()
        .filter_map(|r| r.sampled.as_ref().map(|p| p.frames.len()))
        .max()
        .unwrap_or(0);
    for i in 0..frames {
        let frame = sampled
            .iter()
            .find_map(|r| r.sampled.as_ref().and_then(|p| p.frames.get(i)))
            .map_or(i, |f| f.frame);
        let mut row = vec![frame.to_string()];
        for r in &sampled {
            let cell = r
                .sampled
                .as_ref()
                .and_then(|p| p.frames.get(i))
                .map(|f| {
                    let e = f.error;
                    format!(
                        "{:.3} [{:.3}, {:.3}]",
                        100.0 * e.value,
                        100.0 * e.low,
                        100.0 * e.high
                    )
                })
                .unwrap_or_else(|| "–".to_string());
            row.push(cell);
        }
        t.push(row);
    }
    t.note = sampled.first().and_then(|r| r.sampled.as_ref()).map(|p| {
        format!(
            "Sampled reference: {} receiver pixels per light and frame, traced exactly; \
             brackets hold the 95% interval (Wilson, on the effective sample size).",
            p.samples_per_light
        )
    });
    t
}

pub fn clock_name(clock: &str) -> &'static str {
    if clock == "gpu" {
        "GPU (timer queries)"
    } else {
        "CPU (wall time around glFinish)"
    }
}

/// [`bench_table`] as Markdown.
pub fn markdown(rows: &[BenchRow]) -> String {
    bench_table(rows).to_markdown()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_and_html_escape_and_align() {
        let mut t = Table::new(&[("a|b", Align::Left), ("n", Align::Right)]);
        t.push(vec!["<x>".into(), "1.5".into()]);
        let md = t.to_markdown();
        assert_eq!(md, "| a\\|b | n |\n|---|---:|\n| <x> | 1.5 |\n");
        let html = t.to_html();
        assert!(html.contains("<td style=\"text-align:left\">&lt;x&gt;</td>"));
        assert!(html.contains("<th style=\"text-align:right\">n</th>"));
    }
}
