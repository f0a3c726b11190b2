//! ESRI ASCII grids (`.asc`). Written by hand: the format is a six-line header and numbers, and
//! the crates that read it bring GDAL along.
//!
//! Header keys (case-insensitive, any order): `ncols`, `nrows`, `xllcorner` or `xllcenter`,
//! `yllcorner` or `yllcenter`, `cellsize` (or `dx` and `dy`), optional `NODATA_value`. Then
//! `nrows` rows of `ncols` values, **north row first**, whitespace-separated. Coordinates are
//! taken as metres.

use super::error::{FilePosition, LoadError};
use super::loaded::{flip_rows, LoadedGrid};
use crate::georef::Georeference;
use crate::grid::Grid2;
use isotrack_core::Vec2;
use std::path::Path;

/// Parses an ESRI ASCII grid's bytes (`path` names it in errors): the header, then the rows.
// Long by choice: a header parser, read top to bottom in the order of the file (the header keys,
// their checks, then the rows); split, each piece would need the half-filled header passed along.
pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<LoadedGrid, LoadError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        LoadError::new(
            path,
            Some(FilePosition::Offset(e.valid_up_to() as u64)),
            "not UTF-8 text",
        )
    })?;
    let err =
        |line: usize, m: String| LoadError::new(path, Some(FilePosition::Line(line, None)), m);
    let mut ncols = None;
    let mut nrows = None;
    let mut xll: Option<(f64, bool)> = None; // (value, is_center)
    let mut yll: Option<(f64, bool)> = None;
    let mut cell: Option<(f64, f64)> = None;
    let mut dx = None;
    let mut dy = None;
    let mut nodata = None;
    let mut lines = text.lines().enumerate().peekable();
    // Header: lines whose first token is a known key.
    while let Some((i, line)) = lines.peek().copied() {
        let mut toks = line.split_whitespace();
        let Some(key) = toks.next() else {
            lines.next();
            continue;
        };
        let key_l = key.to_ascii_lowercase();
        let known = [
            "ncols",
            "nrows",
            "xllcorner",
            "xllcenter",
            "yllcorner",
            "yllcenter",
            "cellsize",
            "dx",
            "dy",
            "nodata_value",
        ];
        if !known.contains(&key_l.as_str()) {
            if key.parse::<f64>().is_ok() || key.eq_ignore_ascii_case("nan") {
                break; // data starts
            }
            return Err(err(i + 1, format!("unknown header key `{key}`")));
        }
        let val = toks
            .next()
            .ok_or_else(|| err(i + 1, format!("`{key}` has no value")))?;
        let num: f64 = val
            .parse()
            .map_err(|_| err(i + 1, format!("`{key}` value `{val}` is not a number")))?;
        let count = |v: f64| -> Result<usize, LoadError> {
            if v >= 2.0 && v.fract() == 0.0 && v < 1e8 {
                Ok(v as usize)
            } else {
                Err(err(
                    i + 1,
                    format!("`{key}` must be a whole number >= 2, got {val}"),
                ))
            }
        };
        match key_l.as_str() {
            "ncols" => ncols = Some(count(num)?),
            "nrows" => nrows = Some(count(num)?),
            "xllcorner" => xll = Some((num, false)),
            "xllcenter" => xll = Some((num, true)),
            "yllcorner" => yll = Some((num, false)),
            "yllcenter" => yll = Some((num, true)),
            "cellsize" => cell = Some((num, num)),
            "dx" => dx = Some(num),
            "dy" => dy = Some(num),
            _ => nodata = Some(num),
        }
        lines.next();
    }
    let missing = |k: &str| err(1, format!("header lacks `{k}`"));
    let nx = ncols.ok_or_else(|| missing("ncols"))?;
    let ny = nrows.ok_or_else(|| missing("nrows"))?;
    let (xv, xc) = xll.ok_or_else(|| missing("xllcorner"))?;
    let (yv, yc) = yll.ok_or_else(|| missing("yllcorner"))?;
    let (sx, sy) = match (cell, dx, dy) {
        (Some(c), _, _) => c,
        (None, Some(a), Some(b)) => (a, b),
        _ => return Err(missing("cellsize")),
    };
    // The header's sizes are untrusted: never allocate more than the text could hold (each
    // value takes at least two bytes), and refuse products that overflow.
    let declared = nx
        .checked_mul(ny)
        .filter(|n| *n <= bytes.len() / 2 + 1 && *n <= crate::grid::MAX_NODES)
        .ok_or_else(|| {
            err(
                1,
                format!(
                    "ncols x nrows = {nx} x {ny} values cannot fit in a {}-byte file (or exceed the {} nodes a grid may hold)",
                    bytes.len(),
                    crate::grid::MAX_NODES
                ),
            )
        })?;
    let mut values = Vec::with_capacity(declared);
    let mut last_line = 1;
    for (i, line) in lines {
        last_line = i + 1;
        for (c, tok) in line.split_whitespace().enumerate() {
            let v: f64 = tok.parse().map_err(|_| {
                LoadError::new(
                    path,
                    Some(FilePosition::Line(i + 1, Some(c + 1))),
                    format!("`{tok}` is not a number"),
                )
            })?;
            if values.len() == nx * ny {
                return Err(err(
                    i + 1,
                    format!("more than ncols x nrows = {} values", nx * ny),
                ));
            }
            values.push(if Some(v) == nodata { f64::NAN } else { v });
        }
    }
    if values.len() != nx * ny {
        return Err(err(
            last_line,
            format!(
                "{} values, expected ncols x nrows = {} (truncated?)",
                values.len(),
                nx * ny
            ),
        ));
    }
    flip_rows(&mut values, nx, ny);
    let x0 = if xc { xv } else { xv + 0.5 * sx };
    let y0 = if yc { yv } else { yv + 0.5 * sy };
    let grid = Grid2::new(nx, ny, Vec2::new(x0, y0), [sx, sy], values)
        .map_err(|e| LoadError::grid(path, e))?;
    Ok(LoadedGrid {
        grid,
        georeference: Georeference::Metres { epsg: None },
    })
}
