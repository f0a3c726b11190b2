//! Which paths name one file, and what a file holds (its SHA-256).

use std::path::Path;

/// The SHA-256 of the file at `path`, lowercase hex, read in blocks (memory flat whatever its
/// size; a non-regular file is refused without blocking, `isotrack_fields::io::open_regular`).
/// The one content digest of isotrack's data files: a run records its field files' digests in
/// `summary.json` (`data_files`), `plot`/`report` compare them (a file overwritten in place
/// between two runs is another field), and the Python package checks a pickled scenario's
/// files with it.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    sha256_of(isotrack_fields::io::open_regular(path)?)
}

/// The SHA-256 of a field's data file `path` ([`sha256_file`]), refused from its metadata,
/// before a byte is read, when it is larger than any field's reader accepts
/// ([`isotrack_fields::io::MAX_GRID_FILE_BYTES`]; the error `read_limited` gives): a sweep
/// checks its data files with it before any run (att30n-9: a 4.3 GB file named in `[grid]`
/// was hashed whole, 28 s, then each of its runs refused it).
pub fn sha256_data_file(path: &Path) -> std::io::Result<String> {
    let f = isotrack_fields::io::open_regular(path)?;
    let (len, max) = (
        f.metadata()?.len(),
        isotrack_fields::io::MAX_GRID_FILE_BYTES,
    );
    if len > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("{len} bytes is more than the {max} this reader accepts"),
        ));
    }
    sha256_of(f)
}

/// The SHA-256 (hex) of what file `f` holds from where it stands, read in 1 MiB blocks.
fn sha256_of(mut f: std::fs::File) -> std::io::Result<String> {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    feed(&mut h, &mut f)?;
    Ok(hex(&h.finalize()))
}

/// The SHA-256 (hex) of file `f`'s bytes outside `cut` (the file's bytes before `cut.start`,
/// then those from `cut.end` on), read in 1 MiB blocks: the digest of what isotrack wrote
/// before it put its mark at `cut` (a figure's mark, `isotrack_plot`'s `mark`).
pub fn sha256_outside(f: &mut std::fs::File, cut: std::ops::Range<u64>) -> std::io::Result<String> {
    use sha2::{Digest, Sha256};
    use std::io::{Read, Seek, SeekFrom};
    let mut h = Sha256::new();
    f.seek(SeekFrom::Start(0))?;
    feed(&mut h, &mut (&mut *f).take(cut.start))?;
    f.seek(SeekFrom::Start(cut.end))?;
    feed(&mut h, f)?;
    Ok(hex(&h.finalize()))
}

/// Feeds everything `r` gives to `h`, 1 MiB at a time.
fn feed(h: &mut sha2::Sha256, r: &mut impl std::io::Read) -> std::io::Result<()> {
    use sha2::Digest;
    let mut buf = vec![0u8; 1 << 20];
    loop {
        match r.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => h.update(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
}

/// Lowercase hex of `bytes`.
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Whether two paths name the same existing file (same device and inode), not just the same
/// string: `a/../a/x` and a hard link count.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) if x == y => true,
        _ => {
            #[cfg(unix)]
            {
                use std::os::unix::fs::MetadataExt;
                match (std::fs::metadata(a), std::fs::metadata(b)) {
                    (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
                    _ => false,
                }
            }
            #[cfg(not(unix))]
            false
        }
    }
}

/// The identity of the file at `path` (not followed if a link): its device and inode, `None`
/// when nothing is there. A file put in place by rename since has another: what an interrupted
/// command's note tells its own files from those there before it by.
pub fn identity(path: &Path) -> Option<(u64, u64)> {
    let m = std::fs::symlink_metadata(path).ok()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        Some((0, 0))
    }
}

/// Refuses an existing `path` that is not a regular file (a symbolic link, a FIFO, a
/// directory, a device): as read by `lstat` (`std::fs::symlink_metadata`), so a link is
/// refused, not followed. An absent path is fine (it will be created). Opening a FIFO for
/// writing would block until a reader comes; writing through a link would empty its target.
pub fn refuse_non_regular(path: &Path) -> std::io::Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.file_type().is_file() => Err(std::io::Error::other(format!(
            "{} exists and is not a regular file (a link, FIFO, directory or device): refusing to write it",
            shell_quoted(path)
        ))),
        _ => Ok(()),
    }
}

/// Opens `path` for reading without following a link and without blocking on a FIFO
/// (`O_NOFOLLOW | O_NONBLOCK` on Unix); anything but a regular file is an error (`it is not a
/// regular file`), so a caller reading what is there never hangs nor reads through a link.
pub fn open_read_regular(path: &Path) -> std::io::Result<std::fs::File> {
    let mut o = std::fs::OpenOptions::new();
    o.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
    }
    let f = o.open(path)?;
    if !f.metadata()?.is_file() {
        return Err(std::io::Error::other("it is not a regular file"));
    }
    Ok(f)
}

/// Opens `path` for writing without following a link and without blocking on a FIFO
/// (`O_NOFOLLOW | O_NONBLOCK` on Unix), creating it when absent; `truncate` empties it once it
/// is known to be a regular file. Anything else ([`refuse_non_regular`]) is an error, so the
/// caller exits 73 at once instead of hanging or writing through a link.
pub fn open_regular(path: &Path, read: bool, truncate: bool) -> std::io::Result<std::fs::File> {
    refuse_non_regular(path)?;
    let mut o = std::fs::OpenOptions::new();
    o.read(read).write(true).create(true).truncate(false);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
    }
    let f = o.open(path)?;
    if !f.metadata()?.is_file() {
        return Err(std::io::Error::other(format!(
            "{} is not a regular file: refusing to write it",
            path.display()
        )));
    }
    if truncate {
        f.set_len(0)?;
    }
    Ok(f)
}

/// The one way a command opens an output file for writing: [`open_regular`], emptied.
pub fn create_output(path: &Path) -> std::io::Result<std::fs::File> {
    if crate::cleanup::exiting() && !crate::cleanup::in_whole() {
        // An interrupt is removing the registered files and ending the process: a file created
        // now would be left behind, an error would end the process with another code. (A
        // `cleanup::whole` step under way is waited for by the interrupt: it finishes.)
        crate::cleanup::wait_for_exit();
    }
    open_regular(path, false, true)
}

/// Writes `bytes` to `path` atomically: into a temporary file beside it (same directory), then
/// renamed over it, so a reader (or a crash) sees the old file or the new one, never a mix. An
/// existing `path` that is not a regular file is refused ([`refuse_non_regular`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    write_atomic_with(path, |f| f.write_all(bytes))
}

/// As [`write_atomic`], the temporary file's content written by `write`. The temporary is
/// registered for removal if the command is interrupted ([`crate::cleanup::register`]: Ctrl-C,
/// SIGTERM, SIGHUP) until it is renamed into place or removed (att43-14: Ctrl-C while `report`
/// wrote its page left the whole `.NAME.PID.tmp` behind).
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    refuse_non_regular(path)?;
    let tmp = temp_beside(path);
    let pending = crate::cleanup::register(&tmp);
    let result = create_output(&tmp)
        .and_then(|mut f| write(&mut f).and_then(|()| f.sync_all()))
        .and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drop(pending);
    result
}

/// Gives the file at `path` a fresh inode holding the same bytes: copied to a temporary
/// beside it ([`temp_beside`]), then renamed over it. A hard link to the old file (a `cp -al`
/// or `rsync --link-dest` snapshot) keeps what it held; only the new file grows after this
/// (att36-13 addendum: `sweep --resume` appended its rows to the snapshot's results.csv too).
pub fn renew_inode(path: &Path) -> std::io::Result<()> {
    refuse_non_regular(path)?;
    let tmp = temp_beside(path);
    let pending = crate::cleanup::register(&tmp);
    let result = isotrack_fields::io::open_regular(path)
        .and_then(|mut from| {
            let mut to = create_output(&tmp)?;
            std::io::copy(&mut from, &mut to)?;
            to.sync_all()
        })
        .and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drop(pending);
    result
}

/// A temporary name beside `path` for an atomic write: `.NAME.PID.tmp` in the same directory.
pub fn temp_beside(path: &Path) -> std::path::PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// `path` as a POSIX shell word to paste, as every message naming a file the user is to move
/// or look at names it (att41-2: a refusal printed it raw, so a name with a line break forged
/// its own `error:` line; att39-7: `my run;touch PWNED` was printed bare, and a
/// line break in it forged a line of output): as it is when every character is plain, else in
/// single quotes, or as bash's `$'...'` with escapes when it holds a control character.
///
/// A relative path whose first character is `-` is named `./-x` (att53o-8: `isotrack plot -x`,
/// the command a note gave, was read as an option).
pub fn shell_quoted(path: &Path) -> String {
    let s = path.to_string_lossy();
    let s = if s.starts_with('-') {
        std::borrow::Cow::Owned(format!("./{s}"))
    } else {
        s
    };
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
