"""The memory budget MRA_MAX_BYTES holds in the Python package: an .mra file whose header
declares a huge raster (checksums consistent, made here) is refused with a Python
exception before anything is allocated, and the interpreter goes on."""

import os
import struct
import subprocess
import sys

import numpy as np
import pytest

import mra
from conftest import field


def _crc32c_table():
    table = []
    for n in range(256):
        c = n
        for _ in range(8):
            c = (c >> 1) ^ 0x82F63B78 if c & 1 else c >> 1
        table.append(c)
    return table


_TABLE = _crc32c_table()


def crc32c(data: bytes) -> int:
    c = 0xFFFFFFFF
    for b in data:
        c = _TABLE[(c ^ b) & 0xFF] ^ (c >> 8)
    return c ^ 0xFFFFFFFF


def chunk(kind: bytes, payload: bytes) -> bytes:
    """One chunk as the container frames it: length, kind, payload, CRC-32C of kind and
    payload (little endian)."""
    return (
        struct.pack("<I", len(payload))
        + kind
        + payload
        + struct.pack("<I", crc32c(kind + payload))
    )


def chunks(data: bytes):
    """(kind, start, end) of each chunk after the 8-byte signature."""
    out, at = [], 8
    while at + 12 <= len(data):
        (n,) = struct.unpack_from("<I", data, at)
        out.append((data[at + 4 : at + 8], at, at + 12 + n))
        at += 12 + n
    return out


def forged(side: int) -> bytes:
    """A 37 × 53 image's .mra file whose HEAD declares side × side (extents and the one
    tile's extents, in either axis order), its checksum recomputed, padded by an
    ancillary chunk so that the file's length does not refuse it first."""
    good = mra.encode(field((37, 53), np.uint8), quality=50, levels=3)
    cs = chunks(good)
    kind, s, e = cs[0]
    assert kind == b"HEAD"
    head = good[s + 8 : e - 4]
    big = struct.pack("<II", side, side)
    n = 0
    for dims in [(37, 53), (53, 37)]:
        pat = struct.pack("<II", *dims)
        n += head.count(pat)
        head = head.replace(pat, big)
    assert n >= 1, "the extents were not found in HEAD"
    last = cs[-1]
    assert last[0] == b"MEND"
    return (
        good[:s]
        + chunk(b"HEAD", head)
        + good[e : last[1]]
        + chunk(b"pADs", bytes(120_000))
        + chunk(b"MEND", b"")
    )


def test_a_header_declaring_8000_squared_is_refused_under_16_mib(monkeypatch):
    data = forged(8000)
    # the header alone is readable: it declares 8000 × 8000
    assert mra.info(data)["dims"] == [8000, 8000]
    monkeypatch.setenv("MRA_MAX_BYTES", "16M")
    with pytest.raises(mra.MraError, match="MRA_MAX_BYTES"):
        mra.decode(data)
    with pytest.raises(mra.MraError, match="MRA_MAX_BYTES"):
        mra.decode(data, level=2)
    # the interpreter goes on: the same process still decodes a good file
    a = field((16, 24), np.uint8)
    assert mra.decode(mra.encode(a, lossless=True)).shape == (16, 24)


def test_a_header_declaring_30000_squared_leaves_the_interpreter_alive():
    # in a child interpreter, so that a crash (not an exception) would show as its exit
    code = (
        "import sys, mra\n"
        "data = open(sys.argv[1], 'rb').read()\n"
        "try:\n"
        "    mra.decode(data)\n"
        "except mra.MraError as e:\n"
        "    print('refused:', e)\n"
        "print('alive')\n"
    )
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "huge.mra")
        with open(path, "wb") as f:
            f.write(forged(30000))
        env = dict(os.environ, MRA_MAX_BYTES="256M")
        r = subprocess.run(
            [sys.executable, "-c", code, path],
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[-1] == "alive", r.stdout
    assert lines[0].startswith("refused:") and "MRA_MAX_BYTES" in lines[0], r.stdout
