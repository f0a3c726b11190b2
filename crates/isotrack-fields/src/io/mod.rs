//! Grid loaders: CSV, NumPy `.npy`, ESRI ASCII grid, GeoTIFF.
//!
//! Every loader returns a [`LoadedGrid`] oriented as in the bundled `data/` (row 0 south, column 0
//! west) with its native georeference converted to local metres ([`crate::georef`]), and every
//! failure a [`LoadError`] naming the file and the line or byte offset.

mod asc;
mod csv_grid;
mod geotiff;
mod geotiff_lzw;
mod netcdf;
mod npy;

use crate::georef::Georeference;
use crate::grid::{Grid2, GridError};
use std::fmt;
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

/// Where in a file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FilePosition {
    /// 1-based line (text formats), with an optional 1-based field/column.
    Line(usize, Option<usize>),
    /// Byte offset (binary formats).
    Offset(u64),
}

/// A grid file that cannot be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError {
    /// The file.
    pub path: String,
    /// Where in it, if known.
    pub position: Option<FilePosition>,
    /// What is wrong.
    pub message: String,
    /// The file itself could not be read (missing, not a regular file, no permission, beyond
    /// the size limit), as opposed to what it holds: exit 66 rather than 65 (README, "Exit
    /// codes").
    pub unreadable: bool,
}

/// Shown on one line, whatever the file holds: the path and the message (which quotes names,
/// units and headers read from the file, and the reader crates' errors) are [`Escaped`], so a
/// line feed or a terminal control in them is shown as `\x0a` / `\x1b` (issue 30).
///
/// [`Escaped`]: isotrack_core::numtext::Escaped
impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use isotrack_core::numtext::Escaped;
        let (path, message) = (Escaped(&self.path), Escaped(&self.message));
        match &self.position {
            Some(FilePosition::Line(l, Some(c))) => {
                write!(f, "{path}:{l}: field {c}: {message}")
            }
            Some(FilePosition::Line(l, None)) => write!(f, "{path}:{l}: {message}"),
            Some(FilePosition::Offset(o)) => {
                write!(f, "{path} (byte offset {o}): {message}")
            }
            None => write!(f, "{path}: {message}"),
        }
    }
}

impl std::error::Error for LoadError {}

impl LoadError {
    pub(crate) fn new(
        path: &Path,
        position: Option<FilePosition>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            path: path.display().to_string(),
            position,
            message: message.into(),
            unreadable: false,
        }
    }
    /// The file could not be read at all (see [`LoadError::unreadable`]).
    pub(crate) fn cannot_read(path: &Path, e: std::io::Error) -> Self {
        Self {
            unreadable: true,
            ..Self::new(path, None, format!("cannot read: {e}"))
        }
    }
    pub(crate) fn grid(path: &Path, e: GridError) -> Self {
        Self::new(path, None, e.to_string())
    }
}

/// The largest grid file read, bytes (4 GiB: a grid of [`crate::grid::MAX_NODES`] float64
/// values is 2 GiB; text formats take about twice that).
pub const MAX_GRID_FILE_BYTES: u64 = 4 << 30;

/// Opens an input file for reading, refusing what is not a regular file (a FIFO, a device, a
/// directory) without blocking: the type is looked up (`stat`) before the file is opened,
/// since opening a FIFO for reading waits for a writer, possibly for ever. On Unix the open
/// itself is non-blocking too (`O_NONBLOCK`, which regular files ignore), and the opened file
/// is checked again, so a FIFO swapped in between the two is refused rather than waited on.
/// Every input path of isotrack opens its files through here.
pub fn open_regular(path: &Path) -> std::io::Result<std::fs::File> {
    let not_regular = || {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a device, pipe or directory)",
        )
    };
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let mut opts = std::fs::OpenOptions::new();
    opts.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NONBLOCK);
    }
    let f = opts.open(path)?;
    if !f.metadata()?.is_file() {
        return Err(not_regular());
    }
    Ok(f)
}

/// Reads a whole file of at most `max_bytes`, refusing what is not a regular file (a FIFO,
/// `/dev/zero`, a directory) before reading a byte: such "files" never end, or end anywhere.
/// The size is checked from the metadata and again on the bytes actually read (a `/proc` file
/// that declares 0 bytes, or a file that grows, is stopped with an error one byte past the
/// limit, not read on).
pub fn read_limited(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let f = open_regular(path)?;
    let meta = f.metadata()?;
    let too_big = |n: u64| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("{n} bytes is more than the {max_bytes} this reader accepts"),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    f.take(max_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// A regular file read as a stream, at most `max_bytes` of it: a read past the limit is an
/// error (`InvalidData`), never a silent cut. The limit counts the bytes actually read, not the
/// size the file declares: a `/proc` file declares 0 bytes and can produce gigabytes
/// (`/proc/self/pagemap`), and a file can grow while it is read.
#[derive(Debug)]
pub struct LimitedReader {
    inner: std::fs::File,
    left: u64,
    max_bytes: u64,
}

impl LimitedReader {
    /// The limit this reader enforces, bytes.
    pub fn max_bytes(&self) -> u64 {
        self.max_bytes
    }
}

impl std::io::Read for LimitedReader {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.left == 0 {
            // At the limit: one more byte means the file is longer than allowed.
            let mut probe = [0u8; 1];
            return match self.inner.read(&mut probe)? {
                0 => Ok(0),
                _ => Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("more than the {} bytes this reader accepts", self.max_bytes),
                )),
            };
        }
        let n = buf
            .len()
            .min(usize::try_from(self.left).unwrap_or(usize::MAX));
        let got = self.inner.read(&mut buf[..n])?;
        self.left -= got as u64;
        Ok(got)
    }
}

/// Opens a regular file ([`open_regular`]) for streaming through a [`LimitedReader`] of
/// `max_bytes`; a declared size beyond it is refused at once.
pub fn open_limited(path: &Path, max_bytes: u64) -> std::io::Result<LimitedReader> {
    let f = open_regular(path)?;
    let len = f.metadata()?.len();
    if len > max_bytes {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("{len} bytes is more than the {max_bytes} this reader accepts"),
        ));
    }
    Ok(LimitedReader {
        inner: f,
        left: max_bytes,
        max_bytes,
    })
}

/// As [`read_limited`], as UTF-8 text.
pub fn read_text_limited(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    String::from_utf8(read_limited(path, max_bytes)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// The most values a time series of frames may hold, over all frames: 2^30 (8 GiB of values),
/// and fewer when the memory this process may use holds fewer ([`series_node_limit`]).
pub const MAX_SERIES_NODES: usize = 1 << 30;

/// Bytes of memory a loader holds per value at its peak: the file's own values (up to 8 bytes),
/// their float64 copy, and the float64 frames built from them (NetCDF through `netcdf-reader`;
/// the other formats hold less).
pub const BYTES_PER_LOADED_VALUE: u64 = 24;

/// The memory this process may still use, bytes, where the system says: the smallest of Linux's
/// `MemAvailable` (`/proc/meminfo`), the room left under a cgroup v2 limit (`memory.max` less
/// `memory.current`, as a Slurm job or a container sets) and the room left under an
/// address-space limit (`ulimit -v`, as HPC login nodes and `prlimit` set: the soft limit in
/// `/proc/self/limits` less the process's virtual size `VmSize` in `/proc/self/status`).
/// `None` where none is known. Read by hand: text files, no crate needed for them.
pub fn memory_budget_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        let line = t.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        kib.checked_mul(1024)
    });
    let read_u64 = |f: &str| -> Option<u64> {
        std::fs::read_to_string(Path::new("/sys/fs/cgroup").join(f))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    let cgroup = read_u64("memory.max")
        .map(|max| max.saturating_sub(read_u64("memory.current").unwrap_or(0)));
    [meminfo, cgroup, address_space_room_bytes()]
        .into_iter()
        .flatten()
        .min()
}

/// The room left under this process's soft address-space limit (`RLIMIT_AS`, `ulimit -v`),
/// bytes: the limit less the virtual size already mapped. `None` when unlimited or unknown.
fn address_space_room_bytes() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let limit = parse_address_space_limit(&limits)?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    Some(limit.saturating_sub(parse_vm_size_bytes(&status)?))
}

/// The soft `Max address space` of a `/proc/PID/limits` text, bytes (`None` if `unlimited`).
fn parse_address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// `VmSize` of a `/proc/PID/status` text, bytes (the kernel writes it in kB = 1024 bytes).
fn parse_vm_size_bytes(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let kib: u64 = line["VmSize:".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    kib.checked_mul(1024)
}

/// The most values (frames x nodes) a loader reads with `budget_bytes` of memory:
/// [`MAX_SERIES_NODES`], or fewer when the budget at [`BYTES_PER_LOADED_VALUE`] holds fewer.
pub fn series_node_limit(budget_bytes: Option<u64>) -> usize {
    let by_memory = budget_bytes.map_or(u64::MAX, |b| b / BYTES_PER_LOADED_VALUE);
    MAX_SERIES_NODES.min(usize::try_from(by_memory).unwrap_or(usize::MAX))
}

/// Checks a series' declared size (`frames` of `nx` x `ny` nodes, from a file's header) before
/// anything is allocated for it: each frame within [`crate::grid::MAX_NODES`], and frames x
/// nodes within [`series_node_limit`] of `budget_bytes`. The error names all three counts.
pub(crate) fn check_series_size(
    path: &Path,
    frames: usize,
    nx: usize,
    ny: usize,
    budget_bytes: Option<u64>,
) -> Result<(), LoadError> {
    let frame = nx.checked_mul(ny).filter(|n| *n <= crate::grid::MAX_NODES);
    if frame.is_none() {
        return Err(LoadError::grid(
            path,
            crate::grid::GridError::TooManyNodes { nx, ny },
        ));
    }
    let limit = series_node_limit(budget_bytes);
    let total = frame.and_then(|n| n.checked_mul(frames));
    if total.is_none_or(|n| n > limit) {
        let total = total.map_or_else(|| "more than 2^64".into(), |n| n.to_string());
        let why = match budget_bytes {
            Some(b) if limit < MAX_SERIES_NODES => format!(
                "the {:.1} GiB of memory this process may use holds {limit} at {BYTES_PER_LOADED_VALUE} bytes each while loading",
                b as f64 / f64::from(1u32 << 30)
            ),
            _ => format!("a series holds at most {MAX_SERIES_NODES}"),
        };
        return Err(LoadError::new(
            path,
            None,
            format!(
                "{frames} {} of {ny} x {nx} nodes = {total} values: too many to load ({why})",
                if frames == 1 { "frame" } else { "frames" }
            ),
        ));
    }
    Ok(())
}

/// Frames of a grid time series as read: one or more grids of one geometry, the frame times the
/// file gave (seconds after the first frame; `None` when it gives none: a 3-D `.npy`), and the
/// georeference.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedSeries {
    /// The frames, in file order.
    pub frames: Vec<Grid2>,
    /// Frame times, s after the first frame, when the file carries them.
    pub frame_times_s: Option<Vec<f64>>,
    /// What the file said about its coordinates.
    pub georeference: Georeference,
    /// The unit of the values, when the file gives one (NetCDF's CF `units` attribute of the
    /// data variable, as written: `"K"`, `"ug m-3"`); `None` for the other formats.
    pub units: Option<String>,
    /// What the reader assumed that the file did not say, each naming the file (a NetCDF
    /// projected coordinate without `units`, read as metres); empty for the other formats.
    pub warnings: Vec<String>,
}

/// The one frame of a series, or an error saying the file is a time series.
pub(crate) fn single_frame(path: &Path, s: LoadedSeries) -> Result<LoadedGrid, LoadError> {
    if s.frames.len() != 1 {
        return Err(LoadError::new(
            path,
            None,
            format!(
                "{} frames: a time series (a scenario reads them all with field.kind = \"grid\")",
                s.frames.len()
            ),
        ));
    }
    let grid = s
        .frames
        .into_iter()
        .next()
        .ok_or_else(|| LoadError::new(path, None, "no frame"))?;
    Ok(LoadedGrid {
        grid,
        georeference: s.georeference,
    })
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
    let content = GridFormat::from_signature(&head);
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
        (Some(given), None) => return check_head(path, given, &head).map(|()| given),
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
        Some(f) => check_head(path, f, &head).map(|()| f),
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

/// A grid as read, with the georeference the file carried.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedGrid {
    /// The values, georeferenced in local metres (1 m spacing at the origin when the file has
    /// no georeference).
    pub grid: Grid2,
    /// What the file said about its coordinates.
    pub georeference: Georeference,
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

/// Line numbers of byte offsets in a text, for the `csv` readers: the `csv` crate's own
/// `Position::line` skips blank lines, so an error after one would name the wrong line. Offsets
/// must come in increasing order (records do); each newline is counted once.
pub(crate) struct LineNumbers<'a> {
    bytes: &'a [u8],
    offset: usize,
    line: usize,
}

impl<'a> LineNumbers<'a> {
    /// Lines of `bytes`, the first numbered 1.
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self {
            bytes,
            offset: 0,
            line: 1,
        }
    }

    /// The 1-based line of the record starting at byte `offset` (at or after the previous
    /// offset asked for). `csv` reports a record after blank lines at the first of them, so
    /// line breaks at `offset` are skipped first.
    pub(crate) fn line_of(&mut self, offset: u64) -> usize {
        let mut end = usize::try_from(offset)
            .unwrap_or(usize::MAX)
            .min(self.bytes.len());
        while end < self.bytes.len() && matches!(self.bytes[end], b'\n' | b'\r') {
            end += 1;
        }
        if end > self.offset {
            self.line += self.bytes[self.offset..end]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            self.offset = end;
        }
        self.line
    }
}

/// Builds a grid with no georeference (1 m spacing, origin at 0).
pub(crate) fn plain_grid(
    path: &Path,
    nx: usize,
    ny: usize,
    values: Vec<f64>,
) -> Result<LoadedGrid, LoadError> {
    let grid = Grid2::new(nx, ny, isotrack_core::Vec2::default(), [1.0, 1.0], values)
        .map_err(|e| LoadError::grid(path, e))?;
    Ok(LoadedGrid {
        grid,
        georeference: Georeference::None,
    })
}

/// Flips rows stored north-to-south into the south-to-north layout.
pub(crate) fn flip_rows(values: &mut [f64], nx: usize, ny: usize) {
    for iy in 0..ny / 2 {
        let (a, b) = values.split_at_mut((ny - 1 - iy) * nx);
        a[iy * nx..iy * nx + nx].swap_with_slice(&mut b[..nx]);
    }
}

#[cfg(test)]
mod tests;
