//! Writes a report as `index.html`, its Markdown copy `index.md`, and `results.json`.

use super::{Report, ReproduceError, Section};
use crate::report::table::{Align, Table, escape_html};
use std::path::Path;

const TITLE: &str = "shadowlab: the paper's figures and claims, reproduced";

const CSS: &str = "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;\
line-height:1.45;color:#222}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}\
table{border-collapse:collapse;margin:1em 0;font-size:90%}td,th{border:1px solid #ccc;\
padding:.25em .5em}th{background:#f2f2f2}.source{background:#f7f7f0;border-left:4px solid #cc9;\
padding:.5em 1em}.figures{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0;max-width:330px}\
figure img{max-width:330px;image-rendering:pixelated;border:1px solid #ccc}figcaption{font-size:85%}\
figure.wide,figure.wide img{max-width:100%}code{background:#f2f2f2;padding:0 .2em;font-size:90%}\
.note{font-size:85%;color:#555}";

fn write_file(path: &Path, text: &str) -> Result<(), ReproduceError> {
    std::fs::write(path, text).map_err(super::io(path))
}

fn is_plot(file: &str) -> bool {
    file.starts_with("sweep-") || file == "fig13-14.png" || file == "fig22.png"
}

fn section_html(s: &Section) -> String {
    let mut h = format!(
        "<h2 id=\"{}\">{}</h2>\n<p class=\"source\"><b>Source.</b> {}</p>\n",
        s.id,
        escape_html(&s.title),
        escape_html(&s.source)
    );
    if !s.findings.is_empty() {
        h.push_str("<p><b>Measured.</b></p>\n<ul>\n");
        for f in &s.findings {
            h.push_str(&format!("<li>{}</li>\n", escape_html(f)));
        }
        h.push_str("</ul>\n");
    }
    if !s.figures.is_empty() {
        h.push_str("<div class=\"figures\">\n");
        for f in &s.figures {
            let class = if is_plot(&f.file) {
                " class=\"wide\""
            } else {
                ""
            };
            h.push_str(&format!(
                "<figure{class}><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
                f.file,
                escape_html(&f.caption),
                escape_html(&f.caption)
            ));
        }
        h.push_str("</div>\n");
    }
    for t in &s.tables {
        h.push_str(&t.to_html());
    }
    if !s.regenerate.is_empty() {
        h.push_str("<details><summary>Regenerate</summary>\n<pre>");
        for c in &s.regenerate {
            h.push_str(&escape_html(c));
            h.push('\n');
        }
        h.push_str("</pre></details>\n");
    }
    h
}

fn section_markdown(s: &Section) -> String {
    let mut m = format!("## {}\n\n> **Source.** {}\n\n", s.title, s.source);
    if !s.findings.is_empty() {
        m.push_str("**Measured.**\n\n");
        for f in &s.findings {
            m.push_str(&format!("- {f}\n"));
        }
        m.push('\n');
    }
    for f in &s.figures {
        m.push_str(&format!(
            "![{}]({})\n*{}*\n\n",
            f.caption, f.file, f.caption
        ));
    }
    for t in &s.tables {
        m.push_str(&t.to_markdown());
        m.push('\n');
    }
    if !s.regenerate.is_empty() {
        m.push_str("Regenerate:\n\n```sh\n");
        for c in &s.regenerate {
            m.push_str(c);
            m.push('\n');
        }
        m.push_str("```\n\n");
    }
    m
}

/// Where the run's time went: each section's seconds, loading, and what is left (plots,
/// pages, work between sections), slowest first.
pub fn time_table(report: &Report) -> Table {
    let mut t = Table::new(&[
        ("section", Align::Left),
        ("seconds", Align::Right),
        ("share", Align::Right),
    ]);
    let mut rows: Vec<(String, f64)> = report
        .sections
        .iter()
        .map(|s| (s.id.clone(), s.seconds))
        .collect();
    rows.push(("loading and uploading scenes".into(), report.loading_s));
    let counted: f64 = rows.iter().map(|(_, s)| s).sum();
    rows.push((
        "the rest (orders, plots, pages)".into(),
        (report.elapsed_s - counted).max(0.0),
    ));
    rows.sort_by(|a, b| b.1.total_cmp(&a.1));
    let total = report.elapsed_s.max(f64::MIN_POSITIVE);
    for (name, seconds) in rows {
        t.push(vec![
            name,
            format!("{seconds:.1}"),
            format!("{:.1}%", 100.0 * seconds / total),
        ]);
    }
    t.push(vec![
        "whole run".into(),
        format!("{:.1}", report.elapsed_s),
        "100%".into(),
    ]);
    t
}

pub fn write(report: &Report, out: &Path) -> Result<(), ReproduceError> {
    let minutes = report.elapsed_s / 60.0;
    let how = format!(
        "Every number below was measured in one run of <code>shadowlab reproduce</code> \
         ({minutes:.1} minutes). The paper is Arneson, \"Real-Time Shadows\"; the thesis is \
         Sindholt, \"A comparison of Shadow Algorithms\" (DTU, 2005). Each section says what \
         the source shows, what we measured, and how to regenerate it."
    );
    let mut html = format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{TITLE}</title>\
         <style>{CSS}</style></head><body>\n<h1>{TITLE}</h1>\n<p>{how}</p>\n"
    );
    let mut md = format!(
        "# {TITLE}\n\n{}\n\n",
        how.replace("<code>", "`").replace("</code>", "`")
    );
    html.push_str("<h2>Summary</h2>\n<ul>\n");
    md.push_str("## Summary\n\n");
    for s in &report.summary {
        html.push_str(&format!("<li>{}</li>\n", escape_html(s)));
        md.push_str(&format!("- {s}\n"));
    }
    html.push_str("</ul>\n<h2>Setup</h2>\n<ul>\n");
    md.push_str("\n## Setup\n\n");
    for e in &report.environment {
        html.push_str(&format!("<li>{}</li>\n", escape_html(e)));
        md.push_str(&format!("- {e}\n"));
    }
    html.push_str("</ul>\n<p>Contents: ");
    md.push('\n');
    let links: Vec<String> = report
        .sections
        .iter()
        .map(|s| format!("<a href=\"#{}\">{}</a>", s.id, escape_html(&s.title)))
        .collect();
    html.push_str(&links.join(" · "));
    html.push_str("</p>\n");
    for s in &report.sections {
        html.push_str(&section_html(s));
        md.push_str(&section_markdown(s));
    }
    let time = time_table(report);
    let reuse = format!(
        "{}; a configuration taken from rows kept before costs no time here.",
        report.reuse
    );
    html.push_str("<h2 id=\"time\">Where the time went</h2>\n");
    html.push_str(&format!("<p>{}</p>\n", escape_html(&reuse)));
    html.push_str(&time.to_html());
    md.push_str(&format!("## Where the time went\n\n{reuse}\n\n"));
    md.push_str(&time.to_markdown());
    html.push_str("</body></html>\n");
    write_file(&out.join("index.html"), &html)?;
    write_file(&out.join("index.md"), &md)?;
    write_file(
        &out.join("results.json"),
        &serde_json::to_string_pretty(&report.rows)?,
    )?;
    Ok(())
}
