//! Local metres <-> WGS84 latitude and longitude about a home position.
//!
//! The same projection as the field loaders' georeference
//! (`isotrack_fields::georef`): **equirectangular about the home latitude** `phi_0`, with the mean
//! Earth radius `R = 6 371 008.8 m`:
//!
//! ```text
//! lat = lat_0 + y / R,        lon = lon_0 + x / (R cos(lat_0))      (radians)
//! ```
//!
//! `x` east and `y` north of home, m. Exact at home; the east-west scale is off by
//! `cos(lat)/cos(lat_0) - 1` elsewhere (3e-5 over 5 km at 47 deg): a local flying area, not
//! navigation across a continent.
//!
//! Poles: the east-west scale `cos(lat_0)` vanishes there, so a home (or a lon/lat field's
//! reference latitude) beyond [`MAX_HOME_LAT_DEG`] is refused ([`Frame::of`]); a point north of
//! the north pole (south of the south pole) is carried over it along its meridian
//! (`lat = 180 - lat`, `lon = lon + 180`), so a latitude sent is always within [-90, 90].
//!
//! A scenario whose field is a longitude/latitude grid (NetCDF, GeoTIFF in degrees) is already
//! on the Earth: [`Frame::of`] takes the field's own georeference
//! ([`isotrack_scenario::field::LonLatFrame`]): home is the field's local origin and the
//! east-west scale is the cosine of the grid's reference latitude, so that a position sent is
//! the field file's own coordinate of that point.

use isotrack_fields::georef::EARTH_RADIUS_M;

/// Where the local origin is on the Earth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Home {
    /// Latitude, deg.
    pub lat_deg: f64,
    /// Longitude, deg.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_m: f64,
}

impl Home {
    /// The home of a scenario (`sitl.home_lat_deg`, `home_lon_deg`, `home_alt_m`, defaults
    /// applied).
    pub fn of(s: &isotrack_scenario::Scenario) -> Self {
        let h = &s.file().sitl;
        Self {
            lat_deg: h.home_lat_deg(),
            lon_deg: h.home_lon_deg(),
            alt_m: h.home_alt_m(),
        }
    }

    /// `(lat, lon)` in degrees of the point `x_m` east, `y_m` north of home.
    pub fn to_lat_lon_deg(&self, x_m: f64, y_m: f64) -> (f64, f64) {
        let lat = self.lat_deg + (y_m / EARTH_RADIUS_M).to_degrees();
        let lon =
            self.lon_deg + (x_m / (EARTH_RADIUS_M * self.lat_deg.to_radians().cos())).to_degrees();
        over_the_pole(lat, lon)
    }

    /// `(x east, y north)` in metres of the point at `(lat, lon)` degrees (the inverse of
    /// [`to_lat_lon_deg`](Self::to_lat_lon_deg)).
    pub fn to_local_m(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        let dlon = wrap_lon_deg(lon_deg - self.lon_deg);
        (
            EARTH_RADIUS_M * self.lat_deg.to_radians().cos() * dlon.to_radians(),
            EARTH_RADIUS_M * (lat_deg - self.lat_deg).to_radians(),
        )
    }
}

/// Home and the latitude whose cosine scales east-west distances: where the simulation's local
/// metres are on the Earth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The local origin (and its altitude).
    pub home: Home,
    /// The east-west scale's latitude, deg: home's own, or a lon/lat field's reference latitude.
    pub scale_lat_deg: f64,
}

/// How far, deg, `sitl.home_lat_deg` / `home_lon_deg` may be from a lon/lat field's own origin
/// and still agree with it: 1e-7 deg, `GLOBAL_POSITION_INT`'s resolution (about 1 cm).
pub const HOME_AGREEMENT_DEG: f64 = 1e-7;

/// The largest |latitude|, deg, of home or of a lon/lat field's reference latitude: the range
/// `sitl.home_lat_deg` is checked against when the scenario loads (at 89 deg, `cos(lat_0)` is
/// 0.017, one metre east a 1/0.017 times wider step of longitude; at 90 it is 0 and every
/// longitude is infinite).
pub const MAX_HOME_LAT_DEG: f64 = 89.0;

impl Frame {
    /// The frame of a scenario: a lon/lat field's own georeference (home at the field's local
    /// origin, `sitl.home_alt_m` its altitude), else `sitl.home_*` ([`Home::of`]). An error
    /// when the scenario sets `sitl.home_lat_deg` or `home_lon_deg` to another point than a
    /// lon/lat field's origin (the positions sent would contradict the field's coordinates).
    /// Also an error when home's latitude, or the field's reference latitude, is beyond
    /// [`MAX_HOME_LAT_DEG`] (or not finite).
    pub fn of(s: &isotrack_scenario::Scenario) -> Result<Self, String> {
        let f = Self::of_unchecked(s)?;
        for (what, lat) in [
            (
                if s.lonlat_frame().is_some() {
                    "the field's local origin (its georeference)"
                } else {
                    "sitl.home_lat_deg"
                },
                f.home.lat_deg,
            ),
            (
                "the field's reference latitude (the middle of its grid)",
                f.scale_lat_deg,
            ),
        ] {
            if lat.is_nan() || lat.abs() > MAX_HOME_LAT_DEG {
                return Err(format!(
                    "{what} is at latitude {} deg: isotrack sitl maps local metres to latitude and longitude within {} deg of the equator (the east-west scale cos(lat) vanishes at the poles)",
                    isotrack_core::numtext::Echo(lat),
                    isotrack_core::numtext::Echo(MAX_HOME_LAT_DEG),
                ));
            }
        }
        Ok(f)
    }

    fn of_unchecked(s: &isotrack_scenario::Scenario) -> Result<Self, String> {
        let home = Home::of(s);
        let Some(f) = s.lonlat_frame() else {
            return Ok(Self {
                home,
                scale_lat_deg: home.lat_deg,
            });
        };
        let sitl = &s.file().sitl;
        for (key, given, own) in [
            ("sitl.home_lat_deg", sitl.home_lat_deg, f.lat0_deg),
            ("sitl.home_lon_deg", sitl.home_lon_deg, f.lon0_deg),
        ] {
            if let Some(g) = given {
                let off = wrap_lon_deg(g - own).abs();
                if off.is_nan() || off > HOME_AGREEMENT_DEG {
                    return Err(format!(
                        "{key} = {}: the field is a longitude/latitude grid, whose local origin is at latitude {}, longitude {} deg; leave sitl.home_lat_deg and home_lon_deg unset (the field's own georeference is the home) or set them to that point",
                        isotrack_core::numtext::Echo(g),
                        isotrack_core::numtext::Echo(f.lat0_deg),
                        isotrack_core::numtext::Echo(f.lon0_deg),
                    ));
                }
            }
        }
        Ok(Self {
            home: Home {
                lat_deg: f.lat0_deg,
                lon_deg: wrap_lon_deg(f.lon0_deg),
                alt_m: home.alt_m,
            },
            scale_lat_deg: f.ref_lat_deg,
        })
    }

    /// `(lat, lon)` in degrees of the point `x_m` east, `y_m` north of home:
    /// `lat = lat_0 + y / R`, `lon = lon_0 + x / (R cos(scale_lat))`.
    pub fn to_lat_lon_deg(&self, x_m: f64, y_m: f64) -> (f64, f64) {
        let h = self.home;
        let lat = h.lat_deg + (y_m / EARTH_RADIUS_M).to_degrees();
        let lon = h.lon_deg
            + (x_m / (EARTH_RADIUS_M * self.scale_lat_deg.to_radians().cos())).to_degrees();
        over_the_pole(lat, lon)
    }
}

/// `(lat, lon)` with a latitude past a pole carried over it along its meridian: within
/// [-90, 90], the longitude on the other side (+180 deg) and wrapped to [-180, 180).
fn over_the_pole(lat: f64, lon: f64) -> (f64, f64) {
    // lat in [-90, 270) after folding whole turns; (90, 270) is over the north pole (or,
    // past 180, over the south one too: 180 - lat < -90 cannot happen there).
    let l = (lat + 90.0).rem_euclid(360.0) - 90.0;
    if l > 90.0 {
        (180.0 - l, wrap_lon_deg(lon + 180.0))
    } else {
        (l, wrap_lon_deg(lon))
    }
}

/// A longitude wrapped to `[-180, 180)` degrees.
fn wrap_lon_deg(lon: f64) -> f64 {
    (lon + 180.0).rem_euclid(360.0) - 180.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One degree of latitude is `R pi / 180` = 111 195.08 m; one degree of longitude at 60 deg is
    /// half that.
    #[test]
    fn a_degree_is_r_pi_over_180() {
        let h = Home {
            lat_deg: 60.0,
            lon_deg: 10.0,
            alt_m: 0.0,
        };
        let m_per_deg = 6_371_008.8 * std::f64::consts::PI / 180.0;
        let (lat, lon) = h.to_lat_lon_deg(0.5 * m_per_deg, m_per_deg);
        assert!((lat - 61.0).abs() < 1e-12, "{lat}");
        assert!((lon - 11.0).abs() < 1e-9, "{lon}");
        let (x, y) = h.to_local_m(61.0, 11.0);
        assert!((x - 0.5 * m_per_deg).abs() < 1e-6 && (y - m_per_deg).abs() < 1e-6);
        // Across the antimeridian.
        let h = Home {
            lat_deg: 0.0,
            lon_deg: 179.9999,
            alt_m: 0.0,
        };
        let (_, lon) = h.to_lat_lon_deg(0.0002 * m_per_deg, 0.0);
        assert!((lon + 179.9999).abs() < 1e-9, "{lon}");
        let (x, _) = h.to_local_m(0.0, -179.9999);
        assert!((x - 0.0002 * m_per_deg).abs() < 1e-6, "{x}");
    }

    /// Home at 89 deg north, 10 deg east: two degrees of latitude north is one degree past
    /// the pole, latitude 89 on the meridian 190 = -170 deg; two degrees south of home at -89
    /// is latitude -89 on meridian -170. Every latitude sent stays within [-90, 90].
    #[test]
    fn a_point_past_a_pole_is_carried_over_it() {
        let m_per_deg = 6_371_008.8 * std::f64::consts::PI / 180.0;
        for (home_lat, dy_deg, lat_want, lon_want) in [
            (89.0, 2.0, 89.0, -170.0),
            (-89.0, -2.0, -89.0, -170.0),
            (89.0, 1.0, 90.0, 10.0),
            (89.0, -1.0, 88.0, 10.0),
            (89.0, 361.0, 90.0, 10.0),
        ] {
            let h = Home {
                lat_deg: home_lat,
                lon_deg: 10.0,
                alt_m: 0.0,
            };
            let (lat, lon) = h.to_lat_lon_deg(0.0, dy_deg * m_per_deg);
            assert!(
                (lat - lat_want).abs() < 1e-9,
                "{home_lat} + {dy_deg}: {lat}"
            );
            assert!(
                (lon - lon_want).abs() < 1e-9,
                "{home_lat} + {dy_deg}: {lon}"
            );
            let f = Frame {
                home: h,
                scale_lat_deg: home_lat,
            };
            assert_eq!(f.to_lat_lon_deg(0.0, dy_deg * m_per_deg), (lat, lon));
        }
    }
}
