//! CSV grids (the layout of the bundled `data/`): no header, one row per line, row 0 = south.

use super::{plain_grid, FilePosition, LineNumbers, LoadError, LoadedGrid};
use std::path::Path;

pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<LoadedGrid, LoadError> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    let mut values = Vec::new();
    let mut nx: Option<usize> = None;
    let mut ny = 0usize;
    let mut lines = LineNumbers::new(bytes);
    for rec in rdr.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map(|p| lines.line_of(p.byte()));
            LoadError::new(
                path,
                line.map(|l| FilePosition::Line(l, None)),
                format!("{e}"),
            )
        })?;
        let line = rec.position().map_or(ny + 1, |p| lines.line_of(p.byte()));
        if rec.len() == 1 && rec[0].is_empty() {
            continue; // blank line
        }
        match nx {
            None => nx = Some(rec.len()),
            Some(n) if n != rec.len() => {
                return Err(LoadError::new(
                    path,
                    Some(FilePosition::Line(line, None)),
                    format!("ragged row: {} values, the first row has {n}", rec.len()),
                ))
            }
            _ => {}
        }
        for (c, tok) in rec.iter().enumerate() {
            let v: f64 = tok.parse().map_err(|_| {
                LoadError::new(
                    path,
                    Some(FilePosition::Line(line, Some(c + 1))),
                    format!("`{}` is not a number", isotrack_core::numtext::Clipped(tok)),
                )
            })?;
            values.push(v);
        }
        if values.len() > crate::grid::MAX_NODES {
            return Err(LoadError::new(
                path,
                Some(FilePosition::Line(line, None)),
                format!(
                    "more than the {} nodes a grid may hold",
                    crate::grid::MAX_NODES
                ),
            ));
        }
        ny += 1;
    }
    let Some(nx) = nx else {
        return Err(LoadError::new(path, None, "empty file: no grid rows"));
    };
    plain_grid(path, nx, ny, values)
}
