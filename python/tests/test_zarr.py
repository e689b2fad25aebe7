"""The numcodecs codec through Zarr stores (v2 compressor and v3 serializer), the entry
points, and a store read back in a fresh process."""

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

numcodecs = pytest.importorskip("numcodecs")
zarr = pytest.importorskip("zarr")

from mra._numcodecs import Mra, coded_shape  # noqa: E402
from conftest import field  # noqa: E402

ZARR3 = int(zarr.__version__.split(".")[0]) >= 3


def make(path, a, chunks, fmt, codec):
    if ZARR3:
        kw = {"compressors": codec} if fmt == 2 else {"serializer": _v3(codec)}
        z = zarr.create_array(
            store=str(path), shape=a.shape, chunks=chunks, dtype=a.dtype,
            zarr_format=fmt, fill_value=0, **kw,
        )
    else:
        if fmt == 3:
            pytest.skip("zarr < 3 has no v3 codec API")
        z = zarr.open(str(path), mode="w", shape=a.shape, chunks=chunks, dtype=a.dtype,
                      compressor=codec, fill_value=0)
    z[...] = a
    return z


def _v3(codec):
    from mra._zarr3 import Mra as Mra3

    return Mra3(**{k: v for k, v in codec.get_config().items() if k != "id"})


FORMATS = [2, 3] if ZARR3 else [2]


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("dtype", [np.uint16, np.int16, np.float32])
def test_max_error_bound_holds_through_a_zarr_store_with_partial_edge_chunks(tmp_path, fmt, dtype):
    a = field((70, 90, 45), dtype, seed=5)
    e = 2.0 if np.dtype(dtype).kind in "iu" else 0.01
    make(tmp_path / "s.zarr", a, (32, 32, 32), fmt, Mra(max_error=e))
    b = zarr.open_array(str(tmp_path / "s.zarr"), mode="r")[...]
    assert b.dtype == a.dtype and b.shape == a.shape
    assert np.abs(a.astype(np.float64) - b).max() <= e


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.uint32, np.float32, np.float64])
def test_lossless_is_bit_exact_through_a_zarr_store(tmp_path, fmt, dtype):
    a = field((50, 77), dtype, seed=6)
    make(tmp_path / "s.zarr", a, (16, 32), fmt, Mra(lossless=True))
    b = zarr.open_array(str(tmp_path / "s.zarr"), mode="r")[...]
    assert np.array_equal(a.view(np.uint8), b.view(np.uint8))


@pytest.mark.parametrize("shape,chunks", [((6, 20, 24, 10), (3, 8, 12, 10)), ((40,), (16,)), ((1, 50, 50), (1, 25, 50))])
def test_chunks_of_any_shape_round_trip(tmp_path, shape, chunks):
    a = field(shape, np.uint16, seed=8)
    make(tmp_path / "s.zarr", a, chunks, 2, Mra(lossless=True))
    assert np.array_equal(zarr.open_array(str(tmp_path / "s.zarr"), mode="r")[...], a)


def test_coded_shape_folds_leading_axes_and_lifts_scalars():
    assert coded_shape(()) == (1,)
    assert coded_shape((5,)) == (5,)
    assert coded_shape((2, 3, 4, 5)) == (6, 4, 5)
    assert coded_shape((2, 3, 4, 5, 6)) == (24, 5, 6)


def test_config_round_trips_through_numcodecs_registry():
    c = Mra(psnr=48, data_range=4095, scheme="linear-wide", levels=5)
    cfg = c.get_config()
    assert cfg == {"id": "mra", "rate": "psnr", "value": 48.0, "data_range": 4095.0,
                   "scheme": "linear-wide", "boundary": "symmetric", "levels": 5}
    again = numcodecs.get_codec(json.loads(json.dumps(cfg)))
    assert isinstance(again, Mra) and again.get_config() == cfg
    assert Mra().get_config()["rate"] == "lossless"
    with pytest.raises(ValueError, match="expected"):
        Mra(rate="max_error")
    with pytest.raises(ValueError, match="expected"):
        Mra(max_error=1, lossless=True)


def test_codec_encode_decode_numcodecs_api_with_out_buffer():
    a = field((30, 40), np.float64)
    c = Mra(max_error=1e-3)
    enc = c.encode(a)
    out = np.empty_like(a)
    c.decode(enc, out=out)
    assert np.abs(out - a).max() <= 1e-3
    assert np.abs(c.decode(memoryview(enc)).reshape(a.shape) - a).max() <= 1e-3


def _fresh(code, cwd):
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_store_written_here_is_read_in_a_fresh_process_through_the_entry_point(tmp_path, fmt):
    a = field((40, 60), np.uint16, seed=9)
    make(tmp_path / "s.zarr", a, (16, 16), fmt, Mra(max_error=1))
    b = zarr.open_array(str(tmp_path / "s.zarr"), mode="r")[...]
    np.save(tmp_path / "expected.npy", b)
    # the child never imports mra: zarr (v3) or numcodecs (v2) must find the codec
    out = _fresh(
        """
        import sys, numpy as np, zarr
        assert "mra" not in sys.modules
        b = zarr.open_array("s.zarr", mode="r")[...]
        e = np.load("expected.npy")
        print("same" if b.dtype == e.dtype and np.array_equal(b, e) else "different")
        print("mra" in sys.modules)
        """,
        tmp_path,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["same", "True"]


def test_numcodecs_finds_the_codec_by_id_in_a_fresh_process(tmp_path):
    out = _fresh(
        """
        import numcodecs
        c = numcodecs.get_codec({"id": "mra", "rate": "max_error", "value": 0.5})
        print(type(c).__module__, c.rate, c.value)
        """,
        tmp_path,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["mra._numcodecs", "max_error", "0.5"]


def test_a_corrupt_chunk_raises_value_error(tmp_path):
    a = field((32, 32), np.uint8)
    make(tmp_path / "s.zarr", a, (32, 32), 2, Mra(lossless=True))
    chunk = next(p for p in (tmp_path / "s.zarr").rglob("*") if p.is_file() and not p.name.startswith(".") and p.name != "zarr.json")
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))
    with pytest.raises(ValueError) as excinfo:
        zarr.open_array(str(tmp_path / "s.zarr"), mode="r")[...]
    assert "internal error" not in str(excinfo.value)
