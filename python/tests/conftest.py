"""Shared test data: smooth fields plus noise, scaled to each sample type's range."""

import numpy as np
import pytest

DTYPES = [np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.float32, np.float64]


def field(shape, dtype, seed=0):
    """A smooth field (sum of cosines) plus 2 % noise, spread over most of ``dtype``'s
    range (integers) or over [-1, 1] × 100 (floats)."""
    rng = np.random.default_rng(seed)
    grids = np.meshgrid(*[np.linspace(0, 1, n) for n in shape], indexing="ij")
    f = np.zeros(shape)
    for k, g in enumerate(grids):
        f += np.cos((3 + 2 * k) * np.pi * g + k)
    f = f / max(len(shape), 1) + 0.02 * rng.standard_normal(shape)
    f = (f - f.min()) / (f.max() - f.min())  # [0, 1]
    dt = np.dtype(dtype)
    if dt.kind == "f":
        return ((f * 2 - 1) * 100).astype(dt)
    info = np.iinfo(dt)
    # stay off the extremes so lossy overshoot is not all clamping
    lo = info.min / 2 if info.min < 0 else 0
    hi = min(info.max * 0.9, 2.0**24)
    return np.round(lo + f * (hi - lo)).astype(dt)


@pytest.fixture
def smooth():
    return field
