//! GeoTIFF grids through the pure-Rust `tiff` crate; the GeoTIFF tags (`ModelPixelScale`,
//! `ModelTiepoint`, `GeoKeyDirectory`, GDAL's no-data) are plain TIFF tags read here.
//!
//! What loads (tested on files GDAL wrote, `tests/fixtures/geotiff`): uncompressed, PackBits,
//! Deflate, LZW and ZSTD; horizontal (2) and floating-point (3) predictors; strips or tiles;
//! classic TIFF or BigTIFF; Cloud-Optimised GeoTIFFs (the first image, which COG puts at full
//! resolution, is read and the overviews after it are ignored); one band of uint8..uint64,
//! int8..int64, float16/32/64. JPEG and other lossy or exotic codecs are refused by name.
//! LZW chunks without an end code (GDAL 3.x's tiles) are decoded by [`super::geotiff_lzw`].

use super::error::{FilePosition, LoadError};
use super::loaded::{flip_rows, LoadedGrid};
use crate::georef::{lonlat_spacing_m, Georeference};
use crate::grid::Grid2;
use isotrack_core::Vec2;
use std::io::Cursor;
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

/// GeoKey ids (GeoTIFF 1.1, OGC 19-008r4).
const GT_MODEL_TYPE: u16 = 1024;
const GT_RASTER_TYPE: u16 = 1025;
const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;

/// The `tiff` decoder's limits from isotrack's own (the README's limits table), not the
/// crate's defaults (256 MiB decoded, which refuses a float32 image of 8200 x 8200 the README
/// allows): the decoded image up to [`crate::grid::MAX_NODES`] samples of 8 bytes (2 GiB; the
/// node count and the memory were already checked from the header by
/// [`super::limits::check_series_size`]), and a compressed chunk or a tag's values up to the file's
/// own length (`file_len`, at most [`super::limits::MAX_GRID_FILE_BYTES`]): nothing in a file is
/// longer than the file.
fn decoder_limits(file_len: u64) -> Limits {
    let file =
        usize::try_from(file_len.min(super::limits::MAX_GRID_FILE_BYTES)).unwrap_or(usize::MAX);
    let mut limits = Limits::default();
    limits.decoding_buffer_size = crate::grid::MAX_NODES.saturating_mul(8);
    limits.intermediate_buffer_size = file.max(limits.intermediate_buffer_size);
    limits.ifd_value_size = file.max(limits.ifd_value_size);
    limits
}

pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<LoadedGrid, LoadError> {
    let len = bytes.len() as u64;
    let tiff_err = |e: tiff::TiffError| tiff_error(path, len, e);
    let mut dec = Decoder::new(Cursor::new(bytes))
        .map_err(tiff_err)?
        .with_limits(decoder_limits(len));
    let (w, h) = dec.dimensions().map_err(tiff_err)?;
    let (nx, ny) = (w as usize, h as usize);
    // The header's size is a claim: checked before any pixel is decoded (a compressed image
    // declares what it likes).
    super::limits::check_series_size(path, 1, nx, ny, super::limits::memory_budget_bytes())?;
    match dec.colortype().map_err(tiff_err)? {
        ColorType::Gray(8 | 16 | 32 | 64) => {}
        ColorType::Gray(bits) => {
            return Err(LoadError::new(
                path,
                None,
                format!("{bits}-bit samples are not supported: need 8, 16, 32 or 64 bits per sample (one band)"),
            ))
        }
        other => {
            return Err(LoadError::new(
                path,
                None,
                format!("need one band (grey), found {other:?}"),
            ))
        }
    }
    let GeoTags {
        nodata,
        scale,
        tie,
        keys,
    } = geo_tags(&mut dec).map_err(tiff_err)?;
    let geokey = |id: u16| -> Option<u16> {
        // Header of 4 shorts, then entries (KeyID, TIFFTagLocation, Count, Value); only keys
        // stored inline (location 0) matter here.
        keys.get(4..)?
            .chunks_exact(4)
            .find(|e| e[0] == id && e[1] == 0)
            .map(|e| e[3])
    };
    let img = match dec.read_image() {
        Ok(img) => img,
        Err(e) if super::geotiff_lzw::is_missing_end_code(&e) => DecodingResult::F64(
            super::geotiff_lzw::decode(bytes, nx, ny)
                .map_err(|m| LoadError::new(path, None, format!("invalid LZW GeoTIFF: {m}")))?,
        ),
        Err(e) => return Err(tiff_err(e)),
    };
    let mut values = samples(img);
    if values.len() != nx * ny {
        return Err(LoadError::new(
            path,
            None,
            format!(
                "{} samples for {nx} x {ny} pixels: the image data does not match its size",
                values.len()
            ),
        ));
    }
    if let Some(nd) = nodata {
        for v in &mut values {
            if *v == nd {
                *v = f64::NAN;
            }
        }
    }
    flip_rows(&mut values, nx, ny);
    let (origin, spacing, georeference) = placement(scale, tie, geokey, ny);
    let grid = Grid2::new(nx, ny, origin, spacing, values).map_err(|e| LoadError::grid(path, e))?;
    Ok(LoadedGrid { grid, georeference })
}

/// The tags that place a GeoTIFF's grid: GDAL's no-data value, the model pixel scale and tie
/// point, and the GeoKey directory (empty when absent).
struct GeoTags {
    nodata: Option<f64>,
    scale: Option<Vec<f64>>,
    tie: Option<Vec<f64>>,
    keys: Vec<u16>,
}

fn geo_tags(dec: &mut Decoder<Cursor<&[u8]>>) -> Result<GeoTags, tiff::TiffError> {
    let nodata: Option<f64> = dec
        .find_tag(Tag::GdalNodata)?
        .and_then(|v| v.into_string().ok())
        .and_then(|s| s.trim_matches(char::from(0)).trim().parse().ok());
    let scale = dec
        .find_tag(Tag::ModelPixelScaleTag)?
        .map(|v| v.into_f64_vec())
        .transpose()?;
    let tie = dec
        .find_tag(Tag::ModelTiepointTag)?
        .map(|v| v.into_f64_vec())
        .transpose()?;
    let keys = dec
        .find_tag(Tag::GeoKeyDirectoryTag)?
        .map(|v| v.into_u16_vec())
        .transpose()?
        .unwrap_or_default();
    Ok(GeoTags {
        nodata,
        scale,
        tie,
        keys,
    })
}

/// A TIFF reader's error as a [`LoadError`] of `path` (`len` bytes): an unsupported or
/// unknown compression named with what is read, a truncated file at its end.
fn tiff_error(path: &Path, len: u64, e: tiff::TiffError) -> LoadError {
    let truncated = matches!(&e, tiff::TiffError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof);
    if let tiff::TiffError::UnsupportedError(
        tiff::TiffUnsupportedError::UnsupportedCompressionMethod(method),
    ) = &e
    {
        let name = match method {
            tiff::tags::CompressionMethod::ModernJPEG | tiff::tags::CompressionMethod::JPEG => {
                "JPEG".to_string()
            }
            other => format!("{other:?}"),
        };
        return LoadError::new(
            path,
            None,
            format!(
                "unsupported TIFF compression {name}: isotrack reads uncompressed, PackBits, \
                 Deflate, LZW and ZSTD GeoTIFFs (convert with \
                 `gdal_translate -co COMPRESS=DEFLATE in.tif out.tif`)"
            ),
        );
    }
    if let tiff::TiffError::UnsupportedError(tiff::TiffUnsupportedError::UnknownCompressionMethod) =
        &e
    {
        return LoadError::new(path, None, format!("unknown TIFF compression method ({e})"));
    }
    if truncated {
        LoadError::new(
            path,
            Some(FilePosition::Offset(len)),
            format!("truncated TIFF: the file ends at byte {len} before its data does ({e})"),
        )
    } else {
        LoadError::new(path, None, format!("invalid TIFF: {e}"))
    }
}

/// The samples of an image, as `f64`.
fn samples(img: DecodingResult) -> Vec<f64> {
    match img {
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
        DecodingResult::F16(v) => v.into_iter().map(f64::from).collect(),
    }
}

/// Where the grid is: the origin (its south-west node after the flip), the spacing and the
/// georeference, from the model pixel scale and tie point (`geokey`: the file's inline
/// GeoKeys); metres from (0, 0) with spacing 1 when the file has neither.
fn placement(
    scale: Option<Vec<f64>>,
    tie: Option<Vec<f64>>,
    geokey: impl Fn(u16) -> Option<u16>,
    ny: usize,
) -> (Vec2, [f64; 2], Georeference) {
    match (scale, tie) {
        (Some(s), Some(t)) if s.len() >= 2 && t.len() >= 6 => {
            let (sx, sy) = (s[0], s[1]);
            let (ti, tj, tx, ty) = (t[0], t[1], t[3], t[4]);
            // PixelIsArea (the default): the tie point is a pixel's corner; PixelIsPoint: its
            // centre.
            let c = if geokey(GT_RASTER_TYPE) == Some(2) {
                0.0
            } else {
                0.5
            };
            // After the flip, node (0, 0) is the south-west pixel: column 0, row h-1.
            let x0 = tx + (0.0 - ti + c) * sx;
            let y0 = ty - ((ny - 1) as f64 - tj + c) * sy;
            if geokey(GT_MODEL_TYPE) == Some(2) {
                let ref_lat = y0 + 0.5 * (ny - 1) as f64 * sy;
                (
                    Vec2::default(),
                    lonlat_spacing_m(sx, sy, ref_lat),
                    Georeference::LonLat {
                        lon0_deg: x0,
                        lat0_deg: y0,
                        dlon_deg: sx,
                        dlat_deg: sy,
                        ref_lat_deg: ref_lat,
                    },
                )
            } else {
                (
                    Vec2::new(x0, y0),
                    [sx, sy],
                    Georeference::Metres {
                        epsg: geokey(PROJECTED_CS_TYPE).or(geokey(GEOGRAPHIC_TYPE)),
                    },
                )
            }
        }
        _ => (Vec2::default(), [1.0, 1.0], Georeference::None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 30: a float32 deflate GeoTIFF of 8300 x 8300 (275.6 MB decoded) was refused
    /// ("decoder limits exceeded": the crate's default 256 MiB) though 2^28 nodes are allowed.
    /// The limits admit the largest image the README allows, 2^28 float64 samples, and a
    /// compressed chunk as long as the file.
    #[test]
    fn decoder_limits_admit_the_documented_grids() {
        let l = decoder_limits(3 << 30);
        assert!(l.decoding_buffer_size >= 8300 * 8300 * 4);
        assert!(l.decoding_buffer_size >= (1usize << 28) * 8);
        assert!(l.intermediate_buffer_size >= 3 << 30);
        assert!(l.ifd_value_size >= 3 << 30);
        // Never beyond the 4 GiB a grid file may have, whatever length is claimed.
        assert_eq!(decoder_limits(u64::MAX).intermediate_buffer_size, 4 << 30);
        // A small file keeps the crate's own floors.
        assert_eq!(decoder_limits(1000).intermediate_buffer_size, 128 << 20);
    }
}
