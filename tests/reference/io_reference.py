#!/usr/bin/env python3
"""Tiny files written by other tools, for tests/io.rs (`files_written_by_other_tools`).

Writes tests/reference/io/* with imageio (PNG), tifffile (TIFF, GeoTIFF tags),
pynrrd (NRRD raw / gzip / big endian / detached / RGB), nibabel (NIfTI) and
OpenImageIO (OpenEXR half and float, 16-bit PGM), and tests/reference/io_fixture.json
listing, for each file, the shape (slowest axis first), channels, dtype, every
sample value (row-major, channels interleaved) and the spacing / origin where the
format has them.

Usage:
  pip install numpy imageio tifffile pynrrd nibabel OpenImageIO
  python3 tests/reference/io_reference.py
"""
import json
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "io")


def values(shape, dtype, scale=1.0, offset=0.0):
    n = int(np.prod(shape))
    v = (np.arange(n, dtype=np.float64) * 37 % 101) * scale + offset
    return v.reshape(shape).astype(dtype)


def main():
    import imageio.v3 as iio
    import nibabel as nib
    import nrrd
    import OpenImageIO as oiio
    import tifffile

    os.makedirs(OUT, exist_ok=True)
    cases = []

    def add(name, arr, channels, dtype, spacing=None, origin=None, extra=None):
        d = {
            "file": f"io/{name}",
            "dims": list(arr.shape[: arr.ndim - (1 if channels > 1 else 0)]),
            "channels": channels,
            "dtype": dtype,
            "values": [float(x) for x in arr.reshape(-1)],
        }
        if spacing is not None:
            d["spacing"] = [float(s) for s in spacing]
        if origin is not None:
            d["origin"] = [float(s) for s in origin]
        if extra:
            d.update(extra)
        cases.append(d)

    # PNG (imageio / Pillow)
    a = values((5, 7), np.uint16, 600)
    iio.imwrite(os.path.join(OUT, "png16_gray.png"), a)
    add("png16_gray.png", a, 1, "u16")
    a = values((3, 4, 4), np.uint8, 2)
    iio.imwrite(os.path.join(OUT, "png8_rgba.png"), a)
    add("png8_rgba.png", a, 4, "u8")

    # TIFF (tifffile)
    a = values((6, 5), np.float32, 0.37, -3.0)
    tifffile.imwrite(os.path.join(OUT, "tiff_f32.tif"), a)
    add("tiff_f32.tif", a, 1, "f32")
    a = values((3, 4, 5), np.uint16, 500)
    tifffile.imwrite(os.path.join(OUT, "tiff_u16_stack.tif"), a, photometric="minisblack")
    add("tiff_u16_stack.tif", a, 1, "u16")
    a = values((4, 6), np.int16, 300, -15000)
    tifffile.imwrite(os.path.join(OUT, "tiff_i16_zlib.tif"), a, compression="zlib")
    add("tiff_i16_zlib.tif", a, 1, "i16")
    a = values((4, 5, 3), np.uint8, 2)
    tifffile.imwrite(os.path.join(OUT, "tiff_rgb_u8.tif"), a, photometric="rgb")
    add("tiff_rgb_u8.tif", a, 3, "u8")
    a = values((5, 4), np.float32, 10.5, 700)
    tifffile.imwrite(
        os.path.join(OUT, "geotiff_f32.tif"), a, compression="zlib",
        extratags=[(33550, "d", 3, (30.0, 30.0, 0.0), True),
                   (33922, "d", 6, (0, 0, 0, 557955.0, 5121885.0, 0), True),
                   (34735, "H", 24, (1, 1, 0, 5, 1024, 0, 1, 1, 1025, 0, 1, 1,
                                     3072, 0, 1, 26710, 3076, 0, 1, 9001, 4099, 0, 1, 9001), True)])
    add("geotiff_f32.tif", a, 1, "f32", spacing=[30.0, 30.0],
        extra={"geotiff_tags": [33550, 33922, 34735]})

    # NRRD (pynrrd); arrays are [z, y, x] and written with index_order='C'
    hdr = {"space": "left-posterior-superior",
           "space directions": np.diag([0.5, 0.75, 2.0]),
           "space origin": np.array([-10.0, 20.5, 3.0]), "kinds": ["domain"] * 3}
    a = values((3, 4, 5), np.int16, 40, -2000)
    nrrd.write(os.path.join(OUT, "nrrd_gzip_i16.nrrd"), a, dict(hdr, encoding="gzip"), index_order="C")
    add("nrrd_gzip_i16.nrrd", a, 1, "i16", spacing=[2.0, 0.75, 0.5], origin=[-10.0, 20.5, 3.0])
    a = values((2, 3, 4), np.float32, 0.125, -1)
    nrrd.write(os.path.join(OUT, "nrrd_raw_be_f32.nrrd"), a.astype(">f4"),
               dict(hdr, encoding="raw", endian="big"), index_order="C")
    add("nrrd_raw_be_f32.nrrd", a, 1, "f32", spacing=[2.0, 0.75, 0.5], origin=[-10.0, 20.5, 3.0])
    a = values((3, 4, 5), np.uint16, 600)
    nrrd.write(os.path.join(OUT, "nrrd_detached.nhdr"), a, dict(hdr, encoding="raw"),
               detached_header=True, index_order="C")
    add("nrrd_detached.nhdr", a, 1, "u16", spacing=[2.0, 0.75, 0.5], origin=[-10.0, 20.5, 3.0])
    a = values((4, 5, 3), np.uint8, 2)
    nrrd.write(os.path.join(OUT, "nrrd_rgb_u8.nrrd"), a,
               {"encoding": "raw", "kinds": ["RGB-color", "domain", "domain"]}, index_order="C")
    add("nrrd_rgb_u8.nrrd", a, 3, "u8")

    # NIfTI (nibabel); data arrays are [x, y, z]; mra reads [z, y, x]
    xyz = values((5, 4, 3), np.int16, 50, -1000)
    aff = np.array([[0.8, 0, 0, -20.0], [0, 0.9, 0, 10.0], [0, 0, 2.5, -5.0], [0, 0, 0, 1]])
    img = nib.Nifti1Image(xyz, aff)
    img.header.set_xyzt_units("mm")
    nib.save(img, os.path.join(OUT, "nifti_i16.nii.gz"))
    add("nifti_i16.nii.gz", xyz.transpose(2, 1, 0), 1, "i16", spacing=[2.5, 0.9, 0.8],
        origin=[-20.0, 10.0, -5.0])
    xyz = values((4, 3, 2), np.float32, 0.25)
    nib.save(nib.Nifti1Image(xyz, np.eye(4)), os.path.join(OUT, "nifti_f32.nii"))
    add("nifti_f32.nii", xyz.transpose(2, 1, 0), 1, "f32", spacing=[1.0, 1.0, 1.0])

    # OpenEXR and PGM (OpenImageIO)
    def oiio_write(name, arr, typ):
        h, w = arr.shape[:2]
        c = arr.shape[2] if arr.ndim == 3 else 1
        out = oiio.ImageOutput.create(os.path.join(OUT, name))
        spec = oiio.ImageSpec(w, h, c, typ)
        if name.endswith(".exr"):
            spec.attribute("compression", "zip")
        out.open(os.path.join(OUT, name), spec)
        out.write_image(arr if arr.ndim == 3 else arr[..., None])
        out.close()
    a = (values((3, 4, 3), np.float32, 0.25, -2)).astype(np.float16)
    oiio_write("exr_half_rgb.exr", a, "half")
    add("exr_half_rgb.exr", a.astype(np.float32), 3, "f16")
    a = values((4, 3), np.float32, 1.5, -7)
    oiio_write("exr_float_gray.exr", a, "float")
    add("exr_float_gray.exr", a, 1, "f32")
    a = values((3, 5), np.uint16, 640)
    oiio_write("pgm_u16.pgm", a, "uint16")
    add("pgm_u16.pgm", a, 1, "u16")

    with open(os.path.join(HERE, "io_fixture.json"), "w") as f:
        json.dump({"about": "written by tests/reference/io_reference.py; do not edit",
                   "cases": cases}, f, indent=1)
        f.write("\n")
    print(f"wrote {len(cases)} files")


if __name__ == "__main__":
    main()
