//! Grid loaders: CSV, NumPy `.npy`, ESRI ASCII grid, GeoTIFF.
//!
//! Every loader returns a [`LoadedGrid`] oriented as in the bundled `data/` (row 0 south, column 0
//! west) with its native georeference converted to local metres ([`crate::georef`]), and every
//! failure a [`LoadError`] naming the file and the line or byte offset.

mod asc;
mod csv_grid;
mod error;
mod geotiff;
mod geotiff_lzw;
mod limits;
mod loaded;
mod netcdf;
mod npy;

pub use error::{FilePosition, LoadError};
pub use limits::{
    memory_budget_bytes, open_limited, open_regular, read_limited, read_text_limited,
    series_node_limit, LimitedReader, BYTES_PER_LOADED_VALUE, MAX_GRID_FILE_BYTES,
    MAX_SERIES_NODES,
};
use loaded::single_frame;
pub(crate) use loaded::LineNumbers;
pub use loaded::{LoadedGrid, LoadedSeries};

use std::path::Path;

/// A grid file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridFormat {
    /// Comma-separated values, no header, one grid row per line, row 0 = south; `NaN` = no-data.
    Csv,
    /// NumPy `.npy`, 2-D, shape `(rows, cols)`, row 0 = south; float64/float32/integer dtypes.
    Npy,
    /// ESRI ASCII grid (`.asc`): header `ncols nrows xllcorner|xllcenter yllcorner|yllcenter
    /// cellsize [NODATA_value]`, rows north to south.
    Asc,
    /// GeoTIFF: one band, any integer or float sample type; `ModelPixelScale`/`ModelTiepoint`
    /// georeference, geographic (degrees) or projected (metres); GDAL no-data tag honoured.
    GeoTiff,
    /// NetCDF (3 classic or 4/HDF5) with CF lon/lat (or metre) coordinates, optionally a
    /// time axis (read by the pure-Rust `netcdf-reader`).
    NetCdf,
}

impl GridFormat {
    /// The format of a file name's extension (`csv`, `npy`, `asc`, `tif`/`tiff`).
    pub fn from_extension(path: &Path) -> Option<Self> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "csv" | "txt" => Some(Self::Csv),
            "npy" => Some(Self::Npy),
            "asc" => Some(Self::Asc),
            "tif" | "tiff" => Some(Self::GeoTiff),
            "nc" | "nc4" | "cdf" => Some(Self::NetCdf),
            _ => None,
        }
    }
}

/// Parses the bytes of a file that may hold a time series (a 3-D `.npy`, a NetCDF with a time
/// axis; other formats give one frame). The fuzz targets' entry point.
pub fn parse_series_bytes(
    name: &Path,
    bytes: &[u8],
    format: GridFormat,
    variable: Option<&str>,
) -> Result<LoadedSeries, LoadError> {
    match format {
        GridFormat::NetCdf => netcdf::parse_bytes(name, bytes, variable),
        GridFormat::Npy => npy::parse_series(name, bytes),
        other => {
            let g = parse_grid(name, bytes, other)?;
            Ok(LoadedSeries {
                frames: vec![g.grid],
                frame_times_s: None,
                georeference: g.georeference,
                units: None,
                warnings: Vec::new(),
            })
        }
    }
}

impl GridFormat {
    /// The format's name as `field.format` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Csv => "csv",
            Self::Npy => "npy",
            Self::Asc => "asc",
            Self::GeoTiff => "geotiff",
            Self::NetCdf => "netcdf",
        }
    }

    /// The binary format whose signature `head` (a file's first bytes) starts with: NetCDF-3
    /// (`CDF` and version 1, 2 or 5), HDF5 (NetCDF-4), TIFF or BigTIFF (either byte order),
    /// NumPy `.npy`. `None` for anything else (the text formats have no signature).
    pub fn from_signature(head: &[u8]) -> Option<Self> {
        const HDF5: &[u8] = b"\x89HDF\r\n\x1a\n";
        let netcdf3 = head.len() >= 4 && head.starts_with(b"CDF") && matches!(head[3], 1 | 2 | 5);
        if netcdf3 || head.starts_with(HDF5) {
            Some(Self::NetCdf)
        } else if [b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"]
            .iter()
            .any(|m| head.starts_with(*m))
        {
            Some(Self::GeoTiff)
        } else if head.starts_with(b"\x93NUMPY") {
            Some(Self::Npy)
        } else {
            None
        }
    }

    /// Whether the format is binary, with a signature [`GridFormat::from_signature`] knows.
    fn has_signature(self) -> bool {
        matches!(self, Self::Npy | Self::GeoTiff | Self::NetCdf)
    }
}

/// The format of grid file `path` (README, `field.format`), one rule for a file and for a
/// symbolic link to one (`data.nc -> /store/blob`, `x.csv -> y.nc`):
///
/// 1. the file's **content** first: when its first bytes are a binary format's signature
///    (NetCDF-3, HDF5/NetCDF-4, TIFF/BigTIFF, `.npy`), that is its format, whatever the name;
///    a `format` given (`field.format`) that says otherwise is an error naming both;
/// 2. else the `format` given;
/// 3. else the extension of the name as written (`csv`/`txt`, `asc`, ...), else the
///    extension of the file a symbolic link resolves to;
/// 4. a binary extension (`.nc`, `.npy`, `.tif`) on a file without its signature is an error
///    saying so (not a parser's complaint about byte 0).
fn format_of(path: &Path, format: Option<GridFormat>) -> Result<GridFormat, LoadError> {
    use std::io::Read;
    let mut head = Vec::with_capacity(8);
    open_regular(path)
        .and_then(|f| f.take(8).read_to_end(&mut head))
        .map_err(|e| LoadError::cannot_read(path, e))?;
    format_of_head(path, format, &head)
}

/// [`format_of`] decided from `head`, the file's first (up to 8) bytes as read.
fn format_of_head(
    path: &Path,
    format: Option<GridFormat>,
    head: &[u8],
) -> Result<GridFormat, LoadError> {
    let head = &head[..head.len().min(8)];
    let content = GridFormat::from_signature(head);
    match (format, content) {
        (Some(given), Some(c)) if given != c => {
            return Err(LoadError::new(
                path,
                None,
                format!(
                    "field.format = \"{}\" but the file is {} (its first bytes are the {} signature): drop field.format or name the right file",
                    given.name(),
                    c.name(),
                    c.name()
                ),
            ))
        }
        (_, Some(c)) => return Ok(c),
        (Some(given), None) => return check_head(path, given, head).map(|()| given),
        (None, None) => {}
    }
    let by_name = GridFormat::from_extension(path).or_else(|| {
        std::fs::canonicalize(path)
            .ok()
            .and_then(|t| GridFormat::from_extension(&t))
    });
    match by_name {
        Some(f) if f.has_signature() => Err(LoadError::new(
            path,
            None,
            format!(
                "named as {} but its first bytes are not a {} signature (the content decides the format of binary files): is the link or the name wrong?",
                f.name(),
                f.name()
            ),
        )),
        Some(f) => check_head(path, f, head).map(|()| f),
        None => Err(LoadError::new(
            path,
            None,
            "cannot tell the format from the content or the extension; give it (field.format = csv, npy, asc, geotiff, netcdf)",
        )),
    }
}

/// Refuses at once, from its first bytes, a file that cannot be `format`: a binary format
/// without its signature, or a text format (CSV, ESRI ASCII) starting with a NUL byte (binary
/// data, such as `/proc/self/pagemap`, which would otherwise be read up to the 4 GiB limit
/// before failing).
fn check_head(path: &Path, format: GridFormat, head: &[u8]) -> Result<(), LoadError> {
    if format.has_signature() {
        return Err(LoadError::new(
            path,
            None,
            format!(
                "not a {} file: its first bytes are not the {} signature",
                format.name(),
                format.name()
            ),
        ));
    }
    if head.contains(&0) {
        return Err(LoadError::new(
            path,
            Some(FilePosition::Offset(
                head.iter().position(|&b| b == 0).unwrap_or(0) as u64,
            )),
            format!(
                "a NUL byte: binary data, not a {} grid (text)",
                format.name()
            ),
        ));
    }
    Ok(())
}

/// Loads a grid file as a series of frames: every format gives one frame, except a 3-D `.npy`
/// (`[time, rows, cols]`) and a NetCDF variable with a time dimension, which give one per time.
pub fn load_series(
    path: &Path,
    format: Option<GridFormat>,
    variable: Option<&str>,
) -> Result<LoadedSeries, LoadError> {
    let format = format_of(path, format)?;
    match format {
        // Read through `read_limited` like every other file (regular files, size cap).
        GridFormat::NetCdf => netcdf::parse(path, variable),
        GridFormat::Npy => {
            let bytes = read_limited(path, MAX_GRID_FILE_BYTES)
                .map_err(|e| LoadError::cannot_read(path, e))?;
            npy::parse_series(path, &bytes)
        }
        _ => {
            let g = load_grid(path, Some(format))?;
            Ok(LoadedSeries {
                frames: vec![g.grid],
                frame_times_s: None,
                georeference: g.georeference,
                units: None,
                warnings: Vec::new(),
            })
        }
    }
}

/// The SHA-256 of `bytes`, lowercase hex: isotrack's one content digest of a data file
/// (`isotrack_runs::files::sha256_file` gives the same of a file's bytes).
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// How a loader reads a whole file of at most the given bytes: [`read_limited`], or a stand-in
/// (a test's, to change the file on disk once its bytes are read).
pub type ReadWhole<'a> = &'a dyn Fn(&Path, u64) -> std::io::Result<Vec<u8>>;

/// A grid file loaded as [`load_series`] loads it, with the SHA-256 ([`sha256_hex`]) of the
/// very bytes parsed: the file is read once, into memory, hashed, then parsed from those bytes
/// (att41-22: a digest taken by reading the file again after the load named a file replaced
/// in between by its new content, for a field read from the old one).
pub fn load_series_hashed(
    path: &Path,
    format: Option<GridFormat>,
    variable: Option<&str>,
) -> Result<(LoadedSeries, String), LoadError> {
    load_series_read(path, format, variable, &read_limited)
}

/// As [`load_series_hashed`], the file's bytes read by `read` (the format decided from the
/// first of those bytes, not from another read of the file).
pub fn load_series_read(
    path: &Path,
    format: Option<GridFormat>,
    variable: Option<&str>,
    read: ReadWhole<'_>,
) -> Result<(LoadedSeries, String), LoadError> {
    let bytes = read(path, MAX_GRID_FILE_BYTES).map_err(|e| LoadError::cannot_read(path, e))?;
    let format = format_of_head(path, format, &bytes)?;
    let series = parse_series_bytes(path, &bytes, format, variable)?;
    Ok((series, sha256_hex(&bytes)))
}

/// Loads a grid file; `format` is inferred from the extension when `None`.
pub fn load_grid(path: &Path, format: Option<GridFormat>) -> Result<LoadedGrid, LoadError> {
    load_grid_variable(path, format, None)
}

/// As [`load_grid`], naming the variable to read for formats that hold several (NetCDF).
pub fn load_grid_variable(
    path: &Path,
    format: Option<GridFormat>,
    variable: Option<&str>,
) -> Result<LoadedGrid, LoadError> {
    let format = format_of(path, format)?;
    if format == GridFormat::NetCdf {
        return single_frame(path, load_series(path, Some(format), variable)?);
    }
    let bytes =
        read_limited(path, MAX_GRID_FILE_BYTES).map_err(|e| LoadError::cannot_read(path, e))?;
    parse_grid(path, &bytes, format)
}

/// Parses the bytes of a grid file (any format but NetCDF, which needs a file); `name` is used
/// in error messages. (The fuzz targets' entry point.)
pub fn parse_grid(name: &Path, bytes: &[u8], format: GridFormat) -> Result<LoadedGrid, LoadError> {
    let path = name;
    match format {
        GridFormat::NetCdf => Err(LoadError::new(
            path,
            None,
            "NetCDF needs a file: use load_grid",
        )),
        GridFormat::Csv => csv_grid::parse(path, bytes),
        GridFormat::Npy => npy::parse(path, bytes),
        GridFormat::Asc => asc::parse(path, bytes),
        GridFormat::GeoTiff => geotiff::parse(path, bytes),
    }
}

#[cfg(test)]
mod tests;
