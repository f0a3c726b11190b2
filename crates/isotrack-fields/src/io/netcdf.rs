//! NetCDF grids and grid time series (CF conventions), read by the pure-Rust `netcdf-reader`
//! crate: NetCDF-3 classic and 64-bit offset, NetCDF-4/HDF5 with zlib. No system library.
//!
//! The variable is the one named, or the first with two non-trivial spatial dimensions that is
//! neither a coordinate variable nor a CF bounds variable (named by a `bounds` attribute). Its
//! last two dimensions are (y, x) or (x, y), told apart by their names and their coordinates'
//! CF `axis`, `standard_name` and `units` ((y, x) when nothing says; refused when both are
//! the same axis or a dimension's signals disagree); one leading dimension longer than 1 is time
//! (its frames), any others must have length 1. Coordinates are the 1-D variables
//! named like those dimensions: longitude / latitude (CF `units = degrees_east / degrees_north`,
//! `standard_name`, or the names lon/longitude and lat/latitude) are projected to local metres
//! ([`crate::georef`]); coordinates in metres are used as they are. They must be regularly
//! spaced; decreasing axes are flipped. The time coordinate's CF `units = "<unit> since <date>"`
//! (seconds, minutes, hours or days) gives the frame times, in seconds after the first frame.
//! `_FillValue` / `missing_value` become no-data; `scale_factor` / `add_offset` are applied.
//! Projected coordinates in kilometres (`units = "km"`) are converted to metres, without
//! `units` they are metres (with a warning, [`LoadedSeries::warnings`]); a coordinate in any
//! other unit (`ft`, `degrees` on an axis that is not longitude or latitude), with several
//! `units` values, named longitude / latitude but in metres, or a longitude paired with a
//! length, is refused naming it. The data variable's `units` is
//! returned ([`LoadedSeries::units`]): a scenario without `field.units` takes it.

use super::error::LoadError;
use super::loaded::LoadedSeries;
use crate::georef::{lonlat_spacing_m, Georeference};
use crate::grid::Grid2;
use isotrack_core::Vec2;
use netcdf_reader::{NcFile, NcVariable};
use std::path::Path;

fn attr_str(v: &NcVariable, name: &str) -> Option<String> {
    v.attribute(name)?.value.as_string()
}

/// Why the reader could not decode `v`'s attribute `name`, when it is there but could not be
/// decoded: an HDF5 attribute whose shared (committed) datatype or shared dataspace was not
/// found. The reader keeps such an attribute, under its name, as an opaque value without
/// elements tagged [`hdf5_reader::messages::attribute::UNDECODABLE_TAG`] (patched in
/// vendor/hdf5-reader), so that the file still loads when the attribute is one isotrack does
/// not read (a `comment`), and one it reads is refused rather than taken as absent.
fn undecodable<'a>(v: &'a NcVariable, name: &str) -> Option<&'a str> {
    match &v.attribute(name)?.value {
        netcdf_reader::NcAttrValue::UserDefined {
            dtype: netcdf_reader::NcType::Opaque { tag, .. },
            ..
        } => tag.strip_prefix(hdf5_reader::messages::attribute::UNDECODABLE_TAG),
        _ => None,
    }
}

/// An error naming the variable and the first of the attributes `names` that is there but
/// could not be decoded ([`undecodable`]); `Ok` when none is.
fn refuse_undecodable(v: &NcVariable, names: &[&str]) -> Result<(), String> {
    for name in names {
        if let Some(why) = undecodable(v, name) {
            return Err(format!(
                "variable `{}`: its `{name}` attribute cannot be decoded ({}): isotrack reads it",
                isotrack_core::numtext::Escaped(v.name()),
                isotrack_core::numtext::Clipped(why)
            ));
        }
    }
    Ok(())
}

/// The attributes the reader applies to a variable's values as it reads them (packing,
/// `_Unsigned`) and, for the data variable, masks them with (fill, missing and valid values):
/// one that could not be decoded would be taken as absent, so the values would be wrong.
const VALUE_ATTRIBUTES: [&str; 8] = [
    "scale_factor",
    "add_offset",
    "_Unsigned",
    "_FillValue",
    "missing_value",
    "valid_min",
    "valid_max",
    "valid_range",
];

/// A coordinate's text attribute (`units`, `standard_name`, `axis`): `None` when absent, the
/// text when it is one (a `char` array or a single NC_STRING), an error naming the variable when
/// it is several strings (`["km", "m"]`: which one?) or numbers.
fn attr_text(v: &NcVariable, name: &str) -> Result<Option<String>, String> {
    use netcdf_reader::NcAttrValue;
    refuse_undecodable(v, &[name])?;
    let Some(a) = v.attribute(name) else {
        return Ok(None);
    };
    let text = match &a.value {
        NcAttrValue::Chars(s) => s.clone(),
        NcAttrValue::Strings(list) if list.len() == 1 => list[0].clone(),
        NcAttrValue::Strings(list) => {
            return Err(format!(
                "`{}` has {} values for its `{name}` attribute: need one text",
                isotrack_core::numtext::Escaped(v.name()),
                list.len()
            ))
        }
        _ => {
            return Err(format!(
                "`{}` has a `{name}` attribute that is not a text",
                v.name()
            ))
        }
    };
    if text.contains(char::REPLACEMENT_CHARACTER) {
        return Err(format!(
            "variable `{}`: its `{name}` attribute is not UTF-8 text (`{}`, the bytes that are not UTF-8 shown as U+FFFD): isotrack reads it, so write it in UTF-8",
            isotrack_core::numtext::Escaped(v.name()),
            isotrack_core::numtext::Clipped(&text)
        ));
    }
    // NUL padding at the end of a `char` attribute is the classic netCDF convention; any other
    // control character (an escape sequence, a NUL inside, a line break) or a bidirectional or
    // zero-width format character is no unit or name anyone writes, and would reach
    // `scenario.toml`, messages and figures.
    let text = text.trim_end_matches('\0').to_string();
    if text.chars().any(isotrack_core::numtext::is_not_plain) {
        return Err(format!(
            "variable `{}`: its `{name}` attribute holds a control or format character (`{}`): write it as plain text",
            isotrack_core::numtext::Escaped(v.name()),
            isotrack_core::numtext::Clipped(&text)
        ));
    }
    Ok(Some(text))
}

/// Which horizontal axis a dimension is: x (easting, longitude) or y (northing, latitude).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    X,
    Y,
}

/// The role of a dimension, from its name and its coordinate variable's attributes (CF 1.11
/// section 4: names x / lon / longitude and y / lat / latitude, `axis = "X" | "Y"`,
/// `standard_name` projection_x/y_coordinate, longitude / latitude, grid_longitude /
/// grid_latitude, `units` degrees_east / degrees_north). `Ok(None)` when nothing says; an error
/// when the signals disagree (a `y` in degrees_east).
fn dim_role(dim_name: &str, coord: Option<&NcVariable>) -> Result<Option<Role>, String> {
    let mut says: Vec<(Role, String)> = Vec::new();
    let by_name = |n: &str| match n.to_ascii_lowercase().as_str() {
        "x" | "lon" | "longitude" => Some(Role::X),
        "y" | "lat" | "latitude" => Some(Role::Y),
        _ => None,
    };
    if let Some(r) = by_name(dim_name) {
        says.push((r, format!("its name `{dim_name}`")));
    }
    if let Some(c) = coord {
        if let Some(a) = attr_text(c, "axis")? {
            match a.trim().to_ascii_uppercase().as_str() {
                "X" => says.push((Role::X, "axis = X".into())),
                "Y" => says.push((Role::Y, "axis = Y".into())),
                _ => {}
            }
        }
        if let Some(sn) = attr_text(c, "standard_name")? {
            let sn = sn.trim().to_ascii_lowercase();
            match sn.as_str() {
                "projection_x_coordinate" | "longitude" | "grid_longitude" => {
                    says.push((Role::X, format!("standard_name = {sn}")))
                }
                "projection_y_coordinate" | "latitude" | "grid_latitude" => {
                    says.push((Role::Y, format!("standard_name = {sn}")))
                }
                _ => {}
            }
        }
        if let Some(u) = attr_text(c, "units")? {
            let u = u.trim().to_ascii_lowercase();
            if u.starts_with("degrees_east") || u == "degree_east" {
                says.push((Role::X, format!("units = {u}")));
            } else if u.starts_with("degrees_north") || u == "degree_north" {
                says.push((Role::Y, format!("units = {u}")));
            }
        }
    }
    let Some((first, why)) = says.first() else {
        return Ok(None);
    };
    if let Some((_, other)) = says.iter().find(|(r, _)| r != first) {
        return Err(format!(
            "dimension `{}`: {why} says it is {}, {other} says {}",
            isotrack_core::numtext::Escaped(dim_name),
            if *first == Role::X { "x" } else { "y" },
            if *first == Role::X { "y" } else { "x" },
        ));
    }
    Ok(Some(*first))
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Axis {
    Lon,
    Lat,
    /// A length: metres per unit of the coordinate (1 for `m`, 1000 for `km`).
    Length(f64),
}

/// Metres per unit of a coordinate's CF `units` (UDUNITS spellings of metres and kilometres).
/// `None` for any other unit: such a coordinate is refused, never read as metres.
fn metres_per_unit(units: &str) -> Option<f64> {
    match units.trim().to_ascii_lowercase().as_str() {
        "m" | "metre" | "metres" | "meter" | "meters" => Some(1.0),
        "km" | "kilometre" | "kilometres" | "kilometer" | "kilometers" => Some(1000.0),
        _ => None,
    }
}

/// What a coordinate variable measures, or why it cannot be used (its `units`). A projected
/// coordinate without `units` (or with empty ones) is read as metres, as projected files often
/// leave them out, with a warning pushed onto `warnings` naming it.
fn axis_kind(v: &NcVariable, warnings: &mut Vec<String>) -> Result<Axis, String> {
    let raw_units = attr_text(v, "units")?.unwrap_or_default();
    let units = raw_units.trim().to_ascii_lowercase();
    let std = attr_text(v, "standard_name")?
        .unwrap_or_default()
        .trim()
        .to_ascii_lowercase();
    let name = v.name().to_ascii_lowercase();
    let named_lon = std == "longitude" || name == "lon" || name == "longitude";
    let named_lat = std == "latitude" || name == "lat" || name == "latitude";
    if (named_lon || named_lat) && metres_per_unit(&units).is_some() {
        return Err(format!(
            "coordinate `{}` is a {} by its name or standard_name but has units `{}` (a length): which is it?",
            isotrack_core::numtext::Escaped(v.name()),
            if named_lon { "longitude" } else { "latitude" },
            isotrack_core::numtext::Escaped(raw_units.trim())
        ));
    }
    if units.starts_with("degrees_east") || units == "degree_east" || named_lon {
        Ok(Axis::Lon)
    } else if units.starts_with("degrees_north") || units == "degree_north" || named_lat {
        Ok(Axis::Lat)
    } else if units.is_empty() {
        warnings.push(format!(
            "coordinate `{}` has no units: read as metres",
            isotrack_core::numtext::Escaped(v.name())
        ));
        Ok(Axis::Length(1.0))
    } else {
        metres_per_unit(&units).map(Axis::Length).ok_or_else(|| {
            format!(
                "coordinate `{}` has units `{}`: need metres (`m`), kilometres (`km`), or degrees_east / degrees_north for longitude / latitude",
                v.name(),
                isotrack_core::numtext::Escaped(raw_units.trim())
            )
        })
    }
}

/// The data variable's CF `units`, trimmed (`None` when absent or empty); an error when it is
/// not one UTF-8 text ([`attr_text`]).
fn data_units(v: &NcVariable) -> Result<Option<String>, String> {
    Ok(attr_text(v, "units")?
        .map(|u| u.trim().to_string())
        .filter(|u| !u.is_empty()))
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
            return Err(format!(
                "not regularly spaced (value {k} is {})",
                isotrack_core::numtext::Echo(*v)
            ));
        }
    }
    Ok((values[0], step))
}

/// A CF time unit, read from a `units` attribute by [`cf_time_unit_s`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum CfTimeUnit {
    /// Seconds per unit (1, 60, 3600, 86 400): `v` units are `v * s` seconds.
    Seconds(f64),
    /// Units per second (1000 for milliseconds, 1e6 for microseconds): `v` units are
    /// `v / n` seconds, one correctly rounded division, so `9 ms` is `0.009 s` bit for bit
    /// (`9 * 0.001` is not: 0.001 has no exact binary form).
    PerSecond(f64),
}

impl CfTimeUnit {
    /// `v` of this unit in seconds.
    pub(crate) fn to_s(self, v: f64) -> f64 {
        match self {
            CfTimeUnit::Seconds(s) => v * s,
            CfTimeUnit::PerSecond(n) => v / n,
        }
    }
}

/// The unit of a CF time `units` attribute (`hours since 2019-03-01 00:00:00`): seconds,
/// minutes, hours, days, and the sub-second milliseconds and microseconds xarray writes for
/// sub-second axes, with udunits' names and abbreviations (`ms`, `msec`, `us`, `usec`, `µs`).
/// The reference date must be a calendar date (`YYYY-MM-DD`, optionally a time `hh:mm:ss` and
/// a zone): `hours since 99999999-99-99` is refused, not read as hours from nowhere.
pub(crate) fn cf_time_unit_s(units: &str) -> Option<CfTimeUnit> {
    let unit = units.split_whitespace().next()?.to_lowercase();
    let lower = units.to_ascii_lowercase();
    let (_, reference) = lower.split_once(" since ")?;
    if !cf_reference_date_ok(reference) {
        return None;
    }
    Some(match unit.as_str() {
        "seconds" | "second" | "secs" | "sec" | "s" => CfTimeUnit::Seconds(1.0),
        "minutes" | "minute" | "mins" | "min" => CfTimeUnit::Seconds(60.0),
        "hours" | "hour" | "hrs" | "hr" | "h" => CfTimeUnit::Seconds(3600.0),
        "days" | "day" | "d" => CfTimeUnit::Seconds(86_400.0),
        "milliseconds" | "millisecond" | "msecs" | "msec" | "ms" => CfTimeUnit::PerSecond(1e3),
        "microseconds" | "microsecond" | "usecs" | "usec" | "us" | "\u{b5}s" | "\u{3bc}s" => {
            CfTimeUnit::PerSecond(1e6)
        }
        _ => return None,
    })
}

/// Whether a CF reference time (`1900-01-01`, `2019-03-01 00:00:00.0`, `1970-01-01T00:00:00Z`,
/// `2000-1-1 0:0:0 UTC`) is a date of a calendar: year of 1 to 4 digits, month 1-12, day 1-31,
/// and if given hour 0-24, minute 0-59, second 0-60 (leap second; fractions allowed). A zone
/// after the time is not read.
fn cf_reference_date_ok(reference: &str) -> bool {
    let reference = reference.trim();
    let (date, rest) = match reference.find([' ', 't']) {
        Some(i) => (&reference[..i], reference[i + 1..].trim()),
        None => (reference, ""),
    };
    let number = |s: &str, max_len: usize, lo: u32, hi: u32| {
        !s.is_empty()
            && s.len() <= max_len
            && s.bytes().all(|b| b.is_ascii_digit())
            && s.parse::<u32>().is_ok_and(|v| (lo..=hi).contains(&v))
    };
    let d: Vec<&str> = date.split('-').collect();
    if !(d.len() == 3
        && number(d[0], 4, 0, 9999)
        && number(d[1], 2, 1, 12)
        && number(d[2], 2, 1, 31))
    {
        return false;
    }
    let time = rest.split([' ', 'z', '+']).next().unwrap_or("");
    if time.is_empty() {
        return true;
    }
    let t: Vec<&str> = time.split(':').collect();
    let second_ok = |s: &str| {
        let whole = s.split('.').next().unwrap_or("");
        number(whole, 2, 0, 60) && s.parse::<f64>().is_ok_and(|v| v < 61.0)
    };
    match t.as_slice() {
        [h] => number(h, 2, 0, 24),
        [h, m] => number(h, 2, 0, 24) && number(m, 2, 0, 59),
        [h, m, s] => number(h, 2, 0, 24) && number(m, 2, 0, 59) && second_ok(s),
        _ => false,
    }
}

pub(super) fn parse(path: &Path, variable: Option<&str>) -> Result<LoadedSeries, LoadError> {
    // Read (size-limited by the caller) rather than mapped: the classic header is checked
    // before the reader sees it.
    let bytes = super::limits::read_limited(path, super::limits::MAX_GRID_FILE_BYTES)
        .map_err(|e| LoadError::cannot_read(path, e))?;
    parse_bytes(path, &bytes, variable)
}

/// Checks a classic (CDF-1, -2, -5) header's counts and sizes against the bytes that hold it,
/// before `netcdf-reader` allocates what they declare: a fuzzed header declaring 2^31 attribute
/// values made it abort (out of memory). NetCDF-4 (HDF5) files are passed through.
// Long by choice: a walk through the classic header in the order of its bytes (dimensions,
// global attributes, variables, each with its counts and sizes checked where they are read); the
// cursor and the offsets it checks run through the whole walk.
fn check_classic_header(bytes: &[u8]) -> Result<(), String> {
    if bytes.len() < 4 || &bytes[..3] != b"CDF" {
        return Ok(()); // HDF5 or not NetCDF: the reader says which
    }
    let version = bytes[3];
    if ![1, 2, 5].contains(&version) {
        return Err(format!("unknown classic NetCDF version {version}"));
    }
    // CDF-5 counts are 64-bit; CDF-2 and CDF-5 offsets are.
    let (wide, offset64) = (version == 5, version != 1);
    struct Cur<'a> {
        b: &'a [u8],
        at: usize,
    }
    impl Cur<'_> {
        fn take(&mut self, n: usize) -> Result<&[u8], String> {
            let end = self
                .at
                .checked_add(n)
                .filter(|e| *e <= self.b.len())
                .ok_or_else(|| {
                    format!(
                        "the header declares {n} bytes at offset {} beyond the file",
                        self.at
                    )
                })?;
            let s = &self.b[self.at..end];
            self.at = end;
            Ok(s)
        }
        fn u32(&mut self) -> Result<u64, String> {
            let s = self.take(4)?;
            Ok(u32::from_be_bytes([s[0], s[1], s[2], s[3]]) as u64)
        }
        fn u64(&mut self) -> Result<u64, String> {
            let s = self.take(8)?;
            let mut a = [0u8; 8];
            a.copy_from_slice(s);
            Ok(u64::from_be_bytes(a))
        }
        fn count(&mut self, wide: bool) -> Result<u64, String> {
            if wide {
                self.u64()
            } else {
                self.u32()
            }
        }
        /// A name: its length, then the characters padded to 4 bytes.
        fn name(&mut self, wide: bool) -> Result<(), String> {
            let n = self.count(wide)?;
            let padded = n.checked_add(3).ok_or("name length overflows")? / 4 * 4;
            self.take(usize::try_from(padded).map_err(|_| "name too long")?)?;
            Ok(())
        }
        /// A list header: tag (0 absent, or the expected tag) and element count, each element
        /// at least `min_bytes` long (so a count the file cannot hold is refused).
        fn list(&mut self, tag: u64, wide: bool, min_bytes: u64) -> Result<u64, String> {
            let t = self.u32()?;
            let n = self.count(wide)?;
            if t == 0 && n == 0 {
                return Ok(0);
            }
            if t != tag {
                return Err(format!("list tag {t:#x} where {tag:#x} was expected"));
            }
            let left = (self.b.len() - self.at) as u64;
            if n.saturating_mul(min_bytes) > left {
                return Err(format!(
                    "the header declares {n} entries; the file cannot hold them"
                ));
            }
            Ok(n)
        }
        fn attrs(&mut self, wide: bool) -> Result<(), String> {
            let n = self.list(0x0C, wide, 12)?;
            for _ in 0..n {
                self.name(wide)?;
                let ty = self.u32()?;
                let size = match ty {
                    1 | 2 | 7 => 1,
                    3 | 8 => 2,
                    4 | 5 | 9 => 4,
                    6 | 10 | 11 => 8,
                    t => return Err(format!("unknown attribute type {t}")),
                };
                let count = self.count(wide)?;
                let bytes = count
                    .checked_mul(size)
                    .and_then(|b| b.checked_add(3))
                    .ok_or("attribute size overflows")?
                    / 4
                    * 4;
                self.take(usize::try_from(bytes).map_err(|_| "attribute too large")?)?;
            }
            Ok(())
        }
    }
    let mut c = Cur { b: bytes, at: 4 };
    c.count(wide)?; // numrecs
    let ndims = c.list(0x0A, wide, 8)?;
    for _ in 0..ndims {
        c.name(wide)?;
        c.count(wide)?;
    }
    c.attrs(wide)?;
    let nvars = c.list(0x0B, wide, 16)?;
    for _ in 0..nvars {
        c.name(wide)?;
        let nd = c.count(wide)?;
        let per = if wide { 8 } else { 4 };
        c.take(usize::try_from(nd.saturating_mul(per)).map_err(|_| "too many dimensions")?)?;
        c.attrs(wide)?;
        c.u32()?; // type
        c.count(wide)?; // vsize
        if offset64 {
            c.u64()?;
        } else {
            c.u32()?;
        }
    }
    Ok(())
}

/// As [`parse`], from the file's bytes (`name` names it in errors; the fuzz targets' entry).
pub(super) fn parse_bytes(
    name: &Path,
    bytes: &[u8],
    variable: Option<&str>,
) -> Result<LoadedSeries, LoadError> {
    // The budget is asked for only when a file gets as far as its size check: reading it costs
    // five files of /proc and /sys, more than refusing most malformed files.
    parse_bytes_with(name, bytes, variable, super::limits::memory_budget_bytes)
}

/// As [`parse_bytes`], with `budget_bytes` of memory to load the variable in
/// ([`super::limits::check_series_size`]).
#[cfg(test)]
pub(super) fn parse_bytes_within(
    name: &Path,
    bytes: &[u8],
    variable: Option<&str>,
    budget_bytes: Option<u64>,
) -> Result<LoadedSeries, LoadError> {
    parse_bytes_with(name, bytes, variable, || budget_bytes)
}

/// As [`parse_bytes`], the memory budget from `budget_bytes` when the size is checked.
fn parse_bytes_with(
    name: &Path,
    bytes: &[u8],
    variable: Option<&str>,
    budget_bytes: impl FnOnce() -> Option<u64>,
) -> Result<LoadedSeries, LoadError> {
    check_classic_header(bytes).map_err(|m| {
        LoadError::new(
            name,
            Some(super::error::FilePosition::Offset(0)),
            format!("not a valid NetCDF file: {m}"),
        )
    })?;
    if !bytes.starts_with(HDF5_SIGNATURE) {
        return parse_classic(name, bytes, variable, budget_bytes);
    }
    parse_netcdf4(name, bytes, variable, budget_bytes)
}

/// The reader's refusal of file `name`, `why` clipped: "cannot read as NetCDF: ...".
fn cannot_read(name: &Path, why: &str) -> LoadError {
    LoadError::new(
        name,
        None,
        format!(
            "cannot read as NetCDF: {}",
            isotrack_core::numtext::Clipped(why)
        ),
    )
}

/// A file that does not start with the HDF5 signature: NetCDF-3 (or an HDF5 file behind a
/// user block: its attributes are read as the reader reads them, its groups checked to form a
/// tree first, [`check_group_tree`]).
fn parse_classic(
    name: &Path,
    bytes: &[u8],
    variable: Option<&str>,
    budget_bytes: impl FnOnce() -> Option<u64>,
) -> Result<LoadedSeries, LoadError> {
    let cannot = |e: netcdf_reader::Error| cannot_read(name, &e.to_string());
    let file = NcFile::from_bytes(bytes).map_err(cannot)?;
    if matches!(
        file.format(),
        netcdf_reader::NcFormat::Nc4 | netcdf_reader::NcFormat::Nc4Classic
    ) {
        if let Ok(h5) = hdf5_reader::Hdf5File::from_bytes(bytes) {
            check_group_tree(&h5).map_err(|m| cannot_read(name, &m))?;
        }
    }
    let vars = file.variables().map_err(cannot)?;
    parse_file(name, &file, vars, variable, budget_bytes)
}

/// A NetCDF-4 file: its groups checked to form a tree ([`check_group_tree`]), then read by the
/// strict reader, or leniently ([`parse_lenient`]) where the strict reader refuses a text
/// attribute that is not UTF-8 or a dataset without dimension scales. The bytes are shared by
/// the reader and the second look at the needed text attributes
/// ([`restore_cut_text_attributes`]), one copy as `from_bytes` makes.
fn parse_netcdf4(
    name: &Path,
    bytes: &[u8],
    variable: Option<&str>,
    budget_bytes: impl FnOnce() -> Option<u64>,
) -> Result<LoadedSeries, LoadError> {
    let cannot = |e: netcdf_reader::Error| cannot_read(name, &e.to_string());
    let shared: std::sync::Arc<[u8]> = std::sync::Arc::from(bytes);
    if let Ok(h5) = hdf5_reader::Hdf5File::from_shared_bytes(shared.clone()) {
        check_group_tree(&h5).map_err(|m| cannot_read(name, &m))?;
    }
    let file = NcFile::from_shared_bytes(shared.clone()).map_err(cannot)?;
    match file.variables() {
        Ok(vars) => {
            let mut vars = vars.to_vec();
            restore_cut_text_attributes(&shared, &mut vars);
            parse_file(name, &file, &vars, variable, budget_bytes)
        }
        Err(e) if is_non_utf8_text(&e) || is_missing_dimension_list(&e) => {
            parse_lenient(name, &shared, e, variable, budget_bytes)
        }
        Err(e) => Err(cannot(e)),
    }
}

/// A NetCDF-4 file the strict reader refused with `strict` for a text attribute that is not
/// UTF-8 (a Latin-1 `comment` or `history` from an older tool) or a dataset without dimension
/// scales, where the classic reader (NetCDF-3) reads such bytes as U+FFFD. Opened again
/// leniently, the variables' text attributes that are not UTF-8 are read here as the classic
/// reader reads them; `attr_text` refuses one isotrack reads (`units`, `axis`, ...).
fn parse_lenient(
    name: &Path,
    shared: &std::sync::Arc<[u8]>,
    strict: netcdf_reader::Error,
    variable: Option<&str>,
    budget_bytes: impl FnOnce() -> Option<u64>,
) -> Result<LoadedSeries, LoadError> {
    let cannot = |e: netcdf_reader::Error| cannot_read(name, &e.to_string());
    let bytes: &[u8] = shared;
    let lenient = NcFile::from_bytes_with_options(
        bytes,
        netcdf_reader::NcOpenOptions {
            metadata_mode: netcdf_reader::NcMetadataMode::Lossy,
            ..Default::default()
        },
    )
    .map_err(cannot)?;
    // Datasets without dimension scales (an HDF5 tool's dataset beside the netCDF variables:
    // netCDF-C gives them phony dimensions, xarray opens the file) are left out: isotrack never
    // reads them, and the lenient reader would give them dimensions guessed by size. The
    // variable asked for is refused for it, with the strict reader's error (issue 30,
    // att30c-8).
    let unscaled = datasets_without_dimension_scales(bytes);
    if variable.is_some_and(|v| unscaled.iter().any(|u| u == v)) {
        return Err(cannot(strict));
    }
    let mut vars = lenient.variables().map_err(cannot)?.to_vec();
    vars.retain(|v| !unscaled.contains(&v.name));
    restore_non_utf8_attributes(bytes, &mut vars);
    restore_cut_text_attributes(shared, &mut vars);
    parse_file(name, &lenient, &vars, variable, budget_bytes)
}

/// The deepest nesting of groups below the root read, as netcdf-reader's own limit ("NetCDF
/// group nesting exceeds 64").
const MAX_GROUP_DEPTH: usize = 64;

/// Refuses a NetCDF-4 file whose groups do not form a tree of at most [`MAX_GROUP_DEPTH`]
/// levels, before the reader builds its group tree: a group holding a hard link to itself or
/// to an ancestor (legal HDF5: h5py `g["loop"] = g`, `g["up"] = f["/"]`) made netcdf-reader
/// 0.12.1 (`build_group_recursive`, which keeps no visited set) recurse until the stack
/// overflowed, aborting the process (issue 30, att30d-7). The graph is walked here without
/// recursion, each group known by its object header address: a group met a second time is
/// refused, as a cycle when it is an ancestor of the link (`/g/loop` back to `/g`), as a group
/// linked twice otherwise (the NetCDF data model's groups form a tree, and a group shared by
/// two links at every level doubles the reader's work per level). A group whose members
/// cannot be listed is left for the reader, which refuses it with its own error.
fn check_group_tree(h5: &hdf5_reader::Hdf5File) -> Result<(), String> {
    let Ok(root) = h5.root_group() else {
        return Ok(());
    };
    let mut seen: std::collections::HashMap<u64, String> =
        std::collections::HashMap::from([(root.address(), "/".to_string())]);
    let mut stack = vec![(root, String::new(), 0_usize)];
    while let Some((group, path, depth)) = stack.pop() {
        let Ok(children) = group.groups() else {
            continue;
        };
        // Walked in listing order (the stack pops the first child first).
        let mut found = Vec::with_capacity(children.len());
        for child in children {
            let leaf = child.name().rsplit('/').next().unwrap_or_default();
            let child_path = format!("{path}/{leaf}");
            if let Some(first) = seen.get(&child.address()) {
                let ancestor = first == "/" || child_path.starts_with(&format!("{first}/"));
                return Err(if ancestor {
                    format!(
                        "a group links back to an ancestor (a group cycle; NetCDF groups form \
                         a tree): {child_path} -> {first}"
                    )
                } else {
                    format!(
                        "a group is linked twice (NetCDF groups form a tree): {first} and \
                         {child_path}"
                    )
                });
            }
            if depth + 1 > MAX_GROUP_DEPTH {
                return Err(format!(
                    "group nesting exceeds {MAX_GROUP_DEPTH} levels at {child_path}"
                ));
            }
            seen.insert(child.address(), child_path.clone());
            found.push((child, child_path, depth + 1));
        }
        stack.extend(found.into_iter().rev());
    }
    Ok(())
}

/// The signature an HDF5 file (a NetCDF-4 file) starts with.
const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

/// The text attributes isotrack reads from a variable ([`attr_text`]).
const NEEDED_TEXT_ATTRIBUTES: [&str; 3] = ["units", "axis", "standard_name"];

/// The needed text attributes ([`NEEDED_TEXT_ATTRIBUTES`]) of the root group's variables that
/// hold a NUL before their end (`"m\0 junk"`), given their whole text in `vars`: the reader
/// cuts a null-terminated HDF5 string at its first NUL (`"m"`), which would take a damaged
/// `units` for a good one. With the whole text (trailing padding NULs removed, the NUL inside
/// kept), [`attr_text`] refuses it as a control character, naming the variable and the
/// attribute. Attributes without a NUL inside are left as the reader read them; nothing
/// changes when the file cannot be walked again.
fn restore_cut_text_attributes(bytes: &std::sync::Arc<[u8]>, vars: &mut [NcVariable]) {
    use hdf5_reader::messages::datatype::{Datatype, StringPadding, StringSize, VarLenKind};
    use netcdf_reader::NcAttrValue;
    let Ok(h5) = hdf5_reader::Hdf5File::from_shared_bytes(bytes.clone()) else {
        return;
    };
    let Ok(root) = h5.root_group() else {
        return;
    };
    let Ok(datasets) = root.datasets() else {
        return;
    };
    for ds in datasets {
        let leaf = ds.name().rsplit('/').next().unwrap_or_default();
        let Some(var) = vars.iter_mut().find(|v| v.name == leaf) else {
            continue;
        };
        for a in ds.attributes() {
            if !NEEDED_TEXT_ATTRIBUTES.contains(&a.name.as_str())
                || a.num_elements().ok() != Some(1)
            {
                continue;
            }
            let (raw, padding): (&[u8], StringPadding) = match &a.datatype {
                Datatype::String {
                    size: StringSize::Fixed(len),
                    padding,
                    ..
                } => (
                    &a.raw_data[..(*len as usize).min(a.raw_data.len())],
                    *padding,
                ),
                // One variable-length string: the reader resolved its bytes already.
                Datatype::String {
                    size: StringSize::Variable,
                    padding,
                    ..
                }
                | Datatype::VarLen {
                    kind: VarLenKind::String,
                    padding,
                    ..
                } => (&a.raw_data[..], *padding),
                _ => continue,
            };
            // The padding the type declares at the end: NULs (or spaces) after the text.
            let pad = if padding == StringPadding::SpacePad {
                b' '
            } else {
                0
            };
            let end = raw.iter().rposition(|&b| b != pad).map_or(0, |i| i + 1);
            let text = &raw[..end];
            if !text.contains(&0) {
                continue;
            }
            // Only where the reader's text is the part before the first NUL: the same
            // attribute, cut (not bytes that are something else, such as a reference the
            // reader could not resolve).
            let before_nul = String::from_utf8_lossy(text.split(|&b| b == 0).next().unwrap_or(&[]));
            let Some(at) = var.attributes.iter_mut().find(|x| x.name == a.name) else {
                continue;
            };
            let cut = match &at.value {
                NcAttrValue::Chars(t) => t.trim_end_matches('\0') == before_nul,
                NcAttrValue::Strings(list) if list.len() == 1 => {
                    list[0].trim_end_matches('\0') == before_nul
                }
                _ => false,
            };
            if cut {
                at.value = NcAttrValue::Chars(String::from_utf8_lossy(text).into_owned());
            }
        }
    }
}

/// Whether the reader refused a NetCDF-4 file for a dataset with no dimension scales
/// (`dataset 'extra' is missing required DIMENSION_LIST metadata`).
fn is_missing_dimension_list(e: &netcdf_reader::Error) -> bool {
    e.to_string().contains("is missing required DIMENSION_LIST")
}

/// The root group's datasets with dimensions but no `DIMENSION_LIST` that are not dimension
/// scales themselves: what netCDF-C reads with phony dimensions. Empty when the file cannot be
/// walked.
fn datasets_without_dimension_scales(bytes: &[u8]) -> Vec<String> {
    let Ok(h5) = hdf5_reader::Hdf5File::from_bytes(bytes) else {
        return vec![];
    };
    let Ok(datasets) = h5.root_group().and_then(|r| r.datasets()) else {
        return vec![];
    };
    datasets
        .iter()
        .filter(|ds| {
            let scale = ds
                .attribute("CLASS")
                .and_then(|a| a.read_string())
                .is_ok_and(|c| c == "DIMENSION_SCALE");
            ds.ndim() > 0 && !scale && ds.attribute("DIMENSION_LIST").is_err()
        })
        .map(|ds| ds.name().rsplit('/').next().unwrap_or_default().to_string())
        .collect()
}

/// Whether the reader refused a NetCDF-4 file for a text attribute that is not UTF-8
/// (`attribute 'comment' could not be decoded: ... invalid string data: invalid utf-8 ...`).
fn is_non_utf8_text(e: &netcdf_reader::Error) -> bool {
    let m = e.to_string();
    m.contains("could not be decoded") && m.contains("invalid string data")
}

/// `bytes` as text, those that are not UTF-8 replaced by U+FFFD as the classic NetCDF reader
/// does, padding cut off (at the first NUL, or trailing NULs / spaces as the type pads).
fn lossy_text(bytes: &[u8], padding: hdf5_reader::messages::datatype::StringPadding) -> String {
    use hdf5_reader::messages::datatype::StringPadding;
    let end = match padding {
        StringPadding::NullTerminate => bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len()),
        StringPadding::NullPad => bytes.iter().rposition(|&b| b != 0).map_or(0, |i| i + 1),
        StringPadding::SpacePad => bytes.iter().rposition(|&b| b != b' ').map_or(0, |i| i + 1),
    };
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

/// The text attributes of the root group's variables that the lenient reader left out because
/// they are not UTF-8, added to `vars` with U+FFFD for the bytes that are not (one text, or
/// one per element of an array). Nothing is added when the file cannot be walked again.
fn restore_non_utf8_attributes(bytes: &[u8], vars: &mut [netcdf_reader::NcVariable]) {
    use hdf5_reader::messages::datatype::{Datatype, StringSize, VarLenKind};
    use netcdf_reader::{NcAttrValue, NcAttribute};
    let Ok(h5) = hdf5_reader::Hdf5File::from_bytes(bytes) else {
        return;
    };
    let Ok(root) = h5.root_group() else {
        return;
    };
    let Ok(datasets) = root.datasets() else {
        return;
    };
    let reference_bytes = 4 + usize::from(root.offset_size()) + 4;
    for ds in datasets {
        let leaf = ds.name().rsplit('/').next().unwrap_or_default();
        let Some(var) = vars.iter_mut().find(|v| v.name == leaf) else {
            continue;
        };
        for a in ds.attributes() {
            if var.attribute(&a.name).is_some() {
                continue;
            }
            let n = a.num_elements().unwrap_or(0) as usize;
            let texts: Vec<String> = match &a.datatype {
                Datatype::String {
                    size: StringSize::Fixed(len),
                    padding,
                    ..
                } if *len > 0 => a
                    .raw_data
                    .chunks(*len as usize)
                    .take(n)
                    .map(|c| lossy_text(c, *padding))
                    .collect(),
                Datatype::String {
                    size: StringSize::Variable,
                    padding,
                    ..
                }
                | Datatype::VarLen {
                    kind: VarLenKind::String,
                    padding,
                    ..
                } => {
                    if n == 1 {
                        // One element: the reader resolved its bytes already.
                        vec![lossy_text(&a.raw_data, *padding)]
                    } else {
                        a.raw_data
                            .chunks(reference_bytes)
                            .take(n)
                            .map(|r| {
                                root.resolve_vlen_reference_bytes(r, 1)
                                    .map(|b| lossy_text(&b, *padding))
                                    .unwrap_or_else(|_| char::REPLACEMENT_CHARACTER.into())
                            })
                            .collect()
                    }
                }
                _ => continue,
            };
            let value = match (a.shape.is_empty(), texts.len()) {
                (true, 1) => NcAttrValue::Chars(texts.into_iter().next().unwrap_or_default()),
                _ => NcAttrValue::Strings(texts),
            };
            var.attributes.push(NcAttribute {
                name: a.name.clone(),
                value,
            });
        }
    }
}

/// The grid series of `file`, whose root variables are `vars` (the reader's, or with the
/// text attributes that are not UTF-8 restored: [`restore_non_utf8_attributes`]).
fn parse_file(
    path: &Path,
    file: &NcFile,
    vars: &[NcVariable],
    variable: Option<&str>,
    budget_bytes: impl FnOnce() -> Option<u64>,
) -> Result<LoadedSeries, LoadError> {
    let err = |m: String| LoadError::new(path, None, m);
    let var = data_variable(path, file, vars, variable)?;
    let layout = frame_layout(path, var, vars)?;
    let (nx, ny, n_frames) = (layout.nx, layout.ny, layout.n_frames);
    // Checked before reading: the header's sizes are the file's claim, not a promise (a
    // never-written chunked variable of 4 x 16000 x 16000 fill values is a 10 KB file).
    super::limits::check_series_size(path, n_frames, nx, ny, budget_bytes())?;
    check_packing(path, var)?;
    let units = data_units(var).map_err(err)?;
    let values = read_values(path, file, var, &layout)?;
    let frame_times_s = match layout.time {
        None => None,
        Some(tdim) => frame_times(path, file, vars, tdim)?,
    };
    let xc = coord_values(path, file, vars, &layout.xdim.name)?;
    let yc = coord_values(path, file, vars, &layout.ydim.name)?;
    let mut warnings = Vec::new();
    let placement = match (xc, yc) {
        (Some(x), Some(y)) => placement(path, x, y, &layout, &mut warnings)?,
        _ => Placement::default(),
    };
    Ok(LoadedSeries {
        frames: into_frames(path, values, &layout, &placement)?,
        frame_times_s,
        georeference: placement.georeference,
        units,
        warnings: warnings
            .into_iter()
            .map(|w| {
                format!(
                    "{}: {}",
                    isotrack_core::numtext::Escaped(&path.display().to_string()),
                    isotrack_core::numtext::Escaped(&w)
                )
            })
            .collect(),
    })
}

/// The data variable: the one named, or the first with two non-trivial trailing dimensions
/// that is neither a coordinate variable nor a CF bounds variable.
fn data_variable<'a>(
    path: &Path,
    file: &NcFile,
    vars: &'a [NcVariable],
    variable: Option<&str>,
) -> Result<&'a NcVariable, LoadError> {
    let err = |m: String| LoadError::new(path, None, m);
    let nc = |e: netcdf_reader::Error| {
        err(format!(
            "cannot read as NetCDF: {}",
            isotrack_core::numtext::Clipped(&e.to_string())
        ))
    };
    let dim_names: Vec<&str> = file
        .dimensions()
        .map_err(nc)?
        .iter()
        .map(|d| d.name.as_str())
        .collect();
    let names = || vars.iter().map(|v| v.name()).collect::<Vec<_>>();
    // CF cell bounds (`lat_bnds(lat, nv)`, named by a coordinate's `bounds` or `climatology`
    // attribute) are 2-D too, and xarray writes them before the data: never the data variable.
    let bounds: Vec<String> = vars
        .iter()
        .flat_map(|v| [attr_str(v, "bounds"), attr_str(v, "climatology")])
        .flatten()
        .collect();
    if variable.is_none() {
        // Which variables are bounds decides which is the data variable.
        for v in vars {
            refuse_undecodable(v, &["bounds", "climatology"]).map_err(err)?;
        }
    }
    match variable {
        Some(n) => vars
            .iter()
            .find(|v| v.name() == n)
            .ok_or_else(|| err(format!("no variable `{n}`; the file has {:?}", names()))),
        None => vars
            .iter()
            .find(|v| {
                !dim_names.contains(&v.name())
                    && !bounds.iter().any(|b| b == v.name())
                    && v.dimensions().len() >= 2
                    && v.dimensions()[v.dimensions().len() - 2..]
                        .iter()
                        .all(|d| d.size > 1)
            })
            .ok_or_else(|| err("no 2-D data variable (give field.variable)".into())),
    }
}

/// How a data variable's values make frames: its time dimension (the one leading dimension
/// longer than 1, if any), its y and x dimensions, their sizes, and whether it is stored (x, y).
struct Layout<'a> {
    time: Option<&'a netcdf_reader::NcDimension>,
    ydim: &'a netcdf_reader::NcDimension,
    xdim: &'a netcdf_reader::NcDimension,
    nx: usize,
    ny: usize,
    n_frames: usize,
    transposed: bool,
}

/// The [`Layout`] of `var`, or an error when its dimensions are not (y, x), (x, y) or one of
/// those after a time dimension (other leading dimensions of length 1), or a frame is smaller
/// than 2 x 2.
fn frame_layout<'a>(
    path: &Path,
    var: &'a NcVariable,
    vars: &[NcVariable],
) -> Result<Layout<'a>, LoadError> {
    let err = |m: String| LoadError::new(path, None, m);
    let dims = var.dimensions();
    let lead = &dims[..dims.len().saturating_sub(2)];
    let long_lead: Vec<_> = lead.iter().filter(|d| d.size != 1).collect();
    if dims.len() < 2 || long_lead.len() > 1 {
        return Err(err(format!(
            "variable `{}` has dimensions {:?}; need (y, x), or (time, y, x) with any other leading dimension of length 1",
            var.name(),
            dims.iter().map(|d| (d.name.as_str(), d.size)).collect::<Vec<_>>()
        )));
    }
    // Which of the last two dimensions is x: by their names and coordinate variables' CF
    // attributes. CF recommends (t, y, x), but xarray's `.transpose("x", "y")` and netCDF4
    // write (x, y) as readily; read as (y, x) such a grid is mirrored about its diagonal
    // with nothing to show it. Stored (x, y), each frame is transposed after reading.
    let (a, b) = (&dims[dims.len() - 2], &dims[dims.len() - 1]);
    let coord_var = |name: &str| {
        vars.iter().find(|v| {
            v.name() == name && v.dimensions().len() == 1 && v.dimensions()[0].name == name
        })
    };
    let role = |d: &netcdf_reader::NcDimension| {
        dim_role(&d.name, coord_var(&d.name))
            .map_err(|m| err(format!("variable `{}`: {m}", var.name())))
    };
    let transposed = match (role(a)?, role(b)?) {
        (Some(Role::Y), Some(Role::X))
        | (Some(Role::Y), None)
        | (None, Some(Role::X))
        | (None, None) => false,
        (Some(Role::X), Some(Role::Y)) | (Some(Role::X), None) | (None, Some(Role::Y)) => true,
        (Some(ra), Some(_)) => {
            return Err(err(format!(
                "variable `{}` has dimensions ({}, {}), both {} by their names and coordinates: cannot tell x from y (name them x / y or lon / lat, or give their coordinates `axis = \"X\"` / `\"Y\"`)",
                var.name(),
                isotrack_core::numtext::Escaped(&a.name),
                isotrack_core::numtext::Escaped(&b.name),
                if ra == Role::X { "x" } else { "y" }
            )))
        }
    };
    let (ydim, xdim) = if transposed { (b, a) } else { (a, b) };
    let (ny, nx) = (ydim.size as usize, xdim.size as usize);
    let n_frames = long_lead.first().map_or(1, |d| d.size as usize);
    if nx < 2 || ny < 2 || n_frames < 1 {
        return Err(err(format!(
            "variable `{}` is {n_frames} x {ny} x {nx}: a frame needs at least 2 x 2 values",
            var.name()
        )));
    }
    Ok(Layout {
        time: long_lead.first().copied(),
        ydim,
        xdim,
        nx,
        ny,
        n_frames,
        transposed,
    })
}

/// Issue 30 (att30c-1): the reader takes the first number of a value attribute and ignores
/// one that is no number, so `scale_factor = "2"` (a text), `[2.0, 3.0]` (which one?), `[]`,
/// `0` or `5e-324` (every value 0 or a subnormal) and `_FillValue = "20"` were read as if
/// absent or half-read, with values silently wrong. Each of `names` present on `var` (but
/// `_Unsigned`, a text by convention) must be numbers, as many as netCDF-C takes (one;
/// `missing_value` one or more; `valid_range` two), and a `scale_factor` must be a normal
/// (not zero, not subnormal) number. `Err` names the variable and the attribute.
fn check_value_attributes(var: &NcVariable, names: &[&str]) -> Result<(), String> {
    use isotrack_core::numtext::{Clipped, Echo, Escaped};
    use netcdf_reader::NcAttrValue;
    for &name in names.iter().filter(|n| **n != "_Unsigned") {
        let Some(a) = var.attribute(name) else {
            continue;
        };
        let at = format!("variable `{}`: attribute `{name}`", Escaped(var.name()));
        let Some(values) = a.value.as_f64_vec() else {
            return Err(match &a.value {
                NcAttrValue::Chars(t) => format!(
                    "{at} is a text (`{}`), not a number: write it as a number of the variable's type",
                    Clipped(t)
                ),
                NcAttrValue::Strings(_) => format!("{at} holds strings, not a number"),
                _ => format!("{at} is of a user-defined type, not a number"),
            });
        };
        let need = match name {
            "missing_value" => (1, usize::MAX, "one or more"),
            "valid_range" => (2, 2, "two (min, max)"),
            _ => (1, 1, "one"),
        };
        if values.len() < need.0 || values.len() > need.1 {
            return Err(format!("{at} has {} values: need {}", values.len(), need.2));
        }
        if name == "scale_factor" {
            let x = values[0];
            if x == 0.0 {
                return Err(format!(
                    "{at} is 0: a scale of 0 packs nothing (every value would be 0)"
                ));
            }
            if x.is_finite() && !x.is_normal() {
                return Err(format!(
                    "{at} is {}, a subnormal number: no packing uses a scale that small",
                    Echo(x)
                ));
            }
        }
    }
    Ok(())
}

/// A packing attribute that is not finite turns every value into NaN; say so, rather than
/// "every value is NaN / no-data". One of [`VALUE_ATTRIBUTES`] that could not be decoded is
/// refused naming it ([`refuse_undecodable`]).
fn check_packing(path: &Path, var: &NcVariable) -> Result<(), LoadError> {
    refuse_undecodable(var, &VALUE_ATTRIBUTES).map_err(|m| LoadError::new(path, None, m))?;
    check_value_attributes(var, &VALUE_ATTRIBUTES).map_err(|m| LoadError::new(path, None, m))?;
    for a in ["scale_factor", "add_offset"] {
        if let Some(x) = var
            .attribute(a)
            .and_then(|at| at.value.as_f64_vec())
            .and_then(|v| v.into_iter().find(|x| !x.is_finite()))
        {
            return Err(LoadError::new(
                path,
                None,
                format!(
                    "variable `{}`: attribute `{a}` is {x}, not a finite number",
                    isotrack_core::numtext::Escaped(var.name())
                ),
            ));
        }
    }
    Ok(())
}

/// The data variable's values, unpacked and masked (not finite: NaN), each frame row-major
/// (y, x) in file order.
fn read_values(
    path: &Path,
    file: &NcFile,
    var: &NcVariable,
    layout: &Layout,
) -> Result<Vec<f64>, LoadError> {
    let err = |m: String| LoadError::new(path, None, m);
    let (nx, ny, n_frames) = (layout.nx, layout.ny, layout.n_frames);
    let data = file
        .read_variable_unpacked_masked(var.name())
        .map_err(|e| err(format!("cannot read `{}`: {e}", var.name())))?;
    // Taken over rather than copied (the array is in standard order as read).
    let mut values: Vec<f64> = if data.is_standard_layout() {
        let (mut v, offset) = data.into_raw_vec_and_offset();
        v.drain(..offset.unwrap_or(0).min(v.len()));
        v
    } else {
        data.iter().copied().collect()
    };
    for v in &mut values {
        if !v.is_finite() {
            *v = f64::NAN;
        }
    }
    if values.len() != nx * ny * n_frames {
        return Err(err(format!(
            "{} values for {n_frames} x {ny} x {nx}",
            values.len()
        )));
    }
    if layout.transposed {
        // Each frame stored x-major (value (ix, iy) at ix * ny + iy) to row-major (iy * nx + ix).
        let mut row_major = vec![0.0; nx * ny];
        for frame in values.chunks_mut(nx * ny) {
            for (ix, column) in frame.chunks(ny).enumerate() {
                for (iy, v) in column.iter().enumerate() {
                    row_major[iy * nx + ix] = *v;
                }
            }
            frame.copy_from_slice(&row_major);
        }
    }
    Ok(values)
}

/// The values of the coordinate variable of dimension `name`, with the variable; `None` when
/// the file has none.
///
/// A coordinate variable is 1-D along the dimension of its own name (CF 1.11 section 1.3), so
/// its size is the dimension's, already within the checked size: a variable `x(big)` named
/// like the dimension `x` but along another, huge dimension is not read.
fn coord_values<'a>(
    path: &Path,
    file: &NcFile,
    vars: &'a [NcVariable],
    name: &str,
) -> Result<Option<(Vec<f64>, &'a NcVariable)>, LoadError> {
    match vars
        .iter()
        .find(|v| v.name() == name && v.dimensions().len() == 1 && v.dimensions()[0].name == name)
    {
        None => Ok(None),
        Some(c) => {
            refuse_undecodable(c, &VALUE_ATTRIBUTES[..3])
                .and_then(|()| check_value_attributes(c, &VALUE_ATTRIBUTES[..2]))
                .map_err(|m| LoadError::new(path, None, m))?;
            let vals = file.read_variable_unpacked(name).map_err(|e| {
                LoadError::new(path, None, format!("cannot read coordinate `{name}`: {e}"))
            })?;
            Ok(Some((vals.iter().copied().collect(), c)))
        }
    }
}

/// Frame times from the CF time coordinate of `tdim`, seconds after the first frame; `None`
/// when the file has no such coordinate.
fn frame_times(
    path: &Path,
    file: &NcFile,
    vars: &[NcVariable],
    tdim: &netcdf_reader::NcDimension,
) -> Result<Option<Vec<f64>>, LoadError> {
    let err = |m: String| LoadError::new(path, None, m);
    let Some((t, tv)) = coord_values(path, file, vars, &tdim.name)? else {
        return Ok(None);
    };
    let units = attr_text(tv, "units").map_err(err)?.unwrap_or_default();
    let unit_s = cf_time_unit_s(&units).ok_or_else(|| {
        err(format!(
            "time coordinate `{}` has units `{}`; need `<days|hours|minutes|seconds|milliseconds|microseconds> since <date>`",
            isotrack_core::numtext::Escaped(&tdim.name),
            isotrack_core::numtext::Clipped(&units)
        ))
    })?;
    Ok(Some(t.iter().map(|v| unit_s.to_s(v - t[0])).collect()))
}

/// Where the frames lie, from the x and y coordinates: the georeference, the origin and
/// spacing in local metres, and whether rows (y) or columns (x) run backwards in the file.
struct Placement {
    georeference: Georeference,
    origin: Vec2,
    spacing: [f64; 2],
    flip_y: bool,
    flip_x: bool,
}

impl Default for Placement {
    /// No coordinates: no georeference, 1 m spacing from the origin.
    fn default() -> Self {
        Self {
            georeference: Georeference::None,
            origin: Vec2::default(),
            spacing: [1.0, 1.0],
            flip_y: false,
            flip_x: false,
        }
    }
}

/// The [`Placement`] of the x coordinate `(xs, xv)` and y coordinate `(ys, yv)`: longitude and
/// latitude (projected to local metres), or two lengths (kilometres converted to metres),
/// regularly spaced.
fn placement(
    path: &Path,
    (xs, xv): (Vec<f64>, &NcVariable),
    (ys, yv): (Vec<f64>, &NcVariable),
    layout: &Layout,
    warnings: &mut Vec<String>,
) -> Result<Placement, LoadError> {
    let err = |m: String| LoadError::new(path, None, m);
    let (xdim, ydim, nx, ny) = (layout.xdim, layout.ydim, layout.nx, layout.ny);
    let kx = axis_kind(xv, warnings).map_err(err)?;
    let ky = axis_kind(yv, warnings).map_err(err)?;
    let (lonlat, [fx, fy]) = match (kx, ky) {
        (Axis::Lon, Axis::Lat) => (true, [1.0, 1.0]),
        (Axis::Length(fx), Axis::Length(fy)) => (false, [fx, fy]),
        _ => {
            let what = |a: Axis| match a {
                Axis::Lon => "longitude",
                Axis::Lat => "latitude",
                Axis::Length(_) => "a length",
            };
            return Err(err(format!(
                "coordinates `{}` (x: {}) and `{}` (y: {}) do not make a grid: need longitude and latitude, or two lengths",
                xdim.name,
                what(kx),
                ydim.name,
                what(ky)
            )));
        }
    };
    let (mut x0, mut dx) =
        regular(&xs).map_err(|m| err(format!("coordinate `{}`: {m}", xdim.name)))?;
    let (mut y0, mut dy) =
        regular(&ys).map_err(|m| err(format!("coordinate `{}`: {m}", ydim.name)))?;
    // Kilometres to metres (an exact power of ten: metres stay as they were).
    (x0, dx, y0, dy) = (x0 * fx, dx * fx, y0 * fy, dy * fy);
    let mut p = Placement::default();
    if dy < 0.0 {
        p.flip_y = true;
        y0 += dy * (ny - 1) as f64;
        dy = -dy;
    }
    if dx < 0.0 {
        p.flip_x = true;
        x0 += dx * (nx - 1) as f64;
        dx = -dx;
    }
    if lonlat {
        let ref_lat = y0 + 0.5 * dy * (ny - 1) as f64;
        p.spacing = lonlat_spacing_m(dx, dy, ref_lat);
        p.georeference = Georeference::LonLat {
            lon0_deg: x0,
            lat0_deg: y0,
            dlon_deg: dx,
            dlat_deg: dy,
            ref_lat_deg: ref_lat,
        };
    } else {
        p.origin = Vec2::new(x0, y0);
        p.spacing = [dx, dy];
        p.georeference = Georeference::Metres { epsg: None };
    }
    Ok(p)
}

/// The frames of `values` (row-major, frame after frame), flipped to south-to-north rows and
/// west-to-east columns.
fn into_frames(
    path: &Path,
    mut values: Vec<f64>,
    layout: &Layout,
    p: &Placement,
) -> Result<Vec<Grid2>, LoadError> {
    let (nx, ny, n_frames) = (layout.nx, layout.ny, layout.n_frames);
    // Frames split off the end, the rest shrunk each time: one frame more than the values at
    // most, not a second copy of them all.
    let mut frames = Vec::with_capacity(n_frames);
    for k in (0..n_frames).rev() {
        let mut v = values.split_off(k * nx * ny);
        values.shrink_to_fit();
        if p.flip_y {
            super::loaded::flip_rows(&mut v, nx, ny);
        }
        if p.flip_x {
            for row in v.chunks_mut(nx) {
                row.reverse();
            }
        }
        let g = Grid2::new(nx, ny, p.origin, p.spacing, v)
            .map_err(|e| LoadError::new(path, None, format!("frame {k}: {e}")))?;
        frames.push(g);
    }
    frames.reverse();
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use netcdf3::{DataSet, FileWriter, Version};

    /// Writes a NetCDF-3 classic file: lat (north first), lon, optional time, and a variable
    /// `v(time?, lat, lon)` stored as f32 halved with `scale_factor = 2` and a fill value.
    fn write_nc(path: &Path, times_h: Option<&[f64]>, frames: &[Vec<f32>]) {
        let mut ds = DataSet::new();
        ds.add_fixed_dim("lat", 4).unwrap();
        ds.add_fixed_dim("lon", 3).unwrap();
        ds.add_var_f64("lat", &["lat"]).unwrap();
        ds.add_var_attr_string("lat", "units", "degrees_north")
            .unwrap();
        ds.add_var_f64("lon", &["lon"]).unwrap();
        ds.add_var_attr_string("lon", "units", "degrees_east")
            .unwrap();
        let dims: Vec<&str> = if let Some(t) = times_h {
            ds.add_fixed_dim("time", t.len()).unwrap();
            ds.add_var_f64("time", &["time"]).unwrap();
            ds.add_var_attr_string("time", "units", "hours since 2019-03-01 00:00:00")
                .unwrap();
            vec!["time", "lat", "lon"]
        } else {
            vec!["lat", "lon"]
        };
        ds.add_var_f32("v", &dims).unwrap();
        ds.add_var_attr_f32("v", "_FillValue", vec![-999.0])
            .unwrap();
        ds.add_var_attr_f32("v", "scale_factor", vec![2.0]).unwrap();
        let mut w = FileWriter::create_new(path).unwrap();
        w.set_def(&ds, Version::Classic, 0).unwrap();
        w.write_var_f64("lat", &[51.0, 50.5, 50.0, 49.5]).unwrap();
        w.write_var_f64("lon", &[10.0, 10.5, 11.0]).unwrap();
        if let Some(t) = times_h {
            w.write_var_f64("time", t).unwrap();
        }
        let all: Vec<f32> = frames.iter().flatten().copied().collect();
        w.write_var_f32("v", &all).unwrap();
        w.close().unwrap();
    }

    /// Frame `k`, north row first, halved: (30 - 10 r + c + 100 k) / 2, with a fill at north
    /// row 1, column 1.
    fn frame(k: usize) -> Vec<f32> {
        let mut raw: Vec<f32> = (0..4)
            .flat_map(|r| (0..3).map(move |c| ((30 - 10 * r + c + 100 * k as i32) as f32) / 2.0))
            .collect();
        raw[4] = -999.0;
        raw
    }

    /// A packing attribute that is not finite (`add_offset = inf`, `scale_factor = -inf`) is
    /// named in the error, not reported as "every value is NaN / no-data".
    #[test]
    fn non_finite_packing_attribute_is_named() {
        for (attr, value, shown) in [
            ("add_offset", f64::INFINITY, "is inf"),
            // (NaN cannot be written: netcdf3's writer finds a variable by equality.)
            ("scale_factor", f64::NEG_INFINITY, "is -inf"),
        ] {
            let dir = tempfile::tempdir().unwrap();
            let p = dir.path().join("o.nc");
            let mut ds = DataSet::new();
            ds.add_fixed_dim("lat", 4).unwrap();
            ds.add_fixed_dim("lon", 3).unwrap();
            ds.add_var_f64("lat", &["lat"]).unwrap();
            ds.add_var_f64("lon", &["lon"]).unwrap();
            ds.add_var_f32("v", &["lat", "lon"]).unwrap();
            ds.add_var_attr_f32("v", attr, vec![value as f32]).unwrap();
            let mut w = FileWriter::create_new(&p).unwrap();
            w.set_def(&ds, Version::Classic, 0).unwrap();
            w.write_var_f64("lat", &[51.0, 50.5, 50.0, 49.5]).unwrap();
            w.write_var_f64("lon", &[10.0, 10.5, 11.0]).unwrap();
            w.write_var_f32("v", &[1.0; 12]).unwrap();
            w.close().unwrap();
            let e = crate::io::load_grid(&p, None).unwrap_err().to_string();
            assert!(e.contains(&format!("attribute `{attr}` {shown}")), "{e}");
            assert!(!e.contains("every value is NaN"), "{e}");
        }
    }

    /// Issue 30 (att30c-1): a packing or no-data attribute that is a text, holds the wrong
    /// number of values, or a `scale_factor` of 0 or a subnormal was ignored or half-read
    /// (values unscaled, no-data kept as data, every value 0): refused naming the variable and
    /// the attribute. One number each (and `missing_value` as a list, `valid_range` as a pair)
    /// still load.
    #[test]
    fn value_attributes_of_the_wrong_type_or_count_are_refused() {
        enum A {
            Text(&'static str),
            F64(Vec<f64>),
        }
        let cases: Vec<(&str, A, Option<&str>)> = vec![
            (
                "scale_factor",
                A::Text("2"),
                Some("is a text (`2`), not a number"),
            ),
            ("add_offset", A::Text("5"), Some("is a text")),
            ("missing_value", A::Text("0"), Some("is a text")),
            ("valid_max", A::Text("1"), Some("is a text")),
            ("_FillValue", A::Text("20"), Some("is a text")),
            (
                "scale_factor",
                A::F64(vec![2.0, 3.0]),
                Some("has 2 values: need one"),
            ),
            (
                "scale_factor",
                A::F64(vec![]),
                Some("has 0 values: need one"),
            ),
            (
                "_FillValue",
                A::F64(vec![20.0, 0.0]),
                Some("has 2 values: need one"),
            ),
            (
                "valid_range",
                A::F64(vec![0.0]),
                Some("has 1 values: need two"),
            ),
            (
                "scale_factor",
                A::F64(vec![0.0]),
                Some("a scale of 0 packs nothing"),
            ),
            ("scale_factor", A::F64(vec![5e-324]), Some("subnormal")),
            ("missing_value", A::F64(vec![-1.0, -2.0]), None),
            ("valid_range", A::F64(vec![-10.0, 10.0]), None),
            ("scale_factor", A::F64(vec![2.0]), None),
        ];
        for (attr, value, want) in cases {
            let dir = tempfile::tempdir().unwrap();
            let p = dir.path().join("a.nc");
            let mut ds = DataSet::new();
            ds.add_fixed_dim("lat", 4).unwrap();
            ds.add_fixed_dim("lon", 3).unwrap();
            ds.add_var_f64("lat", &["lat"]).unwrap();
            ds.add_var_f64("lon", &["lon"]).unwrap();
            ds.add_var_f64("conc", &["lat", "lon"]).unwrap();
            match &value {
                A::Text(t) => ds.add_var_attr_string("conc", attr, *t).unwrap(),
                A::F64(v) => ds.add_var_attr_f64("conc", attr, v.clone()).unwrap(),
            }
            let mut w = FileWriter::create_new(&p).unwrap();
            w.set_def(&ds, Version::Classic, 0).unwrap();
            w.write_var_f64("lat", &[51.0, 50.5, 50.0, 49.5]).unwrap();
            w.write_var_f64("lon", &[10.0, 10.5, 11.0]).unwrap();
            w.write_var_f64("conc", &[1.0; 12]).unwrap();
            w.close().unwrap();
            let got = crate::io::load_grid(&p, None);
            match want {
                Some(w) => {
                    let e = got.unwrap_err().to_string();
                    assert!(
                        e.contains(&format!("variable `conc`: attribute `{attr}`"))
                            && e.contains(w),
                        "{attr}: {e}"
                    );
                }
                None => {
                    let g = got.unwrap_or_else(|e| panic!("{attr}: {e}"));
                    let want = if attr == "scale_factor" { 2.0 } else { 1.0 };
                    assert_eq!(g.grid.at(0, 0), want, "{attr}");
                }
            }
        }
    }

    /// Issue 30: a line feed in a unit read from the file (`units = "ft\nerror: forged"`) is
    /// shown escaped: the error stays one line, where the line feed once reached the console.
    #[test]
    fn text_from_the_file_is_shown_on_one_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("lf.nc");
        let mut ds = DataSet::new();
        ds.add_fixed_dim("y", 3).unwrap();
        ds.add_fixed_dim("x", 4).unwrap();
        ds.add_var_f64("y", &["y"]).unwrap();
        ds.add_var_attr_string("y", "units", "m").unwrap();
        ds.add_var_f64("x", &["x"]).unwrap();
        ds.add_var_attr_string("x", "units", "ft\nerror: forged")
            .unwrap();
        ds.add_var_f64("v", &["y", "x"]).unwrap();
        let mut w = FileWriter::create_new(&p).unwrap();
        w.set_def(&ds, Version::Classic, 0).unwrap();
        w.write_var_f64("y", &[0.0, 1.0, 2.0]).unwrap();
        w.write_var_f64("x", &[0.0, 1.0, 2.0, 3.0]).unwrap();
        w.write_var_f64("v", &[0.0; 12]).unwrap();
        w.close().unwrap();
        let e = crate::io::load_grid(&p, None).unwrap_err().to_string();
        // Refused (a control character in a needed attribute), the text shown escaped.
        assert!(e.contains("`ft\\x0aerror: forged`"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        // The path too, and any message (a reader crate's error quoting the file).
        let e = LoadError::new(Path::new("a\nb.nc"), None, "c\rd\ne").to_string();
        assert_eq!(e, "a\\x0ab.nc: c\\x0dd\\x0ae");
    }

    #[test]
    fn cf_time_units_by_name() {
        for (u, s) in [
            ("seconds since 1970-01-01", 1.0),
            ("s since 2000-01-01 00:00:00", 1.0),
            ("Minutes since 2019-03-01", 60.0),
            ("min since 2019-03-01", 60.0),
            ("hours since 2019-03-01 00:00:00", 3600.0),
            ("hr since 2019-03-01", 3600.0),
            ("DAYS since 1900-01-01", 86_400.0),
            ("d since 1900-01-01", 86_400.0),
        ] {
            assert_eq!(cf_time_unit_s(u), Some(CfTimeUnit::Seconds(s)), "{u}");
        }
        for bad in [
            "fortnights since 2000-01-01",
            "hours",
            "hours after 2000",
            "",
        ] {
            assert_eq!(cf_time_unit_s(bad), None, "{bad}");
        }
    }

    #[test]
    fn regular_axes_within_a_millionth_of_a_step() {
        assert_eq!(regular(&[10.0, 12.0, 14.0, 16.0]), Ok((10.0, 2.0)));
        assert_eq!(regular(&[5.0, 4.5, 4.0]), Ok((5.0, -0.5)));
        // Off by 1e-7 of a step (within 1e-6 * step * n): accepted; by 1e-4: refused.
        assert!(regular(&[0.0, 1.0 + 1e-7, 2.0, 3.0]).is_ok());
        let e = regular(&[0.0, 1.0001, 2.0, 3.0]).unwrap_err();
        assert!(e.contains("value 1"), "{e}");
        assert!(regular(&[0.0, 1.0, 2.5, 3.0]).is_err());
        assert!(regular(&[7.0]).unwrap_err().contains("at least 2"));
        assert!(regular(&[]).is_err());
    }

    /// Axes known by their names, `standard_name` or CF units, in either spelling: each file
    /// reads as lon/lat (projected) or metres as its coordinates say.
    #[test]
    fn axes_are_known_by_name_standard_name_or_units() {
        use netcdf3::{DataSet, FileWriter, Version};
        // An axis: its name and its attributes.
        type Axis<'a> = (&'a str, &'a [(&'a str, &'a str)]);
        let write = |x: Axis, y: Axis| {
            let dir = tempfile::tempdir().unwrap();
            let p = dir.path().join("a.nc");
            let mut ds = DataSet::new();
            ds.add_fixed_dim(y.0, 3).unwrap();
            ds.add_fixed_dim(x.0, 4).unwrap();
            for (name, attrs) in [y, x] {
                ds.add_var_f64(name, &[name]).unwrap();
                for (k, v) in attrs {
                    ds.add_var_attr_string(name, k, v).unwrap();
                }
            }
            ds.add_var_f64("v", &[y.0, x.0]).unwrap();
            let mut w = FileWriter::create_new(&p).unwrap();
            w.set_def(&ds, Version::Classic, 0).unwrap();
            w.write_var_f64(y.0, &[50.0, 50.5, 51.0]).unwrap();
            w.write_var_f64(x.0, &[10.0, 10.5, 11.0, 11.5]).unwrap();
            w.write_var_f64("v", &[0.0; 12]).unwrap();
            w.close().unwrap();
            let g = crate::io::load_grid(&p, None).unwrap();
            (g.georeference, dir)
        };
        let lonlat = |g: &Georeference| matches!(g, Georeference::LonLat { .. });
        let cases: [(Axis, Axis, bool); 6] = [
            (("lon", &[]), ("lat", &[]), true),
            (("longitude", &[]), ("latitude", &[]), true),
            (
                ("x", &[("units", "degrees_east")]),
                ("y", &[("units", "degrees_north")]),
                true,
            ),
            (
                ("x", &[("units", "degree_east")]),
                ("y", &[("units", "degree_north")]),
                true,
            ),
            (
                ("i", &[("standard_name", "longitude")]),
                ("j", &[("standard_name", "latitude")]),
                true,
            ),
            (("x", &[("units", "m")]), ("y", &[("units", "m")]), false),
        ];
        for (x, y, want) in cases {
            let (g, _dir) = write(x, y);
            assert_eq!(lonlat(&g), want, "{} / {}: {g:?}", x.0, y.0);
        }
    }

    /// A variable named like a dimension but along another one (`x(other)` beside the dimension
    /// `x`) is not that dimension's coordinate: its values do not describe the grid's columns
    /// (in NetCDF-4 such a variable along a huge never-written dimension was read in full,
    /// past the checked size). The grid loads without a georeference from it.
    #[test]
    fn a_variable_along_another_dimension_is_not_a_coordinate() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.nc");
        let mut ds = DataSet::new();
        ds.add_fixed_dim("y", 3).unwrap();
        ds.add_fixed_dim("x", 4).unwrap();
        ds.add_fixed_dim("other", 10).unwrap();
        ds.add_var_f64("y", &["y"]).unwrap();
        ds.add_var_f64("x", &["other"]).unwrap();
        ds.add_var_f64("v", &["y", "x"]).unwrap();
        let mut w = FileWriter::create_new(&p).unwrap();
        w.set_def(&ds, Version::Classic, 0).unwrap();
        w.write_var_f64("y", &[0.0, 5.0, 10.0]).unwrap();
        let ten: Vec<f64> = (0..10).map(|k| 100.0 + 2.0 * k as f64).collect();
        w.write_var_f64("x", &ten).unwrap();
        w.write_var_f64("v", &[0.0; 12]).unwrap();
        w.close().unwrap();
        let g = crate::io::load_grid(&p, None).unwrap();
        assert_eq!((g.grid.nx(), g.grid.ny()), (4, 3));
        assert!(
            matches!(g.georeference, Georeference::None),
            "{:?}",
            g.georeference
        );
    }

    /// Issue 30: xarray writes sub-second axes in `milliseconds since` / `microseconds since`;
    /// udunits' abbreviations too. Times are converted by one division, so they are the
    /// decimals themselves (`9 ms` = 0.009 s, where `9 * 0.001` is 0.009000000000000001).
    #[test]
    fn sub_second_cf_time_units() {
        for (u, n) in [
            ("milliseconds since 2019-03-01 00:00:00", 1e3),
            ("millisecond since 2019-03-01", 1e3),
            ("ms since 1970-01-01T00:00:00Z", 1e3),
            ("msec since 1970-01-01", 1e3),
            ("microseconds since 2019-03-01 00:00:00", 1e6),
            ("us since 2019-03-01", 1e6),
            ("usec since 2019-03-01", 1e6),
            ("\u{b5}s since 2019-03-01", 1e6),
        ] {
            assert_eq!(cf_time_unit_s(u), Some(CfTimeUnit::PerSecond(n)), "{u}");
        }
        let ms = CfTimeUnit::PerSecond(1e3);
        assert_eq!(ms.to_s(9.0), 0.009);
        assert_eq!(ms.to_s(1001.0), 1.001);
        assert_eq!(CfTimeUnit::PerSecond(1e6).to_s(250_000.0), 0.25);
        // A file whose time axis is in milliseconds: frames 0, 9 and 1001 ms after the first.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ms.nc");
        let mut ds = DataSet::new();
        ds.add_fixed_dim("time", 3).unwrap();
        ds.add_fixed_dim("y", 2).unwrap();
        ds.add_fixed_dim("x", 2).unwrap();
        ds.add_var_f64("time", &["time"]).unwrap();
        ds.add_var_attr_string("time", "units", "milliseconds since 2024-05-01 12:00:00")
            .unwrap();
        ds.add_var_f64("v", &["time", "y", "x"]).unwrap();
        let mut w = FileWriter::create_new(&p).unwrap();
        w.set_def(&ds, Version::Classic, 0).unwrap();
        w.write_var_f64("time", &[5000.0, 5009.0, 6001.0]).unwrap();
        w.write_var_f64("v", &[0.0; 12]).unwrap();
        w.close().unwrap();
        let s = crate::io::load_series(&p, None, None).unwrap();
        assert_eq!(s.frame_times_s, Some(vec![0.0, 0.009, 1.001]));
    }

    #[test]
    fn reads_a_cf_lonlat_grid_with_fill_scale_and_flip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.nc");
        write_nc(&p, None, &[frame(0)]);
        let g = crate::io::load_grid(&p, None).unwrap();
        assert_eq!((g.grid.nx(), g.grid.ny()), (3, 4));
        assert_eq!(g.grid.at(0, 0), 0.0, "south-west after the flip");
        assert_eq!(g.grid.at(2, 3), 32.0);
        assert!(g.grid.at(1, 2).is_nan(), "fill value");
        let Georeference::LonLat {
            lon0_deg, lat0_deg, ..
        } = g.georeference
        else {
            panic!("{:?}", g.georeference)
        };
        assert_eq!((lon0_deg, lat0_deg), (10.0, 49.5));
    }

    /// A time axis: one frame per time, the CF `hours since` read as seconds after the first.
    #[test]
    fn reads_frames_and_cf_times() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.nc");
        write_nc(&p, Some(&[6.0, 7.0, 9.0]), &[frame(0), frame(1), frame(2)]);
        let s = crate::io::load_series(&p, None, None).unwrap();
        assert_eq!(s.frames.len(), 3);
        assert_eq!(s.frame_times_s, Some(vec![0.0, 3600.0, 10800.0]));
        assert_eq!(s.frames[2].at(0, 0), 200.0);
        let e = crate::io::load_grid(&p, None).unwrap_err();
        assert!(e.message.contains("3 frames"), "{e}");
        assert_eq!(
            cf_time_unit_s("days since 1970-01-01"),
            Some(CfTimeUnit::Seconds(86_400.0))
        );
        assert_eq!(cf_time_unit_s("fortnights since 1970-01-01"), None);
        // Issue 30 item 19: the reference must be a date.
        for bad in [
            "hours since 99999999-99-99",
            "hours since 2019-13-01",
            "hours since 2019-03-32",
            "hours since 2019-03-01 25:00:00",
            "hours since 2019-03-01 00:61:00",
            "hours since yesterday",
            "hours since ",
        ] {
            assert_eq!(cf_time_unit_s(bad), None, "{bad}");
        }
        for good in [
            "hours since 1900-01-01 00:00:00.0",
            "seconds since 1970-01-01T00:00:00Z",
            "days since 2000-1-1 0:0:0 UTC",
            "minutes since 2019-03-01 12:30",
            "hours since 2019-03-01 00:00:00 +00:00",
        ] {
            assert!(cf_time_unit_s(good).is_some(), "{good}");
        }
        assert_eq!(cf_time_unit_s("hours"), None);
    }

    /// The bundled ERA5 file (NetCDF-4/HDF5, zlib) equals its `.npy` twin (float32) frame by
    /// frame, and its frame times are hourly.
    #[test]
    fn the_bundled_era5_netcdf_equals_its_npy() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/era5_t2m_uk");
        let nc = crate::io::load_series(&dir.join("era5_t2m_uk.nc"), None, Some("t2m")).unwrap();
        let npy = crate::io::load_series(&dir.join("era5_t2m_uk.npy"), None, None).unwrap();
        assert_eq!(nc.frames.len(), 168);
        assert_eq!(npy.frames.len(), 168);
        let t = nc.frame_times_s.unwrap();
        assert_eq!(t[1], 3600.0);
        assert_eq!(t[167], 167.0 * 3600.0);
        for (a, b) in nc.frames.iter().zip(&npy.frames) {
            assert_eq!((a.nx(), a.ny()), (49, 33));
            for iy in 0..33 {
                for ix in 0..49 {
                    assert!((a.at(ix, iy) - b.at(ix, iy)).abs() < 1e-4, "{ix} {iy}");
                }
            }
        }
        let Georeference::LonLat {
            lon0_deg,
            lat0_deg,
            dlon_deg,
            ..
        } = nc.georeference
        else {
            panic!()
        };
        assert_eq!((lon0_deg, lat0_deg, dlon_deg), (-10.0, 50.0, 0.25));
    }
}
