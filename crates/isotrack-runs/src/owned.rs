//! Whether a file isotrack is about to replace or remove is isotrack's own (README: "isotrack
//! never removes a file it may not have written"), and as isotrack wrote it (att42-8: the
//! user's edits of it are the user's): one test for each kind of file, shared by every command
//! that writes into a directory. A run's files: [`crate::rundir::not_an_earlier_run`] (a
//! `mavlink.tlog` only beside a flight's summary); a figure: its isotrack mark, which carries
//! the SHA-256 and size of the figure as written (`isotrack_plot::refuse_foreign_figure`, where
//! the mark is written); a table (`compare`'s `comparison.csv`, `check --map`'s
//! `stability_map.csv` and `verify.csv`): its size and SHA-256 as recorded in the directory's
//! [`TABLE_RECORD`] when isotrack wrote it ([`refuse_foreign_csv`], [`record_table`]); any
//! other file by its first bytes ([`refuse_foreign`] with [`empty_or_starts_with`]: a
//! benchmark's files) or as a JSON object with isotrack's keys ([`json_object_with`]: a sweep's
//! `sweep.json`, `crate::sweep::manifest::refuse_foreign_sweep_files`). Anything else of the
//! name is the user's: refused (73, naming it) before the command computes, runs or draws
//! anything.

use crate::failure::{exit, Failure};
use std::path::Path;

/// The file in an output directory recording each table isotrack wrote there (att42-8): a JSON
/// object, a table's file name -> `{"bytes": N, "sha256": "HEX"}` of the table as written,
/// replaced each time a table is ([`record_table`]). A table there whose size or SHA-256 is no
/// longer the recorded one was edited since (the user's copy now): never replaced.
pub const TABLE_RECORD: &str = ".isotrack-tables.json";

/// The largest [`TABLE_RECORD`] read, bytes: a few entries of ~100 bytes each.
const MAX_TABLE_RECORD_BYTES: u64 = 64 << 10;

/// A table as isotrack wrote it: its size and SHA-256 (lowercase hex).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Written {
    bytes: u64,
    sha256: String,
}

/// [`TABLE_RECORD`]'s content: a table's file name -> how isotrack wrote it.
type TableRecord = std::collections::BTreeMap<String, Written>;

/// The [`TABLE_RECORD`] of directory `dir`: `Ok(None)` when there is none, an error (the
/// reason) when what is there is not such a record (a file of the user's of that name, a link,
/// a FIFO, more than [`MAX_TABLE_RECORD_BYTES`]), never replaced then.
fn read_table_record(dir: &Path) -> Result<Option<TableRecord>, String> {
    use std::io::Read;
    let path = dir.join(TABLE_RECORD);
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(None);
    }
    let mut text = String::new();
    crate::files::open_read_regular(&path)
        .and_then(|f| f.take(MAX_TABLE_RECORD_BYTES + 1).read_to_string(&mut text))
        .map_err(|e| format!("it cannot be read: {e}"))?;
    if text.len() as u64 > MAX_TABLE_RECORD_BYTES {
        return Err(format!("it is larger than {MAX_TABLE_RECORD_BYTES} bytes"));
    }
    let record: TableRecord = serde_json::from_str(&text)
        .map_err(|e| format!("it is not isotrack's record of its tables: {e}"))?;
    let hex64 = |h: &str| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit());
    if let Some((name, _)) = record.iter().find(|(_, w)| !hex64(&w.sha256)) {
        return Err(format!("its entry for {name:?} holds no SHA-256"));
    }
    Ok(Some(record))
}

/// Refuses (73) a [`TABLE_RECORD`] in `dir` that is not isotrack's ([`read_table_record`]),
/// naming it: isotrack would replace it as it records a table.
fn table_record_in(dir: &Path) -> Result<Option<TableRecord>, Failure> {
    read_table_record(dir).map_err(|why| Failure {
        code: exit::CANTCREAT,
        message: format!(
            "{} is not isotrack's record of the tables it wrote ({why}), and isotrack never replaces a file it did not write: move it away, or use another --out",
            shell_quoted(&dir.join(TABLE_RECORD))
        ),
    })
}

/// The directory a table at `path` is in (`.` for a bare name).
fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// `path`'s file name, as [`TABLE_RECORD`] keys it.
fn name_of(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Refuses (73) an existing `path` that is not isotrack's table as isotrack wrote it, before
/// anything is computed (att39-1, att41-11, att42-8, att44-4): a table is isotrack's only while
/// its directory's [`TABLE_RECORD`] holds its size and SHA-256. Refused: one whose size or
/// SHA-256 is not the recorded one (edited since isotrack wrote it: a user's annotated copy, a
/// spreadsheet's re-export), one the record has no entry for (isotrack records every table it
/// writes there: the user's own file of that name), and any table in a directory without a
/// record (att44-4: the record is what tells isotrack's table from the user's edit of it, and a
/// copy made with `cp -r D/* E/` leaves it behind, so nothing there proves the table unedited;
/// an older isotrack's table, which recorded no digests, is refused likewise: its grace of one
/// release is over). A record that is not isotrack's is refused too, whatever the table.
/// `what` names the table (`an isotrack comparison`). A link, FIFO or directory at `path` is
/// refused (it cannot be read as a regular file).
pub fn refuse_foreign_csv(path: &Path, what: &str) -> Result<(), Failure> {
    let record = table_record_in(dir_of(path))?;
    if std::fs::symlink_metadata(path).is_err() {
        return Ok(());
    }
    // A link, FIFO, directory or device: refused as every output is (never read through).
    crate::files::refuse_non_regular(path).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: e.to_string(),
    })?;
    let why = match record.as_ref().map(|r| r.get(&name_of(path))) {
        Some(Some(w)) => match as_written(path, w) {
            Ok(true) => return Ok(()),
            Ok(false) => format!(
                "it was edited since isotrack wrote it: its size or SHA-256 is no longer the one recorded in {TABLE_RECORD}; if the edits are yours to keep, move it away or rename it"
            ),
            Err(e) => format!("it cannot be read: {e}"),
        },
        Some(None) => format!(
            "isotrack records every table it writes here in {TABLE_RECORD}, and it records none of this name: your own file"
        ),
        None => format!(
            "no {TABLE_RECORD} beside it records it, and isotrack records every table it writes: your own file, a copy made without that record (`cp -r D/* E/` leaves it behind) or an older isotrack's table, which nothing shows unedited; if it is an isotrack table you no longer need, remove it"
        ),
    };
    Err(Failure {
        code: exit::CANTCREAT,
        message: format!(
            "{} is not {what} as isotrack wrote it ({why}): refusing to replace it; move it away or use another --out",
            shell_quoted(path)
        ),
    })
}

/// Whether the regular file `path` is empty or begins with `prefix` (reads at most its
/// length, never through a link nor from a FIFO: [`crate::files::open_read_regular`]).
pub fn empty_or_starts_with(path: &Path, prefix: &[u8]) -> std::io::Result<bool> {
    use std::io::Read;
    let mut head = Vec::with_capacity(prefix.len());
    crate::files::open_read_regular(path)?
        .take(prefix.len() as u64)
        .read_to_end(&mut head)?;
    Ok(head.is_empty() || head == prefix)
}

/// Refuses (73) an existing `path` that is not a regular file (a link, FIFO, directory:
/// [`crate::files::refuse_non_regular`]'s message), that `ours` does not find isotrack's
/// (`Ok(false)`: the message says `why_not`), or that cannot be read: "PATH is not WHAT (WHY): refusing to replace it; move it away or
/// use another --out", the path quoted for a shell. `Ok` when nothing is at `path`. The one
/// refusal of a file isotrack names itself that is the user's (README, "Outputs").
pub fn refuse_foreign(
    path: &Path,
    ours: impl FnOnce(&Path) -> std::io::Result<bool>,
    what: &str,
    why_not: &str,
) -> Result<(), Failure> {
    if std::fs::symlink_metadata(path).is_err() {
        return Ok(());
    }
    // A link, FIFO, directory or device: refused as every output is (never read through).
    crate::files::refuse_non_regular(path).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: e.to_string(),
    })?;
    let why = match ours(path) {
        Ok(true) => return Ok(()),
        Ok(false) => why_not.to_string(),
        Err(e) => format!("it cannot be read: {e}"),
    };
    Err(Failure {
        code: exit::CANTCREAT,
        message: format!(
            "{} is not {what} ({why}): refusing to replace it; move it away or use another --out",
            shell_quoted(path)
        ),
    })
}

/// Reads the regular file `path` whole if it holds at most `max` bytes (`Ok(None)` when it
/// holds more: never read whole), without following a link nor blocking on a FIFO
/// ([`crate::files::open_read_regular`]).
pub fn read_capped(path: &Path, max: u64) -> std::io::Result<Option<Vec<u8>>> {
    use std::io::Read;
    let f = crate::files::open_read_regular(path)?;
    if f.metadata()?.len() > max {
        return Ok(None);
    }
    let mut bytes = Vec::new();
    f.take(max + 1).read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= max).then_some(bytes))
}

/// Whether the regular file `path` (at most `max` bytes, else not) is a JSON object with a
/// string at each of `strings` and a number at each of `numbers`: how isotrack tells its own
/// JSON (a sweep's `sweep.json`, `interpolate`'s sidecar) from the user's file of that name.
pub fn json_object_with(
    path: &Path,
    max: u64,
    strings: &[&str],
    numbers: &[&str],
) -> std::io::Result<bool> {
    let Some(bytes) = read_capped(path, max)? else {
        return Ok(false);
    };
    let Ok(serde_json::Value::Object(m)) = serde_json::from_slice(&bytes) else {
        return Ok(false);
    };
    Ok(strings
        .iter()
        .all(|k| m.get(*k).is_some_and(|v| v.is_string()))
        && numbers
            .iter()
            .all(|k| m.get(*k).is_some_and(|v| v.is_number())))
}

/// Whether the regular file `path` is `w` (its size from the metadata first: a file of another
/// size is not read at all; then its SHA-256).
fn as_written(path: &Path, w: &Written) -> std::io::Result<bool> {
    let mut f = crate::files::open_read_regular(path)?;
    let len = f.metadata()?.len();
    Ok(len == w.bytes && crate::files::sha256_outside(&mut f, 0..0)? == w.sha256)
}

/// Records table `path` as isotrack wrote it (`bytes`, what was written there) in its
/// directory's [`TABLE_RECORD`] (replaced atomically), so a later command tells it from the
/// user's edit of it ([`refuse_foreign_csv`]); `bytes` `None` forgets the entry (a table
/// isotrack removed). Call after the table is in place, in a directory whose record
/// [`refuse_foreign_csv`] has accepted (under the directory's lock).
pub fn record_table(path: &Path, bytes: Option<&[u8]>) -> std::io::Result<()> {
    let dir = dir_of(path);
    let mut record = read_table_record(dir)
        .map_err(std::io::Error::other)?
        .unwrap_or_default();
    match bytes {
        Some(b) => {
            let w = Written {
                bytes: b.len() as u64,
                sha256: isotrack_fields::io::sha256_hex(b),
            };
            record.insert(name_of(path), w);
        }
        None => {
            if record.remove(&name_of(path)).is_none() {
                return Ok(());
            }
        }
    }
    let mut text = serde_json::to_string_pretty(&record).map_err(std::io::Error::other)?;
    text.push('\n');
    crate::files::write_atomic(&dir.join(TABLE_RECORD), text.as_bytes())
}

/// Writes table `path` as every isotrack table is written: `bytes` into a temporary file
/// renamed over it ([`crate::files::write_atomic`]: a hard-linked copy of the old table keeps
/// its bytes, att46-2), then recorded in the directory's [`TABLE_RECORD`] ([`record_table`]),
/// both as one step an interrupt never cuts ([`crate::cleanup::whole`]): the table there is
/// always the one its record holds. For a directory whose record and table
/// [`refuse_foreign_csv`] has accepted, under the directory's lock.
pub fn write_table(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    crate::cleanup::whole(|| {
        crate::files::write_atomic(path, bytes)?;
        record_table(path, Some(bytes))
    })
}

/// Removes isotrack's table `path` (when there) and forgets it in its directory's
/// [`TABLE_RECORD`], as one step an interrupt never cuts ([`crate::cleanup::whole`]): a table
/// that no longer describes what is beside it (`check --map`'s `verify.csv` as the chart is
/// replaced, `compare`'s `comparison.csv` as a law's run is). Returns whether one was there.
/// For a table [`refuse_foreign_csv`] has accepted, under the directory's lock.
pub fn remove_table(path: &Path) -> std::io::Result<bool> {
    crate::cleanup::whole(|| {
        let there = match std::fs::remove_file(path) {
            Ok(()) => true,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
            Err(e) => return Err(e),
        };
        record_table(path, None)?;
        Ok(there)
    })
}

/// Re-exported: [`crate::files::shell_quoted`] is where a path is named for a message.
pub use crate::files::shell_quoted;

#[cfg(test)]
mod tests {
    use super::*;

    /// att39-7: the directory in the note's advice pastes into a POSIX shell as one word (bash
    /// for a control character): plain as is, else single-quoted, a quote closed and escaped.
    #[test]
    fn the_notes_directory_is_one_shell_word() {
        assert_eq!(shell_quoted(Path::new("/tmp/run_1.d")), "/tmp/run_1.d");
        assert_eq!(
            shell_quoted(Path::new("my run;touch PWNED")),
            "'my run;touch PWNED'"
        );
        assert_eq!(shell_quoted(Path::new("it's")), "'it'\\''s'");
        assert_eq!(shell_quoted(Path::new("-x")), "./-x");
        assert_eq!(shell_quoted(Path::new("-a b")), "'./-a b'");
        assert_eq!(shell_quoted(Path::new("a/-x")), "a/-x");
        assert_eq!(
            shell_quoted(Path::new("inj\u{1b}[2J\nnote")),
            "$'inj\\x1b[2J\\x0anote'"
        );
    }

    /// Bytes this thread has read through `read` calls so far (`rchar` of
    /// `/proc/thread-self/io`; `None` where the kernel does not give it): what a test measures
    /// a reader's cost by, never the wall clock.
    fn bytes_read_by_this_thread() -> Option<u64> {
        let io = std::fs::read_to_string("/proc/thread-self/io").ok()?;
        io.lines()
            .find_map(|l| l.strip_prefix("rchar:"))
            .and_then(|v| v.trim().parse().ok())
    }

    /// att44-4: without a record beside it a table is never isotrack's, whatever it holds:
    /// isotrack's header with its rows (a copy made with `cp -r D/* E/`, the record left
    /// behind, then annotated or not), the header alone, anything else; each is refused (73)
    /// saying no record holds it, and a huge file is not read at all (a 4 GiB sparse file
    /// answers from under 1 MiB read). Nothing there is fine.
    #[test]
    fn without_a_record_no_table_is_isotracks() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("t.csv");
        for text in [
            "a,b,c\n1,2,3\n",
            "a,b,c\n1,2,3\n# mine,,\n",
            "a,b,c",
            "",
            "MY DATA\n",
        ] {
            std::fs::write(&p, text).unwrap();
            let e = refuse_foreign_csv(&p, "a table of mine").unwrap_err();
            assert_eq!(e.code, exit::CANTCREAT);
            assert!(
                e.message
                    .contains("no .isotrack-tables.json beside it records it"),
                "{}",
                e.message
            );
            assert_eq!(std::fs::read_to_string(&p).unwrap(), text);
        }
        let f = std::fs::File::create(&p).unwrap();
        f.set_len(4 << 30).unwrap();
        drop(f);
        let before = bytes_read_by_this_thread();
        assert!(refuse_foreign_csv(&p, "x").is_err());
        if let (Some(a), Some(b)) = (before, bytes_read_by_this_thread()) {
            assert!(b - a < 1 << 20, "{} bytes read", b - a);
        }
        assert!(refuse_foreign_csv(&d.path().join("none.csv"), "x").is_ok());
    }

    /// att42-8: a table isotrack recorded is its own only as written. The record holds what
    /// was written (its size and the SHA-256 `sha256sum` gives: FIPS 180-2's `abc` vector
    /// checks the digest); the same first line with one cell edited, or with a row appended, is
    /// the user's (refused 73, "edited since isotrack wrote it"), and so is a table of another
    /// name the record does not hold; a record that is not isotrack's is refused.
    #[test]
    fn a_recorded_table_is_isotracks_only_as_written() {
        let d = tempfile::tempdir().unwrap();
        let refuse = |p: &Path| refuse_foreign_csv(p, "a table of mine");
        let t = d.path().join("t.csv");
        // No record yet: refused (above); recorded as written, isotrack's.
        std::fs::write(&t, "a,b\n1,2\n").unwrap();
        assert!(refuse(&t).is_err());
        record_table(&t, Some(b"a,b\n1,2\n")).unwrap();
        assert!(refuse(&t).is_ok());
        // The record: size 8 and the digest of these 8 bytes, computed independently.
        let rec: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.path().join(TABLE_RECORD)).unwrap())
                .unwrap();
        assert_eq!(rec["t.csv"]["bytes"], 8);
        assert_eq!(
            isotrack_fields::io::sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(
            rec["t.csv"]["sha256"],
            isotrack_fields::io::sha256_hex(b"a,b\n1,2\n")
        );
        // Edited: the same size (one cell changed), then another size (a row added).
        for edited in ["a,b\n1,3\n", "a,b\n1,2\n3,4\n"] {
            std::fs::write(&t, edited).unwrap();
            let e = refuse(&t).unwrap_err();
            assert_eq!(e.code, exit::CANTCREAT);
            assert!(
                e.message.contains("edited since isotrack wrote it"),
                "{}",
                e.message
            );
            assert!(
                e.message.contains(&t.display().to_string()),
                "{}",
                e.message
            );
            assert_eq!(std::fs::read_to_string(&t).unwrap(), edited);
        }
        // Another table of isotrack's header, not in the record: the user's.
        let u = d.path().join("u.csv");
        std::fs::write(&u, "a,b\n9,9\n").unwrap();
        let e = refuse(&u).unwrap_err();
        assert!(
            e.message.contains("records none of this name"),
            "{}",
            e.message
        );
        // Nothing there: fine, whatever the record; a forgotten table is no longer recorded.
        assert!(refuse(&d.path().join("v.csv")).is_ok());
        record_table(&t, None).unwrap();
        std::fs::write(&t, "a,b\n1,2\n").unwrap();
        assert!(refuse(&t).is_err());
        // A record that is not isotrack's is refused (it would be replaced), table or not.
        std::fs::write(d.path().join(TABLE_RECORD), "my notes\n").unwrap();
        let e = refuse(&d.path().join("v.csv")).unwrap_err();
        assert!(e.message.contains(TABLE_RECORD), "{}", e.message);
        assert!(record_table(&t, Some(b"x")).is_err());
        assert_eq!(
            std::fs::read_to_string(d.path().join(TABLE_RECORD)).unwrap(),
            "my notes\n"
        );
    }
}
