//! Tiled or stripped LZW GeoTIFFs whose chunks lack the LZW end-of-information code, as GDAL 3.x
//! writes them: libtiff stops reading a chunk once it has its bytes, while the `tiff` crate
//! (0.11.3, the newest) requires the end code and fails with "no lzw end code found". Here each
//! chunk is decompressed with `weezl` (the LZW decoder the `tiff` crate itself uses) until it
//! has the chunk's bytes, end code or not; the predictor is undone and the samples converted.
//! Written by hand because no maintained crate decodes such files; used only when the `tiff`
//! crate has refused the file for that reason (its tags are still read through it).
//!
//! Predictors (TIFF 6.0 section 14; Adobe Technical Note 3): 2, horizontal differencing of
//! whole samples along each chunk row; 3, floating point: each row's samples split into byte
//! planes (most significant first), then the bytes differenced along the row.

use std::io::Cursor;
use tiff::decoder::{ChunkType, Decoder};
use tiff::tags::Tag;

/// Whether `e` is the `tiff` crate's refusal of an LZW chunk without an end code.
pub(super) fn is_missing_end_code(e: &tiff::TiffError) -> bool {
    matches!(e, tiff::TiffError::IoError(io) if io.to_string().contains("no lzw end code"))
}

fn tag_u64(dec: &mut Decoder<Cursor<&[u8]>>, tag: Tag, default: u64) -> Result<u64, String> {
    match dec.find_tag(tag).map_err(|e| e.to_string())? {
        None => Ok(default),
        Some(v) => v.into_u64().map_err(|e| e.to_string()),
    }
}

fn tag_vec(dec: &mut Decoder<Cursor<&[u8]>>, tag: Tag) -> Result<Vec<u64>, String> {
    dec.find_tag(tag)
        .map_err(|e| e.to_string())?
        .ok_or_else(|| format!("no {tag:?} tag"))?
        .into_u64_vec()
        .map_err(|e| e.to_string())
}

/// Decompresses one chunk into `out` (its full size), tolerating a missing end code: an error
/// only when the data ends before `out` is full.
fn decompress(chunk: &[u8], out: &mut [u8]) -> Result<(), String> {
    let mut dec =
        weezl::decode::Configuration::with_tiff_size_switch(weezl::BitOrder::Msb, 8).build();
    let (mut inp, mut filled) = (chunk, 0);
    while filled < out.len() {
        let r = dec.decode_bytes(inp, &mut out[filled..]);
        inp = &inp[r.consumed_in..];
        filled += r.consumed_out;
        match r.status {
            Ok(weezl::LzwStatus::Ok) => {}
            Ok(weezl::LzwStatus::Done | weezl::LzwStatus::NoProgress) => break,
            Err(e) => return Err(format!("invalid LZW data: {e}")),
        }
    }
    if filled < out.len() {
        return Err(format!(
            "an LZW chunk decodes to {filled} of its {} bytes (truncated file?)",
            out.len()
        ));
    }
    Ok(())
}

/// The image's samples, row 0 north, as `f64`.
pub(super) fn decode(bytes: &[u8], nx: usize, ny: usize) -> Result<Vec<f64>, String> {
    let mut dec = Decoder::new(Cursor::new(bytes)).map_err(|e| e.to_string())?;
    let bits = tag_u64(&mut dec, Tag::BitsPerSample, 1)?;
    let format = tag_u64(&mut dec, Tag::SampleFormat, 1)?;
    let predictor = tag_u64(&mut dec, Tag::Predictor, 1)?;
    let bps = match bits {
        8 | 16 | 32 | 64 => bits as usize / 8,
        b => return Err(format!("{b}-bit samples")),
    };
    let (offsets, counts) = match dec.get_chunk_type() {
        ChunkType::Tile => (
            tag_vec(&mut dec, Tag::TileOffsets)?,
            tag_vec(&mut dec, Tag::TileByteCounts)?,
        ),
        ChunkType::Strip => (
            tag_vec(&mut dec, Tag::StripOffsets)?,
            tag_vec(&mut dec, Tag::StripByteCounts)?,
        ),
    };
    let tiled = dec.get_chunk_type() == ChunkType::Tile;
    let (cw, ch) = dec.chunk_dimensions();
    let (cw, ch) = (cw as usize, ch as usize);
    // A chunk's size is the header's claim too: no larger than the image or 2^24 pixels
    // (GDAL's largest default tiles are 512 x 512), so a 2 x 2 image cannot ask for 2 GiB.
    if cw == 0 || ch == 0 || cw.saturating_mul(ch) > (nx * ny).max(1 << 24) {
        return Err(format!("chunks of {cw} x {ch} pixels"));
    }
    let across = nx.div_ceil(cw);
    let needed = across * ny.div_ceil(ch);
    if offsets.len() < needed || counts.len() < needed {
        return Err(format!(
            "{} chunks where {needed} are needed",
            offsets.len()
        ));
    }
    // The header says: `II` little-endian, `MM` big-endian.
    let big_endian = bytes.starts_with(b"MM");
    let mut values = vec![0.0; nx * ny];
    let mut raw = Vec::new();
    for k in 0..needed {
        let (cx, cy) = (k % across * cw, k / across * ch);
        // A tile is stored whole; the last strip only as far as the image goes.
        let rows = if tiled { ch } else { ch.min(ny - cy) };
        let start = usize::try_from(offsets[k]).unwrap_or(usize::MAX);
        let chunk = start
            .checked_add(usize::try_from(counts[k]).unwrap_or(usize::MAX))
            .and_then(|end| bytes.get(start..end))
            .ok_or_else(|| format!("chunk {k} lies beyond the file's {} bytes", bytes.len()))?;
        raw.clear();
        raw.resize(cw * rows * bps, 0);
        decompress(chunk, &mut raw).map_err(|m| format!("chunk {k}: {m}"))?;
        for (r, row) in raw.chunks_exact_mut(cw * bps).enumerate() {
            let samples = row_samples(row, bps, predictor, big_endian)?;
            let y = cy + r;
            if y >= ny {
                break;
            }
            for (c, &s) in samples.iter().enumerate().take(nx.saturating_sub(cx)) {
                values[y * nx + cx + c] = sample_value(s, bits as u32, format)?;
            }
        }
    }
    Ok(values)
}

/// A chunk row's samples as raw bits, the predictor undone.
fn row_samples(
    row: &mut [u8],
    bps: usize,
    predictor: u64,
    big_endian: bool,
) -> Result<Vec<u64>, String> {
    let n = row.len() / bps;
    let from = |b: &[u8], big: bool| {
        b.iter().enumerate().fold(0u64, |acc, (i, &x)| {
            acc | u64::from(x) << (8 * if big { bps - 1 - i } else { i })
        })
    };
    match predictor {
        1 | 2 => {
            let mut s: Vec<u64> = row.chunks_exact(bps).map(|b| from(b, big_endian)).collect();
            if predictor == 2 {
                let mask = if bps == 8 {
                    u64::MAX
                } else {
                    (1u64 << (8 * bps)) - 1
                };
                for i in 1..n {
                    s[i] = s[i].wrapping_add(s[i - 1]) & mask;
                }
            }
            Ok(s)
        }
        3 => {
            for i in 1..row.len() {
                row[i] = row[i].wrapping_add(row[i - 1]);
            }
            Ok((0..n)
                .map(|k| (0..bps).fold(0u64, |acc, j| acc << 8 | u64::from(row[j * n + k])))
                .collect())
        }
        p => Err(format!("predictor {p}")),
    }
}

/// A sample's value from its bits: SampleFormat 1 unsigned, 2 signed, 3 IEEE float.
fn sample_value(bits: u64, width: u32, format: u64) -> Result<f64, String> {
    Ok(match (format, width) {
        (1, _) => bits as f64,
        (2, 64) => bits as i64 as f64,
        (2, w) => ((bits << (64 - w)) as i64 >> (64 - w)) as f64,
        (3, 32) => f64::from(f32::from_bits(bits as u32)),
        (3, 64) => f64::from_bits(bits),
        (f, w) => return Err(format!("sample format {f} with {w} bits")),
    })
}
