//! MD3 parsing, then placing frame 0 and assembling a player from three copies.
#![no_main]
use libfuzzer_sys::fuzz_target;
use shadowlab::q3::md3;

fuzz_target!(|data: &[u8]| {
    let Ok(m) = md3::parse(data) else { return };
    let _ = md3::place_model(&m, 0, glam::Mat4::IDENTITY);
    let _ = md3::assemble_player(&m, &m, &m, 0, 0);
});
