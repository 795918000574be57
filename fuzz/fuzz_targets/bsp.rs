//! See `shadowlab::fuzz_entry::bsp` for what this target covers; `tests/fuzz_regressions.rs`
//! replays its crash inputs through the same function.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| shadowlab::fuzz_entry::bsp(data));
