//! The time-series readers (a 3-D `.npy`, NetCDF-3/4 from bytes) and the series they make must
//! never panic; the first byte picks the format.
#![no_main]
use isotrack_fields::grid::{AfterLastFrame, GridSeries, Interpolation, TimeInterpolation};
use isotrack_fields::io::{parse_series_bytes, GridFormat};
use isotrack_fields::ScalarField;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else { return };
    let format = if sel % 2 == 0 { GridFormat::Npy } else { GridFormat::NetCdf };
    if let Ok(s) = parse_series_bytes(std::path::Path::new("fuzz"), rest, format, None) {
        let n = s.frames.len();
        let times: Vec<f64> = s.frame_times_s.unwrap_or_else(|| (0..n).map(|k| k as f64).collect());
        if let Ok(series) = GridSeries::new(
            s.frames,
            times,
            Interpolation::Bicubic,
            TimeInterpolation::Cubic,
            0.0,
            1.0,
            AfterLastFrame::End,
        ) {
            let [x0, x1, y0, y1] = series.extent_m();
            let p = isotrack_core::Vec2::new(0.5 * (x0 + x1), 0.5 * (y0 + y1));
            let _ = series.value(0.5, p);
            let _ = series.time_derivative(0.5, p);
        }
    }
});
