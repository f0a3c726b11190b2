//! Adversarial inputs for the loaders (the fuzz targets' seeds): huge declared sizes with
//! little data must be errors, never an attempt to allocate the declared size.

use isotrack_fields::io::{parse_grid, GridFormat};
use std::path::Path;

fn npy(shape: &str, data: &[u8]) -> Vec<u8> {
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}");
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
fn huge_declared_sizes_are_errors() {
    let asc = b"ncols 99999999\nnrows 99999999\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n";
    let e = parse_grid(Path::new("big.asc"), asc, GridFormat::Asc).unwrap_err();
    assert!(e.to_string().contains("big.asc"), "{e}");
    let e = parse_grid(
        Path::new("big.npy"),
        &npy("(100000000, 100000000)", &[0u8; 16]),
        GridFormat::Npy,
    )
    .unwrap_err();
    assert!(e.to_string().contains("big.npy"), "{e}");
    let e = parse_grid(
        Path::new("ovf.npy"),
        &npy("(18446744073709551615, 2)", &[0u8; 16]),
        GridFormat::Npy,
    )
    .unwrap_err();
    assert!(e.to_string().contains("ovf.npy"), "{e}");
}

#[test]
fn degenerate_inputs_are_errors() {
    for (name, bytes, f) in [
        ("a.csv", &b"\n\n\n"[..], GridFormat::Csv),
        ("b.csv", &b",,,\n,,,\n"[..], GridFormat::Csv),
        ("c.csv", &b"1e400,1\n1,1\n"[..], GridFormat::Csv),
        (
            "d.asc",
            &b"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 0\n1 2\n3 4\n"[..],
            GridFormat::Asc,
        ),
        (
            "e.tif",
            &b"MM\x00*\x00\x00\x00\x08\xff\xff"[..],
            GridFormat::GeoTiff,
        ),
        ("f.npy", &b"\x93NUMPY\x01\x00\xff\xff"[..], GridFormat::Npy),
    ] {
        let e = parse_grid(Path::new(name), bytes, f).unwrap_err();
        assert!(e.to_string().contains(name), "{e}");
    }
}

/// A fuzzed `.npy` header of nested brackets kept the Python-literal parser busy for 17 s per
/// parse (fuzz artifact `slow-unit-4361...`, grid target): refused at once by the header check.
#[test]
fn nested_npy_headers_are_refused_fast() {
    let bytes = include_bytes!("fuzz/slow-npy-nested-header.bin");
    // The fuzz target's first byte picks the format (1 = npy).
    let t = std::time::Instant::now();
    let e = parse_grid(Path::new("slow.npy"), &bytes[1..], GridFormat::Npy).unwrap_err();
    assert!(e.message.contains("not a valid .npy file"), "{e}");
    assert!(t.elapsed().as_secs_f64() < 1.0);
}

/// A fuzzed 3-D `.npy` of shape (199998000098, 700000007, 0) passed the size checks (zero
/// values) and aborted allocating 2e11 frames (series target): frames need 2 x 2 values.
#[test]
fn zero_width_series_are_refused() {
    let bytes = include_bytes!("fuzz/npy-zero-width-series.bin");
    let e = isotrack_fields::io::parse_series_bytes(
        Path::new("z.npy"),
        &bytes[1..],
        GridFormat::Npy,
        None,
    )
    .unwrap_err();
    assert!(e.message.contains("at least 2 x 2"), "{e}");
}

/// A fuzzed classic NetCDF header declaring 2^31 attribute values made netcdf-reader abort out
/// of memory (series target): classic headers are checked against the file first.
#[test]
fn netcdf_headers_are_checked_before_allocation() {
    let bytes = include_bytes!("fuzz/netcdf-huge-attribute.bin");
    let e = isotrack_fields::io::parse_series_bytes(
        Path::new("h.nc"),
        &bytes[1..],
        GridFormat::NetCdf,
        None,
    )
    .unwrap_err();
    assert!(e.message.contains("not a valid NetCDF file"), "{e}");
}

/// Under `ulimit -v` (an address-space limit, as HPC login nodes set, and as the fuzz runs use:
/// scripts/fuzz.sh) the memory budget is the room under the limit, not the machine's
/// `MemAvailable`: the never-written 16000 x 16000 NetCDF-4 frame (256 000 000 values, 6.1 GB
/// at 24 bytes each) is refused naming the memory, where it aborted allocating (fuzz target
/// netcdf4, seeded with the fixtures). Run in a child process under `ulimit -v` 3 GiB.
#[cfg(target_os = "linux")]
#[test]
fn the_memory_budget_honours_an_address_space_limit() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/netcdf/unwritten_1x16000x16000.nc");
    if std::env::var_os("ISOTRACK_TEST_UNDER_ULIMIT").is_some() {
        let budget = isotrack_fields::io::memory_budget_bytes().unwrap();
        assert!(budget < 3 << 30, "{budget}");
        let e = isotrack_fields::io::load_series(&p, None, None).unwrap_err();
        assert!(
            e.message
                .contains("1 frame of 16000 x 16000 nodes = 256000000 values"),
            "{e}"
        );
        assert!(
            e.message.contains("GiB of memory this process may use"),
            "{e}"
        );
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 3145728 && exec \"$0\" --exact --test-threads=1 the_memory_budget_honours_an_address_space_limit")
        .arg(&exe)
        .env("ISOTRACK_TEST_UNDER_ULIMIT", "1")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 passed"));
}
