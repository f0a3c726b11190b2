//! The NetCDF reader (NetCDF-3 classic and NetCDF-4/HDF5 through `netcdf-reader`) must return a
//! series or an error for any bytes, never panic, abort or allocate what a header merely
//! declares. Seeds: the xarray fixture matrix (crates/isotrack-fields/tests/fixtures/netcdf,
//! written by scripts/make-netcdf-fixtures.py), which scripts/fuzz.sh passes as a seed directory.
#![no_main]
use isotrack_fields::io::{parse_series_bytes, GridFormat};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(s) = parse_series_bytes(std::path::Path::new("fuzz.nc"), data, GridFormat::NetCdf, None) {
        // A loaded series is consistent: frames of one size, one time per frame when given.
        let n = s.frames.len();
        assert!(n >= 1);
        assert!(s.frames.iter().all(|f| (f.nx(), f.ny()) == (s.frames[0].nx(), s.frames[0].ny())));
        if let Some(t) = &s.frame_times_s {
            assert_eq!(t.len(), n);
        }
    }
});
