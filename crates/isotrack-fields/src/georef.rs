//! Georeference: from file coordinates to the local metres the simulation runs in.
//!
//! Projection for longitude/latitude grids and stations: **equirectangular about a reference
//! latitude** `phi_0` (the grid's or the stations' middle latitude), with the mean Earth radius
//! `R = 6 371 008.8 m`:
//!
//! ```text
//! x = R * cos(phi_0) * (lambda - lambda_0),   y = R * (phi - phi_0')
//! ```
//!
//! (angles in radians; `lambda_0`, `phi_0'` put the south-west node at the local origin). A regular
//! lon/lat grid stays a regular grid in metres, with `dx = R cos(phi_0) dlambda`, `dy = R dphi`.
//! The east-west scale is exact at `phi_0` and off by `cos(phi)/cos(phi_0) - 1` elsewhere (about
//! 3 % at 5 degrees from `phi_0` at mid-latitudes): fine for tracking studies on maps that the
//! paper itself rescales, not for navigation.

use isotrack_core::Vec2;

/// Mean Earth radius (IUGG), m.
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;

/// What a file said about its coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Georeference {
    /// Nothing: node spacing 1 m, origin 0 (give `field.spacing_m` / `field.origin_m`).
    None,
    /// Coordinates in metres (projected, or a local Cartesian grid).
    Metres {
        /// EPSG code, if the file gave one.
        epsg: Option<u16>,
    },
    /// A regular longitude/latitude grid, projected as described in the module docs.
    LonLat {
        /// Longitude of the south-west node, degrees.
        lon0_deg: f64,
        /// Latitude of the south-west node, degrees.
        lat0_deg: f64,
        /// Longitude step, degrees.
        dlon_deg: f64,
        /// Latitude step, degrees.
        dlat_deg: f64,
        /// Reference latitude of the projection, degrees.
        ref_lat_deg: f64,
    },
}

/// Equirectangular projection of `(lon, lat)` degrees to local metres relative to
/// `(lon0, lat0)`, with the east-west scale of `ref_lat`.
pub fn lonlat_to_local_m(
    lon_deg: f64,
    lat_deg: f64,
    lon0_deg: f64,
    lat0_deg: f64,
    ref_lat_deg: f64,
) -> Vec2 {
    let k = EARTH_RADIUS_M * std::f64::consts::PI / 180.0;
    Vec2::new(
        k * ref_lat_deg.to_radians().cos() * (lon_deg - lon0_deg),
        k * (lat_deg - lat0_deg),
    )
}

/// Node spacing in metres of a regular lon/lat grid (see the module docs).
pub fn lonlat_spacing_m(dlon_deg: f64, dlat_deg: f64, ref_lat_deg: f64) -> [f64; 2] {
    let k = EARTH_RADIUS_M * std::f64::consts::PI / 180.0;
    [k * ref_lat_deg.to_radians().cos() * dlon_deg, k * dlat_deg]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_degree_of_latitude_is_111_km() {
        let p = lonlat_to_local_m(10.0, 51.0, 10.0, 50.0, 50.0);
        assert!((p.y - 111_195.08).abs() < 1.0, "{}", p.y);
        // One degree of longitude at 60 N is half of one at the equator.
        let q = lonlat_to_local_m(11.0, 60.0, 10.0, 60.0, 60.0);
        assert!((q.x - 0.5 * 111_195.08).abs() < 1.0, "{}", q.x);
    }
}
