//! The station reader must never panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = isotrack_fields::stations::Stations::from_csv_bytes(std::path::Path::new("fuzz.csv"), data, "value");
});
