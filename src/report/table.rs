//! Markdown tables of bench rows.

use super::bench::BenchRow;

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

/// One line per configuration: frame time, ratio to shadows off, error, and per-stage medians.
pub fn markdown(rows: &[BenchRow]) -> String {
    let stages = stage_names(rows);
    let mut s = String::from(
        "| scene | configuration | lights | frame ms (median) | × shadows off | error % | error % excl. boundary |",
    );
    for st in &stages {
        s.push_str(&format!(" {st} ms |"));
    }
    s.push_str("\n|---|---|---:|---:|---:|---:|---:|");
    for _ in &stages {
        s.push_str("---:|");
    }
    s.push('\n');
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.3} | {:.3} |",
            r.scene,
            r.label,
            r.lights,
            r.frame_ms.median,
            r.ratio_to_shadows_off,
            100.0 * r.error.total,
            100.0 * r.error.total_excl_boundary
        ));
        for st in &stages {
            match r.pass_ms.get(st) {
                Some(ms) => s.push_str(&format!(" {ms:.2} |")),
                None => s.push_str(" – |"),
            }
        }
        s.push('\n');
    }
    if let Some(r) = rows.first() {
        s.push_str(&format!(
            "\n{}x{}, {} measured frames per configuration, pass times from the {} clock.\n",
            r.width,
            r.height,
            r.frames,
            if r.clock == "gpu" {
                "GPU (timer queries)"
            } else {
                "CPU (wall time around glFinish)"
            }
        ));
    }
    s
}
