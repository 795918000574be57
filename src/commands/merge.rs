//! `shadowlab merge`: the parts of a sharded run (`--shard K/N --out DIR`) joined into what one
//! run writes, after checking they are all of it exactly once and were made alike.

use super::bench::{ROWS, write_outputs};
use super::check::{LINES, failures};
use anyhow::{Context, Result, bail};
use shadowlab::report::bench::BenchRow;
use shadowlab::report::reproduce;
use shadowlab::report::shard::{self, Manifest, ShardError};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The parts' folders (each holds shard.json), in any order.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Also write the merged run to DIR, as one unsharded run's `--out` would (needed for
    /// `reproduce`, whose output is a folder).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<()> {
    let (whole, parts) = shard::complete_run(&args.parts)?;
    match whole.command.as_str() {
        "check" => merge_check(&whole, &parts, args.out.as_ref()),
        "bench" => merge_bench(&whole, &parts, args.out.as_ref()),
        "reproduce" => {
            let out = args
                .out
                .as_ref()
                .context("merging parts of `reproduce` needs --out DIR for the report")?;
            let report = reproduce::merge(&whole.units, &parts, out)?;
            whole.write(out)?;
            eprintln!(
                "wrote {} ({} sections, {} configurations, {:.1} minutes of the parts)",
                out.join("index.html").display(),
                report.sections.len(),
                report.rows.len(),
                report.elapsed_s / 60.0
            );
            Ok(())
        }
        other => bail!("cannot merge parts of `{other}`"),
    }
}

/// `bench`'s rows in the sweep's order: its table on stdout and, in `out`, its rows and plot
/// (as `bench --out` writes them).
fn merge_bench(whole: &Manifest, parts: &[PathBuf], out: Option<&PathBuf>) -> Result<()> {
    let mut rows: Vec<BenchRow> = Vec::new();
    for dir in parts {
        let path = dir.join(ROWS);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| ShardError::Read(path.clone(), e.to_string()))?;
        let part: Vec<BenchRow> = serde_json::from_str(&text)
            .with_context(|| format!("{}: not bench rows", path.display()))?;
        rows.extend(part);
    }
    let rows = shard::in_run_order(&whole.units, rows, |r| r.label.clone())?;
    let scene = rows.first().map(|r| r.scene.clone()).unwrap_or_default();
    let (w, h) = rows.first().map_or((0, 0), |r| (r.width, r.height));
    let title = format!("{scene}: error against frame time ({w}x{h})");
    let (json, plot) = match out {
        Some(dir) => {
            whole.write(dir)?;
            (Some(dir.join(ROWS)), dir.join("bench.png"))
        }
        None => (None, PathBuf::from("bench.png")),
    };
    write_outputs(&rows, json.as_deref(), &title, &plot)
}

/// `check`'s JSON lines, one per map in the run's order, on stdout (and in `out`).
fn merge_check(whole: &Manifest, parts: &[PathBuf], out: Option<&PathBuf>) -> Result<()> {
    // (map, line, whether the map could not be checked)
    let mut lines: Vec<(String, String, bool)> = Vec::new();
    for dir in parts {
        let path = dir.join(LINES);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| ShardError::Read(path.clone(), e.to_string()))?;
        for line in text.lines().filter(|l| !l.trim().is_empty()) {
            let value: serde_json::Value = serde_json::from_str(line)
                .with_context(|| format!("{}: not a check line", path.display()))?;
            let map = value["map"]
                .as_str()
                .with_context(|| format!("{}: a line without its map", path.display()))?;
            let failed = value.get("error").is_some();
            lines.push((map.to_string(), line.to_string(), failed));
        }
    }
    let ordered = shard::in_run_order(&whole.units, lines, |(map, ..)| map.clone())?;
    let failed = ordered.iter().filter(|(.., failed)| *failed).count();
    let text: String = ordered.iter().map(|(_, l, _)| format!("{l}\n")).collect();
    if let Some(dir) = out {
        whole.write(dir)?;
        std::fs::write(dir.join(LINES), &text)?;
    }
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(text.as_bytes())?;
    stdout.flush()?;
    failures(failed, ordered.len())
}
