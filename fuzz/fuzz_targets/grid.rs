//! Every grid loader must return a grid or an error, never panic; the first byte picks it.
#![no_main]
use isotrack_fields::io::{parse_grid, GridFormat};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else { return };
    let format = match sel % 4 {
        0 => GridFormat::Csv,
        1 => GridFormat::Npy,
        2 => GridFormat::Asc,
        _ => GridFormat::GeoTiff,
    };
    if let Ok(g) = parse_grid(std::path::Path::new("fuzz"), rest, format) {
        // A loaded grid is usable: interpolate anywhere inside it.
        use isotrack_fields::ScalarField;
        let f = isotrack_fields::grid::GridField::new(g.grid, Default::default());
        let [x0, x1, y0, y1] = f.grid().extent_m();
        let _ = f.value(0.0, isotrack_core::Vec2::new(0.5 * (x0 + x1), 0.5 * (y0 + y1)));
    }
});
