#!/usr/bin/env python3
"""Writes the NetCDF test fixtures with xarray, the way today's climate tools write them.

Run from the repository root in a virtual environment (not needed by CI: the outputs are
committed, and this script documents how they were made):

    python3 -m venv target/fixenv
    target/fixenv/bin/pip install xarray netCDF4 h5netcdf h5py numpy
    target/fixenv/bin/python scripts/make-netcdf-fixtures.py

The matrix (one file each, `<engine>_<format>_<coords>_<layout>.nc`):
  * engines netCDF4 (netCDF-C) and h5netcdf (h5py), formats NETCDF4, NETCDF4_CLASSIC and
    NETCDF3_64BIT (h5netcdf writes NETCDF4 only);
  * coordinates lon/lat (latitude stored north first, as ERA5 does) or projected x/y in metres
    (with a `crs` grid-mapping variable), each with a bounds variable (`lat_bnds`, ...);
  * CF attributes on every variable: axis, standard_name, long_name, units, comment, bounds
    (enough of them that HDF5 moves a coordinate's attributes to dense storage, the case
    netcdf-reader 0.7 could not read);
  * layouts: contiguous (a fixed time axis: HDF5 cannot store an unlimited one contiguously),
    chunked, zlib levels 1 and 9 (level 9 with shuffle), all with an unlimited time axis, plus
    an int16 variable packed with scale_factor / add_offset; NetCDF-3 has contiguous and
    record (unlimited) layouts;
  * a 2-D file (no time axis) per engine;
  * projected x/y in kilometres (`<engine>_<format>_xykm_<layout>.nc`, one per format and
    engine): the loader converts them to metres, the same grid as the `xy` files;
  * the same data stored (time, x, y) and (x, y) (`T` after the layout; xarray's
    `.transpose`): the loader tells x from y by the coordinates and gives the same grid;
  * not in the manifest: `refused_xy_ft.nc` (x/y in feet), `refused_lon_y.nc` (longitude
    beside a y in metres), `refused_xy_two_units.nc` (x's units an NC_STRING array
    ["km", "m"]), `refused_lonlat_m.nc` (lon / lat in metres) and `refused_xy_both_x.nc` (y
    renamed `b` and marked axis X), which the loader must refuse naming the coordinate; `warned_xy_no_units.nc`
    (x / y without units), read as metres with a warning; `latin1_*.nc` (text attributes in
    Latin-1, which must load) and `refused_latin1_units_*.nc` (a `units` in Latin-1, refused
    naming the variable and the attribute): see `non_utf8`; `refused_nul_*.nc` and
    `nul_comment.nc` (a NUL inside a text attribute): see `nul_inside`; `many_attributes.nc`
    (700 attributes of 1 kB on `v`): see `many_attributes`; `committed_*.nc` and
    `refused_committed_units_x.nc` (attributes of committed HDF5 datatypes): see
    `committed_types`; `sohm_*.nc` (messages shared through the SOHM table): see
    `shared_messages`; `refused_group_*.nc` (groups that do not form a tree): see
    `group_links`.

Run with file names as arguments to (re)write only those (the others are left as they are):

    target/fixenv/bin/python scripts/make-netcdf-fixtures.py netcdf4_nc4_xykm_contig.nc

Every file holds the same data: 3 frames of 5 x 6 nodes, v = 10 + 0.125 * k for small
integers k (exact in float32, float64 and the packed int16), one node missing (NaN / fill).
Its twins, written here too: `series.npy` (time, rows south first, columns), `frame0.csv`
(the first frame, rows south first) and `times_s.csv` (the frame times in seconds after the
first: 0, 3600, 10800). The loader test requires every file to give exactly these.
"""
import os
import sys

import numpy as np
import pandas as pd
import xarray as xr

OUT = os.path.join(os.path.dirname(__file__), "..", "crates", "isotrack-fields", "tests",
                   "fixtures", "netcdf")
NT, NY, NX = 3, 5, 6
LON0, DLON = 10.0, 0.5          # lon = 10.0, 10.5, ..., 12.5
LAT0, DLAT = 50.0, 0.25         # lat (south to north) = 50.0, ..., 51.0; stored north first
X0, DX = 500_000.0, 1000.0      # x = 500000, ..., 505000 m
Y0, DY = 4_600_000.0, 2000.0    # y = 4600000, ..., 4608000 m (stored south first)
TIMES = pd.to_datetime(["2020-01-01T06:00", "2020-01-01T07:00", "2020-01-01T09:00"])
TIME_UNITS = "hours since 2020-01-01 00:00:00"


def values():
    """(time, rows south first, cols): 10 + 0.125 * (3 i + 7 j + 40 t), node (t0, j1, i2) NaN."""
    t, j, i = np.mgrid[0:NT, 0:NY, 0:NX]
    v = 10.0 + 0.125 * (3 * i + 7 * j + 40 * t)
    v[0, 1, 2] = np.nan
    return v


def cf(axis, standard_name, long_name, units, comment):
    a = dict(standard_name=standard_name, long_name=long_name, comment=comment)
    if axis:
        a["axis"] = axis
    if units:
        a["units"] = units
    return a


def bounds(centres, step):
    return np.stack([centres - 0.5 * step, centres + 0.5 * step], axis=1)


def dataset(coords, with_time):
    v = values()
    if coords == "lonlat":
        xn, yn = "lon", "lat"
        xs = LON0 + DLON * np.arange(NX)
        ys = (LAT0 + DLAT * np.arange(NY))[::-1]  # north first
        v = v[:, ::-1, :]
        xa = cf("X", "longitude", "longitude", "degrees_east", "cell centres")
        ya = cf("Y", "latitude", "latitude", "degrees_north", "cell centres, north first")
        (dx, dy) = (DLON, -DLAT)
    else:
        # xy: metres; xykm: kilometres (X0 / 1000 = 500.0 and steps 1.0, 2.0: exact);
        # xyft and lony: refused by the loader.
        unit = {"xy": "m", "xykm": "km", "xyft": "ft", "lony": "m"}[coords]
        scale = 1000.0 if unit == "km" else 1.0
        xn, yn = ("lon", "y") if coords == "lony" else ("x", "y")
        xs = (X0 + DX * np.arange(NX)) / scale
        ys = (Y0 + DY * np.arange(NY)) / scale
        xa = cf("X", "projection_x_coordinate", "easting", unit, "UTM zone 33N")
        ya = cf("Y", "projection_y_coordinate", "northing", unit, "UTM zone 33N")
        if coords == "lony":
            xs = LON0 + DLON * np.arange(NX)
            xa = cf("X", "longitude", "longitude", "degrees_east", "a longitude beside metres")
        (dx, dy) = (xs[1] - xs[0], ys[1] - ys[0])
    xa["bounds"] = xn + "_bnds"
    ya["bounds"] = yn + "_bnds"
    va = cf(None, "air_temperature", "air temperature", "K", "synthetic: 10 + k / 8")
    data_vars = {}
    coord_vars = {
        xn: (xn, xs, xa),
        yn: (yn, ys, ya),
    }
    data_vars[xn + "_bnds"] = ((xn, "nv"), bounds(xs, dx),
                               dict(long_name=xn + " cell bounds", comment="edges", units=xa["units"]))
    data_vars[yn + "_bnds"] = ((yn, "nv"), bounds(ys, dy),
                               dict(long_name=yn + " cell bounds", comment="edges", units=ya["units"]))
    if coords != "lonlat":
        va["grid_mapping"] = "crs"
        data_vars["crs"] = ((), np.int32(0),
                            dict(grid_mapping_name="transverse_mercator", long_name="CRS",
                                 comment="EPSG:32633", epsg_code="EPSG:32633"))
    if with_time:
        data_vars["v"] = (("time", yn, xn), v, va)
        coord_vars["time"] = ("time", TIMES, cf("T", "time", "time", None, "hourly, one gap"))
        coord_vars["time"][2]["bounds"] = "time_bnds"
        tb = np.stack([TIMES - pd.Timedelta("30min"), TIMES + pd.Timedelta("30min")], axis=1)
        data_vars["time_bnds"] = (("time", "nv"), tb, dict(long_name="time bounds", comment="+-30 min"))
    else:
        data_vars["v"] = ((yn, xn), v[0], va)
    ds = xr.Dataset(data_vars, coords=coord_vars)
    ds.attrs = dict(Conventions="CF-1.11", title="isotrack NetCDF fixture",
                    comment="written by scripts/make-netcdf-fixtures.py")
    return ds


def encoding(ds, layout, with_time, fmt):
    enc = {"time": dict(units=TIME_UNITS, calendar="standard")} if with_time else {}
    if with_time:
        enc["time_bnds"] = dict(units=TIME_UNITS, calendar="standard", dtype="float64")
    v = {}
    if layout == "contig":
        v["contiguous"] = True
    elif layout in ("chunk", "zlib1", "zlib9", "packed"):
        v["chunksizes"] = (1, 3, 4) if with_time else (3, 4)
        if layout == "zlib1":
            v.update(zlib=True, complevel=1)
        elif layout == "zlib9":
            v.update(zlib=True, complevel=9, shuffle=True)
        elif layout == "packed":
            v.update(dtype="int16", scale_factor=0.125, add_offset=10.0, _FillValue=-32767,
                     zlib=True, complevel=4)
    if layout not in ("packed",):
        v["dtype"] = "float32" if "f4" in layout or fmt == "NETCDF3_64BIT" else "float64"
    enc["v"] = v
    return enc


def write(engine, fmt, coords, layout, with_time=True, name=None, transposed=False, edit=None):
    ds = dataset(coords, with_time)
    if transposed:
        # The same data stored (time, x, y) / (x, y): xarray's `.transpose`, as users write it.
        xn, yn = ("lon", "lat") if coords == "lonlat" else ("x", "y")
        ds["v"] = ds["v"].transpose(*(["time"] if with_time else []), xn, yn)
    if edit:
        ds = edit(ds) or ds
    enc = encoding(ds, layout, with_time, fmt)
    if transposed and "chunksizes" in enc["v"]:
        enc["v"]["chunksizes"] = (1, 4, 3) if with_time else (4, 3)
    unlimited = ["time"] if with_time and layout != "contig" else None
    tag = {"NETCDF4": "nc4", "NETCDF4_CLASSIC": "nc4classic", "NETCDF3_64BIT": "nc3"}[fmt]
    t = "T" if transposed else ""
    name = name or f"{engine}_{tag}_{coords}_{layout}{t}{'' if with_time else '_2d'}.nc"
    if ONLY and name not in ONLY:
        return name
    path = os.path.join(OUT, name)
    if os.path.exists(path):
        os.remove(path)
    ds.to_netcdf(path, engine=engine, format=fmt, encoding=enc, unlimited_dims=unlimited)
    return name


def unwritten(frames):
    """A decompression bomb: `frames` x 16000 x 16000 float64, chunked and zlib-compressed but
    never written, so every chunk is absent and the ~10 KB file declares 8 GB of fill values
    per four frames. The loader must refuse it before allocating (issue 30, item 3)."""
    import netCDF4

    name = f"unwritten_{frames}x16000x16000.nc"
    path = os.path.join(OUT, name)
    with netCDF4.Dataset(path, "w", format="NETCDF4") as nc:
        nc.createDimension("time", frames)
        nc.createDimension("y", 16000)
        nc.createDimension("x", 16000)
        nc.createVariable("v", "f8", ("time", "y", "x"), zlib=True, complevel=4,
                          chunksizes=(1, 1000, 1000))
    return name


def non_utf8():
    """Text attributes that are not UTF-8, as older tools write them (a Latin-1 `comment`,
    `history` or `units`: netCDF-C stores NC_CHAR bytes as they are given). Not in the
    manifest. NetCDF-3 reads such bytes as U+FFFD; NetCDF-4 must do the same (issue 30), so
    `latin1_*.nc` (Latin-1 `comment` / `long_name` on every variable and a Latin-1 global
    `history`) load to the same grid and times as their twins, while `refused_latin1_*.nc`
    (a Latin-1 `units` on the data variable `v`, on the coordinate `x`, on `time`) are refused
    naming the variable and the attribute."""
    import h5py
    import netCDF4

    latin1 = "caf\xe9 \xe0 25 \xb0C".encode("latin-1")

    def comments(ds):
        for name in list(ds.variables):
            ds[name].attrs["comment"] = latin1
        ds["v"].attrs["long_name"] = "temp\xe9rature".encode("latin-1")
        ds.attrs["history"] = "cr\xe9\xe9 par un outil".encode("latin-1")

    def units_v(ds):
        ds["v"].attrs["units"] = "\xb0C".encode("latin-1")

    def units_x(ds):
        ds["x"].attrs["units"] = "m\xe8tres".encode("latin-1")

    write("netcdf4", "NETCDF4", "xy", "contig", name="latin1_netcdf4_nc4_xy_contig.nc",
          edit=comments)
    write("netcdf4", "NETCDF4", "lonlat", "zlib1", name="latin1_netcdf4_nc4_lonlat_zlib1.nc",
          edit=comments)
    write("netcdf4", "NETCDF3_64BIT", "xy", "unlim", name="latin1_netcdf4_nc3_xy_unlim.nc",
          edit=comments)
    # h5netcdf refuses bytes that are not UTF-8; h5py writes them (a fixed-length string).
    name = write("h5netcdf", "NETCDF4", "xy", "chunk", name="latin1_h5netcdf_nc4_xy_chunk.nc")
    if not ONLY or name in ONLY:
        with h5py.File(os.path.join(OUT, name), "a") as f:
            for v in ("v", "x", "y", "time"):
                f[v].attrs["comment"] = np.bytes_(latin1)
            f.attrs["history"] = np.bytes_(latin1)
    write("netcdf4", "NETCDF4", "xy", "contig", name="refused_latin1_units_v.nc", edit=units_v)
    write("netcdf4", "NETCDF3_64BIT", "xy", "contig", name="refused_latin1_units_v_nc3.nc",
          edit=units_v)
    write("netcdf4", "NETCDF4", "xy", "contig", name="refused_latin1_units_x.nc", edit=units_x)
    # xarray writes the time axis's units itself: set afterwards, with netCDF4.
    name = write("netcdf4", "NETCDF4", "xy", "zlib1", name="refused_latin1_units_time.nc")
    if not ONLY or name in ONLY:
        with netCDF4.Dataset(os.path.join(OUT, name), "a") as nc:
            nc["time"].setncattr("units", TIME_UNITS.encode() + b"\xa0")


def nul_inside():
    """A NUL inside a needed text attribute (issue 30): `refused_nul_units_x.nc` (netCDF-C:
    x's `units` the NC_CHAR text "m\\0km"), `refused_nul_axis_y_h5py.nc` (h5py: y's `axis` a
    fixed-length string "Y\\0X") and `refused_nul_units_time.nc` (time's units with a NUL
    before a second date) are refused naming the variable and the attribute, where a reader
    that cuts at the NUL would take "m", "Y" or the first date; `nul_comment.nc` (a NUL inside
    every variable's `comment`, which isotrack does not read) loads as its twins do. Not in the
    manifest."""
    import h5py
    import netCDF4

    def units_x(ds):
        ds["x"].attrs["units"] = "m\0km"

    def comments(ds):
        for name in list(ds.variables):
            ds[name].attrs["comment"] = "before\0after"

    write("netcdf4", "NETCDF4", "xy", "contig", name="refused_nul_units_x.nc", edit=units_x)
    write("netcdf4", "NETCDF4", "xy", "zlib1", name="nul_comment.nc", edit=comments)
    name = write("h5netcdf", "NETCDF4", "xy", "chunk", name="refused_nul_axis_y_h5py.nc")
    if not ONLY or name in ONLY:
        with h5py.File(os.path.join(OUT, name), "a") as f:
            f["y"].attrs["axis"] = np.bytes_(b"Y\0X")
    name = write("netcdf4", "NETCDF4", "xy", "zlib1", name="refused_nul_units_time.nc")
    if not ONLY or name in ONLY:
        with netCDF4.Dataset(os.path.join(OUT, name), "a") as nc:
            nc["time"].setncattr("units", TIME_UNITS + "\0days since 1900-01-01")


def many_attributes():
    """`many_attributes.nc`: the data variable with 700 attributes of 1 000 characters, about
    700 kB of dense attribute storage, past the 512 kB the root of its fractal heap addresses
    directly (netCDF-C's heap: blocks of 512 B to 64 kB, 4 a row), so its last attributes sit
    below a child indirect block, which hdf5-reader 0.12.1 read past the block's end
    ("unexpected end of data"; fixed in vendor/hdf5-reader). Loads as its twins do; not in the
    manifest."""

    def attrs(ds):
        for i in range(700):
            ds["v"].attrs[f"note_{i:03d}"] = f"{i:03d} " + "x" * 996

    write("netcdf4", "NETCDF4", "xy", "contig", name="many_attributes.nc", edit=attrs)


def committed_types():
    """Attributes of a committed (named) HDF5 datatype, as h5py writes them with
    `attrs.create(..., dtype=group["T"])` (and netCDF-C for user-defined types): the attribute
    holds a reference to the type's object header instead of the type (issue 30, fix30d).
    hdf5-reader 0.12.1 refused the whole file ("shared datatype/dataspace in attribute v2 is not
    supported"). `committed_comment.nc`: a `comment` of a committed string type on every
    variable, which isotrack does not read; `committed_units.nc`: `units` of a committed string
    type on `v`, `x` and `y`. Both load as their twins do (`units` "K"). Not in the manifest:
    `refused_committed_units_x.nc`, x's `units` reference pointing at no datatype (address 0,
    the superblock), refused naming `x` and `units` where a reader that skips it would take x
    without units as metres."""
    import h5py

    def add(name, attrs):
        path = os.path.join(OUT, name)
        with h5py.File(path, "a") as f:
            for var, attr, text in attrs:
                tname = f"{attr}_{var}_t"
                f[tname] = np.dtype(f"S{len(text)}")
                if attr in f[var].attrs:
                    del f[var].attrs[attr]
                f[var].attrs.create(attr, np.bytes_(text.encode()), dtype=f[tname])
        return path

    name = write("h5netcdf", "NETCDF4", "xy", "chunk", name="committed_comment.nc")
    if not ONLY or name in ONLY:
        add(name, [(v, "comment", "a committed type") for v in ("v", "x", "y", "time")])
    name = write("netcdf4", "NETCDF4", "xy", "contig", name="committed_units.nc")
    if not ONLY or name in ONLY:
        add(name, [("v", "units", "K"), ("x", "units", "m"), ("y", "units", "m")])
    name = write("netcdf4", "NETCDF4", "xy", "contig", name="refused_committed_units_x.nc")
    if not ONLY or name in ONLY:
        path = add(name, [("x", "units", "m")])
        data = bytearray(open(path, "rb").read())
        # The attribute message (version 2 or 3, flags 1: a shared datatype), name "units":
        # its datatype field, a shared message (version, type 2, 8-byte address), made to
        # point at address 0. x's attributes are in dense storage: the message is in a
        # fractal heap direct block, whose checksum is then written again.
        hits = []
        at = data.find(b"units\0")
        while at >= 0:
            v2 = data[at - 8] == 2 and data[at - 7] == 1 and data[at - 6:at - 4] == b"\6\0"
            v3 = data[at - 9] == 3 and data[at - 8] == 1 and data[at - 7:at - 5] == b"\6\0"
            if v2 or v3:
                hits.append(at + 6)
            at = data.find(b"units\0", at + 1)
        assert len(hits) == 1, hits
        ref = hits[0]
        assert data[ref + 1] == 2, data[ref:ref + 10]
        block = data.rfind(b"FHDB", 0, ref)
        check = direct_block_checksum(data, block)
        data[ref + 2:ref + 10] = bytes(8)
        check(data)
        open(path, "wb").write(bytes(data))


def direct_block_checksum(data, start):
    """The fractal heap direct block at `start` (signature FHDB): its size (a power of two) and
    where its checksum is (after the block offset, whose length the heap header sets) found by
    the checksum that matches, and a function writing the checksum of the block in `data` there
    (HDF5: lookup3 of the whole block, the checksum field zeroed)."""
    for offset_bytes in range(1, 9):
        at = start + 13 + offset_bytes
        stored = int.from_bytes(data[at:at + 4], "little")
        for k in range(9, 17):
            end = start + (1 << k)
            if end > len(data):
                break
            image = bytearray(data[start:end])
            image[at - start:at - start + 4] = bytes(4)
            if lookup3(image) == stored:
                def write(d, at=at, end=end):
                    image = bytearray(d[start:end])
                    image[at - start:at - start + 4] = bytes(4)
                    d[at:at + 4] = lookup3(image).to_bytes(4, "little")
                return write
    raise AssertionError(f"no direct block checksum found at {start}")


def lookup3(data, initval=0):
    """Bob Jenkins' lookup3 `hashlittle`, the checksum of HDF5 metadata (H5_checksum_lookup3)."""
    m = 0xFFFFFFFF

    def rot(x, k):
        return ((x << k) | (x >> (32 - k))) & m

    def u32(b, i):
        return int.from_bytes(b[i:i + 4], "little")

    n = len(data)
    a = b = c = (0xDEADBEEF + n + initval) & m
    i = 0
    while n > 12:
        a = (a + u32(data, i)) & m
        b = (b + u32(data, i + 4)) & m
        c = (c + u32(data, i + 8)) & m
        a = (a - c) & m; a ^= rot(c, 4); c = (c + b) & m
        b = (b - a) & m; b ^= rot(a, 6); a = (a + c) & m
        c = (c - b) & m; c ^= rot(b, 8); b = (b + a) & m
        a = (a - c) & m; a ^= rot(c, 16); c = (c + b) & m
        b = (b - a) & m; b ^= rot(a, 19); a = (a + c) & m
        c = (c - b) & m; c ^= rot(b, 4); b = (b + a) & m
        n -= 12
        i += 12
    if n == 0:
        return c
    tail = bytes(data[i:i + n]) + bytes(12 - n)
    a = (a + u32(tail, 0)) & m
    b = (b + u32(tail, 4)) & m
    c = (c + u32(tail, 8)) & m
    c ^= b; c = (c - rot(b, 14)) & m
    a ^= c; a = (a - rot(c, 11)) & m
    b ^= a; b = (b - rot(a, 25)) & m
    c ^= b; c = (c - rot(b, 16)) & m
    a ^= c; a = (a - rot(c, 4)) & m
    b ^= a; b = (b - rot(a, 14)) & m
    c ^= b; c = (c - rot(b, 24)) & m
    return c


# File names given on the command line: only those are written (all when none).
ONLY = set(sys.argv[1:])


def foreign_objects():
    """Objects an HDF5 tool adds beside the netCDF variables, which isotrack never reads (issue
    30, att30c-8): `extra_dataset.nc`, a dataset `extra` written by h5py without dimension
    scales (no DIMENSION_LIST: netCDF-C reads it with phony dimensions, xarray opens the file);
    `deep_committed_type.nc`, a committed datatype nested 50 levels (past hdf5-reader's 32)
    linked in the root group. Both load as their twin `netcdf4_nc4_xy_contig.nc`; `extra` asked
    for by name is refused. Not in the manifest."""
    import h5py

    name = write("netcdf4", "NETCDF4", "xy", "contig", name="extra_dataset.nc")
    if not ONLY or name in ONLY:
        with h5py.File(os.path.join(OUT, name), "a") as f:
            f.create_dataset("extra", data=np.array([1, 2, 3], dtype="i4"))
    name = write("netcdf4", "NETCDF4", "xy", "contig", name="deep_committed_type.nc")
    if not ONLY or name in ONLY:
        t = h5py.h5t.NATIVE_INT8.copy()
        for _ in range(50):
            c = h5py.h5t.create(h5py.h5t.COMPOUND, t.get_size())
            c.insert(b"m", 0, t)
            t = c
        with h5py.File(os.path.join(OUT, name), "a") as f:
            t.commit(f.id, b"T_deep")


def group_links():
    """Groups that do not form a tree, which the loader must refuse naming the link (issue 30,
    att30d-7: netcdf-reader built the group tree recursively without a visited set, so a
    cycle overflowed the stack): `refused_group_loop.nc` (a group `g` holding a hard link
    `loop` to itself, h5py `g["loop"] = g`), `refused_group_up.nc` (`g/up` a link to the root),
    `refused_group_twice.nc` (`a/s` and `b/s` the same group: no cycle) and
    `refused_group_deep.nc` (3000 nested groups `g/g/...`, past the 64 levels read). Each is
    the twin `netcdf4_nc4_xy_contig.nc` plus those groups. Not in the manifest."""
    import h5py

    def loop(f):
        g = f.create_group("g")
        g["loop"] = g

    def up(f):
        f.create_group("g")["up"] = f["/"]

    def twice(f):
        s = f.create_group("a").create_group("s")
        f.create_group("b")["s"] = s

    def deep(f):
        g = f
        for _ in range(3000):
            g = g.create_group("g")

    for suffix, edit in (("loop", loop), ("up", up), ("twice", twice), ("deep", deep)):
        name = write("netcdf4", "NETCDF4", "xy", "contig", name=f"refused_group_{suffix}.nc")
        if not ONLY or name in ONLY:
            # The newest format: 3000 groups in compact link storage, ~0.4 MB.
            with h5py.File(os.path.join(OUT, name), "a", libver="latest") as f:
                edit(f)


# libhdf5's shared-message index flags (H5Opublic.h, `H5O_SHMESG_*_FLAG`): 1 << the message
# type ID of the HDF5 file format specification, "Shared Object Header Message Table" (dataspace
# 0x0001 -> bit 1, datatype 0x0003 -> bit 3, fill value 0x0005 -> bit 5, filter pipeline 0x000B ->
# bit 11, attribute 0x000C -> bit 12).
SOHM_DATASPACES, SOHM_DATATYPES, SOHM_FILL, SOHM_PLINE, SOHM_ATTRS = 0x2, 0x8, 0x20, 0x800, 0x1000
SOHM_ALL = 0x182A
SOHM_KINDS = (("dataspaces", SOHM_DATASPACES), ("datatypes", SOHM_DATATYPES), ("fill", SOHM_FILL),
              ("pline", SOHM_PLINE), ("attrs", SOHM_ATTRS))


def sohm_files():
    """{file name: (index flags, one per index; B-tree form; extra attributes on `v`)} of
    `shared_messages`."""
    files = {}
    for form in ("", "_btree"):
        for kind, flags in SOHM_KINDS:
            files[f"sohm_{kind}{form}.nc"] = ([flags], bool(form), 0)
        files[f"sohm_all{form}.nc"] = ([SOHM_ALL], bool(form), 0)
        files[f"sohm_separate{form}.nc"] = ([f for _, f in SOHM_KINDS], bool(form), 0)
        # Two indexes, in both orders (ver30b-1: a datatype was looked up in the dataspace index).
        files[f"sohm_dataspaces_datatypes{form}.nc"] = ([SOHM_DATASPACES, SOHM_DATATYPES], bool(form), 0)
        files[f"sohm_datatypes_dataspaces{form}.nc"] = ([SOHM_DATATYPES, SOHM_DATASPACES], bool(form), 0)
        # 12 more attributes on `v` (21 in all; dense storage, as the 9 above: a fractal heap
        # and a v2 B-tree of names, each record naming a shared attribute's ID in the
        # shared-message heap).
        files[f"sohm_attrs_dense{form}.nc"] = ([SOHM_ATTRS], bool(form), 12)
        files[f"sohm_all_dense{form}.nc"] = ([SOHM_ALL], bool(form), 12)
        files[f"sohm_separate_dense{form}.nc"] = ([f for _, f in SOHM_KINDS], bool(form), 12)
    return files


def shared_messages():
    """Files whose object header messages are shared through HDF5's shared object header
    message (SOHM) table (issue 30: att30c-11, ver30b-1, ver30b-8), `sohm_files()`: each kind
    libhdf5 can share (dataspaces, datatypes, fill values, filter pipelines, attributes) alone
    in one index (`sohm_<kind>.nc`), all in one index (`sohm_all.nc`, flags 0x182a), each in
    its own index (`sohm_separate.nc`, five indexes) and dataspaces and datatypes in two
    (`sohm_dataspaces_datatypes.nc`, `sohm_datatypes_dataspaces.nc`), each in list form and
    in B-tree form (`H5Pset_shared_mesg_phase_change`: a list of up to 200 messages, or
    `*_btree.nc`, a v2 B-tree from the first message). `v` has 9 attributes (xarray's 5,
    `_FillValue` and netCDF's 3), so libhdf5 keeps them in dense storage (more than 8), 21
    in `*_dense*.nc`; `crs` and `time_bnds` have few (compact storage). The data is
    `netcdf4_nc4_xy_zlib1.nc`'s (chunked and deflated, so that there is a filter pipeline to share), written through
    h5netcdf into a file created with a file-creation property list holding the SOHM indexes
    (`H5Pset_shared_mesg_nindexes`, `H5Pset_shared_mesg_index`, called through ctypes on the
    libhdf5 h5py bundles: h5py has no binding for them; the flags are libhdf5's, 1 << message
    type ID) and the latest file format. netCDF-C reads each; hdf5-reader 0.12.1 refused them
    ("failed to load SOHM table: unexpected end of data"), and after that fix, separate indexes
    ("unsupported dataspace version 17") and shared dense attributes ("undefined address").
    Not in the manifest: `sohm_fixtures_load_as_their_twin` loads each, and
    vendor/hdf5-reader/tests/sohm.rs reads each with hdf5-reader."""
    import ctypes
    import glob

    import h5netcdf
    import h5py

    libs = glob.glob(os.path.join(os.path.dirname(h5py.__file__), "..", "h5py.libs", "libhdf5-*.so*"))
    lib = ctypes.CDLL(libs[0]) if libs else ctypes.CDLL("libhdf5.so")
    for name, (indexes, btree, extra) in sohm_files().items():
        if ONLY and name not in ONLY:
            continue
        path = os.path.join(OUT, name)
        if os.path.exists(path):
            os.remove(path)
        fcpl = h5py.h5p.create(h5py.h5p.FILE_CREATE)
        plist = ctypes.c_int64(fcpl.id)
        assert lib.H5Pset_shared_mesg_nindexes(plist, ctypes.c_uint(len(indexes))) >= 0
        for i, flags in enumerate(indexes):
            assert lib.H5Pset_shared_mesg_index(plist, ctypes.c_uint(i), ctypes.c_uint(flags),
                                                ctypes.c_uint(0)) >= 0
        # An index is a list up to `max_list` messages (libhdf5's default 50: the attribute
        # indexes here hold 62 to 99) and a v2 B-tree past it: 200 keeps each a list, 0 makes
        # each a B-tree from its first message.
        max_list, min_btree = (0, 0) if btree else (200, 200)
        assert lib.H5Pset_shared_mesg_phase_change(plist, ctypes.c_uint(max_list),
                                                   ctypes.c_uint(min_btree)) >= 0
        fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
        fapl.set_libver_bounds(h5py.h5f.LIBVER_LATEST, h5py.h5f.LIBVER_LATEST)
        fid = h5py.h5f.create(path.encode(), h5py.h5f.ACC_TRUNC, fcpl=fcpl, fapl=fapl)
        ds = dataset("xy", True)
        for i in range(extra):
            ds["v"].attrs[f"note_{i:02d}"] = f"note {i}: " + "abc" * (i + 1)
        with h5netcdf.File(h5py.File(fid), "a") as f:
            ds.dump_to_store(xr.backends.H5NetCDFStore(f),
                             encoding=encoding(ds, "zlib1", True, "NETCDF4"))


def main():
    os.makedirs(OUT, exist_ok=True)
    for f in os.listdir(OUT):
        if f.endswith(".nc") and not ONLY:
            os.remove(os.path.join(OUT, f))
    v = values()
    np.save(os.path.join(OUT, "series.npy"), v)
    np.savetxt(os.path.join(OUT, "frame0.csv"), v[0], delimiter=",", fmt="%.3f")
    secs = (TIMES - TIMES[0]).total_seconds().to_numpy()
    np.savetxt(os.path.join(OUT, "times_s.csv"), secs, fmt="%.1f")
    names = []
    for engine in ("netcdf4", "h5netcdf"):
        formats = ("NETCDF4", "NETCDF4_CLASSIC", "NETCDF3_64BIT") if engine == "netcdf4" else ("NETCDF4",)
        for fmt in formats:
            layouts = (("contig", "unlim") if fmt == "NETCDF3_64BIT"
                       else ("contig", "chunk", "zlib1", "zlib9", "packed"))
            for coords in ("lonlat", "xy"):
                for layout in layouts:
                    names.append(write(engine, fmt, coords, layout))
        names.append(write(engine, formats[0], "lonlat", "contig", with_time=False))
        for fmt in formats:
            layout = "unlim" if fmt == "NETCDF3_64BIT" else ("contig" if fmt == "NETCDF4" else "zlib1")
            names.append(write(engine, fmt, "xykm", layout))
    # Stored (time, x, y) or (x, y) (`T` after the layout): the axes are known by their
    # coordinates, so each loads to the same grid as its (time, y, x) twin.
    names.append(write("netcdf4", "NETCDF4", "xy", "contig", transposed=True))
    names.append(write("netcdf4", "NETCDF4", "xy", "zlib1", transposed=True))
    names.append(write("netcdf4", "NETCDF3_64BIT", "xy", "unlim", transposed=True))
    names.append(write("netcdf4", "NETCDF4_CLASSIC", "lonlat", "chunk", transposed=True))
    names.append(write("netcdf4", "NETCDF4", "lonlat", "contig", with_time=False, transposed=True))
    # Not in the manifest: they must be refused.
    def units(value):
        def edit(ds):
            ds["x"].attrs["units"] = value
        return edit

    def no_units(ds):
        for c in ("x", "y"):
            del ds[c].attrs["units"]
            del ds[c + "_bnds"].attrs["units"]

    def lonlat_in_metres(ds):
        ds["lon"].attrs["units"] = "m"
        ds["lat"].attrs["units"] = "m"
        ds["lon_bnds"].attrs["units"] = "m"
        ds["lat_bnds"].attrs["units"] = "m"

    def both_x(ds):
        # Dimensions `x` and `b`, b's coordinate marked axis X as well: which is y?
        ds = ds.rename({"y": "b", "y_bnds": "b_bnds"})
        ds["b"].attrs.update(axis="X", standard_name="projection_x_coordinate", bounds="b_bnds")
        return ds

    write("netcdf4", "NETCDF4", "xy", "contig", name="refused_xy_two_units.nc",
          edit=units(["km", "m"]))
    write("netcdf4", "NETCDF4", "lonlat", "contig", name="refused_lonlat_m.nc",
          edit=lonlat_in_metres)
    write("netcdf4", "NETCDF4", "xy", "contig", name="refused_xy_both_x.nc", edit=both_x)
    write("netcdf4", "NETCDF4", "xy", "contig", name="warned_xy_no_units.nc", edit=no_units)
    write("netcdf4", "NETCDF4", "xyft", "contig", name="refused_xy_ft.nc")
    write("netcdf4", "NETCDF4", "lony", "contig", name="refused_lon_y.nc")
    non_utf8()
    nul_inside()
    many_attributes()
    committed_types()
    foreign_objects()
    shared_messages()
    group_links()
    for frames in (1, 4, 5):
        if not ONLY or f"unwritten_{frames}x16000x16000.nc" in ONLY:
            unwritten(frames)  # not in the manifest: they must not load
    with open(os.path.join(OUT, "MANIFEST.txt"), "w") as m:
        m.write("# written by scripts/make-netcdf-fixtures.py; the loader test reads every file listed\n")
        for n in sorted(names):
            m.write(n + "\n")
    for f in sorted(os.listdir(OUT)):
        print(f, os.path.getsize(os.path.join(OUT, f)))


if __name__ == "__main__":
    main()
