//! Every input the fuzz targets crashed, hung or ran out of memory on, and one hand-made hostile
//! input for each target the fuzzers found nothing in, replayed through the same calls the target
//! makes (`shadowlab::fuzz_entry`). Each lives in `tests/fuzz-inputs/<target>/`, minimized and
//! small; the fix made it pass. A replay must return without a panic and without a large
//! allocation (the hang it guards against took 4 GB); time is not measured (`scripts/fuzz.sh`
//! gives the fuzzers their timeout).

use shadowlab::fuzz_entry::{TARGETS, Target};
use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

/// Growth of this process's peak resident memory one replay may cause. The patch input once
/// tessellated 66 million vertices (about 4 GB); every loader refuses such counts before it
/// allocates, and no input here needs more than a few megabytes.
const PEAK_GROWTH: u64 = 256 << 20;

/// This process's peak resident memory (VmHWM), in bytes.
fn peak_rss() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(0, |kb| kb << 10)
}

/// Runs `target` on `bytes`; a panic fails the test naming the target and the input.
fn replay((name, run): &Target, bytes: &[u8], what: &str) {
    let before = peak_rss();
    if let Err(e) = catch_unwind(AssertUnwindSafe(|| run(bytes))) {
        let message = e
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        panic!("fuzz target `{name}` panicked on {what}: {message}");
    }
    let grew = peak_rss().saturating_sub(before);
    assert!(
        grew < PEAK_GROWTH,
        "fuzz target `{name}` on {what}: peak memory grew by {} MiB",
        grew >> 20
    );
}

#[test]
fn every_crash_input_replays_cleanly() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-inputs");
    let mut replayed: BTreeMap<&str, usize> = TARGETS.iter().map(|(t, _)| (*t, 0)).collect();
    for entry in std::fs::read_dir(&root).expect("tests/fuzz-inputs exists") {
        let dir = entry.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        let target = TARGETS
            .iter()
            .find(|(t, _)| *t == name)
            .unwrap_or_else(|| panic!("tests/fuzz-inputs/{name}: no fuzz target of that name"));
        for input in std::fs::read_dir(&dir).unwrap() {
            let path = input.unwrap().path();
            let bytes = std::fs::read(&path).unwrap();
            assert!(
                bytes.len() <= 4096,
                "{}: keep inputs minimized",
                path.display()
            );
            replay(target, &bytes, &path.display().to_string());
            *replayed.get_mut(target.0).unwrap() += 1;
        }
    }
    println!("replayed per target: {replayed:?}");
    for (target, n) in &replayed {
        assert!(
            *n >= 1,
            "fuzz target `{target}` has no input in tests/fuzz-inputs/{target}/"
        );
    }
}

#[test]
fn every_target_takes_empty_and_junk_input() {
    for target in TARGETS {
        for (i, input) in [&b""[..], b"\0", b"\xff\xfe garbage {{{ [[ ", &[0x80; 300]]
            .iter()
            .enumerate()
        {
            replay(target, input, &format!("junk input {i}"));
        }
    }
}
