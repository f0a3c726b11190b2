//! NumPy `.npy` grids: 2-D, shape `(rows, cols)`, row 0 = south, C or Fortran order.

use super::{plain_grid, FilePosition, LoadError, LoadedGrid};
use npyz::{DType, NpyFile, Order, TypeChar};
use std::path::Path;

pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<LoadedGrid, LoadError> {
    let npy = NpyFile::new(bytes).map_err(|e| {
        LoadError::new(
            path,
            Some(FilePosition::Offset(0)),
            format!("not a valid .npy file: {e}"),
        )
    })?;
    let shape = npy.shape().to_vec();
    if shape.len() != 2 {
        return Err(LoadError::new(
            path,
            None,
            format!("expected a 2-D array, found shape {shape:?}"),
        ));
    }
    let (ny, nx) = (shape[0] as usize, shape[1] as usize);
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
    if nx
        .checked_mul(ny)
        .is_none_or(|n| n > crate::grid::MAX_NODES)
    {
        return Err(LoadError::grid(
            path,
            crate::grid::GridError::TooManyNodes { nx, ny },
        ));
    }
    // The header's shape is untrusted: refuse a data size beyond the file before reading.
    let item = ts.num_bytes().unwrap_or(8) as u128;
    if (ny as u128) * (nx as u128) * item > bytes.len() as u128 {
        return Err(LoadError::new(
            path,
            None,
            format!(
                "shape {shape:?} needs more data than the {}-byte file holds (truncated file?)",
                bytes.len()
            ),
        ));
    }
    let bad = |e: std::io::Error| {
        LoadError::new(
            path,
            None,
            format!("cannot read the data ({ts}): {e} (truncated file?)"),
        )
    };
    let mut values: Vec<f64> = match (ts.type_char(), ts.size_field()) {
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
    if values.len() != nx * ny {
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
        let mut c = vec![0.0; nx * ny];
        for iy in 0..ny {
            for ix in 0..nx {
                c[iy * nx + ix] = values[ix * ny + iy];
            }
        }
        values = c;
    }
    plain_grid(path, nx, ny, values)
}
