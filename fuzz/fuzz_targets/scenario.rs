//! The scenario parser must never panic, whatever the text (and a valid scenario must build).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = isotrack_scenario::parse_scenario(text, "<fuzz>", &[]);
    }
});
