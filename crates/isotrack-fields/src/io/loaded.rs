//! Grids and series as read, and the helpers the format readers share to build them.

use super::error::LoadError;
use crate::georef::Georeference;
use crate::grid::Grid2;
use std::path::Path;

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

/// A grid as read, with the georeference the file carried.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedGrid {
    /// The values, georeferenced in local metres (1 m spacing at the origin when the file has
    /// no georeference).
    pub grid: Grid2,
    /// What the file said about its coordinates.
    pub georeference: Georeference,
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
