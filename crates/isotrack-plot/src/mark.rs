//! The mark every figure isotrack writes carries (att38-9), so that a later `plot` or
//! `run --plot` can tell its own figure from the user's file of the same name and never
//! replaces a file isotrack did not write: a PNG's `tEXt` chunk `Software` = `isotrack`
//! (after `IHDR`), a GIF's comment extension `isotrack` (before its trailer), an SVG's
//! closing comment `<!-- isotrack figure -->` (after the root element). Readers ignore all
//! three; the pixels are unchanged.

use std::path::Path;

/// The text of the mark.
const MARK: &[u8] = b"isotrack";
/// The PNG `tEXt` chunk's data: keyword `Software`, a NUL, the mark.
const PNG_TEXT: &[u8] = b"Software\0isotrack";
/// The SVG's closing comment.
const SVG_MARK: &str = "<!-- isotrack figure -->\n";
/// The PNG signature.
const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The CRC-32 (ISO 3309, as PNG's chunks use) of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    c ^ 0xffff_ffff
}

/// `bytes` (a PNG) with the mark's `tEXt` chunk after `IHDR`; `None` if not a PNG.
fn png_marked(bytes: &[u8]) -> Option<Vec<u8>> {
    // Signature (8) + IHDR: length (4) + type (4) + 13 data + CRC (4).
    let ihdr_end = 8 + 4 + 4 + 13 + 4;
    if bytes.len() < ihdr_end || &bytes[..8] != PNG_SIGNATURE || &bytes[12..16] != b"IHDR" {
        return None;
    }
    let mut chunk = Vec::with_capacity(12 + PNG_TEXT.len());
    chunk.extend_from_slice(&(PNG_TEXT.len() as u32).to_be_bytes());
    let mut body = b"tEXt".to_vec();
    body.extend_from_slice(PNG_TEXT);
    chunk.extend_from_slice(&body);
    chunk.extend_from_slice(&crc32(&body).to_be_bytes());
    let mut out = Vec::with_capacity(bytes.len() + chunk.len());
    out.extend_from_slice(&bytes[..ihdr_end]);
    out.extend_from_slice(&chunk);
    out.extend_from_slice(&bytes[ihdr_end..]);
    Some(out)
}

/// The most PNG chunks looked at for the mark: isotrack puts it right after `IHDR` (the
/// second chunk); a few more are allowed for, never a walk through a file's every chunk.
const PNG_CHUNKS_LOOKED_AT: usize = 16;

/// Reads `buf.len()` bytes of `f` at `at`; `false` when the file holds fewer.
fn read_at(f: &mut std::fs::File, at: u64, buf: &mut [u8]) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    f.seek(SeekFrom::Start(at)).is_ok() && f.read_exact(buf).is_ok()
}

/// Whether PNG file `f` (`len` bytes) holds the mark's `tEXt` chunk before its image data:
/// its chunk headers are read one by one (12 bytes each, the data skipped), the first
/// [`PNG_CHUNKS_LOOKED_AT`] at most (att41-18: the whole file was read into memory).
fn png_has_mark(f: &mut std::fs::File, len: u64) -> bool {
    let mut signature = [0u8; 8];
    if !read_at(f, 0, &mut signature) || signature != PNG_SIGNATURE {
        return false;
    }
    let mut at = 8u64;
    for _ in 0..PNG_CHUNKS_LOOKED_AT {
        let mut head = [0u8; 8];
        if !read_at(f, at, &mut head) {
            return false;
        }
        let n = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
        let kind = &head[4..8];
        let end = at + 8 + n;
        if kind == b"IDAT" || kind == b"IEND" || end > len {
            return false;
        }
        if kind == b"tEXt" && n == PNG_TEXT.len() as u64 {
            let mut data = [0u8; PNG_TEXT.len()];
            if read_at(f, at + 8, &mut data) && data == PNG_TEXT {
                return true;
            }
        }
        at = end + 4;
    }
    false
}

/// Whether file `f` (`len` bytes) ends with `tail` then `after` more bytes (read: those
/// bytes only).
fn ends_with(f: &mut std::fs::File, len: u64, tail: &[u8], after: u64) -> bool {
    let n = tail.len() as u64 + after;
    if len < n {
        return false;
    }
    let mut buf = vec![0u8; tail.len()];
    read_at(f, len - n, &mut buf) && buf == tail
}

/// The GIF comment extension holding the mark: introducer, label, one sub-block, terminator.
fn gif_comment() -> Vec<u8> {
    let mut c = vec![0x21, 0xfe, MARK.len() as u8];
    c.extend_from_slice(MARK);
    c.push(0);
    c
}

/// `bytes` (a GIF) with the mark's comment before the trailer; `None` if not a GIF.
fn gif_marked(bytes: &[u8]) -> Option<Vec<u8>> {
    if !(bytes.starts_with(b"GIF8") && bytes.last() == Some(&0x3b)) {
        return None;
    }
    let mut out = bytes[..bytes.len() - 1].to_vec();
    out.extend_from_slice(&gif_comment());
    out.push(0x3b);
    Some(out)
}

/// Marks the figure at `path` by its extension (`png`, `gif`, `svg`; others are left as
/// they are).
pub(crate) fn mark(path: &Path) -> Result<(), String> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "png" | "gif" => {
            let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
            let marked = if ext == "png" {
                png_marked(&bytes)
            } else {
                gif_marked(&bytes)
            };
            match marked {
                Some(m) => std::fs::write(path, m).map_err(|e| e.to_string()),
                None => Ok(()),
            }
        }
        "svg" => {
            use std::io::Write;
            let mut f = std::fs::OpenOptions::new()
                .append(true)
                .open(path)
                .map_err(|e| e.to_string())?;
            f.write_all(SVG_MARK.as_bytes()).map_err(|e| e.to_string())
        }
        _ => Ok(()),
    }
}

/// Whether the file at `path` carries isotrack's mark (by its extension; an unreadable file,
/// a link or a FIFO does not). Reads only where the mark is (att41-18: the whole file was
/// read, 20 GB of memory for a 20 GB file): an SVG's and a GIF's last bytes, a PNG's first
/// chunk headers; never through a link nor from a FIFO
/// ([`isotrack_runs::files::open_read_regular`]).
pub fn is_isotrack_figure(path: &Path) -> bool {
    let Ok(mut f) = isotrack_runs::files::open_read_regular(path) else {
        return false;
    };
    let Ok(len) = f.metadata().map(|m| m.len()) else {
        return false;
    };
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "png" => png_has_mark(&mut f, len),
        // The comment, then the trailer; a GIF longer than the comment alone.
        "gif" => {
            let c = gif_comment();
            len > c.len() as u64 && ends_with(&mut f, len, &c, 1)
        }
        "svg" => ends_with(&mut f, len, SVG_MARK.as_bytes(), 0),
        _ => false,
    }
}

/// Refuses to replace `path` with a figure when a file is there that isotrack did not write
/// (no mark: the user's own file of that name, or a figure of an isotrack older than the
/// mark), naming it (shell-quoted, att41-2) and what to do (att38-9); `Ok` when nothing is there or the file is an
/// isotrack figure.
pub fn refuse_foreign_figure(path: &Path) -> Result<(), String> {
    match std::fs::symlink_metadata(path) {
        Err(_) => Ok(()),
        Ok(m) if m.is_file() && is_isotrack_figure(path) => Ok(()),
        // A link, FIFO or directory is refused where the figure is written, naming it.
        Ok(m) if !m.is_file() => Ok(()),
        Ok(_) => Err(format!(
            "{} is not a figure isotrack wrote (it has no isotrack mark: your own file of that name, or a figure of an older isotrack, which did not mark its figures), and isotrack never replaces a file it did not write: move it away, or draw elsewhere (--out DIR)",
            isotrack_runs::owned::shell_quoted(path)
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CRC-32 of "IEND" is the one every PNG ends with, `ae 42 60 82`, and of
    /// "123456789" the standard check value `cbf43926`.
    #[test]
    fn crc_is_pngs() {
        assert_eq!(crc32(b"IEND"), 0xae42_6082);
        assert_eq!(crc32(b"123456789"), 0xcbf4_3926);
    }

    /// A PNG chunk: length, type, data, CRC over type and data.
    fn chunk(kind: &[u8], data: &[u8]) -> Vec<u8> {
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        c.extend_from_slice(&body);
        c.extend_from_slice(&crc32(&body).to_be_bytes());
        c
    }

    /// att41-18: a marked PNG, GIF and SVG are told as isotrack's, the same files unmarked
    /// are not; a 20 GiB file of each name (sparse) is answered from a few bytes: under 1 MiB
    /// read (before, it was read whole: 20 GB of memory, minutes).
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
    fn the_mark_is_read_where_it_is_never_the_whole_file() {
        let d = tempfile::tempdir().unwrap();
        let mut png = PNG_SIGNATURE.to_vec();
        png.extend(chunk(b"IHDR", &[0, 0, 0, 1, 0, 0, 0, 1, 8, 2, 0, 0, 0]));
        png.extend(chunk(b"IDAT", b"x"));
        png.extend(chunk(b"IEND", b""));
        let files: [(&str, Vec<u8>); 3] = [
            ("a.png", png),
            ("a.gif", b"GIF89a\x01\x00\x01\x00\x00\x00\x00;".to_vec()),
            (
                "a.svg",
                b"<svg xmlns=\"http://www.w3.org/2000/svg\"/>\n".to_vec(),
            ),
        ];
        for (name, bytes) in &files {
            let p = d.path().join(name);
            std::fs::write(&p, bytes).unwrap();
            assert!(!is_isotrack_figure(&p), "{name} unmarked");
            mark(&p).unwrap();
            assert!(is_isotrack_figure(&p), "{name} marked");
            assert!(refuse_foreign_figure(&p).is_ok(), "{name}");
            let huge = d.path().join(format!("huge_{name}"));
            let f = std::fs::File::create(&huge).unwrap();
            f.set_len(20 << 30).unwrap();
            drop(f);
            let before = bytes_read_by_this_thread();
            assert!(!is_isotrack_figure(&huge), "{name} huge");
            assert!(refuse_foreign_figure(&huge).is_err(), "{name} huge");
            if let (Some(a), Some(b)) = (before, bytes_read_by_this_thread()) {
                assert!(b - a < 1 << 20, "{name}: {} bytes read", b - a);
            }
        }
        // A PNG with a huge chunk before the mark's place is not walked through either.
        let p = d.path().join("b.png");
        let mut png = PNG_SIGNATURE.to_vec();
        png.extend(chunk(b"IHDR", &[0, 0, 0, 1, 0, 0, 0, 1, 8, 2, 0, 0, 0]));
        std::fs::write(&p, &png).unwrap();
        assert!(!is_isotrack_figure(&p));
    }
}
