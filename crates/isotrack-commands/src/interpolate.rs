//! `isotrack interpolate`: station values onto a grid file.

use crate::cli::{InterpolateArgs, Method};
use crate::exit;
use crate::run::Failure;
use isotrack_core::numtext::{Echo, Num};
use isotrack_fields::grid::Grid2;
use isotrack_fields::stations::{
    Idw, OrdinaryKriging, StationGridError, StationInterpolator, Stations,
};
use serde_json::json;
use std::io::Write;

/// Writes a grid as CSV in the `data/` layout (no header, row 0 south), numbers in
/// shortest round-trip form.
pub fn write_grid_csv(path: &std::path::Path, g: &Grid2) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(isotrack_runs::files::create_output(path)?);
    for iy in 0..g.ny() {
        let row: Vec<String> = (0..g.nx())
            .map(|ix| crate::output::num(g.at(ix, iy)))
            .collect();
        writeln!(out, "{}", row.join(","))?;
    }
    out.flush()
}

/// Runs the command.
pub fn interpolate(a: &InterpolateArgs) -> Result<(), Failure> {
    check_options(a)?;
    let stations = Stations::from_csv(&a.stations, &a.value_column).map_err(|e| Failure {
        code: if e.unreadable {
            exit::NOINPUT
        } else {
            exit::DATAERR
        },
        message: e.to_string(),
    })?;
    let spacing_m = a.spacing_m.unwrap_or(stations.default_spacing_m());
    let n = stations.values.len();
    let projection = stations.projection;
    let (grid, method) = station_grid(a, stations, spacing_m)?;
    let cant = |e: std::io::Error| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", a.out.display()),
    };
    let side = sidecar_path(&a.out)?;
    prepare_outputs(a, &side)?;
    write_grid_csv(&a.out, &grid).map_err(cant)?;
    let (lo, hi) = grid.value_range();
    let sidecar = sidecar_json(a, &grid, n, projection, method);
    isotrack_runs::files::write_atomic(
        &side,
        (serde_json::to_string_pretty(&sidecar).unwrap_or_default() + "\n").as_bytes(),
    )
    .map_err(cant)?;
    outln!(
        "wrote {} ({} x {} nodes, {} m spacing, values {} .. {}) and {}",
        a.out.display(),
        grid.nx(),
        grid.ny(),
        Num(spacing_m),
        Num(lo),
        Num(hi),
        side.display()
    );
    Ok(())
}

/// `--spacing-m` and `--idw-power`, each a finite number > 0 (the power not subnormal).
fn check_options(a: &InterpolateArgs) -> Result<(), Failure> {
    if let Some(sp) = a.spacing_m.filter(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(Failure {
            code: exit::USAGE,
            message: format!("--spacing-m must be a finite number > 0, got {}", Echo(sp)),
        });
    }
    if !(a.idw_power.is_finite() && a.idw_power > 0.0 && a.idw_power.is_normal()) {
        return Err(Failure {
            code: exit::USAGE,
            message: format!(
                "--idw-power must be a finite number > 0 (not subnormal), got {}",
                Echo(a.idw_power)
            ),
        });
    }
    Ok(())
}

/// The stations interpolated by `--method` onto a grid over their extent, `spacing_m` apart,
/// and the method as the sidecar records it (the kriging's fitted variogram with it). A grid
/// too fine is a usage error (`--spacing-m`), a kriging that cannot be fitted a data error.
fn station_grid(
    a: &InterpolateArgs,
    stations: Stations,
    spacing_m: f64,
) -> Result<(Grid2, serde_json::Value), Failure> {
    let data = |m: String| Failure {
        code: exit::DATAERR,
        message: m,
    };
    let extent = stations.extent_m();
    let (grid, method) = match a.method {
        Method::Idw => {
            let idw = Idw::new(stations, a.idw_power);
            (
                idw.to_grid(extent, spacing_m),
                json!({"method": "idw", "power": a.idw_power}),
            )
        }
        Method::Kriging => {
            let ok = OrdinaryKriging::new(stations)
                .map_err(|e| data(format!("{}: {e}", a.stations.display())))?;
            let v = ok.variogram();
            (
                ok.to_grid(extent, spacing_m),
                json!({"method": "ordinary_kriging", "variogram": {
                    "model": format!("{:?}", v.model).to_lowercase(),
                    "nugget": v.nugget, "partial_sill": v.sill, "range_m": v.range_m}}),
            )
        }
    };
    let grid = grid.map_err(|e| match e {
        StationGridError::TooFine { .. } => Failure {
            code: exit::USAGE,
            message: format!("--spacing-m: {e}"),
        },
        StationGridError::Grid(_) => data(e.to_string()),
    })?;
    Ok((grid, method))
}

/// The sidecar of grid `out`: the same name with `.json`. A grid named `*.json` (any case)
/// is refused (64, naming `--out` and the file): its sidecar would be written over the grid
/// itself (att42-7).
fn sidecar_path(out: &std::path::Path) -> Result<std::path::PathBuf, Failure> {
    let side = out.with_extension("json");
    let is_json = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if is_json {
        return Err(Failure {
            code: exit::USAGE,
            message: format!(
                "--out {}: the grid's JSON sidecar is written to the grid's name with `.json` ({}), which would replace the grid itself: name the grid with another extension (`.csv`)",
                isotrack_runs::owned::shell_quoted(out),
                isotrack_runs::owned::shell_quoted(&side)
            ),
        });
    }
    Ok(side)
}

/// Whether the file at `path` (at most 1 MiB) is an isotrack grid's sidecar: a JSON object
/// whose `derived` says `interpolated by isotrack` (every sidecar has, since the command came).
fn is_sidecar(path: &std::path::Path) -> std::io::Result<bool> {
    let bytes = isotrack_runs::owned::read_capped(path, 1 << 20)?.unwrap_or_default();
    let v: serde_json::Value = serde_json::from_slice(&bytes).unwrap_or_default();
    Ok(v["derived"]
        .as_str()
        .is_some_and(|d| d.starts_with("interpolated by isotrack")))
}

/// The outputs (`--out` and its `.json` sidecar `side`) checked before either is written:
/// neither is the stations file, the directory exists, neither is a link or other non-regular
/// file, and `side`, a name isotrack chose, is no file of the user's ([`is_sidecar`]; README,
/// "Outputs": the grid, named on the command line, is replaced as `cp` replaces a file).
fn prepare_outputs(a: &InterpolateArgs, side: &std::path::Path) -> Result<(), Failure> {
    let cant = |e: std::io::Error| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", a.out.display()),
    };
    // Neither output replaces the stations file it is made from (64).
    for o in [a.out.as_path(), side] {
        if let Some(message) = crate::output::input_clash(std::slice::from_ref(&a.stations), o) {
            return Err(Failure {
                code: exit::USAGE,
                message,
            });
        }
    }
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(cant)?;
    }
    for o in [a.out.as_path(), side] {
        isotrack_runs::files::refuse_non_regular(o).map_err(cant)?;
    }
    isotrack_runs::owned::refuse_foreign(
        side,
        is_sidecar,
        "an isotrack grid's sidecar",
        "not a JSON object whose `derived` says `interpolated by isotrack`",
    )
}

/// The grid's sidecar: what it was derived from, its layout, shape, spacing, origin and
/// projection (for lon/lat stations), the interpolation `method` and the values' range.
fn sidecar_json(
    a: &InterpolateArgs,
    grid: &Grid2,
    n: usize,
    projection: Option<(f64, f64, f64)>,
    method: serde_json::Value,
) -> serde_json::Value {
    let (lo, hi) = grid.value_range();
    json!({
        "derived": format!("interpolated by isotrack {} from {} ({} stations, column `{}`); a derived product, not measured data",
            env!("CARGO_PKG_VERSION"), a.stations.display(), n, a.value_column),
        "layout": "row-major values[iy][ix]; row 0 = southernmost row, column 0 = westernmost column; CSV without header",
        "shape_rows_cols": [grid.ny(), grid.nx()],
        "spacing_m": grid.spacing_m(),
        "origin_m": [grid.origin_m().x, grid.origin_m().y],
        "projection": projection.map(|(lon0, lat0, ref_lat)| json!({
            "kind": "equirectangular", "lon0_deg": lon0, "lat0_deg": lat0, "ref_lat_deg": ref_lat,
            "earth_radius_m": isotrack_fields::georef::EARTH_RADIUS_M})),
        "interpolation": method,
        "value_min": lo,
        "value_max": hi,
    })
}
