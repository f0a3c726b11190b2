//! The scenario parser must never panic, whatever the text (and a valid scenario must build).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        // A scenario that validates must build: the sensor, the step plan and the controller
        // are the builders that `expect` what validation promised (issue 16, class 1).
        if let Ok(s) = isotrack_scenario::parse_scenario(text, "<fuzz>", &[]) {
            let _ = s.sensor();
            let _ = s.plan();
            let _ = s.controller();
            let _ = s.max_turn_rate_radps();
        }
    }
});
