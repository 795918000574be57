//! The text formats: shader scripts, entity lumps, .rtlights, .skin and animation.cfg.
#![no_main]
use libfuzzer_sys::fuzz_target;
use shadowlab::q3::{entities, md3, rtlights, shader};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = shader::parse_shader_script(&text);
    if let Ok(ents) = entities::parse_entities(&text) {
        let _ = entities::spawn_points(&ents);
        let _ = entities::light_entities(&ents);
    }
    let _ = rtlights::parse_rtlights(&text);
    let _ = md3::parse_skin(&text);
    let _ = md3::parse_animation_cfg(&text);
});
