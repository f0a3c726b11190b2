#!/usr/bin/env python3
"""Writes the GeoTIFF test fixtures with GDAL (through rasterio), the way data portals do.

Run from the repository root in a virtual environment with rasterio and numpy:

    python3 -m venv .venv && .venv/bin/pip install rasterio numpy
    .venv/bin/python scripts/make-geotiff-fixtures.py

Every file holds the same 40 x 30 grid of small integers (exact in uint8, int16, float32 and
float64), projected (EPSG:32633, 25 m pixels), so the loader tests can require that every
layout and codec gives exactly the grid of `grid.csv` (rows north first, as a GeoTIFF stores
them). The outputs are committed; this script documents how they were made.
"""
import os

import numpy as np
import rasterio
import rasterio.shutil
from rasterio.transform import from_origin

OUT = os.path.join(os.path.dirname(__file__), "..", "crates", "isotrack-fields", "tests",
                   "fixtures", "geotiff")
NX, NY = 40, 30
X0, Y_TOP, PIX = 500000.0, 4_650_000.0, 25.0


def grid():
    # A smooth hill (a Gaussian) rounded to integers in [10, 250]: every dtype holds it exactly.
    j, i = np.mgrid[0:NY, 0:NX]
    z = 10 + 240 * np.exp(-(((i - 23.0) / 11.0) ** 2 + ((j - 12.0) / 9.0) ** 2))
    return np.round(z)


def write(name, dtype, **opts):
    z = grid().astype(dtype)
    profile = dict(driver="GTiff", width=NX, height=NY, count=1, dtype=dtype,
                   crs="EPSG:32633", transform=from_origin(X0, Y_TOP, PIX, PIX))
    profile.update(opts)
    path = os.path.join(OUT, name)
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(z, 1)
    return path


def main():
    os.makedirs(OUT, exist_ok=True)
    np.savetxt(os.path.join(OUT, "grid.csv"), grid()[::-1], delimiter=",", fmt="%.1f")
    write("uncompressed_f64.tif", "float64")
    write("deflate_f32.tif", "float32", compress="deflate")
    write("deflate_pred2_i16.tif", "int16", compress="deflate", predictor=2)
    write("deflate_pred3_f32.tif", "float32", compress="deflate", predictor=3)
    write("deflate_pred3_f64.tif", "float64", compress="deflate", predictor=3)
    write("lzw_u8.tif", "uint8", compress="lzw")
    write("lzw_pred2_u8.tif", "uint8", compress="lzw", predictor=2)
    write("zstd_f32.tif", "float32", compress="zstd")
    write("zstd_pred2_i16.tif", "int16", compress="zstd", predictor=2)
    write("tiled_deflate_f32.tif", "float32", compress="deflate", tiled=True,
          blockxsize=16, blockysize=16)
    write("bigtiff_deflate_f64.tif", "float64", compress="deflate", BIGTIFF="YES")
    # Tiled LZW as GDAL 3.x writes it: libtiff stops reading a tile once it has its bytes, so
    # GDAL's tiles may lack the LZW end-of-information code (issue 30, item 2).
    for name, dtype, pred in [("tiled_lzw_f32.tif", "float32", None),
                              ("tiled_lzw_pred3_f32.tif", "float32", 3),
                              ("tiled_lzw_i16.tif", "int16", None),
                              ("tiled_lzw_pred2_i16.tif", "int16", 2),
                              ("tiled_lzw_pred2_u8.tif", "uint8", 2)]:
        opts = dict(compress="lzw", tiled=True, blockxsize=16, blockysize=16)
        if pred:
            opts["predictor"] = pred
        write(name, dtype, **opts)
    write("jpeg_u8.tif", "uint8", compress="jpeg")
    # Cloud-Optimised GeoTIFF with overviews: full resolution first, then 2x and 4x.
    with rasterio.open(os.path.join(OUT, "uncompressed_f64.tif")) as src:
        z = src.read(1)
        profile = src.profile
    profile.update(driver="COG", dtype="float32", compress="deflate", predictor=3,
                   blocksize=16, overview_resampling="average", overviews="AUTO")
    # COG is a copy driver: build in memory with overviews, then copy.
    tmp = os.path.join(OUT, "_tmp.tif")
    with rasterio.open(tmp, "w", driver="GTiff", width=NX, height=NY, count=1,
                       dtype="float32", crs="EPSG:32633",
                       transform=from_origin(X0, Y_TOP, PIX, PIX)) as dst:
        dst.write(z.astype("float32"), 1)
        dst.build_overviews([2, 4], rasterio.enums.Resampling.average)
    rasterio.shutil.copy(tmp, os.path.join(OUT, "cog_deflate_f32.tif"), driver="COG",
                         compress="deflate", predictor=3, blocksize=16, overviews="FORCE_USE_EXISTING")
    os.remove(tmp)
    for f in sorted(os.listdir(OUT)):
        print(f, os.path.getsize(os.path.join(OUT, f)))


if __name__ == "__main__":
    main()
