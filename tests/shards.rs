//! Sharded and resumed runs as a person runs them. `check` over a handful of maps and a small
//! `bench` sweep, each split two ways, the two shards run as two processes at once (`--shard
//! K/N --out DIR`) and joined by `shadowlab merge`, give the single run's error figures
//! exactly (`check` needs OpenArena's data: `scripts/fetch-openarena.sh`). A part given twice,
//! or one missing, is one clear error. A `bench --keep` sweep stopped halfway and run again
//! measures only the rest, and gives the uninterrupted run's error figures.

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
    both_shards_at_once(|k| {
        let out = part(k);
        let mut c = check(
            &data,
            &["--shard", &format!("{k}/2"), "--out", out.to_str().unwrap()],
        );
        c.stdout(std::process::Stdio::null());
        c
    });
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

/// Shards 1/2 and 2/2 as two processes at once (`shard(k)` makes shard k's command), both
/// succeeding.
fn both_shards_at_once(shard: impl Fn(usize) -> Command) {
    let running: Vec<_> = (1..=2)
        .map(|k| {
            shard(k)
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut s in running {
        assert!(s.wait().unwrap().success());
    }
}

/// `merge`'s error for `parts`, which must fail.
fn merge_err(parts: &[PathBuf]) -> String {
    let out = shadowlab().arg("merge").args(parts).output().unwrap();
    assert!(!out.status.success());
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// `bench` on the built-in scene, small and quick: two techniques, two map sizes.
fn bench(out: &Path, sweep_sizes: &str, extra: &[&str]) -> Command {
    let mut c = shadowlab();
    c.args([
        "bench", "--size", "160x120", "--warmup", "0", "--frames", "1",
    ])
    .args(["--sweep", "technique=shadow_map,shadow_volume"])
    .args(["--sweep", &format!("shadow_map.size={sweep_sizes}")])
    .arg("--out")
    .arg(out)
    .args(extra)
    .stdout(std::process::Stdio::null());
    c
}

/// Each row's label and error figures (times differ run to run).
fn bench_errors(dir: &Path) -> Vec<(String, serde_json::Value, serde_json::Value)> {
    let text = std::fs::read_to_string(dir.join("rows.json")).unwrap();
    let rows: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    rows.into_iter()
        .map(|r| {
            (
                r["label"].as_str().unwrap().to_string(),
                r["error"].clone(),
                r["error_per_light"].clone(),
            )
        })
        .collect()
}

fn succeeds(mut c: Command) -> String {
    let out = c.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{err}");
    err
}

#[test]
fn a_bench_sweep_split_two_ways_and_merged_equals_one_run() {
    let dir = std::env::temp_dir().join(format!("shadowlab-bench-shards-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    succeeds(bench(&dir.join("single"), "128,512", &[]));
    let single = bench_errors(&dir.join("single"));
    assert_eq!(single.len(), 4);
    // The figures compared are not all zero: the maps err somewhere.
    assert!(
        single
            .iter()
            .any(|(_, e, _)| e["total"].as_f64().unwrap() > 0.0),
        "{single:?}"
    );
    let part = |k: usize| dir.join(format!("part{k}"));
    both_shards_at_once(|k| bench(&part(k), "128,512", &["--shard", &format!("{k}/2")]));
    assert_eq!(
        (bench_errors(&part(1)).len(), bench_errors(&part(2)).len()),
        (2, 2)
    );
    let mut merge = shadowlab();
    merge
        .arg("merge")
        .args([part(2), part(1)])
        .arg("--out")
        .arg(dir.join("merged"))
        .stdout(std::process::Stdio::null());
    succeeds(merge);
    assert_eq!(bench_errors(&dir.join("merged")), single);
    assert!(dir.join("merged").join("bench.png").is_file());
    let out = merge_err(&[part(2), part(2)]);
    assert!(out.contains("are both shard 2/2"), "{out}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bench_sweep_resumed_after_an_interruption_equals_one_run() {
    let dir = std::env::temp_dir().join(format!("shadowlab-bench-resume-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let keep = dir.join("kept");
    let keep_args = ["--keep", keep.to_str().unwrap()];
    succeeds(bench(&dir.join("whole"), "128,512", &[]));
    // Stopped after the 128-texel maps: half the sweep kept.
    let first = succeeds(bench(&dir.join("stopped"), "128", &keep_args));
    assert!(first.contains("reused 0 of 2 configurations"), "{first}");
    // A row being written when the run was killed is measured again.
    std::fs::write(keep.join("0123.json.partial"), "{\"label\":").unwrap();
    let resumed = succeeds(bench(&dir.join("resumed"), "128,512", &keep_args));
    assert!(
        resumed.contains("reused 2 of 4 configurations"),
        "{resumed}"
    );
    assert_eq!(
        bench_errors(&dir.join("resumed")),
        bench_errors(&dir.join("whole"))
    );
    // Run again: nothing left to measure.
    let again = succeeds(bench(&dir.join("again"), "128,512", &keep_args));
    assert!(again.contains("reused 4 of 4 configurations"), "{again}");
    std::fs::remove_dir_all(&dir).ok();
}
