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

/// Whether PNG `bytes` hold the mark's `tEXt` chunk before their image data.
fn png_has_mark(bytes: &[u8]) -> bool {
    if bytes.len() < 8 || &bytes[..8] != PNG_SIGNATURE {
        return false;
    }
    let mut at = 8usize;
    while at + 8 <= bytes.len() {
        let len = u32::from_be_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
        let kind = &bytes[at + 4..at + 8];
        let Some(end) = (at + 8).checked_add(len as usize) else {
            return false;
        };
        if kind == b"IDAT" || kind == b"IEND" || end > bytes.len() {
            return false;
        }
        if kind == b"tEXt" && &bytes[at + 8..end] == PNG_TEXT {
            return true;
        }
        at = end + 4;
    }
    false
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

/// Whether the file at `path` carries isotrack's mark (by its extension; an unreadable file
/// does not).
pub fn is_isotrack_figure(path: &Path) -> bool {
    let Ok(bytes) = std::fs::read(path) else {
        return false;
    };
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "png" => png_has_mark(&bytes),
        "gif" => {
            let c = gif_comment();
            bytes.len() > c.len() && bytes[..bytes.len() - 1].ends_with(&c)
        }
        "svg" => bytes.ends_with(SVG_MARK.as_bytes()),
        _ => false,
    }
}

/// Refuses to replace `path` with a figure when a file is there that isotrack did not write
/// (no mark: the user's own file of that name, or a figure of an isotrack older than the
/// mark), naming it and what to do (att38-9); `Ok` when nothing is there or the file is an
/// isotrack figure.
pub fn refuse_foreign_figure(path: &Path) -> Result<(), String> {
    match std::fs::symlink_metadata(path) {
        Err(_) => Ok(()),
        Ok(m) if m.is_file() && is_isotrack_figure(path) => Ok(()),
        // A link, FIFO or directory is refused where the figure is written, naming it.
        Ok(m) if !m.is_file() => Ok(()),
        Ok(_) => Err(format!(
            "{} is not a figure isotrack wrote (it has no isotrack mark: your own file of that name, or a figure of an older isotrack, which did not mark its figures), and isotrack never replaces a file it did not write: move it away, or draw elsewhere (--out DIR)",
            path.display()
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
}
