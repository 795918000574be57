//! Sharded runs as a person runs them: `check` over a handful of maps split two ways, the two
//! shards run as two processes at once (`--shard K/N --out DIR`), joined by `shadowlab merge`,
//! give the single run's lines, error figures exactly (OpenArena data:
//! `scripts/fetch-openarena.sh`). A part given twice, or one missing, is one clear error.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn shadowlab() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shadowlab"))
}

/// Three small maps; oa_ctf4ish's shadow maps err, so the figures compared are not all zero.
const MAPS: [&str; 3] = ["kaos", "islanddm", "oa_ctf4ish"];

fn check(data: &Path, extra: &[&str]) -> Command {
    let mut c = shadowlab();
    c.arg("check")
        .arg("--data")
        .arg(data)
        .args(MAPS)
        .args(extra);
    c
}

fn lines(out: &Output) -> Vec<serde_json::Value> {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// A check line without its times (which differ run to run).
fn without_times(mut line: serde_json::Value) -> serde_json::Value {
    line.as_object_mut().unwrap().remove("load_ms");
    for run in line["runs"].as_array_mut().unwrap() {
        run.as_object_mut().unwrap().remove("frame_ms");
    }
    line
}

#[test]
fn check_split_two_ways_and_merged_equals_one_run() {
    let data = common::openarena_data();
    let dir = std::env::temp_dir().join(format!("shadowlab-shards-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let single = lines(&check(&data, &[]).output().unwrap());
    let part = |k: usize| dir.join(format!("part{k}"));
    let shards: Vec<_> = (1..=2)
        .map(|k| {
            let shard = format!("{k}/2");
            let out = part(k);
            check(&data, &["--shard", &shard, "--out", out.to_str().unwrap()])
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut s in shards {
        assert!(s.wait().unwrap().success());
    }
    // In any order.
    let merged = lines(
        &shadowlab()
            .arg("merge")
            .args([part(2), part(1)])
            .output()
            .unwrap(),
    );
    assert_eq!(merged.len(), MAPS.len());
    let errors: Vec<f64> = single
        .iter()
        .flat_map(|l| l["runs"].as_array().unwrap().clone())
        .map(|r| r["error_percent"].as_f64().unwrap())
        .collect();
    assert!(errors.iter().any(|&e| e > 0.0), "{errors:?}");
    let (single, merged): (Vec<_>, Vec<_>) = (
        single.into_iter().map(without_times).collect(),
        merged.into_iter().map(without_times).collect(),
    );
    assert_eq!(single, merged);
    // Each shard checked its own maps only.
    let part_lines = |k: usize| {
        std::fs::read_to_string(part(k).join("check.jsonl"))
            .unwrap()
            .lines()
            .count()
    };
    assert_eq!((part_lines(1), part_lines(2)), (2, 1));
    for (parts, says) in [
        (vec![part(1), part(1)], "are both shard 1/2"),
        (vec![part(1)], "shard 2/2 missing"),
    ] {
        let out = merge_err(&parts);
        assert!(out.contains(says), "{out}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `merge`'s error for `parts`, which must fail.
fn merge_err(parts: &[PathBuf]) -> String {
    let out = shadowlab().arg("merge").args(parts).output().unwrap();
    assert!(!out.status.success());
    String::from_utf8_lossy(&out.stderr).to_string()
}
