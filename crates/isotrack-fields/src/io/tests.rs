//! Loader tests: every format reads the same grid; every malformed file is a clear error naming
//! the file and the line or offset.

use super::limits::{parse_address_space_limit, parse_vm_size_bytes};
use super::*;
use crate::georef::Georeference;
use isotrack_core::Vec2;
use std::io::Write;

fn tmp(name: &str, bytes: &[u8]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::File::create(&p).unwrap().write_all(bytes).unwrap();
    (dir, p)
}

fn err_of(name: &str, bytes: &[u8]) -> LoadError {
    let (_d, p) = tmp(name, bytes);
    load_grid(&p, None).expect_err("should fail")
}

/// A 3 x 4 grid (3 columns, 4 rows), row 0 south: value = 10*row + col.
fn expected() -> Vec<f64> {
    (0..4)
        .flat_map(|r| (0..3).map(move |c| (10 * r + c) as f64))
        .collect()
}

#[test]
fn csv_reads_rows_south_first() {
    let text = "0,1,2\n10,11,12\n20,21,22\n30,31,32\n";
    let (_d, p) = tmp("g.csv", text.as_bytes());
    let g = load_grid(&p, None).unwrap();
    assert_eq!((g.grid.nx(), g.grid.ny()), (3, 4));
    assert_eq!(g.grid.values(), expected().as_slice());
    assert_eq!(g.georeference, Georeference::None);
}

#[test]
fn csv_nan_is_nodata() {
    let (_d, p) = tmp("g.csv", b"1,NaN\n3,4\n");
    let g = load_grid(&p, None).unwrap();
    assert!(g.grid.at(1, 0).is_nan());
    assert_eq!(g.grid.nodata_count(), 1);
}

#[test]
fn csv_errors_name_file_and_line() {
    let e = err_of("ragged.csv", b"1,2,3\n4,5\n");
    assert_eq!(e.position, Some(FilePosition::Line(2, None)));
    assert!(e.to_string().contains("ragged.csv:2"), "{e}");
    assert!(e.message.contains("ragged"), "{e}");
    let e = err_of("token.csv", b"1,2\n3,abc\n");
    assert_eq!(e.position, Some(FilePosition::Line(2, Some(2))));
    assert!(e.message.contains("abc"), "{e}");
    let e = err_of("empty.csv", b"");
    assert!(e.message.contains("empty"), "{e}");
    let e = err_of("allnan.csv", b"NaN,NaN\nNaN,NaN\n");
    assert!(e.message.contains("NaN"), "{e}");
    let e = err_of("one.csv", b"1,2,3\n");
    assert!(e.message.contains("2 x 2"), "{e}");
}

fn npy_bytes(descr: &str, shape: &str, fortran: bool, data: &[u8]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

#[test]
fn npy_reads_float64_float32_int_and_fortran_order() {
    let f64s: Vec<u8> = expected().iter().flat_map(|v| v.to_le_bytes()).collect();
    let (_d, p) = tmp("g.npy", &npy_bytes("<f8", "(4, 3)", false, &f64s));
    assert_eq!(
        load_grid(&p, None).unwrap().grid.values(),
        expected().as_slice()
    );

    let f32s: Vec<u8> = expected()
        .iter()
        .flat_map(|v| (*v as f32).to_le_bytes())
        .collect();
    let (_d, p) = tmp("g.npy", &npy_bytes("<f4", "(4, 3)", false, &f32s));
    assert_eq!(
        load_grid(&p, None).unwrap().grid.values(),
        expected().as_slice()
    );

    let i16s: Vec<u8> = expected()
        .iter()
        .flat_map(|v| (*v as i16).to_le_bytes())
        .collect();
    let (_d, p) = tmp("g.npy", &npy_bytes("<i2", "(4, 3)", false, &i16s));
    assert_eq!(
        load_grid(&p, None).unwrap().grid.values(),
        expected().as_slice()
    );

    // Fortran order: column-major storage of the same array.
    let e = expected();
    let fort: Vec<u8> = (0..3)
        .flat_map(|c| (0..4).map(move |r| (r, c)))
        .flat_map(|(r, c)| e[r * 3 + c].to_le_bytes())
        .collect();
    let (_d, p) = tmp("g.npy", &npy_bytes("<f8", "(4, 3)", true, &fort));
    assert_eq!(
        load_grid(&p, None).unwrap().grid.values(),
        expected().as_slice()
    );
}

#[test]
fn npy_errors() {
    let e = err_of("u.npy", &npy_bytes("<U3", "(2, 2)", false, &[0u8; 48]));
    assert!(e.message.contains("dtype"), "{e}");
    let e = err_of("c.npy", &npy_bytes("<c16", "(2, 2)", false, &[0u8; 64]));
    assert!(e.message.contains("dtype"), "{e}");
    let e = err_of("s.npy", &npy_bytes("<f8", "(12,)", false, &[0u8; 96]));
    assert!(e.message.contains("2-D"), "{e}");
    let e = err_of("t.npy", &npy_bytes("<f8", "(4, 3)", false, &[0u8; 40]));
    assert!(e.message.contains("truncated"), "{e}");
    let e = err_of("junk.npy", b"not an npy file at all");
    assert!(e.to_string().contains("junk.npy"), "{e}");
}

#[test]
fn asc_reads_north_first_with_nodata_and_corner_origin() {
    let text = "ncols 3\nnrows 4\nxllcorner 100\nyllcorner 200\ncellsize 10\nNODATA_value -9999\n\
                30 31 32\n20 21 -9999\n10 11 12\n0 1 2\n";
    let (_d, p) = tmp("g.asc", text.as_bytes());
    let g = load_grid(&p, None).unwrap();
    assert_eq!(g.grid.at(2, 0), 2.0);
    assert!(g.grid.at(2, 2).is_nan());
    assert_eq!(g.grid.at(0, 3), 30.0);
    assert_eq!(g.grid.origin_m(), isotrack_core::Vec2::new(105.0, 205.0));
    assert_eq!(g.grid.spacing_m(), [10.0, 10.0]);
}

#[test]
fn asc_errors() {
    let e = err_of(
        "a.asc",
        b"ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 x 6\n",
    );
    assert_eq!(e.position, Some(FilePosition::Line(7, Some(2))));
    let e = err_of(
        "b.asc",
        b"ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5\n",
    );
    assert!(e.message.contains("truncated"), "{e}");
    let e = err_of(
        "c.asc",
        b"ncols 3\nnrows 2\nxllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n",
    );
    assert!(e.message.contains("yllcorner"), "{e}");
    let e = err_of("d.asc", b"ncols three\n");
    assert_eq!(e.position, Some(FilePosition::Line(1, None)));
}

/// The header's other forms: cell-centre origins (`xllcenter`, `yllcenter`), separate `dx`/`dy`
/// (rectangular cells), keys in any case; and each header error names its own line.
#[test]
fn asc_centre_origin_rectangular_cells_and_header_lines() {
    let text = "NCOLS 3\nnrows 2\nxllcenter 100\nYLLCENTER 200\ndx 10\ndy 20\n3 4 5\n0 1 2\n";
    let (_d, p) = tmp("c.asc", text.as_bytes());
    let g = load_grid(&p, None).unwrap();
    assert_eq!(g.grid.origin_m(), Vec2::new(100.0, 200.0));
    assert_eq!(g.grid.spacing_m(), [10.0, 20.0]);
    assert_eq!((g.grid.at(0, 0), g.grid.at(2, 1)), (0.0, 5.0));
    // Corner origins move by half a cell each way (10 by 20 cells).
    let text = "ncols 3\nnrows 2\nxllcorner 100\nyllcorner 200\ndx 10\ndy 20\n3 4 5\n0 1 2\n";
    let (_d, p) = tmp("k.asc", text.as_bytes());
    assert_eq!(
        load_grid(&p, None).unwrap().grid.origin_m(),
        Vec2::new(105.0, 210.0)
    );
    // dx alone is not a cell size.
    let e = err_of(
        "dx.asc",
        b"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ndx 1\n1 2\n3 4\n",
    );
    assert!(e.message.contains("cellsize"), "{e}");
    // Errors on header lines 2, 3 and 4 name those lines.
    let e = err_of("n.asc", b"ncols 2\nnrows 1.5\n");
    assert_eq!(e.position, Some(FilePosition::Line(2, None)), "{e}");
    assert!(e.message.contains("whole number >= 2"), "{e}");
    let e = err_of("v.asc", b"ncols 2\nnrows 2\nxllcorner\n");
    assert_eq!(e.position, Some(FilePosition::Line(3, None)), "{e}");
    let e = err_of("u.asc", b"ncols 2\nnrows 2\nxllcorner 0\nfoo 1\n");
    assert_eq!(e.position, Some(FilePosition::Line(4, None)), "{e}");
    let e = err_of("w.asc", b"ncols 2\nnrows 2\nxllcorner abc\n");
    assert_eq!(e.position, Some(FilePosition::Line(3, None)), "{e}");
    // Counts: 2 and just below 1e8 are whole numbers; 1, 2.5 and 1e8 are not.
    for bad in ["1", "2.5", "100000000"] {
        let e = err_of("c.asc", format!("ncols {bad}\n").as_bytes());
        assert!(e.message.contains("whole number >= 2"), "{bad}: {e}");
    }
    // One value too many, on data line 2 (file line 7).
    let e = err_of(
        "m.asc",
        b"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4 5\n",
    );
    assert_eq!(e.position, Some(FilePosition::Line(7, None)), "{e}");
    assert!(e.message.contains("more than"), "{e}");
    // Truncated: the error names the last line read.
    let e = err_of(
        "t.asc",
        b"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3\n",
    );
    assert_eq!(e.position, Some(FilePosition::Line(7, None)), "{e}");
}

/// Blank lines are skipped, and errors after them still name the file's own line.
#[test]
fn csv_blank_lines_and_line_numbers() {
    let (_d, p) = tmp("b.csv", b"1,2\n\n3,4\n");
    let g = load_grid(&p, None).unwrap();
    assert_eq!((g.grid.nx(), g.grid.ny()), (2, 2));
    assert_eq!(g.grid.values(), &[1.0, 2.0, 3.0, 4.0]);
    let e = err_of("r.csv", b"1,2\n\n3,4,5\n");
    assert_eq!(e.position, Some(FilePosition::Line(3, None)), "{e}");
    let e = err_of("t.csv", b"1,2\n3,4\n\n5,x\n");
    assert_eq!(e.position, Some(FilePosition::Line(4, Some(2))), "{e}");
}

/// Writes a one-band float GeoTIFF with the tags GDAL writes.
fn geotiff_bytes(geographic: bool, nodata: Option<&str>) -> Vec<u8> {
    geotiff_bytes_tied(geographic, nodata, (0.0, 0.0))
}

/// [`geotiff_bytes`] with its tie point at raster position `(i, j)` (column, row from the top)
/// instead of the corner, the model position moved to match: the same georeference.
fn geotiff_bytes_tied(geographic: bool, nodata: Option<&str>, (ti, tj): (f64, f64)) -> Vec<u8> {
    use tiff::encoder::{colortype::Gray64Float, TiffEncoder};
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf).unwrap();
        let mut img = enc.new_image::<Gray64Float>(3, 4).unwrap();
        // TIFF rows are north first.
        let e = expected();
        let north_first: Vec<f64> = (0..4)
            .rev()
            .flat_map(|r| e[r * 3..r * 3 + 3].to_vec())
            .collect();
        let (sx, sy, tx, ty) = if geographic {
            (0.5, 0.25, 10.0, 51.0)
        } else {
            (30.0, 30.0, 500_000.0, 5_000_120.0)
        };
        img.encoder()
            .write_tag(Tag::ModelPixelScaleTag, &[sx, sy, 0.0][..])
            .unwrap();
        img.encoder()
            .write_tag(
                Tag::ModelTiepointTag,
                &[ti, tj, 0.0, tx + ti * sx, ty - tj * sy, 0.0][..],
            )
            .unwrap();
        let keys: Vec<u16> = if geographic {
            vec![1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326]
        } else {
            vec![1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 32632]
        };
        img.encoder()
            .write_tag(Tag::GeoKeyDirectoryTag, &keys[..])
            .unwrap();
        if let Some(nd) = nodata {
            img.encoder().write_tag(Tag::GdalNodata, nd).unwrap();
        }
        img.write_data(&north_first).unwrap();
    }
    buf.into_inner()
}

use tiff::tags::Tag;

#[test]
fn geotiff_projected_reads_georeference() {
    let (_d, p) = tmp("g.tif", &geotiff_bytes(false, Some("11")));
    let g = load_grid(&p, None).unwrap();
    assert_eq!(g.georeference, Georeference::Metres { epsg: Some(32632) });
    assert_eq!(g.grid.spacing_m(), [30.0, 30.0]);
    // Pixel-is-area: tie point at the NW corner; SW pixel centre = (tx + 15, ty - 4*30 + 15).
    assert_eq!(
        g.grid.origin_m(),
        isotrack_core::Vec2::new(500_015.0, 5_000_015.0)
    );
    assert_eq!(g.grid.at(2, 3), 32.0);
    assert!(g.grid.at(1, 1).is_nan(), "GDAL no-data 11");
}

/// A tie point inside the raster (column 1, row 2) instead of its corner gives the same grid.
#[test]
fn geotiff_tie_point_inside_the_raster() {
    for geographic in [false, true] {
        let (_d, a) = tmp("a.tif", &geotiff_bytes(geographic, None));
        let (_e, b) = tmp("b.tif", &geotiff_bytes_tied(geographic, None, (1.0, 2.0)));
        let (a, b) = (load_grid(&a, None).unwrap(), load_grid(&b, None).unwrap());
        assert_eq!(a.georeference, b.georeference);
        assert_eq!(a.grid.origin_m(), b.grid.origin_m());
        assert_eq!(a.grid.spacing_m(), b.grid.spacing_m());
    }
}

#[test]
fn geotiff_geographic_is_projected_to_metres() {
    let (_d, p) = tmp("g.tiff", &geotiff_bytes(true, None));
    let g = load_grid(&p, None).unwrap();
    let Georeference::LonLat {
        lon0_deg, lat0_deg, ..
    } = g.georeference
    else {
        panic!("{:?}", g.georeference)
    };
    assert!((lon0_deg - 10.25).abs() < 1e-12 && (lat0_deg - 50.125).abs() < 1e-12);
    let [dx, dy] = g.grid.spacing_m();
    // 0.25 degrees of latitude = 27.8 km; 0.5 degrees of longitude at 50.5 N = 35.4 km.
    assert!((dy - 27_798.77).abs() < 1.0, "{dy}");
    assert!(
        (dx - 0.5 * 111_195.08 * 50.5f64.to_radians().cos()).abs() < 1.0,
        "{dx}"
    );
}

#[test]
fn geotiff_truncated_and_garbage() {
    let full = geotiff_bytes(false, None);
    let e = err_of("t.tif", &full[..full.len() - 40]);
    assert!(e.to_string().contains("t.tif"), "{e}");
    assert!(
        e.message.contains("truncated") || e.message.contains("invalid"),
        "{e}"
    );
    let e = err_of("h.tif", &full[..6]);
    assert!(e.to_string().contains("h.tif"), "{e}");
    let e = err_of("z.tif", b"II*\x00garbage garbage garbage");
    assert!(e.to_string().contains("z.tif"), "{e}");
}

#[test]
fn unknown_extension_and_missing_file() {
    let e = err_of("g.xyz", b"1,2\n3,4\n");
    assert!(e.message.contains("format"), "{e}");
    let e = load_grid(Path::new("/nonexistent/g.csv"), None).unwrap_err();
    assert!(e.message.contains("cannot read"), "{e}");
}

#[test]
fn shared_data_csv_and_npy_agree() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/volcano");
    let a = load_grid(&Path::new(dir).join("volcano.csv"), None).unwrap();
    let b = load_grid(&Path::new(dir).join("volcano.npy"), None).unwrap();
    assert_eq!(a.grid.values(), b.grid.values());
    assert_eq!((a.grid.nx(), a.grid.ny()), (61, 87));
    assert_eq!(a.grid.value_range(), (94.0, 195.0));
}

/// GeoTIFFs written by GDAL (scripts/make-geotiff-fixtures.py): every codec, predictor, layout
/// and sample type gives exactly the grid of `grid.csv`, with the same georeference.
#[test]
fn geotiffs_written_by_gdal_load_like_the_csv() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/geotiff");
    let csv = load_grid(&dir.join("grid.csv"), None).unwrap();
    let (nx, ny) = (csv.grid.nx(), csv.grid.ny());
    assert_eq!((nx, ny), (40, 30));
    // The fixtures: 25 m pixels, north-west corner (500000, 4650000) in EPSG:32633, so the
    // south-west pixel's centre is at (500012.5, 4650000 - 29.5*25).
    let origin = Vec2::new(500_012.5, 4_650_000.0 - 29.5 * 25.0);
    for name in [
        "uncompressed_f64.tif",
        "deflate_f32.tif",
        "deflate_pred2_i16.tif",
        "deflate_pred3_f32.tif",
        "deflate_pred3_f64.tif",
        "lzw_u8.tif",
        "lzw_pred2_u8.tif",
        "zstd_f32.tif",
        "zstd_pred2_i16.tif",
        "tiled_deflate_f32.tif",
        "tiled_lzw_f32.tif",
        "tiled_lzw_pred3_f32.tif",
        "tiled_lzw_i16.tif",
        "tiled_lzw_pred2_i16.tif",
        "tiled_lzw_pred2_u8.tif",
        "bigtiff_deflate_f64.tif",
        "cog_deflate_f32.tif",
    ] {
        let g = load_grid(&dir.join(name), None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((g.grid.nx(), g.grid.ny()), (nx, ny), "{name}");
        assert_eq!(g.grid.values(), csv.grid.values(), "{name}");
        assert_eq!(g.grid.spacing_m(), [25.0, 25.0], "{name}");
        assert_eq!(g.grid.origin_m(), origin, "{name}");
        assert_eq!(
            g.georeference,
            Georeference::Metres { epsg: Some(32633) },
            "{name}"
        );
    }
    let e = load_grid(&dir.join("jpeg_u8.tif"), None).expect_err("JPEG is not supported");
    assert!(e.message.contains("JPEG"), "{e}");
    assert!(e.to_string().contains("jpeg_u8.tif"), "{e}");
}

/// Regression (hostile inputs): an object array is named as such, not "truncated".
#[test]
fn npy_object_dtype_is_named() {
    let e = err_of("o.npy", &npy_bytes("|O", "(2, 2)", false, &[0u8; 32]));
    assert!(
        e.message.contains("`|O`") && e.message.contains("Python objects"),
        "{e}"
    );
    assert!(!e.message.contains("truncated"), "{e}");
}

/// A minimal little-endian baseline TIFF: 2 x 2 pixels of `bits` bits, one band, one strip.
fn tiff_with_bits(bits: u16) -> Vec<u8> {
    let data_at = 8u32;
    let data = [0u8; 4];
    let ifd_at = data_at + data.len() as u32;
    let mut b = vec![b'I', b'I', 42, 0];
    b.extend(ifd_at.to_le_bytes());
    b.extend(data);
    // (tag, type SHORT=3 / LONG=4, count, value)
    let entries: [(u16, u16, u32, u32); 9] = [
        (256, 3, 1, 2),               // ImageWidth
        (257, 3, 1, 2),               // ImageLength
        (258, 3, 1, u32::from(bits)), // BitsPerSample
        (259, 3, 1, 1),               // Compression: none
        (262, 3, 1, 1),               // Photometric: BlackIsZero
        (273, 4, 1, data_at),         // StripOffsets
        (277, 3, 1, 1),               // SamplesPerPixel
        (278, 3, 1, 2),               // RowsPerStrip
        (279, 4, 1, 4),               // StripByteCounts
    ];
    b.extend((entries.len() as u16).to_le_bytes());
    for (tag, ty, count, value) in entries {
        b.extend(tag.to_le_bytes());
        b.extend(ty.to_le_bytes());
        b.extend(count.to_le_bytes());
        b.extend(value.to_le_bytes());
    }
    b.extend(0u32.to_le_bytes());
    b
}

/// Regression (hostile inputs): a 7-bit GeoTIFF is refused for its bit depth, not as "more than
/// one band?"; the same file at 8 bits reads.
#[test]
fn geotiff_odd_bit_depth_is_named() {
    let e = err_of("b7.tif", &tiff_with_bits(7));
    assert!(e.message.contains("7-bit samples"), "{e}");
    let (_d, p) = tmp("b8.tif", &tiff_with_bits(8));
    let g = load_grid(&p, None).unwrap();
    assert_eq!((g.grid.nx(), g.grid.ny()), (2, 2));
}

/// Regression (hostile inputs): values beyond the grid limit are an error naming the value and
/// the node (a 1e308 grid once ran and reported "the field has no value at (1, 1)").
#[test]
fn grid_values_beyond_the_limit_are_refused() {
    let e = err_of("big.csv", b"0,1e308\n2,3\n");
    assert!(
        e.message.contains("1e308") && e.message.contains("column 1, row 0"),
        "{e}"
    );
    let (_d, p) = tmp("ok.csv", b"0,1e99\n2,3\n");
    assert!(load_grid(&p, None).is_ok());
}

/// att43-5: a file read whole is allocated fallibly. Beyond the memory budget it is refused
/// before any allocation, and an allocation the system refuses (2^62 bytes: more than any
/// address space holds) is an `OutOfMemory` error naming the bytes, where `Vec::with_capacity`
/// aborted the process ("memory allocation of 3221225472 bytes failed", rc 134). Through a
/// loader, the error is the Limits table's memory refusal (65, not 66: `unreadable` false),
/// naming the file and the bytes.
#[test]
fn a_file_too_large_for_memory_is_an_error_not_an_abort() {
    use super::limits::whole_file_buffer;
    let e = whole_file_buffer(1 << 62, None).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::OutOfMemory);
    assert!(e.to_string().contains("4611686018427387904 bytes"), "{e}");
    assert!(e.to_string().contains("refused to allocate"), "{e}");
    let e = whole_file_buffer(3 << 30, Some(1 << 30)).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::OutOfMemory);
    assert!(
        e.to_string().contains("3221225472 bytes (3.00 GiB)")
            && e.to_string().contains("(1.00 GiB: MemAvailable"),
        "{e}"
    );
    // Within the budget: the room for exactly the file's bytes.
    let b = whole_file_buffer(1000, Some(1 << 30)).unwrap();
    assert!(b.is_empty() && b.capacity() >= 1000);
    let (_d, p) = tmp("g.csv", b"1,2\n3,4\n");
    let le = LoadError::cannot_read(&p, e);
    assert!(!le.unreadable, "{le:?}");
    assert!(
        le.to_string()
            .contains("g.csv: too large to load: its 3221225472 bytes"),
        "{le}"
    );
}

/// Regression (hostile inputs): devices, pipes and directories are refused before a byte is
/// read (`/dev/zero` once grew the process to 18.7 GB), and files beyond the limit too.
#[test]
fn non_regular_and_oversized_files_are_refused() {
    #[cfg(unix)]
    {
        let e = load_grid(Path::new("/dev/zero"), Some(GridFormat::Csv)).unwrap_err();
        assert!(e.message.contains("not a regular file"), "{e}");
    }
    let dir = tempfile::tempdir().unwrap();
    let e = load_grid(dir.path(), Some(GridFormat::Npy)).unwrap_err();
    assert!(e.message.contains("not a regular file"), "{e}");
    let (_d, p) = tmp("g.csv", &[b'1'; 100]);
    let e = read_limited(&p, 99).unwrap_err();
    assert!(
        e.to_string().contains("100 bytes is more than the 99"),
        "{e}"
    );
    assert_eq!(read_limited(&p, 100).unwrap().len(), 100);
}

/// Regression (hostile inputs): a header claiming more nodes than a grid may hold is refused
/// before anything is allocated, whatever the format.
#[test]
fn declared_sizes_beyond_the_node_limit_are_refused() {
    let e = err_of(
        "h.npy",
        &npy_bytes("|u1", "(70000, 70000)", false, &[0u8; 16]),
    );
    assert!(e.message.contains("more than the 268435456"), "{e}");
    let e = err_of(
        "h.asc",
        b"ncols 70000\nnrows 70000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n",
    );
    assert!(e.message.contains("ncols x nrows"), "{e}");
}

/// Regression (fuzzing, series target): a crafted `.npy` header kept the Python-literal parser
/// busy for more than 20 minutes; headers are checked first (length, characters, digit runs).
#[test]
fn npy_headers_are_checked_before_parsing() {
    let long_digits = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}e{}, 2), }}",
        "9".repeat(30),
        "1".repeat(30)
    );
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend((long_digits.len() as u16).to_le_bytes());
    b.extend(long_digits.as_bytes());
    let t = std::time::Instant::now();
    let e = err_of("d.npy", &b);
    assert!(e.message.contains("more than 20 digits"), "{e}");
    assert!(t.elapsed().as_secs() < 5);
    let e = err_of("c.npy", b"\x93NUMPY\x01\x00\x05\x00{\x01\x02\x03}");
    assert!(e.message.contains("byte 0x01"), "{e}");
    let e = err_of("l.npy", b"\x93NUMPY\x01\x00\xff\xff{}");
    assert!(e.message.contains("header of 65535 bytes"), "{e}");
}

/// The header checks at their bounds: the magic and minimum length, version 2's 4-byte
/// length, the header's size limit and extent, one dict with at most one tuple, digit runs of
/// 20 (accepted) and 21 (refused), and the shape checks of frames and series.
#[test]
fn npy_header_checks_at_their_bounds() {
    let f8 = |n: usize| -> Vec<u8> { (0..n).flat_map(|k| (k as f64).to_le_bytes()).collect() };
    // A valid 2 x 2 grid, and the same in format version 2 (4-byte header length).
    let v1 = npy_bytes("<f8", "(2, 2)", false, &f8(4));
    let (_d, p) = tmp("v1.npy", &v1);
    assert_eq!(
        load_grid(&p, None).unwrap().grid.values(),
        &[0.0, 1.0, 2.0, 3.0]
    );
    let hlen = u16::from_le_bytes([v1[8], v1[9]]) as usize;
    let mut v2 = b"\x93NUMPY\x02\x00".to_vec();
    v2.extend((hlen as u32).to_le_bytes());
    v2.extend(&v1[10..]);
    let (_d, p) = tmp("v2.npy", &v2);
    assert_eq!(
        load_grid(&p, None).unwrap().grid.values(),
        &[0.0, 1.0, 2.0, 3.0]
    );
    // Too short for the magic and length; version 2 without its 4 length bytes; version 4.
    for (name, b) in [
        ("short.npy", b"\x93NUMPY\x01".to_vec()),
        ("v2short.npy", b"\x93NUMPY\x02\x00\x00\x00".to_vec()),
        ("v4.npy", b"\x93NUMPY\x04\x00\x00\x00\x00\x00".to_vec()),
    ] {
        let e = err_of(name, &b);
        assert!(e.message.contains("not a valid .npy file"), "{name}: {e}");
    }
    // A header running past the file's end.
    let mut cut = v1.clone();
    cut.truncate(40);
    let e = err_of("cut.npy", &cut);
    assert!(e.message.contains("within the file"), "{e}");
    // Two dicts, or two tuples: refused before the parser.
    for shape in ["(2, 2), 'x': {}", "(2, 2), 'x': (1,)"] {
        let e = err_of("two.npy", &npy_bytes("<f8", shape, false, &f8(4)));
        assert!(
            e.message.contains("one dict with one shape tuple"),
            "{shape}: {e}"
        );
    }
    // Digit runs: 20 digits are a number (here a too-large frame), 21 are refused outright.
    let e = err_of(
        "d20.npy",
        &npy_bytes("<f8", &format!("(2, {})", "9".repeat(20)), false, &[]),
    );
    assert!(!e.message.contains("more than 20 digits"), "{e}");
    let e = err_of(
        "d21.npy",
        &npy_bytes("<f8", &format!("(2, 1{})", "0".repeat(20)), false, &[]),
    );
    assert!(e.message.contains("more than 20 digits"), "{e}");
    // A frame must be at least 2 x 2; a series at least one frame; data must fit the file.
    for shape in ["(1, 5)", "(5, 1)", "(3, 1, 4)", "(0, 2, 2)"] {
        let e = err_of("s.npy", &npy_bytes("<f8", shape, false, &f8(8)));
        assert!(e.message.contains("at least 2 x 2"), "{shape}: {e}");
    }
    let e = err_of("t.npy", &npy_bytes("<f8", "(3, 2)", false, &f8(5)));
    assert!(e.message.contains("truncated"), "{e}");
    // Exactly the data the shape needs: read (2 frames of 2 x 2 as a series).
    let b = npy_bytes("<f8", "(2, 2, 2)", false, &f8(8));
    let s = parse_series_bytes(std::path::Path::new("s.npy"), &b, GridFormat::Npy, None);
    assert!(s.is_ok(), "{:?}", s.err());
}

/// `read_text_limited` reads a text file whole, and refuses bytes that are not UTF-8 and a file
/// over the limit (with the limit's size in the message).
#[test]
fn text_is_read_whole_within_its_limit() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.txt");
    std::fs::write(&p, "level = 10\nname = \"é\"\n").unwrap();
    assert_eq!(
        read_text_limited(&p, 1000).unwrap(),
        "level = 10\nname = \"é\"\n"
    );
    // Exactly at the limit is fine; one byte under it is not.
    let n = std::fs::metadata(&p).unwrap().len();
    assert!(read_text_limited(&p, n).is_ok());
    assert!(read_text_limited(&p, n - 1).is_err());
    std::fs::write(&p, [0x66u8, 0xff, 0xfe]).unwrap();
    let e = read_text_limited(&p, 1000).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
}

fn netcdf_fixture(name: &str) -> (std::path::PathBuf, Vec<u8>) {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/netcdf")
        .join(name);
    let b = std::fs::read(&p).unwrap();
    (p, b)
}

/// The limit in values: 2^30, or the budget at 24 bytes a value when that is fewer.
#[test]
fn series_node_limit_follows_the_memory_budget() {
    assert_eq!(series_node_limit(None), 1 << 30);
    assert_eq!(series_node_limit(Some(24 * 1000)), 1000);
    assert_eq!(series_node_limit(Some(24 * 1000 + 23)), 1000);
    assert_eq!(series_node_limit(Some(u64::MAX)), 1 << 30);
    #[cfg(target_os = "linux")]
    assert!(memory_budget_bytes().is_some_and(|b| b > 0));
}

/// Regression (issue 30): a 8 KB NetCDF-4 file, chunked and zlib-compressed but never written,
/// declares 4 frames of 16000 x 16000 fill values; it aborted the process allocating 8.2 GB.
/// With 8 GiB to spend (24 bytes a value: 357 913 941 values) it is refused before reading,
/// and the error counts frames x nodes.
#[test]
fn an_unwritten_netcdf_series_is_refused_by_frames_times_nodes() {
    let (p, b) = netcdf_fixture("unwritten_4x16000x16000.nc");
    let e = super::netcdf::parse_bytes_within(&p, &b, None, Some(8 << 30)).unwrap_err();
    assert!(
        e.message
            .contains("4 frames of 16000 x 16000 nodes = 1024000000 values"),
        "{e}"
    );
    assert!(e.message.contains("8.0 GiB"), "{e}");
    assert!(e.message.contains("357913941"), "{e}");
    // One frame (256 000 000 values) is more than 4 GiB holds (178 956 970).
    let (p1, b1) = netcdf_fixture("unwritten_1x16000x16000.nc");
    let e = super::netcdf::parse_bytes_within(&p1, &b1, None, Some(4 << 30)).unwrap_err();
    assert!(e.message.contains("1 frame of 16000 x 16000"), "{e}");
    // Five frames are beyond 2^30 values on any machine, through the public loader.
    let (p5, _) = netcdf_fixture("unwritten_5x16000x16000.nc");
    let e = load_series(&p5, None, None).unwrap_err();
    assert!(
        e.message
            .contains("5 frames of 16000 x 16000 nodes = 1280000000 values"),
        "{e}"
    );
    assert!(e.message.contains("too many to load"), "{e}");
    let e = super::netcdf::parse_bytes_within(&p5, &std::fs::read(&p5).unwrap(), None, None)
        .unwrap_err();
    assert!(e.message.contains("at most 1073741824"), "{e}");
}

/// The budget is exact: a 3 x 5 x 6 fixture (90 values) loads with 90 x 24 bytes, not 89 x 24.
#[test]
fn the_memory_budget_is_applied_at_its_bound() {
    let (p, b) = netcdf_fixture("netcdf4_nc4_lonlat_zlib1.nc");
    let s = super::netcdf::parse_bytes_within(&p, &b, None, Some(90 * 24)).unwrap();
    assert_eq!(s.frames.len(), 3);
    let e = super::netcdf::parse_bytes_within(&p, &b, None, Some(89 * 24)).unwrap_err();
    assert!(e.message.contains("= 90 values"), "{e}");
}

/// GDAL's tiled LZW without end codes (issue 30, item 2) cut short anywhere in its tiles is
/// an error naming the file, never a panic or a grid of zeros.
#[test]
fn tiled_lzw_cut_short_is_an_error() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/geotiff/tiled_lzw_f32.tif");
    let full = std::fs::read(&p).unwrap();
    assert!(parse_grid(&p, &full, GridFormat::GeoTiff).is_ok());
    for cut in (full.len() / 2..full.len()).step_by(97) {
        let e = parse_grid(&p, &full[..cut], GridFormat::GeoTiff).unwrap_err();
        assert!(e.to_string().contains("tiled_lzw_f32.tif"), "{cut}: {e}");
    }
}

/// The same grid, bit for bit (no-data `NaN`s included), and the same georeference.
fn assert_same(a: &LoadedGrid, b: &LoadedGrid) {
    let bits = |g: &LoadedGrid| {
        g.grid
            .values()
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(a), bits(b));
    assert_eq!((a.grid.nx(), a.grid.ny()), (b.grid.nx(), b.grid.ny()));
    assert_eq!(a.georeference, b.georeference);
}

/// Hostile review of issue 30: a symbolic link to a grid. The format comes from the file's
/// signature first (NetCDF, HDF5, TIFF, npy), then `field.format`, then the extension of the
/// name as written, then the link target's; a `field.format` that contradicts the signature is
/// an error naming both, and a binary extension without its signature is refused from the
/// first bytes.
#[cfg(unix)]
#[test]
fn symlinked_grids_follow_their_content() {
    use std::os::unix::fs::symlink;
    let d = tempfile::tempdir().unwrap();
    let nc = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/netcdf/h5netcdf_nc4_lonlat_contig_2d.nc");
    let npy = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/volcano/volcano.npy");
    let csv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/volcano/volcano.csv");
    let want_nc = load_grid(&nc, None).unwrap();
    let want_npy = load_grid(&npy, None).unwrap();
    // `data.nc -> /store/blob`: a blob without an extension, read by its name's extension and
    // confirmed by its content.
    let blob = d.path().join("blob");
    std::fs::copy(&nc, &blob).unwrap();
    let link = d.path().join("data.nc");
    symlink(&blob, &link).unwrap();
    assert_same(&load_grid(&link, None).unwrap(), &want_nc);
    // The blob itself has no extension: its signature says NetCDF.
    assert_same(&load_grid(&blob, None).unwrap(), &want_nc);
    // `x.csv -> y.nc` and `x.csv -> volcano.npy`: the content wins over the name.
    let x = d.path().join("x.csv");
    symlink(&nc, &x).unwrap();
    assert_same(&load_grid(&x, None).unwrap(), &want_nc);
    let xn = d.path().join("xn.csv");
    symlink(&npy, &xn).unwrap();
    assert_same(&load_grid(&xn, None).unwrap(), &want_npy);
    // A format given that the content contradicts: an error naming both.
    let e = load_grid(&x, Some(GridFormat::Csv)).unwrap_err();
    assert!(
        e.message
            .contains("field.format = \"csv\" but the file is netcdf"),
        "{e}"
    );
    // `latest -> volcano.csv`: no extension on the link, the target's (a text format).
    let latest = d.path().join("latest");
    symlink(&csv, &latest).unwrap();
    assert_same(
        &load_grid(&latest, None).unwrap(),
        &load_grid(&csv, None).unwrap(),
    );
    // `data.nc -> volcano.csv`: a binary extension on text: refused from the first bytes.
    let fake = d.path().join("fake.nc");
    symlink(&csv, &fake).unwrap();
    let e = load_grid(&fake, None).unwrap_err();
    assert!(
        e.message
            .contains("named as netcdf but its first bytes are not a netcdf signature"),
        "{e}"
    );
    let e = load_grid(&csv, Some(GridFormat::Npy)).unwrap_err();
    assert!(
        e.message
            .contains("not a npy file: its first bytes are not the npy signature"),
        "{e}"
    );
}

#[test]
fn signatures_name_their_formats() {
    for (head, want) in [
        (&b"CDF\x01\0\0\0\0"[..], Some(GridFormat::NetCdf)),
        (b"CDF\x02", Some(GridFormat::NetCdf)),
        (b"CDF\x05", Some(GridFormat::NetCdf)),
        (b"CDF\x03", None),
        (b"\x89HDF\r\n\x1a\n", Some(GridFormat::NetCdf)),
        (b"II*\0", Some(GridFormat::GeoTiff)),
        (b"MM\0*", Some(GridFormat::GeoTiff)),
        (b"II+\0", Some(GridFormat::GeoTiff)),
        (b"MM\0+", Some(GridFormat::GeoTiff)),
        (b"\x93NUMPY\x01\0", Some(GridFormat::Npy)),
        (b"1,2,3\n", None),
        (b"", None),
    ] {
        assert_eq!(GridFormat::from_signature(head), want, "{head:?}");
    }
}

/// A `/proc` or `/sys` file declares 0 bytes (or 4096) whatever it produces: read as a CSV grid,
/// `/proc/self/pagemap` once took 11 s and 4 GiB of memory before failing, and (issue 30)
/// 7 s to the grid's size cap once the data file was read whole. Every opener refuses such a
/// file from its filesystem (`fstatfs`: `/proc` is 0x9fa0, `/sys` 0x62656572) before a byte is
/// read, saying what it is; a regular file is read as before.
#[cfg(target_os = "linux")]
#[test]
fn proc_files_are_refused_before_a_byte_is_read() {
    let pseudo = |e: &dyn std::fmt::Display| e.to_string().contains("kernel pseudo-file");
    for (path, fs) in [
        ("/proc/self/pagemap", "/proc"),
        ("/proc/self/maps", "/proc"),
        ("/sys/kernel/mm/transparent_hugepage/enabled", "/sys"),
    ] {
        let p = Path::new(path);
        if !p.exists() {
            continue;
        }
        let e = open_regular(p).unwrap_err();
        assert!(pseudo(&e) && e.to_string().contains(fs), "{path}: {e}");
        assert!(pseudo(&read_limited(p, 1 << 30).unwrap_err()), "{path}");
        assert!(pseudo(&open_limited(p, 1 << 30).unwrap_err()), "{path}");
        let e = load_grid(p, Some(GridFormat::Csv)).unwrap_err();
        assert!(pseudo(&e) && e.to_string().contains(path), "{path}: {e}");
    }
    let (_d, p) = tmp("g.csv", b"0,1\n2,3\n");
    assert_eq!(read_limited(&p, 100).unwrap(), b"0,1\n2,3\n");
    // A file that grows past the limit once opened (8 bytes declared, 40 there when read) is
    // stopped one byte past the limit, counted on the bytes read: an error, not a cut.
    let mut r = open_limited(&p, 16).unwrap();
    std::fs::write(&p, [b'1'; 40]).unwrap();
    let mut buf = Vec::new();
    let e = std::io::Read::read_to_end(&mut r, &mut buf).unwrap_err();
    assert!(e.to_string().contains("more than the 16 bytes"), "{e}");
    assert_eq!(buf.len(), 16);
}

/// The address-space limit (`ulimit -v`) as `/proc/self/limits` and `/proc/self/status` write it.
#[test]
fn address_space_limit_and_virtual_size_are_read_from_proc() {
    let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                  Max stack size            8388608              unlimited            bytes     \n\
                  Max address space         3221225472           unlimited            bytes     \n";
    assert_eq!(parse_address_space_limit(limits), Some(3 << 30));
    let unlimited =
        "Max address space         unlimited            unlimited            bytes     \n";
    assert_eq!(parse_address_space_limit(unlimited), None);
    let status = "Name:\tx\nVmPeak:\t  999 kB\nVmSize:\t   12345 kB\nVmRSS:\t 5 kB\n";
    assert_eq!(parse_vm_size_bytes(status), Some(12345 * 1024));
    assert_eq!(parse_vm_size_bytes("Name:\tx\n"), None);
}

/// att41-22: the digest a load gives is of the bytes it parsed, not of the file as it is after
/// the load. The read stand-in reads the file, then renames another grid over it (as an editor
/// or `mv` replaces a file) before the loader sees the bytes: the loader parses the first grid
/// and names its SHA-256 (`sha256sum` of the text: 9bad80dc...), not the second's (39768365...),
/// which the file on disk now holds. Deterministic: the replacement happens inside the read.
#[test]
fn the_digest_is_of_the_bytes_parsed_not_the_file_after() {
    const OLD: &str = "0,1,2\n10,11,12\n20,21,22\n30,31,32\n";
    const NEW: &str = "100,101,102\n110,111,112\n120,121,122\n130,131,132\n";
    const OLD_SHA256: &str = "9bad80dc300f30f8e4254a6025fde01952b4a378655dbd2c11405b20e70d8472";
    const NEW_SHA256: &str = "39768365d30bd35f3790aacbf5e60e7e1fe99fe9e5c78b92dd46e1c9f9294e2e";
    // FIPS 180-2's test vector: the digest function itself.
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    let (d, p) = tmp("g.csv", OLD.as_bytes());
    let replacement = d.path().join("new.csv");
    std::fs::write(&replacement, NEW).unwrap();
    let read_then_replace = |path: &Path, max: u64| {
        let bytes = read_limited(path, max);
        std::fs::rename(&replacement, path).unwrap();
        bytes
    };
    let (series, digest) = load_series_read(&p, None, None, &read_then_replace).unwrap();
    assert_eq!(series.frames[0].values(), expected().as_slice());
    assert_eq!(digest, OLD_SHA256);
    // The file now holds the other grid (what a digest read after the load named).
    assert_eq!(sha256_hex(&std::fs::read(&p).unwrap()), NEW_SHA256);
    let (now, now_digest) = load_series_hashed(&p, None, None).unwrap();
    assert_eq!(now_digest, NEW_SHA256);
    assert_eq!(now.frames[0].values()[0], 100.0);
}
