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
    use std::io::BufRead;
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
    let mut offset = rdr.read_line(&mut line).map_err(cannot)? as u64;
    let cut_at = |at: u64| -> Result<(), Failure> {
        if !repair {
            return Ok(());
        }
        let repair_fail = |e: std::io::Error| {
            fail(
                exit::CANTCREAT,
                format!("cannot repair {}: {e}", path.display()),
            )
        };
        std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(repair_fail)?
            .set_len(at)
            .map_err(repair_fail)
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
    let header = std::mem::take(&mut line);
    let columns: Vec<String> = csv_fields(&header).ok_or_else(|| {
        fail(
            exit::DATAERR,
            format!("{}:1: the header is not a CSV line", path.display()),
        )
    })?;
    let outcome_col = columns.iter().position(|c| c == "outcome");
    let warnings_col = columns.iter().position(|c| c == "warnings");
    let mut rows = vec![];
    let mut invalid = 0;
    let mut flagged = Flagged::default();
    for number in 2u64.. {
        line.clear();
        let n = rdr.read_line(&mut line).map_err(|e| {
            fail(
                exit::DATAERR,
                format!("{}:{number}: damaged row ({e})", path.display()),
            )
        })?;
        if n == 0 {
            break;
        }
        if !line.ends_with('\n') {
            cut_at(offset)?;
            break;
        }
        // Rows are written whole; a line that does not check is a damaged file, not ours to
        // guess at.
        let rules = RowRules {
            header: &columns,
            total,
            plan,
            spans,
        };
        let id = check_row(&rules, &line).map_err(|why| {
            let shown: String = line.trim_end().chars().take(120).collect();
            fail(
                exit::DATAERR,
                format!(
                    "{}:{number}: damaged row ({why}): `{shown}`; remove the line (or the file) and --resume",
                    path.display()
                ),
            )
        })?;
        let fields = csv_fields(&line).unwrap_or_default();
        let cell = |c: Option<usize>| c.and_then(|c| fields.get(c)).map(String::as_str);
        let outcome = cell(outcome_col);
        if outcome == Some("invalid_scenario") {
            invalid += 1;
        }
        if outcome.is_some_and(|o| o != "completed")
            || cell(warnings_col).is_some_and(|w| !w.is_empty())
        {
            flagged.add(id);
        }
        rows.push(RowRef {
            id,
            file,
            offset,
            len: n,
            line: number,
        });
        offset += n as u64;
    }
    Ok(ResultsIndex {
        header,
        rows,
        invalid,
        flagged,
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
    let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(cant)?);
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
    std::fs::rename(&tmp, path).map_err(cant)
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
