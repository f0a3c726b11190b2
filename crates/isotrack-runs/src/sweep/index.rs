//! The index of a `results.csv` (where each row is, never the rows: memory stays flat however
//! large the sweep), and the sorted rewrite of indexed rows.

use crate::failure::{exit, fail, Failure};
use crate::sweep::check::{check_row, RowRules, RunSpans};
use crate::sweep::rows::csv_fields;
use isotrack_scenario::sweep::SweepPlan;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The largest `results.csv` that `--resume` and `merge` read, bytes (1 TiB: a billion runs at
/// a kilobyte a row), counted on the bytes read: a `/proc` file or a file that grows is stopped
/// there.
pub const MAX_RESULTS_FILE_BYTES: u64 = 1 << 40;

/// The longest line of a `results.csv` that `--resume` and `merge` hold, bytes with its
/// newline (1 MiB). A row isotrack writes is the run id, the plan's values, a dozen metrics and
/// the outcome and warnings cells: a few kilobytes at most. A longer line is refused (65)
/// before it is held, so one huge row cannot exhaust memory.
pub const MAX_RESULTS_LINE_BYTES: u64 = 1 << 20;

/// Reads one line of at most [`MAX_RESULTS_LINE_BYTES`] into `line` (appended), its length in
/// bytes; `Ok(None)` for a line longer than that (nothing more than the limit is held).
fn read_line_bounded(
    rdr: &mut impl std::io::BufRead,
    line: &mut String,
) -> std::io::Result<Option<usize>> {
    use std::io::{BufRead, Read};
    let n = rdr
        .by_ref()
        .take(MAX_RESULTS_LINE_BYTES + 1)
        .read_line(line)?;
    if n as u64 > MAX_RESULTS_LINE_BYTES {
        return Ok(None);
    }
    Ok(Some(n))
}

/// The first line of results file `path` with its newline (empty for a file without a
/// complete one), at most [`MAX_RESULTS_LINE_BYTES`] held.
pub fn read_header(path: &Path) -> Result<String, Failure> {
    let cannot = |e: std::io::Error| {
        fail(
            exit::NOINPUT,
            format!("cannot read {}: {e}", path.display()),
        )
    };
    let mut rdr = std::io::BufReader::new(
        isotrack_fields::io::open_limited(path, MAX_RESULTS_FILE_BYTES).map_err(cannot)?,
    );
    let mut line = String::new();
    match read_line_bounded(&mut rdr, &mut line) {
        Ok(Some(_)) if line.ends_with('\n') => Ok(line),
        Ok(Some(_)) => Ok(String::new()),
        Ok(None) => Err(fail(
            exit::DATAERR,
            format!(
                "{}:1: a line longer than {} bytes, longer than any row isotrack writes: a damaged file; remove the line (or the file)",
                path.display(),
                MAX_RESULTS_LINE_BYTES
            ),
        )),
        // Not UTF-8: no header isotrack writes.
        Err(e) if e.kind() == std::io::ErrorKind::InvalidData => Err(fail(
            exit::DATAERR,
            format!("{}:1: the header is not UTF-8 text", path.display()),
        )),
        Err(e) => Err(cannot(e)),
    }
}

/// One row of a results file: its run id and where its line is (not the line: a sweep's
/// memory must not grow with its run count).
#[derive(Clone, Copy, Debug)]
pub struct RowRef {
    /// The run id.
    pub id: u64,
    /// Which of the indexed files.
    pub file: usize,
    /// Where the line starts, bytes.
    pub offset: u64,
    /// The line's length with its newline, bytes.
    pub len: usize,
    /// 1-based line number, for messages.
    pub line: u64,
}

/// A results file, indexed: its header, where each row is, and how many rows are
/// `invalid_scenario`.
pub struct ResultsIndex {
    /// The header line, with its newline (empty for a file without a complete header).
    pub header: String,
    /// The rows, in file order.
    pub rows: Vec<RowRef>,
    /// How many rows are `invalid_scenario`.
    pub invalid: u64,
    /// The rows of runs that did not complete or ended with a warning.
    pub flagged: Flagged,
}

/// The runs of a results file that did not complete (`outcome` other than `completed`) or
/// ended with a warning (a non-empty `warnings` cell): how many, and the smallest few ids
/// (a sweep's tally names them; the reasons are in the rows).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Flagged {
    /// How many.
    pub count: u64,
    /// The smallest [`Flagged::SHOWN`] of their ids, sorted.
    pub first_ids: Vec<u64>,
}

impl Flagged {
    /// How many ids a tally names.
    pub const SHOWN: usize = 5;

    /// Counts run `id`, keeping the smallest [`Flagged::SHOWN`] ids (rows come in any order).
    pub fn add(&mut self, id: u64) {
        self.count += 1;
        let at = self.first_ids.partition_point(|&x| x < id);
        if at < Self::SHOWN {
            self.first_ids.insert(at, id);
            self.first_ids.truncate(Self::SHOWN);
        }
    }
}

/// Indexes `path` (file number `file` for [`RowRef::file`]) in one streaming pass, checking
/// every row (field count, `run_id` below `total`, known outcome, numeric metrics, the bounds
/// of the run's own step counts from `spans`). A cut-off last
/// line (a killed sweep) is left out, and with `repair` cut from the file.
pub fn index_results(
    path: &Path,
    file: usize,
    repair: bool,
    total: u64,
    plan: &SweepPlan,
    spans: &RunSpans<'_>,
) -> Result<ResultsIndex, Failure> {
    let cannot = |e: std::io::Error| {
        fail(
            exit::NOINPUT,
            format!("cannot read {}: {e}", path.display()),
        )
    };
    let mut rdr = std::io::BufReader::new(
        isotrack_fields::io::open_limited(path, MAX_RESULTS_FILE_BYTES).map_err(cannot)?,
    );
    let mut line = String::new();
    let mut offset = read_line_bounded(&mut rdr, &mut line)
        .map_err(cannot)?
        .ok_or_else(|| line_too_long(path, 1))? as u64;
    let cut_at = |at: u64| {
        if repair {
            cut_results(path, at)
        } else {
            Ok(())
        }
    };
    if !line.ends_with('\n') {
        // No complete header: an empty file, or one cut before its first newline.
        cut_at(0)?;
        return Ok(ResultsIndex {
            header: String::new(),
            rows: vec![],
            invalid: 0,
            flagged: Flagged::default(),
        });
    }
    let mut index = ResultsIndex {
        header: std::mem::take(&mut line),
        rows: vec![],
        invalid: 0,
        flagged: Flagged::default(),
    };
    let columns: Vec<String> = csv_fields(&index.header).ok_or_else(|| {
        fail(
            exit::DATAERR,
            format!("{}:1: the header is not a CSV line", path.display()),
        )
    })?;
    let outcome_col = columns.iter().position(|c| c == "outcome");
    let warnings_col = columns.iter().position(|c| c == "warnings");
    for number in 2u64.. {
        let n = read_row_line(&mut rdr, &mut line, path, number)?;
        if n == 0 {
            break;
        }
        if !line.ends_with('\n') {
            cut_at(offset)?;
            break;
        }
        let rules = RowRules {
            header: &columns,
            total,
            plan,
            spans,
        };
        let id = checked_row(&rules, path, number, &line)?;
        index.count(id, &line, outcome_col, warnings_col);
        index.rows.push(RowRef {
            id,
            file,
            offset,
            len: n,
            line: number,
        });
        offset += n as u64;
    }
    Ok(index)
}

impl ResultsIndex {
    /// Counts checked row `line` of run `id`: an `invalid_scenario` one (its `outcome` in
    /// column `outcome_col`), and one that did not complete or has a warning (its `warnings`
    /// in column `warnings_col`) flagged.
    fn count(
        &mut self,
        id: u64,
        line: &str,
        outcome_col: Option<usize>,
        warnings_col: Option<usize>,
    ) {
        let fields = csv_fields(line).unwrap_or_default();
        let cell = |c: Option<usize>| c.and_then(|c| fields.get(c)).map(String::as_str);
        let outcome = cell(outcome_col);
        if outcome == Some("invalid_scenario") {
            self.invalid += 1;
        }
        if outcome.is_some_and(|o| o != "completed")
            || cell(warnings_col).is_some_and(|w| !w.is_empty())
        {
            self.flagged.add(id);
        }
    }
}

/// Reads row line `number` of results file `path` into `line` (cleared first); its length in
/// bytes, 0 at the end of the file.
fn read_row_line(
    rdr: &mut impl std::io::BufRead,
    line: &mut String,
    path: &Path,
    number: u64,
) -> Result<usize, Failure> {
    line.clear();
    read_line_bounded(rdr, line)
        .map_err(|e| {
            fail(
                exit::DATAERR,
                format!("{}:{number}: damaged row ({e})", path.display()),
            )
        })?
        .ok_or_else(|| line_too_long(path, number))
}

/// The failure for line `number` of results file `path` longer than any row isotrack writes.
fn line_too_long(path: &Path, number: u64) -> Failure {
    fail(
        exit::DATAERR,
        format!(
            "{}:{number}: a line longer than {} bytes, longer than any row isotrack writes: a damaged file; remove the line (or the file)",
            path.display(),
            MAX_RESULTS_LINE_BYTES
        ),
    )
}

/// Cuts results file `path` to its first `at` bytes (a cut-off last line dropped on
/// `--resume`).
fn cut_results(path: &Path, at: u64) -> Result<(), Failure> {
    let repair_fail = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot repair {}: {e}", path.display()),
        )
    };
    crate::files::open_regular(path, false, false)
        .map_err(repair_fail)?
        .set_len(at)
        .map_err(repair_fail)
}

/// The run id of row `line` (line `number` of `path`) once it checks against `rules`
/// ([`check_row`]): rows are written whole, so a line that does not check is a damaged file,
/// not ours to guess at.
fn checked_row(rules: &RowRules<'_>, path: &Path, number: u64, line: &str) -> Result<u64, Failure> {
    check_row(rules, line).map_err(|why| {
        let shown: String = line.trim_end().chars().take(120).collect();
        fail(
            exit::DATAERR,
            format!(
                "{}:{number}: damaged row ({why}): `{shown}`; remove the line (or the file) and --resume",
                path.display()
            ),
        )
    })
}

/// Sorts `rows` by run id; the ids that appear more than once (first occurrences listed).
pub fn sort_rows(rows: &mut [RowRef]) -> Vec<RowRef> {
    rows.sort_by_key(|r| (r.id, r.file, r.offset));
    rows.windows(2)
        .filter(|w| w[0].id == w[1].id)
        .map(|w| w[1])
        .collect()
}

/// Writes the sorted `rows` (read back from `sources`, by [`RowRef::file`]) under `header` to
/// `path` atomically (temporary file, then rename). Memory: one line at a time.
pub fn write_sorted(
    path: &Path,
    header: &str,
    rows: &[RowRef],
    sources: &[PathBuf],
) -> Result<(), Failure> {
    write_sorted_temp(path, header, rows, sources)?.put_in_place()
}

/// A table written into its temporary beside `path` ([`write_sorted_temp`]), removed if the
/// command is interrupted before [`SortedTable::put_in_place`] renames it (or if this is
/// dropped first).
pub struct SortedTable {
    tmp: PathBuf,
    path: PathBuf,
    _pending: crate::cleanup::Pending,
}

impl SortedTable {
    /// Renames the table into place.
    pub fn put_in_place(self) -> Result<(), Failure> {
        std::fs::rename(&self.tmp, &self.path).map_err(|e| {
            fail(
                exit::CANTCREAT,
                format!("cannot write {}: {e}", self.path.display()),
            )
        })
    }
}

impl Drop for SortedTable {
    fn drop(&mut self) {
        // Gone once renamed into place; else not left behind.
        let _ = std::fs::remove_file(&self.tmp);
    }
}

/// As [`write_sorted`], into a temporary beside `path` for the caller to put in place (a
/// merge: with its manifest, in one step an interrupt never cuts).
pub fn write_sorted_temp(
    path: &Path,
    header: &str,
    rows: &[RowRef],
    sources: &[PathBuf],
) -> Result<SortedTable, Failure> {
    use std::io::{Read, Seek, SeekFrom};
    let tmp = path.with_extension("csv.tmp");
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", path.display()),
        )
    };
    let mut inputs = sources
        .iter()
        .map(|p| {
            isotrack_fields::io::open_regular(p)
                .map(std::io::BufReader::new)
                .map_err(|e| fail(exit::NOINPUT, format!("cannot read {}: {e}", p.display())))
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    // Removed if the command is interrupted while it is written (att43-14), until renamed.
    let table = SortedTable {
        _pending: crate::cleanup::register(&tmp),
        tmp: tmp.clone(),
        path: path.to_path_buf(),
    };
    let mut f = std::io::BufWriter::new(crate::files::create_output(&tmp).map_err(cant)?);
    f.write_all(header.as_bytes()).map_err(cant)?;
    let mut at = vec![u64::MAX; inputs.len()];
    let mut buf = Vec::new();
    for r in rows {
        let src = &mut inputs[r.file];
        // Rows finish roughly in id order, so most reads follow on from the last: seek (which
        // drops the reader's buffer) only when they do not.
        if at[r.file] != r.offset {
            src.seek(SeekFrom::Start(r.offset)).map_err(cant)?;
        }
        buf.resize(r.len, 0);
        src.read_exact(&mut buf).map_err(cant)?;
        at[r.file] = r.offset + r.len as u64;
        f.write_all(&buf).map_err(cant)?;
    }
    f.into_inner()
        .map_err(|e| cant(e.into_error()))?
        .sync_all()
        .map_err(cant)?;
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::Flagged;

    /// Rows come in any order (a sweep's rows as they finish, shards one after the other): the
    /// tally keeps the count and the smallest five ids, sorted.
    #[test]
    fn flagged_keeps_the_count_and_the_smallest_ids() {
        let mut f = Flagged::default();
        for id in [40, 7, 99, 3, 12, 8, 1, 500] {
            f.add(id);
        }
        assert_eq!(f.count, 8);
        assert_eq!(f.first_ids, [1, 3, 7, 8, 12]);
    }
}
