//! The sweep parser and its run indexing must never panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(plan) = isotrack_scenario::sweep::SweepPlan::parse(text, std::path::Path::new("fuzz.toml")) {
            let n = plan.total().min(64);
            for id in 0..n {
                let _ = plan.run_overrides(id);
            }
        }
    }
});
