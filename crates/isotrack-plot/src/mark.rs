//! The mark every figure isotrack writes carries (att38-9), so that a later `plot` or
//! `run --plot` can tell its own figure from the user's file of the same name and never
//! replaces a file isotrack did not write, nor one the user edited since (att42-8): the mark
//! holds the size and SHA-256 of the figure as isotrack drew it, without the mark
//! (`isotrack sha256:HEX bytes:N`), in a PNG's `tEXt` chunk `Software` (after `IHDR`), a GIF's
//! comment extension (before its trailer), an SVG's closing comment
//! `<!-- isotrack figure sha256:HEX bytes:N -->` (after the root element). Readers ignore all
//! three; the pixels are unchanged. A figure whose bytes outside its mark no longer have that
//! size and digest was edited (annotations added in Inkscape or by hand): the user's now.
//! A mark without a digest (`Software` = `isotrack`, the comment `isotrack`,
//! `<!-- isotrack figure -->`: an isotrack from before att42-8) is accepted as isotrack's for
//! this release (README, "one release of grace").

use std::path::Path;

/// The text every mark starts with.
const MARK: &str = "isotrack";
/// The PNG `tEXt` chunk's keyword and its NUL, before the mark.
const PNG_KEYWORD: &[u8] = b"Software\0";
/// The SVG's closing comment, before the mark's digest (and its end, [`SVG_END`]).
const SVG_START: &str = "<!-- isotrack figure";
/// The SVG's closing comment's end.
const SVG_END: &str = " -->\n";
/// The PNG signature.
const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
/// The longest mark text looked at (the digest's is 97 bytes and a size's digits).
const MAX_MARK_TEXT: usize = 160;

/// The mark's text for `content`, the figure's bytes as drawn: `isotrack sha256:HEX bytes:N`.
fn mark_text(content: &[u8]) -> String {
    format!(
        "{MARK} sha256:{} bytes:{}",
        isotrack_fields::io::sha256_hex(content),
        content.len()
    )
}

/// What a mark's text after [`MARK`] says: `""` (an older isotrack's mark, no digest) or
/// ` sha256:HEX bytes:N`; `None` for anything else (no isotrack mark).
fn parse_digest(rest: &[u8]) -> Option<Option<(String, u64)>> {
    if rest.is_empty() {
        return Some(None);
    }
    let rest = std::str::from_utf8(rest).ok()?;
    let (sha, bytes) = rest.strip_prefix(" sha256:")?.split_once(" bytes:")?;
    let hex = sha.len() == 64 && sha.bytes().all(|b| b.is_ascii_hexdigit());
    let n = bytes
        .parse::<u64>()
        .ok()
        .filter(|_| bytes.bytes().all(|b| b.is_ascii_digit()))?;
    hex.then(|| Some((sha.to_ascii_lowercase(), n)))
}

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
    let mut data = PNG_KEYWORD.to_vec();
    data.extend_from_slice(mark_text(bytes).as_bytes());
    let mut chunk = Vec::with_capacity(12 + data.len());
    chunk.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let mut body = b"tEXt".to_vec();
    body.extend_from_slice(&data);
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

/// A mark found in a figure: where it is (the bytes isotrack added) and the digest it holds
/// (`None`: an older isotrack's mark, without one).
struct Found {
    at: std::ops::Range<u64>,
    digest: Option<(String, u64)>,
}

/// The mark's `tEXt` chunk of PNG file `f` (`len` bytes), before its image data: its chunk
/// headers are read one by one (12 bytes each, the data skipped), the first
/// [`PNG_CHUNKS_LOOKED_AT`] at most (att41-18: the whole file was read into memory).
fn png_mark(f: &mut std::fs::File, len: u64) -> Option<Found> {
    let mut signature = [0u8; 8];
    if !read_at(f, 0, &mut signature) || signature != PNG_SIGNATURE {
        return None;
    }
    let mut at = 8u64;
    for _ in 0..PNG_CHUNKS_LOOKED_AT {
        let mut head = [0u8; 8];
        if !read_at(f, at, &mut head) {
            return None;
        }
        let n = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
        let kind = &head[4..8];
        let end = at + 8 + n;
        if kind == b"IDAT" || kind == b"IEND" || end + 4 > len {
            return None;
        }
        let lead = PNG_KEYWORD.len() + MARK.len();
        if kind == b"tEXt"
            && (lead as u64..=(PNG_KEYWORD.len() + MAX_MARK_TEXT) as u64).contains(&n)
        {
            let mut data = vec![0u8; n as usize];
            if read_at(f, at + 8, &mut data) && data.starts_with(PNG_KEYWORD) {
                let text = &data[PNG_KEYWORD.len()..];
                if let Some(digest) = text.strip_prefix(MARK.as_bytes()).and_then(parse_digest) {
                    return Some(Found {
                        at: at..end + 4,
                        digest,
                    });
                }
            }
        }
        at = end + 4;
    }
    None
}

/// The last `n` bytes of file `f` (`len` bytes; all of it when shorter).
fn tail(f: &mut std::fs::File, len: u64, n: u64) -> Option<Vec<u8>> {
    let n = n.min(len);
    let mut buf = vec![0u8; n as usize];
    read_at(f, len - n, &mut buf).then_some(buf)
}

/// The mark's comment extension of GIF file `f` (`len` bytes), just before its trailer:
/// introducer `21 fe`, one sub-block (its length, the mark), terminator `00`, then `3b`. Reads
/// the file's last bytes only.
fn gif_mark(f: &mut std::fs::File, len: u64) -> Option<Found> {
    let t = tail(f, len, (MAX_MARK_TEXT + 6) as u64)?;
    let n = t.len();
    if n < 6 || t[n - 2..] != [0, 0x3b] {
        return None;
    }
    // The comment's text ends at n - 2; its length byte stands just before it.
    (MARK.len()..=MAX_MARK_TEXT.min(255)).find_map(|k| {
        let start = n.checked_sub(2 + k + 3)?;
        let text = &t[start + 3..n - 2];
        (t[start..start + 2] == [0x21, 0xfe] && usize::from(t[start + 2]) == k).then_some(())?;
        let digest = text.strip_prefix(MARK.as_bytes()).and_then(parse_digest)?;
        // A GIF longer than the comment alone (its header, at least).
        (len > (n - start) as u64 + 1).then(|| Found {
            at: len - (n - start) as u64..len - 1,
            digest,
        })
    })
}

/// The mark's closing comment of SVG file `f` (`len` bytes): its last bytes only.
fn svg_mark(f: &mut std::fs::File, len: u64) -> Option<Found> {
    let t = tail(
        f,
        len,
        (SVG_START.len() + MAX_MARK_TEXT + SVG_END.len()) as u64,
    )?;
    let body = t.strip_suffix(SVG_END.as_bytes())?;
    let start = body
        .windows(SVG_START.len())
        .rposition(|w| w == SVG_START.as_bytes())?;
    let digest = parse_digest(&body[start + SVG_START.len()..])?;
    Some(Found {
        at: len - (t.len() - start) as u64..len,
        digest,
    })
}

/// `bytes` (a GIF) with the mark's comment before the trailer; `None` if not a GIF.
fn gif_marked(bytes: &[u8]) -> Option<Vec<u8>> {
    if !(bytes.starts_with(b"GIF8") && bytes.last() == Some(&0x3b)) {
        return None;
    }
    let text = mark_text(bytes);
    let mut out = bytes[..bytes.len() - 1].to_vec();
    out.extend_from_slice(&[0x21, 0xfe, text.len() as u8]);
    out.extend_from_slice(text.as_bytes());
    out.extend_from_slice(&[0, 0x3b]);
    Some(out)
}

/// The extension of `path`, lowercase.
fn ext_of(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Marks the figure at `path` by its extension (`png`, `gif`, `svg`; others are left as
/// they are), with the size and digest of its bytes as drawn ([`mark_text`]).
pub(crate) fn mark(path: &Path) -> Result<(), String> {
    let ext = ext_of(path);
    if !matches!(ext.as_str(), "png" | "gif" | "svg") {
        return Ok(());
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let marked = match ext.as_str() {
        "png" => png_marked(&bytes),
        "gif" => gif_marked(&bytes),
        _ => {
            let mut m = bytes.clone();
            let text = mark_text(&bytes);
            let rest = text.strip_prefix(MARK).unwrap_or_default();
            m.extend_from_slice(format!("{SVG_START}{rest}{SVG_END}").as_bytes());
            Some(m)
        }
    };
    match marked {
        // Rewritten in place, never created: an interrupt that removed the temporary figure
        // meanwhile must not see it come back (`isotrack_runs::cleanup`).
        Some(m) => std::fs::OpenOptions::new()
            .write(true)
            .truncate(true)
            .open(path)
            .and_then(|mut f| std::io::Write::write_all(&mut f, &m))
            .map_err(|e| e.to_string()),
        None => Ok(()),
    }
}

/// Whose a figure file is, by its isotrack mark ([`figure_status`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FigureStatus {
    /// No isotrack mark (the user's own file; an isotrack from before the mark drew figures
    /// without it), or not a regular file isotrack can read.
    Unmarked,
    /// An older isotrack's mark without a digest (accepted as isotrack's this release).
    Legacy,
    /// isotrack's, as it drew it: the bytes outside the mark have the mark's size and SHA-256.
    AsDrawn,
    /// isotrack's mark, but the bytes outside it are no longer what isotrack drew: edited since.
    Edited,
}

/// Whose the file at `path` is, by its mark (by its extension; an unreadable file, a link or a
/// FIFO is [`FigureStatus::Unmarked`]). Reads where the mark is (att41-18: the whole file was
/// read, 20 GB of memory for a 20 GB file): an SVG's and a GIF's last bytes, a PNG's first
/// chunk headers; then, only for a file of the size its mark records (the size isotrack drew),
/// the rest to check its digest; never through a link nor from a FIFO
/// ([`isotrack_runs::files::open_read_regular`]).
pub fn figure_status(path: &Path) -> FigureStatus {
    let Ok(mut f) = isotrack_runs::files::open_read_regular(path) else {
        return FigureStatus::Unmarked;
    };
    let Ok(len) = f.metadata().map(|m| m.len()) else {
        return FigureStatus::Unmarked;
    };
    let found = match ext_of(path).as_str() {
        "png" => png_mark(&mut f, len),
        "gif" => gif_mark(&mut f, len),
        "svg" => svg_mark(&mut f, len),
        _ => None,
    };
    match found {
        None => FigureStatus::Unmarked,
        Some(Found { digest: None, .. }) => FigureStatus::Legacy,
        Some(Found {
            at,
            digest: Some((sha, bytes)),
        }) => {
            let as_drawn = len - (at.end - at.start) == bytes
                && isotrack_runs::files::sha256_outside(&mut f, at).is_ok_and(|h| h == sha);
            if as_drawn {
                FigureStatus::AsDrawn
            } else {
                FigureStatus::Edited
            }
        }
    }
}

/// Whether the file at `path` is isotrack's figure as isotrack drew it (or an older isotrack's
/// marked figure, this release): [`figure_status`].
pub fn is_isotrack_figure(path: &Path) -> bool {
    matches!(
        figure_status(path),
        FigureStatus::AsDrawn | FigureStatus::Legacy
    )
}

/// Refuses to replace `path` with a figure when a file is there that isotrack did not write (no
/// mark: the user's own file of that name, or a figure of an older isotrack, which did not mark
/// its figures) or that was edited since isotrack drew it (att42-8: its mark's digest no longer
/// matches), naming it (shell-quoted, att41-2) and what to do (att38-9); `Ok` when nothing is
/// there or the file is an isotrack figure ([`is_isotrack_figure`]). An unmarked file is never
/// isotrack's, whatever is beside it (att44-11: `check --map` took one beside an unrecorded
/// chart table for an older isotrack's figure, and replaced the user's own).
pub fn refuse_foreign_figure(path: &Path) -> Result<(), String> {
    let quoted = || isotrack_runs::owned::shell_quoted(path);
    match std::fs::symlink_metadata(path) {
        Err(_) => Ok(()),
        // A link, FIFO or directory is refused where the figure is written, naming it.
        Ok(m) if !m.is_file() => Ok(()),
        Ok(_) => match figure_status(path) {
            FigureStatus::AsDrawn | FigureStatus::Legacy => Ok(()),
            FigureStatus::Unmarked => Err(format!(
                "{} is not a figure isotrack wrote (it has no isotrack mark: your own file of that name, or a figure of an older isotrack, which did not mark its figures), and isotrack never replaces a file it did not write: move it away, or draw elsewhere (--out DIR)",
                quoted()
            )),
            FigureStatus::Edited => Err(format!(
                "{} was edited since isotrack wrote it (its bytes no longer have the size and SHA-256 its isotrack mark records), and isotrack never replaces your edits: move it away or rename it to keep them, or draw elsewhere (--out DIR)",
                quoted()
            )),
        },
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

    /// att42-8: a figure is isotrack's only as isotrack drew it. Marked, each of a PNG, a GIF
    /// and an SVG records the size and SHA-256 of its bytes as drawn (computed here from the
    /// unmarked bytes: the mark is all that was added); a byte of it changed (an annotation
    /// added to the SVG, a pixel of the PNG, the GIF's header) makes it the user's, refused with
    /// a message naming it and saying it was edited; an older isotrack's mark without a digest
    /// is accepted (this release's grace); the same file unmarked is not isotrack's.
    #[test]
    fn an_edited_figure_is_the_users() {
        let d = tempfile::tempdir().unwrap();
        let mut png = PNG_SIGNATURE.to_vec();
        png.extend(chunk(b"IHDR", &[0, 0, 0, 1, 0, 0, 0, 1, 8, 2, 0, 0, 0]));
        png.extend(chunk(b"IDAT", b"pixels"));
        png.extend(chunk(b"IEND", b""));
        let gif = b"GIF89a\x01\x00\x01\x00\x00\x00\x00;".to_vec();
        let svg = b"<svg xmlns=\"http://www.w3.org/2000/svg\"><rect/></svg>\n".to_vec();
        // Where an edit goes in each: a pixel byte, the GIF's width, inside the SVG's root.
        let edit = |name: &str, b: &mut Vec<u8>| match name {
            "a.png" => {
                let at = b.windows(6).position(|w| w == b"pixels").unwrap();
                b[at] = b'P';
            }
            "a.gif" => b[6] = 2,
            _ => {
                let at = b.windows(6).position(|w| w == b"</svg>").unwrap();
                b.splice(at..at, b"<text>my note</text>".iter().copied());
            }
        };
        let legacy: [(&str, Vec<u8>); 3] = [
            ("a.png", {
                let mut p = png[..33].to_vec();
                p.extend(chunk(b"tEXt", b"Software\0isotrack"));
                p.extend_from_slice(&png[33..]);
                p
            }),
            ("a.gif", {
                let mut g = gif[..gif.len() - 1].to_vec();
                g.extend_from_slice(b"\x21\xfe\x08isotrack\x00;");
                g
            }),
            ("a.svg", {
                let mut s = svg.clone();
                s.extend_from_slice(b"<!-- isotrack figure -->\n");
                s
            }),
        ];
        for ((name, plain), (_, old)) in [("a.png", png), ("a.gif", gif), ("a.svg", svg)]
            .into_iter()
            .zip(legacy)
        {
            let p = d.path().join(name);
            std::fs::write(&p, &plain).unwrap();
            assert_eq!(figure_status(&p), FigureStatus::Unmarked, "{name}");
            mark(&p).unwrap();
            assert_eq!(figure_status(&p), FigureStatus::AsDrawn, "{name}");
            let marked = std::fs::read(&p).unwrap();
            let text = format!(
                "isotrack sha256:{} bytes:{}",
                isotrack_fields::io::sha256_hex(&plain),
                plain.len()
            );
            // The mark is all that was added (the layout README gives): the drawing back
            // without it.
            let expected = match name {
                "a.png" => {
                    let mut data = b"Software\0".to_vec();
                    data.extend_from_slice(text.as_bytes());
                    let mut e = plain[..33].to_vec();
                    e.extend(chunk(b"tEXt", &data));
                    e.extend_from_slice(&plain[33..]);
                    e
                }
                "a.gif" => {
                    let mut e = plain[..plain.len() - 1].to_vec();
                    e.extend_from_slice(&[0x21, 0xfe, text.len() as u8]);
                    e.extend_from_slice(text.as_bytes());
                    e.extend_from_slice(&[0, 0x3b]);
                    e
                }
                _ => {
                    let mut e = plain.clone();
                    e.extend_from_slice(
                        format!("<!-- isotrack figure{} -->\n", &text[8..]).as_bytes(),
                    );
                    e
                }
            };
            assert_eq!(marked, expected, "{name}");
            let mut edited = marked.clone();
            edit(name, &mut edited);
            std::fs::write(&p, &edited).unwrap();
            assert_eq!(figure_status(&p), FigureStatus::Edited, "{name}");
            assert!(!is_isotrack_figure(&p), "{name}");
            let e = refuse_foreign_figure(&p).unwrap_err();
            assert!(e.contains("was edited since isotrack wrote it"), "{e}");
            assert!(e.contains(&p.display().to_string()), "{e}");
            // An older isotrack's mark, without a digest: accepted, this release.
            std::fs::write(&p, &old).unwrap();
            assert_eq!(figure_status(&p), FigureStatus::Legacy, "{name}");
            assert!(refuse_foreign_figure(&p).is_ok(), "{name}");
        }
    }
}
