//! Why a figure could not be made, and the one way a figure opens its input files.

/// Why a figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A run directory or one of its files is missing or cannot be read.
    #[error("{0}")]
    Input(String),
    /// A file was read but its content cannot be plotted (malformed, or values no axis can
    /// show).
    #[error("{0}")]
    Data(String),
    /// Drawing or writing the image failed.
    #[error("cannot draw {path}: {message}")]
    Draw {
        /// The image being written.
        path: String,
        /// What failed.
        message: String,
    },
}

/// The largest file a plot reads, bytes (a trace of 4 GiB is some 40 million rows, far beyond
/// what a figure can show); non-regular files (`/dev/zero`, pipes) are refused.
pub const MAX_INPUT_BYTES: u64 = 4 << 30;

/// Opens `path` for a streaming reader after checking it is a regular file; at most
/// [`MAX_INPUT_BYTES`] are read from it, counted on the bytes read (a `/proc` file declares 0
/// bytes), and a read past them is an error.
pub(crate) fn open_input(
    path: &std::path::Path,
) -> Result<isotrack_fields::io::LimitedReader, PlotError> {
    isotrack_fields::io::open_limited(path, MAX_INPUT_BYTES)
        .map_err(|e| PlotError::Input(format!("{}: {e}", path.display())))
}
