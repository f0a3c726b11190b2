//! NumPy `.npy` grids: 2-D, shape `(rows, cols)`, or a time series of frames, 3-D, shape
//! `(time, rows, cols)`; row 0 = south, C or Fortran order.

use super::error::{FilePosition, LoadError};
use super::loaded::{LoadedGrid, LoadedSeries};
use crate::georef::Georeference;
use crate::grid::Grid2;
use isotrack_core::Vec2;
use npyz::{DType, NpyFile, Order, TypeChar, TypeStr};
use std::path::Path;

/// The longest `.npy` header accepted, bytes (a real one is under 200).
const MAX_NPY_HEADER: usize = 4096;

/// Checks a `.npy` header before the `npyz` parser sees it: its Python-literal grammar
/// backtracks exponentially on some crafted digit runs (a fuzzed header once kept it busy for
/// more than 20 minutes). A real header is a short dict of a dtype string, a boolean and a
/// shape tuple: length, characters and digit runs are bounded here.
fn check_header(path: &Path, bytes: &[u8]) -> Result<(), LoadError> {
    let bad = |m: String| LoadError::new(path, Some(FilePosition::Offset(0)), m);
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(bad("not a valid .npy file: no NumPy magic".into()));
    }
    let (len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(bad(format!("not a valid .npy file: version {v}"))),
    };
    if len > MAX_NPY_HEADER || start + len > bytes.len() {
        return Err(bad(format!(
            "not a valid .npy file: a header of {len} bytes (at most {MAX_NPY_HEADER}, within the file)"
        )));
    }
    let header = &bytes[start..start + len];
    let allowed = |c: u8| c.is_ascii_alphanumeric() || b" \t\n\r{}()':,<>|=_.-+\"".contains(&c);
    if let Some(c) = header.iter().find(|&&c| !allowed(c)) {
        return Err(bad(format!(
            "not a valid .npy file: byte {c:#04x} in the header"
        )));
    }
    // One dict holding one shape tuple: nesting is what makes the parser backtrack.
    let count = |c: u8| header.iter().filter(|&&x| x == c).count();
    if count(b'{') != 1 || count(b'}') != 1 || count(b'(') > 1 || count(b')') > 1 {
        return Err(bad(
            "not a valid .npy file: the header is not one dict with one shape tuple".into(),
        ));
    }
    let mut run = 0;
    for &c in header {
        run = if c.is_ascii_digit() { run + 1 } else { 0 };
        if run > 20 {
            return Err(bad(
                "not a valid .npy file: a number of more than 20 digits in the header".into(),
            ));
        }
    }
    check_shape(path, header)
}

/// Checks the header's shape tuple before `npyz` multiplies it out: `npyz` takes the product of
/// the dimensions unchecked, which overflows (a panic in debug builds, a wrapped size in release)
/// on a fuzzed shape such as `(199998000098, 700000007, 0)`. A zero or one-wide frame is refused
/// here too, because the product is formed before any later check could see the zero.
fn check_shape(path: &Path, header: &[u8]) -> Result<(), LoadError> {
    let (Some(open), Some(close)) = (
        header.iter().position(|&c| c == b'('),
        header.iter().position(|&c| c == b')'),
    ) else {
        // No tuple: npyz reports the missing shape itself.
        return Ok(());
    };
    if close < open {
        return Err(LoadError::new(
            path,
            Some(FilePosition::Offset(0)),
            "not a valid .npy file: the shape tuple is malformed".to_string(),
        ));
    }
    let text = String::from_utf8_lossy(&header[open + 1..close]);
    let mut dims = Vec::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        // Trailing `L` of Python 2 longs is accepted by npyz as well.
        let digits = part.trim_end_matches('L');
        match digits.parse::<u64>() {
            Ok(d) => dims.push(d),
            // Anything else is npyz's to report (its message names the token).
            Err(_) => return Ok(()),
        }
    }
    if (2..=3).contains(&dims.len()) && dims[dims.len() - 2..].iter().any(|&d| d < 2) {
        return Err(LoadError::new(
            path,
            None,
            format!("shape {dims:?}: a frame needs at least 2 x 2 values, and a series one frame"),
        ));
    }
    if dims
        .iter()
        .try_fold(1u64, |n, &d| n.checked_mul(d))
        .is_none()
    {
        return Err(LoadError::new(
            path,
            None,
            format!("shape {dims:?}: the number of values overflows 64 bits"),
        ));
    }
    Ok(())
}

/// A 2-D array (a 3-D one is refused here: use [`parse_series`]).
pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<LoadedGrid, LoadError> {
    super::loaded::single_frame(path, parse_series(path, bytes)?)
}

/// A 2-D array as one frame, or a 3-D `(time, rows, cols)` array as frames (no frame times: the
/// file has none).
pub(super) fn parse_series(path: &Path, bytes: &[u8]) -> Result<LoadedSeries, LoadError> {
    check_header(path, bytes)?;
    let npy = NpyFile::new(bytes).map_err(|e| {
        LoadError::new(
            path,
            Some(FilePosition::Offset(0)),
            format!("not a valid .npy file: {e}"),
        )
    })?;
    let shape = npy.shape().to_vec();
    let (nt, ny, nx) = match shape[..] {
        [r, c] => (1, r as usize, c as usize),
        [t, r, c] => (t as usize, r as usize, c as usize),
        _ => {
            return Err(LoadError::new(
                path,
                None,
                format!("expected a 2-D (rows, cols) or 3-D (time, rows, cols) array, found shape {shape:?}"),
            ))
        }
    };
    let order = npy.order();
    let dtype = npy.dtype();
    let DType::Plain(ts) = &dtype else {
        return Err(LoadError::new(
            path,
            None,
            format!("unsupported dtype {dtype:?}: need a plain numeric dtype"),
        ));
    };
    // The dtype first: an object array (`|O`, pickled Python objects) has no fixed item size,
    // and reading it as numbers once reported a "truncated file".
    let numeric = matches!(
        (ts.type_char(), ts.size_field()),
        (TypeChar::Float, 4 | 8) | (TypeChar::Int | TypeChar::Uint, 1 | 2 | 4 | 8)
    );
    if !numeric {
        let hint = if ts.type_char() == TypeChar::Object {
            " (Python objects, stored pickled): save a numeric array, e.g. `np.save(f, a.astype(float))`"
        } else {
            ""
        };
        return Err(LoadError::new(
            path,
            None,
            format!("unsupported dtype `{ts}`{hint}; need float64, float32 or an integer type"),
        ));
    }
    if nx < 2 || ny < 2 || nt < 1 {
        return Err(LoadError::new(
            path,
            None,
            format!("shape {shape:?}: a frame needs at least 2 x 2 values, and a series one frame"),
        ));
    }
    super::limits::check_series_size(path, nt, nx, ny, super::limits::memory_budget_bytes())?;
    // The header's shape is untrusted: refuse a data size beyond the file before reading.
    let item = ts.num_bytes().unwrap_or(8) as u128;
    if (nt as u128) * (ny as u128) * (nx as u128) * item > bytes.len() as u128 {
        return Err(LoadError::new(
            path,
            None,
            format!(
                "shape {shape:?} needs more data than the {}-byte file holds (truncated file?)",
                bytes.len()
            ),
        ));
    }
    let values = read_values(path, npy, ts)?;
    let frames = into_frames(path, values, (nt, ny, nx), order, &shape)?;
    Ok(LoadedSeries {
        frames,
        frame_times_s: None,
        georeference: Georeference::None,
        units: None,
        warnings: Vec::new(),
    })
}

/// The array's values as `f64`, from any of the numeric dtypes [`parse_series`] takes.
fn read_values(path: &Path, npy: NpyFile<&[u8]>, ts: &TypeStr) -> Result<Vec<f64>, LoadError> {
    let bad = |e: std::io::Error| {
        LoadError::new(
            path,
            None,
            format!("cannot read the data ({ts}): {e} (truncated file?)"),
        )
    };
    let values: Vec<f64> = match (ts.type_char(), ts.size_field()) {
        (TypeChar::Float, 8) => npy.into_vec::<f64>().map_err(bad)?,
        (TypeChar::Float, 4) => npy
            .into_vec::<f32>()
            .map_err(bad)?
            .into_iter()
            .map(f64::from)
            .collect(),
        (TypeChar::Int, 1) => npy
            .into_vec::<i8>()
            .map_err(bad)?
            .into_iter()
            .map(f64::from)
            .collect(),
        (TypeChar::Int, 2) => npy
            .into_vec::<i16>()
            .map_err(bad)?
            .into_iter()
            .map(f64::from)
            .collect(),
        (TypeChar::Int, 4) => npy
            .into_vec::<i32>()
            .map_err(bad)?
            .into_iter()
            .map(f64::from)
            .collect(),
        (TypeChar::Int, 8) => npy
            .into_vec::<i64>()
            .map_err(bad)?
            .into_iter()
            .map(|v| v as f64)
            .collect(),
        (TypeChar::Uint, 1) => npy
            .into_vec::<u8>()
            .map_err(bad)?
            .into_iter()
            .map(f64::from)
            .collect(),
        (TypeChar::Uint, 2) => npy
            .into_vec::<u16>()
            .map_err(bad)?
            .into_iter()
            .map(f64::from)
            .collect(),
        (TypeChar::Uint, 4) => npy
            .into_vec::<u32>()
            .map_err(bad)?
            .into_iter()
            .map(f64::from)
            .collect(),
        (TypeChar::Uint, 8) => npy
            .into_vec::<u64>()
            .map_err(bad)?
            .into_iter()
            .map(|v| v as f64)
            .collect(),
        _ => {
            return Err(LoadError::new(
                path,
                None,
                format!("unsupported dtype `{ts}`: need float64, float32 or an integer type"),
            ))
        }
    };
    Ok(values)
}

/// `values` (`nt` frames of `ny` rows of `nx`, in the file's `order`) as `nt` grids.
fn into_frames(
    path: &Path,
    mut values: Vec<f64>,
    (nt, ny, nx): (usize, usize, usize),
    order: Order,
    shape: &[u64],
) -> Result<Vec<Grid2>, LoadError> {
    let n = nx * ny;
    if values.len() != n * nt {
        return Err(LoadError::new(
            path,
            None,
            format!(
                "{} values for shape {shape:?} (truncated file?)",
                values.len()
            ),
        ));
    }
    if order == Order::Fortran {
        // Element [k][iy][ix] sits at ix*ny*nt + iy*nt + k.
        let mut c = vec![0.0; n * nt];
        for k in 0..nt {
            for iy in 0..ny {
                for ix in 0..nx {
                    c[k * n + iy * nx + ix] = values[ix * ny * nt + iy * nt + k];
                }
            }
        }
        values = c;
    }
    // Frames split off the end one at a time: the values are never held twice over.
    let mut frames = Vec::with_capacity(nt);
    for k in (0..nt).rev() {
        let v = values.split_off(k * n);
        let g = Grid2::new(nx, ny, Vec2::default(), [1.0, 1.0], v).map_err(|e| {
            if nt > 1 {
                LoadError::new(path, None, format!("frame {k}: {e}"))
            } else {
                LoadError::grid(path, e)
            }
        })?;
        frames.push(g);
    }
    frames.reverse();
    Ok(frames)
}
