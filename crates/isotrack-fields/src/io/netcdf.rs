//! NetCDF grids (CF conventions) through the system libnetcdf (cargo feature `netcdf`).
//!
//! The variable is the one named, or the first with two non-trivial dimensions that is not a
//! coordinate variable. Its last two dimensions are (y, x); leading dimensions must have length 1
//! (one time step). Coordinates are the 1-D variables named like those dimensions: longitude /
//! latitude (CF `units = degrees_east / degrees_north`, `standard_name`, or the names
//! lon/longitude and lat/latitude) are projected to local metres ([`crate::georef`]); coordinates
//! in metres are used as they are. They must be regularly spaced; decreasing axes are flipped.
//! `_FillValue` / `missing_value` become no-data; `scale_factor` / `add_offset` are applied.

use super::{LoadError, LoadedGrid};
use crate::georef::{lonlat_spacing_m, Georeference};
use crate::grid::Grid2;
use isotrack_core::Vec2;
use netcdf::AttributeValue;
use std::path::Path;

fn attr_f64(v: &netcdf::Variable<'_>, name: &str) -> Option<f64> {
    match v.attribute_value(name)?.ok()? {
        AttributeValue::Double(x) => Some(x),
        AttributeValue::Float(x) => Some(f64::from(x)),
        AttributeValue::Short(x) => Some(f64::from(x)),
        AttributeValue::Int(x) => Some(f64::from(x)),
        AttributeValue::Schar(x) => Some(f64::from(x)),
        AttributeValue::Uchar(x) => Some(f64::from(x)),
        AttributeValue::Ushort(x) => Some(f64::from(x)),
        AttributeValue::Uint(x) => Some(f64::from(x)),
        AttributeValue::Doubles(x) => x.first().copied(),
        AttributeValue::Floats(x) => x.first().map(|v| f64::from(*v)),
        _ => None,
    }
}

fn attr_str(v: &netcdf::Variable<'_>, name: &str) -> Option<String> {
    match v.attribute_value(name)?.ok()? {
        AttributeValue::Str(s) => Some(s),
        _ => None,
    }
}

#[derive(PartialEq)]
enum Axis {
    Lon,
    Lat,
    Metres,
}

fn axis_kind(v: &netcdf::Variable<'_>) -> Axis {
    let units = attr_str(v, "units")
        .unwrap_or_default()
        .to_ascii_lowercase();
    let std = attr_str(v, "standard_name")
        .unwrap_or_default()
        .to_ascii_lowercase();
    let name = v.name().to_ascii_lowercase();
    if units.starts_with("degrees_east")
        || units == "degree_east"
        || std == "longitude"
        || name == "lon"
        || name == "longitude"
    {
        Axis::Lon
    } else if units.starts_with("degrees_north")
        || units == "degree_north"
        || std == "latitude"
        || name == "lat"
        || name == "latitude"
    {
        Axis::Lat
    } else {
        Axis::Metres
    }
}

/// First value and step of a regular axis, or why not.
fn regular(values: &[f64]) -> Result<(f64, f64), String> {
    if values.len() < 2 {
        return Err(format!(
            "{} coordinate values; at least 2 are needed",
            values.len()
        ));
    }
    let step = (values[values.len() - 1] - values[0]) / (values.len() - 1) as f64;
    for (k, v) in values.iter().enumerate() {
        if (v - (values[0] + k as f64 * step)).abs()
            > 1e-6 * step.abs().max(1e-12) * values.len() as f64
        {
            return Err(format!("not regularly spaced (value {k} is {v})"));
        }
    }
    Ok((values[0], step))
}

pub(super) fn parse(path: &Path, variable: Option<&str>) -> Result<LoadedGrid, LoadError> {
    let err = |m: String| LoadError::new(path, None, m);
    let file = netcdf::open(path).map_err(|e| err(format!("cannot open as NetCDF: {e}")))?;
    let dim_names: Vec<String> = file.dimensions().map(|d| d.name()).collect();
    let var = match variable {
        Some(n) => file.variable(n).ok_or_else(|| {
            err(format!(
                "no variable `{n}`; the file has {:?}",
                file.variables().map(|v| v.name()).collect::<Vec<_>>()
            ))
        })?,
        None => file
            .variables()
            .find(|v| {
                !dim_names.contains(&v.name())
                    && v.dimensions().iter().filter(|d| d.len() > 1).count() == 2
            })
            .ok_or_else(|| err("no 2-D data variable (give field.variable)".into()))?,
    };
    let dims = var.dimensions();
    if dims.len() < 2 || dims[..dims.len() - 2].iter().any(|d| d.len() != 1) {
        return Err(err(format!(
            "variable `{}` has dimensions {:?}; need (..., y, x) with any leading dimension of length 1",
            var.name(),
            dims.iter().map(|d| (d.name(), d.len())).collect::<Vec<_>>()
        )));
    }
    let (ydim, xdim) = (&dims[dims.len() - 2], &dims[dims.len() - 1]);
    let (ny, nx) = (ydim.len(), xdim.len());
    // Checked before reading: the header's sizes are the file's claim, not a promise.
    if nx
        .checked_mul(ny)
        .is_none_or(|n| n > crate::grid::MAX_NODES)
    {
        return Err(LoadError::grid(
            path,
            crate::grid::GridError::TooManyNodes { nx, ny },
        ));
    }
    let mut values: Vec<f64> = var
        .get_values::<f64, _>(..)
        .map_err(|e| err(format!("cannot read `{}`: {e}", var.name())))?;
    if values.len() != nx * ny {
        return Err(err(format!("{} values for {ny} x {nx}", values.len())));
    }
    let fill = attr_f64(&var, "_FillValue");
    let missing = attr_f64(&var, "missing_value");
    let scale = attr_f64(&var, "scale_factor").unwrap_or(1.0);
    let offset = attr_f64(&var, "add_offset").unwrap_or(0.0);
    for v in &mut values {
        if Some(*v) == fill || Some(*v) == missing || !v.is_finite() {
            *v = f64::NAN;
        } else {
            *v = *v * scale + offset;
        }
    }
    let coord = |name: String| -> Result<Option<(Vec<f64>, Axis)>, LoadError> {
        match file.variable(&name) {
            None => Ok(None),
            Some(c) => {
                let vals = c
                    .get_values::<f64, _>(..)
                    .map_err(|e| err(format!("cannot read coordinate `{name}`: {e}")))?;
                Ok(Some((vals, axis_kind(&c))))
            }
        }
    };
    let xc = coord(xdim.name())?;
    let yc = coord(ydim.name())?;
    let (mut grid_values, mut georeference, mut origin, mut spacing) =
        (values, Georeference::None, Vec2::default(), [1.0, 1.0]);
    if let (Some((xs, xk)), Some((ys, yk))) = (xc, yc) {
        let (mut x0, mut dx) =
            regular(&xs).map_err(|m| err(format!("coordinate `{}`: {m}", xdim.name())))?;
        let (mut y0, mut dy) =
            regular(&ys).map_err(|m| err(format!("coordinate `{}`: {m}", ydim.name())))?;
        if dy < 0.0 {
            super::flip_rows(&mut grid_values, nx, ny);
            y0 += dy * (ny - 1) as f64;
            dy = -dy;
        }
        if dx < 0.0 {
            for row in grid_values.chunks_mut(nx) {
                row.reverse();
            }
            x0 += dx * (nx - 1) as f64;
            dx = -dx;
        }
        if xk == Axis::Lon && yk == Axis::Lat {
            let ref_lat = y0 + 0.5 * dy * (ny - 1) as f64;
            spacing = lonlat_spacing_m(dx, dy, ref_lat);
            georeference = Georeference::LonLat {
                lon0_deg: x0,
                lat0_deg: y0,
                dlon_deg: dx,
                dlat_deg: dy,
                ref_lat_deg: ref_lat,
            };
        } else {
            origin = Vec2::new(x0, y0);
            spacing = [dx, dy];
            georeference = Georeference::Metres { epsg: None };
        }
    }
    let grid =
        Grid2::new(nx, ny, origin, spacing, grid_values).map_err(|e| LoadError::grid(path, e))?;
    Ok(LoadedGrid { grid, georeference })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_cf_lonlat_grid_with_fill_and_flip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.nc");
        {
            let mut f = netcdf::create(&p).unwrap();
            f.add_dimension("lat", 4).unwrap();
            f.add_dimension("lon", 3).unwrap();
            let mut lat = f.add_variable::<f64>("lat", &["lat"]).unwrap();
            lat.put_attribute("units", "degrees_north").unwrap();
            // North first: decreasing latitude.
            lat.put_values(&[51.0, 50.5, 50.0, 49.5], ..).unwrap();
            let mut lon = f.add_variable::<f64>("lon", &["lon"]).unwrap();
            lon.put_attribute("units", "degrees_east").unwrap();
            lon.put_values(&[10.0, 10.5, 11.0], ..).unwrap();
            let mut v = f.add_variable::<f32>("pm25", &["lat", "lon"]).unwrap();
            v.set_fill_value(-999.0f32).unwrap();
            v.put_attribute("scale_factor", 2.0f32).unwrap();
            // row r (north first) = 30 - 10 r + col, stored halved (scale_factor 2).
            let raw: Vec<f32> = (0..4)
                .flat_map(|r| (0..3).map(move |c| ((30 - 10 * r + c) as f32) / 2.0))
                .collect();
            let mut raw = raw;
            raw[4] = -999.0; // north row 1, column 1 -> NaN
            v.put_values(&raw, ..).unwrap();
        }
        let g = crate::io::load_grid(&p, None).unwrap();
        assert_eq!((g.grid.nx(), g.grid.ny()), (3, 4));
        assert_eq!(g.grid.at(0, 0), 0.0, "south-west after the flip");
        assert_eq!(g.grid.at(2, 3), 32.0);
        assert!(g.grid.at(1, 2).is_nan(), "fill value");
        let Georeference::LonLat {
            lon0_deg, lat0_deg, ..
        } = g.georeference
        else {
            panic!()
        };
        assert_eq!((lon0_deg, lat0_deg), (10.0, 49.5));
        let [dx, dy] = g.grid.spacing_m();
        assert!((dy - 55_597.54).abs() < 1.0, "{dy}");
        assert!(
            (dx - 55_597.54 * 50.25f64.to_radians().cos()).abs() < 1.0,
            "{dx}"
        );
    }

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("junk.nc");
        std::fs::write(&p, b"CDF\x01garbage").unwrap();
        let e = crate::io::load_grid(&p, None).unwrap_err();
        assert!(e.to_string().contains("junk.nc"), "{e}");
        let p2 = dir.path().join("one.nc");
        {
            let mut f = netcdf::create(&p2).unwrap();
            f.add_dimension("t", 3).unwrap();
            f.add_dimension("y", 2).unwrap();
            f.add_dimension("x", 2).unwrap();
            f.add_variable::<f64>("v", &["t", "y", "x"]).unwrap();
        }
        let e = crate::io::load_grid_variable(&p2, None, Some("v")).unwrap_err();
        assert!(e.message.contains("length 1"), "{e}");
        let e = crate::io::load_grid_variable(&p2, None, Some("w")).unwrap_err();
        assert!(e.message.contains("no variable"), "{e}");
    }
}
