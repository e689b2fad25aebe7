"""mra.encode / mra.decode: every sample type in every rate mode, shapes, levels,
regions, and bad bytes."""

import numpy as np
import pytest

import mra
from conftest import DTYPES, field


def range_of(a):
    return float(a.max()) - float(a.min())


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_lossless_round_trip_is_bit_exact_for_every_dtype(dtype):
    a = field((37, 53), dtype)
    b = mra.decode(mra.encode(a, lossless=True))
    assert b.dtype == a.dtype and b.shape == a.shape
    assert np.array_equal(a.view(np.uint8), b.view(np.uint8))


def test_lossless_keeps_float_specials_bit_exact():
    a = field((16, 16), np.float32)
    a[0, 0], a[1, 1], a[2, 2] = np.nan, np.inf, -0.0
    b = mra.decode(mra.encode(a, lossless=True))
    assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_max_error_bound_holds_for_every_dtype(dtype):
    a = field((48, 61), dtype, seed=1)
    e = 3.0 if np.dtype(dtype).kind in "iu" else 0.05
    b = mra.decode(mra.encode(a, max_error=e))
    assert b.dtype == a.dtype and b.shape == a.shape
    err = np.abs(a.astype(np.float64) - b.astype(np.float64)).max()
    assert err <= e, (err, e)


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_psnr_target_is_reached_as_compare_measures_it(dtype):
    a = field((64, 64), dtype, seed=2)
    r = range_of(a)
    b = mra.decode(mra.encode(a, psnr=45.0, data_range=r))
    m = mra.compare(a, b, data_range=r)
    assert m["psnr"] is None or m["psnr"] >= 45.0 - 1e-6, m


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_bpp_target_bounds_the_file_size(dtype):
    a = field((64, 64), dtype, seed=3)
    data = mra.encode(a, bpp=1.5)
    assert len(data) * 8 / a.size <= 1.5
    b = mra.decode(data)
    assert b.dtype == a.dtype and b.shape == a.shape
    # a coarse but real approximation: well above the PSNR of a constant image
    flat = np.full_like(a, a.mean().astype(a.dtype))
    r = range_of(a)
    assert mra.compare(a, b, data_range=r)["psnr"] > mra.compare(a, flat, data_range=r)["psnr"] + 10


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
@pytest.mark.parametrize("rate", [{"quality": 60}, {"keep": 5}, {"threshold": 0.01}])
def test_quality_keep_and_threshold_round_trip_every_dtype(dtype, rate):
    a = field((40, 44), dtype, seed=4)
    if "threshold" in rate:
        rate = {"threshold": 0.01 * range_of(a)}
    b = mra.decode(mra.encode(a, **rate))
    assert b.dtype == a.dtype and b.shape == a.shape
    assert mra.compare(a, b, data_range=range_of(a))["psnr"] > 25


def test_higher_quality_gives_more_bytes_and_less_error():
    a = field((64, 64), np.uint16)
    lo, hi = mra.encode(a, quality=30), mra.encode(a, quality=80)
    assert len(lo) < len(hi)
    e_lo = mra.compare(a, mra.decode(lo))["mse"]
    e_hi = mra.compare(a, mra.decode(hi))["mse"]
    assert e_hi < e_lo


@pytest.mark.parametrize("shape", [(300,), (33, 17), (9, 20, 24)])
def test_one_to_three_spatial_axes(shape):
    a = field(shape, np.int16)
    assert np.array_equal(mra.decode(mra.encode(a, lossless=True)), a)
    b = mra.decode(mra.encode(a, max_error=2))
    assert b.shape == shape and np.abs(b.astype(int) - a).max() <= 2


def test_channels_last_keeps_channels_and_their_values():
    rgb = np.stack([field((40, 50), np.uint8, seed=s) for s in range(3)], axis=-1)
    assert np.array_equal(mra.decode(mra.encode(rgb, lossless=True, channels_last=True)), rgb)
    b = mra.decode(mra.encode(rgb, max_error=1, channels_last=True))
    assert b.shape == (40, 50, 3)
    assert np.abs(b.astype(int) - rgb).max() <= 1


def test_non_contiguous_and_big_endian_inputs_are_read_in_array_order():
    a = field((30, 40), np.uint16)
    for view in (a.T, a[::2, ::3], a.astype(">u2")):
        assert np.array_equal(mra.decode(mra.encode(view, lossless=True)), np.asarray(view))


def test_level_decodes_a_smaller_preview():
    a = field((128, 96), np.uint8)
    data = mra.encode(a, quality=70, levels=4)
    b = mra.decode(data, level=2)
    assert b.shape == (32, 24)
    # the preview is the coarse image: close to 4x4 block means (within 5 % of the range)
    means = a.reshape(32, 4, 24, 4).mean(axis=(1, 3))
    assert np.abs(b - means).mean() < 0.05 * 255
    with pytest.raises(ValueError, match="expected one of the levels"):
        mra.decode(data, level=9)


def test_region_is_the_crop_of_the_whole_decode():
    a = field((64, 80), np.uint16)
    data = mra.encode(a, max_error=4)
    full = mra.decode(data)
    part = mra.decode(data, region=(slice(10, 30), (5, 70)))
    assert np.array_equal(part, full[10:30, 5:70])
    assert part.flags.c_contiguous
    with pytest.raises(ValueError, match="invalid region"):
        mra.decode(data, region=((0, 100),))


def test_region_of_a_tiled_file_reads_only_its_tiles():
    a = field((96, 80), np.uint16)
    data = mra.encode(a, max_error=2, tile=(32, 32))
    i = mra.info(data)
    assert i["tiles"] == 9 and i["tile"] == [32, 32] and i["dims"] == [96, 80]
    full = mra.decode(data)
    assert np.abs(full.astype(np.int64) - a).max() <= 2
    for region in [(slice(0, 96), slice(0, 80)), ((40, 41), (5, 70)), (slice(33, 95),)]:
        index = tuple(slice(*r) if isinstance(r, tuple) else r for r in region)
        assert np.array_equal(mra.decode(data, region=region), full[index])
    # a corrupt tile that the region does not meet is never read
    last = [c for c in i["chunks"] if c["kind"] == "TILE" and c["tile"] == 8][0]
    bad = bytearray(data)
    bad[last["offset"] + last["bytes"] // 2] ^= 0xFF
    bad = bytes(bad)
    with pytest.raises(ValueError):
        mra.decode(bad)
    assert np.array_equal(mra.decode(bad, region=((0, 64), (0, 64))), full[:64, :64])
    with pytest.raises(ValueError):
        mra.decode(bad, region=((64, 96), (64, 80)))
    # coarser levels decode whole, then crop
    half = mra.decode(data, level=1)
    assert np.array_equal(mra.decode(data, level=1, region=((3, 20),)), half[3:20])
    with pytest.raises(ValueError, match="invalid tile"):
        mra.encode(a, tile=(32,))


def test_info_reports_the_header():
    a = field((20, 30), np.float32)
    i = mra.info(mra.encode(a, max_error=0.5))
    assert i["sample_type"] == "f32" and i["max_error"] == 0.5
    assert sorted(i["dims"]) == [20, 30]


def test_rate_keywords_are_exclusive_and_checked():
    a = field((16, 16), np.uint8)
    with pytest.raises(ValueError, match="expected one of"):
        mra.encode(a, lossless=True, max_error=1)
    with pytest.raises(ValueError, match="expected"):
        mra.encode(a, scheme="nope")
    with pytest.raises(ValueError, match="expected only with psnr"):
        mra.encode(a, bpp=1, data_range=255)


def test_negative_counts_raise_value_error_not_overflow_error():
    a = field((16, 16), np.uint8)
    b = mra.encode(a, lossless=True)
    calls = [
        lambda: mra.encode(a, levels=-1),
        lambda: mra.encode(a, tile=[-8, 8]),
        lambda: mra.decode(b, level=-1),
        lambda: mra.analyze(a, levels=-2),
        lambda: mra.upscale(a, factor=-2),
        lambda: mra.upscale(a, order=-1),
        lambda: mra.downscale(a, levels=-1),
    ]
    for call in calls:
        with pytest.raises(ValueError, match=r"invalid \w+: -\d+ \(expected"):
            call()


def test_unsupported_types_and_shapes_raise_with_the_expected_values():
    with pytest.raises(TypeError, match="expected one of uint8"):
        mra.encode(np.zeros((8, 8), np.int64))
    with pytest.raises(ValueError, match=r"spatial axes.*expected 1 to 3"):
        mra.encode(np.zeros((2, 2, 2, 2), np.uint8))
    with pytest.raises(ValueError, match="expected"):
        mra.encode(np.zeros((0, 4), np.uint8))


def _no_panic(excinfo):
    assert "internal error" not in str(excinfo.value), str(excinfo.value)


def test_bad_bytes_raise_value_error_never_crash():
    a = field((40, 50), np.uint16)
    good = mra.encode(a, max_error=2)
    rng = np.random.default_rng(7)
    bad = [b"", b"garbage", b"\x89MRA" + bytes(100), rng.bytes(2000)]
    bad += [good[:n] for n in sorted(set(np.linspace(0, len(good) - 1, 40).astype(int)))]
    for pos in rng.integers(0, len(good), 60):
        flipped = bytearray(good)
        flipped[pos] ^= 1 << int(rng.integers(0, 8))
        bad.append(bytes(flipped))
    for data in bad:
        try:
            mra.decode(data)
        except ValueError as e:
            assert "internal error" not in str(e), str(e)
            assert "\n" not in str(e)
    # the plain cases are errors, not silent successes
    for data in bad[:4] + [good[: len(good) // 2]]:
        with pytest.raises(ValueError) as excinfo:
            mra.decode(data)
        _no_panic(excinfo)


def test_truncated_file_decodes_with_allow_truncated():
    a = field((64, 64), np.uint8)
    good = mra.encode(a, quality=70)
    cut = good[: int(len(good) * 0.7)]
    with pytest.raises(ValueError):
        mra.decode(cut)
    b = mra.decode(cut, allow_truncated=True)
    assert b.shape == a.shape


def test_decode_accepts_buffers_without_copy_semantics_changing_results():
    a = field((30, 30), np.int32)
    data = mra.encode(a, lossless=True)
    for buf in (bytearray(data), memoryview(data), np.frombuffer(data, np.uint8)):
        assert np.array_equal(mra.decode(buf), a)
