//! The benchmark's suite file: parsing, its checks and their error locations, the seed draws
//! and the suite as run (`Suite::to_toml`) must never panic, and the suite as run must read back
//! as the same suite.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match isotrack_league::Suite::parse(text, "fuzz.toml", Path::new(".")) {
        Ok(suite) => {
            for task in suite.tasks.iter().take(8) {
                for seed in suite.scoring_seeds.iter().take(4) {
                    let _ = isotrack_league::suite::seed_overrides(task, *seed);
                }
            }
            let again = suite.to_toml("as run");
            let back = isotrack_league::Suite::parse(&again, "again.toml", Path::new("."))
                .unwrap_or_else(|e| panic!("the suite as run does not read back: {e}\n{again}"));
            assert_eq!(back.tasks, suite.tasks);
            assert_eq!(
                (&back.controllers, &back.scoring_seeds, &back.tuning_seeds, back.scoring),
                (&suite.controllers, &suite.scoring_seeds, &suite.tuning_seeds, suite.scoring)
            );
        }
        Err(e) => {
            let _ = e.to_string();
        }
    }
});
