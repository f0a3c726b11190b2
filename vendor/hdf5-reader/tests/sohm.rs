//! isotrack: files whose object header messages are shared through the shared object header
//! message (SOHM) table, written by libhdf5 (h5py and h5netcdf, through
//! `scripts/make-netcdf-fixtures.py`, `shared_messages`, in the isotrack repository): every
//! kind libhdf5 can share (dataspaces, datatypes, fill values, filter pipelines, attributes)
//! alone, all in one index and each in its own index, in list form and in B-tree form, and a
//! variable with more than 8 shared attributes (dense attribute storage). Each must read back
//! exactly the values the script wrote (see PATCHED.md). The fixtures are the isotrack
//! workspace's: run from a checkout of it (`cargo test --release` in vendor/hdf5-reader).

use std::path::PathBuf;

use hdf5_reader::{Dataset, Hdf5File};

const NT: usize = 3;
const NY: usize = 5;
const NX: usize = 6;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../crates/isotrack-fields/tests/fixtures/netcdf")
        .join(name)
}

/// The script's names, `sohm_files()`: (name, extra `note_NN` attributes on `v`).
fn sohm_files() -> Vec<(String, usize)> {
    let mut files = Vec::new();
    for form in ["", "_btree"] {
        for kind in [
            "dataspaces",
            "datatypes",
            "fill",
            "pline",
            "attrs",
            "all",
            "separate",
            "dataspaces_datatypes",
            "datatypes_dataspaces",
        ] {
            files.push((format!("sohm_{kind}{form}.nc"), 0));
        }
        for kind in ["attrs", "all", "separate"] {
            files.push((format!("sohm_{kind}_dense{form}.nc"), 12));
        }
    }
    files
}

fn text(ds: &Dataset, name: &str) -> String {
    let attr = ds
        .attribute(name)
        .unwrap_or_else(|e| panic!("{}: attribute {name}: {e}", ds.name()));
    attr.read_string()
        .unwrap_or_else(|e| panic!("{}: attribute {name}: {e}", ds.name()))
}

fn f64s(ds: &Dataset) -> Vec<f64> {
    ds.read_array::<f64>()
        .unwrap_or_else(|e| panic!("{}: {e}", ds.name()))
        .iter()
        .copied()
        .collect()
}

/// `v` is 10 + 0.125 (3 i + 7 j + 40 t) (time t, row j, column i), NaN at (0, 1, 2), its
/// `_FillValue` NaN, deflated in chunks of (1, 3, 4); x = 500 000 + 1000 i m, y = 4 600 000 +
/// 2000 j m (the script's `values`, `dataset("xy", True)` and `encoding(.., "zlib1", ..)`).
fn check(name: &str, extra: usize) {
    let file = Hdf5File::open(fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let v = file
        .dataset("v")
        .unwrap_or_else(|e| panic!("{name}: v: {e}"));
    assert_eq!(v.shape(), &[NT as u64, NY as u64, NX as u64], "{name}");
    assert_eq!(v.chunks(), Some(vec![1, 3, 4]), "{name}");
    let got = f64s(&v);
    assert_eq!(got.len(), NT * NY * NX, "{name}");
    for t in 0..NT {
        for j in 0..NY {
            for i in 0..NX {
                let g = got[(t * NY + j) * NX + i];
                if (t, j, i) == (0, 1, 2) {
                    assert!(g.is_nan(), "{name}: v[0, 1, 2] = {g}");
                } else {
                    let want = 10.0 + 0.125 * (3 * i + 7 * j + 40 * t) as f64;
                    assert_eq!(g, want, "{name}: v[{t}, {j}, {i}]");
                }
            }
        }
    }
    let fill = v
        .fill_value()
        .unwrap_or_else(|| panic!("{name}: no fill value"));
    let fill = fill
        .value
        .as_deref()
        .unwrap_or_else(|| panic!("{name}: fill value undefined"));
    assert_eq!(fill.len(), 8, "{name}");
    assert!(
        f64::from_le_bytes(fill.try_into().unwrap()).is_nan(),
        "{name}"
    );
    let fv = v.attribute("_FillValue").unwrap();
    assert!(fv.read_scalar::<f64>().unwrap().is_nan(), "{name}");
    assert_eq!(text(&v, "units"), "K", "{name}");
    assert_eq!(text(&v, "standard_name"), "air_temperature", "{name}");
    assert_eq!(text(&v, "long_name"), "air temperature", "{name}");
    assert_eq!(text(&v, "comment"), "synthetic: 10 + k / 8", "{name}");
    assert_eq!(text(&v, "grid_mapping"), "crs", "{name}");
    for i in 0..extra {
        let want = format!("note {i}: {}", "abc".repeat(i + 1));
        assert_eq!(text(&v, &format!("note_{i:02}")), want, "{name}");
    }
    // DIMENSION_LIST, _Netcdf4Coordinates, _Netcdf4Dimid, _FillValue and the five above.
    assert_eq!(v.attributes().len(), 9 + extra, "{name}");
    for a in v.attributes() {
        assert!(a.undecodable_reason().is_none(), "{name}: {}", a.name);
    }

    let x = file
        .dataset("x")
        .unwrap_or_else(|e| panic!("{name}: x: {e}"));
    let want: Vec<f64> = (0..NX).map(|i| 500_000.0 + 1000.0 * i as f64).collect();
    assert_eq!(f64s(&x), want, "{name}");
    assert_eq!(text(&x, "units"), "m", "{name}");
    assert_eq!(text(&x, "axis"), "X", "{name}");
    let y = file
        .dataset("y")
        .unwrap_or_else(|e| panic!("{name}: y: {e}"));
    let want: Vec<f64> = (0..NY).map(|j| 4_600_000.0 + 2000.0 * j as f64).collect();
    assert_eq!(f64s(&y), want, "{name}");
    assert_eq!(
        text(&y, "standard_name"),
        "projection_y_coordinate",
        "{name}"
    );
    // Few attributes: compact storage in the object header (shared ones point into the
    // shared-message heap).
    let crs = file
        .dataset("crs")
        .unwrap_or_else(|e| panic!("{name}: crs: {e}"));
    assert_eq!(
        crs.read_array::<i32>()
            .unwrap()
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        [0]
    );
    assert_eq!(
        text(&crs, "grid_mapping_name"),
        "transverse_mercator",
        "{name}"
    );
    assert_eq!(text(&crs, "epsg_code"), "EPSG:32633", "{name}");
    let tb = file
        .dataset("time_bnds")
        .unwrap_or_else(|e| panic!("{name}: time_bnds: {e}"));
    assert_eq!(text(&tb, "long_name"), "time bounds", "{name}");
    assert_eq!(text(&tb, "comment"), "+-30 min", "{name}");
    let time = file
        .dataset("time")
        .unwrap_or_else(|e| panic!("{name}: time: {e}"));
    let hours: Vec<i64> = time.read_array::<i64>().unwrap().iter().copied().collect();
    assert_eq!(hours, [6, 7, 9], "{name}");
    // The script's TIME_UNITS, "hours since 2020-01-01 00:00:00", as xarray writes it.
    assert_eq!(text(&time, "units"), "hours since 2020-01-01", "{name}");
}

/// Checks every file, then fails naming each that did not read back.
fn check_all(files: impl Iterator<Item = (String, usize)>) {
    let failed: Vec<String> = files
        .filter(|(name, extra)| std::panic::catch_unwind(|| check(name, *extra)).is_err())
        .map(|(name, _)| name)
        .collect();
    assert!(failed.is_empty(), "not read back: {failed:?}");
}

/// Whether the file shares attributes (the script's `attrs`, `all` and `separate` indexes).
fn shares_attributes(name: &str) -> bool {
    ["attrs", "all", "separate"]
        .iter()
        .any(|kind| name.starts_with(&format!("sohm_{kind}")))
}

/// ver30b-1: dataspaces, datatypes, fill values or filter pipelines shared, each kind alone
/// and dataspaces and datatypes in two indexes (a datatype was looked up in the dataspace
/// index: "unsupported dataspace version 17").
#[test]
fn each_kind_alone_and_in_separate_indexes_reads_back() {
    check_all(
        sohm_files()
            .into_iter()
            .filter(|(n, _)| !shares_attributes(n)),
    );
}

/// ver30b-8: attributes shared, alone, with every kind in one index and in five indexes: `v`
/// has 9 or 21 (dense storage: the name B-tree's records hold shared-message heap IDs, and
/// the object has no heap of its own: "undefined address"), `crs` and `time_bnds` a few
/// (compact).
#[test]
fn shared_attributes_read_back() {
    check_all(
        sohm_files()
            .into_iter()
            .filter(|(n, _)| shares_attributes(n)),
    );
}
