//! Whether a file isotrack is about to replace or remove is isotrack's own (README: "isotrack
//! never removes a file it may not have written"): one test for each kind of file, shared by
//! every command that writes into a directory. A run's files: [`crate::rundir::not_an_earlier_run`]
//! (a `mavlink.tlog` only beside a flight's summary); a figure: its isotrack mark
//! (`isotrack_plot::refuse_foreign_figure`, where the mark is written); a table: its first line
//! is isotrack's header for that file ([`refuse_foreign_csv`]: `compare`'s `comparison.csv`,
//! `check --map`'s `stability_map.csv` and `verify.csv`); any other file by its first bytes
//! ([`refuse_foreign`] with [`empty_or_starts_with`]: a benchmark's files) or as a JSON object
//! with isotrack's keys ([`json_object_with`]: a sweep's `sweep.json`,
//! `crate::sweep::manifest::refuse_foreign_sweep_files`). Anything else of the name is the
//! user's: refused (73, naming it) before the command computes, runs or draws anything.

use crate::failure::{exit, Failure};
use std::path::Path;

/// Whether the first line of the regular file `path` is one of `headers` exactly. Reads at
/// most the longest header and its line end (never the whole file: a 20 GB file costs what a
/// small one does), never through a link nor from a FIFO
/// ([`crate::files::open_read_regular`]).
pub fn first_line_is(path: &Path, headers: &[String]) -> std::io::Result<bool> {
    use std::io::Read;
    let max = headers.iter().map(String::len).max().unwrap_or(0) + 1;
    let mut head = Vec::with_capacity(max);
    crate::files::open_read_regular(path)?
        .take(max as u64)
        .read_to_end(&mut head)?;
    let first = head.split(|b| *b == b'\n').next().unwrap_or_default();
    Ok(headers.iter().any(|h| h.as_bytes() == first))
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

/// Refuses (73) an existing `path` that is not isotrack's table: its first line is none of
/// `headers` (every header isotrack has written for that file, the present one first;
/// [`first_line_is`]), or it cannot be read. `what` names the table (`an isotrack
/// comparison`), `whose` the header's writer (`compare's`). `Ok` when nothing is at `path`; a
/// link, FIFO or directory there is refused too ([`refuse_foreign`]).
pub fn refuse_foreign_csv(
    path: &Path,
    headers: &[String],
    what: &str,
    whose: &str,
) -> Result<(), Failure> {
    let why_not = format!(
        "its first line is not {whose} header `{}`",
        headers.first().map(String::as_str).unwrap_or_default()
    );
    refuse_foreign(path, |p| first_line_is(p, headers), what, &why_not)
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

/// `path` as a POSIX shell word to paste, as every message naming a file the user is to move
/// or look at names it (att41-2: a refusal printed it raw, so a name with a line break forged
/// its own `error:` line; att39-7: `my run;touch PWNED` was printed bare, and a
/// line break in it forged a line of output): as it is when every character is plain, else in
/// single quotes, or as bash's `$'...'` with escapes when it holds a control character.
pub fn shell_quoted(path: &Path) -> String {
    let s = path.to_string_lossy();
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./+,:@%=".contains(c);
    if !s.is_empty() && s.chars().all(plain) {
        return s.into_owned();
    }
    if s.chars().any(char::is_control) {
        let body: String = s
            .chars()
            .map(|c| match c {
                '\\' => "\\\\".to_string(),
                '\'' => "\\'".to_string(),
                c if c.is_control() && (c as u32) < 0x80 => format!("\\x{:02x}", c as u32),
                c if c.is_control() => format!("\\u{:04x}", c as u32),
                c => c.to_string(),
            })
            .collect();
        return format!("$'{body}'");
    }
    format!("'{}'", s.replace('\'', "'\\''"))
}

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
        assert_eq!(
            shell_quoted(Path::new("inj\u{1b}[2J\nnote")),
            "$'inj\\x1b[2J\\x0anote'"
        );
    }

    /// A table is isotrack's only when its first line is a header exactly: not a prefix of
    /// one, not one with more after it on the line; a huge file is not read whole (a 4 GiB
    /// sparse file answers from under 1 MiB read).
    /// Bytes this thread has read through `read` calls so far (`rchar` of
    /// `/proc/thread-self/io`; `None` where the kernel does not give it): what a test measures
    /// a reader's cost by, never the wall clock.
    fn bytes_read_by_this_thread() -> Option<u64> {
        let io = std::fs::read_to_string("/proc/thread-self/io").ok()?;
        io.lines()
            .find_map(|l| l.strip_prefix("rchar:"))
            .and_then(|v| v.trim().parse().ok())
    }

    #[test]
    fn a_table_is_told_by_its_first_line() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("t.csv");
        let headers = ["a,b,c".to_string(), "a,b".to_string()];
        for (text, ours) in [
            ("a,b,c\n1,2,3\n", true),
            ("a,b\n1,2\n", true),
            ("a,b,c", true),
            ("a,b,c,d\n", false),
            ("a\n", false),
            ("", false),
            ("MY DATA\n", false),
        ] {
            std::fs::write(&p, text).unwrap();
            assert_eq!(first_line_is(&p, &headers).unwrap(), ours, "{text:?}");
            let r = refuse_foreign_csv(&p, &headers, "a table of mine", "its");
            assert_eq!(r.is_ok(), ours, "{text:?}");
            if let Err(e) = r {
                assert_eq!(e.code, exit::CANTCREAT);
                assert!(
                    e.message
                        .contains("its first line is not its header `a,b,c`"),
                    "{}",
                    e.message
                );
            }
        }
        let f = std::fs::File::create(&p).unwrap();
        f.set_len(4 << 30).unwrap();
        drop(f);
        let before = bytes_read_by_this_thread();
        assert!(refuse_foreign_csv(&p, &headers, "x", "y").is_err());
        if let (Some(a), Some(b)) = (before, bytes_read_by_this_thread()) {
            assert!(b - a < 1 << 20, "{} bytes read", b - a);
        }
        assert!(refuse_foreign_csv(&d.path().join("none.csv"), &headers, "x", "y").is_ok());
    }
}
