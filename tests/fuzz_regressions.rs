//! Every input the fuzz targets crashed, hung or ran out of memory on, replayed through the
//! same calls the target makes (`shadowlab::fuzz_entry`). Each lives in
//! `tests/fuzz-inputs/<target>/`, minimized and small; the fix made it pass.

use shadowlab::fuzz_entry::TARGETS;
use std::path::Path;
use std::time::{Duration, Instant};

/// A replay slower than this (in a release build) counts as the hang coming back.
const SLOW: Duration = Duration::from_secs(2);

#[test]
fn every_crash_input_replays_cleanly() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-inputs");
    let mut replayed = 0;
    for entry in std::fs::read_dir(&root).expect("tests/fuzz-inputs exists") {
        let dir = entry.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        let (_, run) = TARGETS
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
            let start = Instant::now();
            run(&bytes);
            let took = start.elapsed();
            assert!(
                cfg!(debug_assertions) || took < SLOW,
                "{}: took {took:?}",
                path.display()
            );
            replayed += 1;
        }
    }
    println!("replayed {replayed} fuzz inputs");
}

#[test]
fn every_target_takes_empty_and_junk_input() {
    for (name, run) in TARGETS {
        for input in [&b""[..], b"\0", b"\xff\xfe garbage {{{ [[ ", &[0x80; 300]] {
            run(input);
        }
        let _ = name;
    }
}
