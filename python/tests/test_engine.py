"""mra.analyze / synthesize, upscale / downscale and compare."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import mra
from conftest import field

SCHEMES = ["haar", "chaikin", "cubic", "linear", "linear-wide", "chaikin-wide", "cubic-wide", "cdf97"]


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("boundary", ["symmetric", "periodic", "interpolating"])
def test_analyze_then_synthesize_reconstructs(scheme, boundary):
    a = field((37, 64), np.float64)
    d = mra.analyze(a, scheme=scheme, boundary=boundary, levels=3)
    b = mra.synthesize(d)
    assert b.dtype == np.float64
    assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()


def test_analyze_splits_coarse_and_details_by_level_and_axis():
    a = field((64, 48), np.float32)
    d = mra.analyze(a, scheme="haar", levels=2)
    assert d.coarse.dtype == np.float32
    assert d.coarse.shape == (16, 12)
    assert [sorted(x) for x in d.details] == [["ad", "da", "dd"]] * 2
    assert d.details[0]["dd"].shape == (16, 12)  # coarsest level first
    assert d.details[1]["dd"].shape == (32, 24)
    b = mra.synthesize(d)
    assert np.abs(a - b).max() <= 1e-4 * np.abs(a).max()


def test_constant_input_has_zero_details():
    d = mra.analyze(np.full((32, 40), 7.0), scheme="cubic", levels=3)
    for level in d.details:
        for block in level.values():
            assert np.abs(block).max() < 1e-9


def test_zeroed_details_give_the_coarse_approximation():
    a = field((64, 64), np.float64)
    d = mra.analyze(a, scheme="cdf97", levels=2)
    for level in d.details:
        for block in level.values():
            block[...] = 0
    smooth = mra.synthesize(d)
    err = np.abs(smooth - a)
    assert 0 < err.mean() < 0.1 * np.abs(a).max()


def test_analyze_along_chosen_axes_only():
    a = field((16, 20, 3), np.float64)
    d = mra.analyze(a, scheme="haar", levels=1, axes=[0, 1])
    assert d.coarse.shape == (8, 10, 3)
    assert sorted(d.details[0]) == ["ad", "da", "dd"]
    assert np.allclose(mra.synthesize(d), a)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_upscale_area_mode_keeps_cell_means(dtype):
    a = field((20, 30), dtype)
    if a.dtype.kind != "f":
        # away from the type's ends, where rounding the overshoot would clip it
        a = (a * 0.5 + np.iinfo(dtype).max * 0.25).astype(dtype)
    b = mra.upscale(a, 2, clamp="off")
    assert b.dtype == a.dtype and b.shape == (40, 60)
    means = b.astype(np.float64).reshape(20, 2, 30, 2).mean(axis=(1, 3))
    tol = 1e-3 * float(np.abs(a).max()) if a.dtype.kind == "f" else 1.0
    assert np.abs(means - a).max() <= tol


def test_upscale_size_axes_and_channels():
    a = field((10, 12, 3), np.uint8)
    assert mra.upscale(a, 3, channels_last=True).shape == (30, 36, 3)
    assert mra.upscale(a, 2, axes=[-1], channels_last=True).shape == (10, 24, 3)
    assert mra.upscale(a[..., 0], size=(15, 17)).shape == (15, 17)
    v = field((6, 8, 10), np.int16)
    assert mra.upscale(v, 2, mode="interpolate", scheme="cubic").shape == (12, 16, 20)


def test_upscale_refuses_an_output_over_the_memory_budget():
    with pytest.raises(ValueError, match="exceeds the limit"):
        mra.upscale(np.zeros((64, 64, 64), np.uint8), 1024)


def test_downscale_keeps_type_and_range():
    a = field((64, 40), np.uint16)
    b = mra.downscale(a, 2)
    assert b.dtype == np.uint16 and b.shape == (16, 10)
    assert a.min() <= b.min() and b.max() <= a.max()
    assert mra.downscale(a, 1, axes=[0]).shape == (32, 40)


def test_compare_matches_its_definitions():
    a = field((40, 40), np.uint8)
    assert mra.compare(a, a)["psnr"] is None
    assert mra.compare(a, a)["ssim"] == pytest.approx(1.0)
    b = a.copy()
    b[3, 4] = a[3, 4] ^ 16
    m = mra.compare(a, b)
    mse = np.mean((a.astype(float) - b) ** 2)
    assert m["mse"] == pytest.approx(mse)
    assert m["psnr"] == pytest.approx(10 * np.log10(255.0**2 / mse))
    assert m["max_abs_error"] == 16
    assert m["dims"] == [40, 40] and m["dtype"] == "u8"
    with pytest.raises(ValueError, match="expected"):
        mra.compare(a, a[:10])


def _mra_binary():
    env = os.environ.get("MRA_BIN")
    if env:
        return env
    root = Path(__file__).resolve().parents[2]
    for p in (root / "target" / "release" / "mra", root / "target" / "debug" / "mra"):
        if p.exists():
            return str(p)
    return shutil.which("mra")


def test_compare_gives_the_same_object_as_the_command_line(tmp_path):
    exe = _mra_binary()
    if exe is None:
        pytest.skip("no mra binary (build with cargo build --release or set MRA_BIN)")
    a = field((24, 33), np.uint16)
    b = mra.decode(mra.encode(a, quality=40))
    a.tofile(tmp_path / "a.raw")
    b.tofile(tmp_path / "b.raw")
    out = subprocess.run(
        [exe, "compare", str(tmp_path / "a.raw"), str(tmp_path / "b.raw"),
         "--dims", "33x24", "--dtype", "u16", "--json"],
        capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    cli = json.loads(out.stdout)
    py = mra.compare(a, b)
    assert py == cli
