"""The ``mra`` codec for numcodecs (Zarr v2 compressors, and anything that reads a
numcodecs JSON config), registered through the ``numcodecs.codecs`` entry point.

A chunk of any shape is coded as an array of at most 3 spatial axes: a 0-d chunk as one
sample, a chunk of more than 3 axes with its leading axes folded into one (``(T, Z, Y,
X)`` as ``(T·Z, Y, X)``). Decoding returns the chunk's samples in that coded shape; Zarr
reshapes them to the chunk's shape. Zarr pads an edge chunk to the full chunk shape
with the fill value, so a partial edge chunk is coded like any other.
"""

from __future__ import annotations

from typing import Any, Dict, Optional

import numpy as np
from numcodecs.abc import Codec
from numcodecs.compat import ensure_contiguous_ndarray_like, ensure_ndarray_like, ndarray_copy

from . import _rate_of, decode, encode


def coded_shape(shape: tuple) -> tuple:
    """The shape a chunk of ``shape`` is coded in (at most 3 axes, at least 1)."""
    if len(shape) == 0:
        return (1,)
    if len(shape) > 3:
        return (int(np.prod(shape[:-2])),) + tuple(shape[-2:])
    return tuple(shape)


class Mra(Codec):
    """numcodecs codec ``mra``: the mra codec on each chunk.

    ``Mra(max_error=0.5)``, ``Mra(lossless=True)`` (the default), ``Mra(psnr=50,
    data_range=4095)``, ``Mra(bpp=2)``, ``Mra(quality=60)``; ``scheme``, ``boundary`` and
    ``levels`` as :func:`mra.encode`. The JSON config is ``{"id": "mra", "rate": …,
    "value": …, "data_range": …, "scheme": …, "boundary": …, "levels": …}``.
    """

    codec_id = "mra"

    def __init__(
        self,
        rate: Optional[str] = None,
        value: Optional[float] = None,
        data_range: Optional[float] = None,
        scheme: str = "cdf97",
        boundary: str = "symmetric",
        levels: int = 6,
        *,
        lossless: Optional[bool] = None,
        max_error: Optional[float] = None,
        psnr: Optional[float] = None,
        bpp: Optional[float] = None,
        quality: Optional[float] = None,
        keep: Optional[float] = None,
        threshold: Optional[float] = None,
    ):
        named = dict(
            lossless=lossless,
            max_error=max_error,
            psnr=psnr,
            bpp=bpp,
            quality=quality,
            keep=keep,
            threshold=threshold,
        )
        if rate is not None:
            if any(v is not None for v in named.values()):
                raise ValueError(
                    "invalid rate: rate= and a rate keyword (expected one of the two)"
                )
            if rate == "lossless":
                named["lossless"] = True
            elif rate in named:
                named[rate] = value
            else:
                raise ValueError(
                    f"invalid rate: {rate} (expected lossless, max_error, psnr, bpp, "
                    "quality, keep or threshold)"
                )
            if rate != "lossless" and value is None:
                raise ValueError(f"invalid value: None for rate {rate} (expected a number)")
        elif not any(v is not None for v in named.values()):
            named["lossless"] = True
        self.rate, self.value = _rate_of(**named)
        self.data_range = None if data_range is None else float(data_range)
        if self.data_range is not None and self.rate != "psnr":
            raise ValueError(
                f"invalid data_range: {data_range} (expected only with the psnr rate)"
            )
        self.scheme = str(scheme)
        self.boundary = str(boundary)
        self.levels = int(levels)

    def get_config(self) -> Dict[str, Any]:
        return {
            "id": self.codec_id,
            "rate": self.rate,
            "value": self.value,
            "data_range": self.data_range,
            "scheme": self.scheme,
            "boundary": self.boundary,
            "levels": self.levels,
        }

    def _rate_kwargs(self) -> Dict[str, Any]:
        if self.rate == "lossless":
            return {"lossless": True}
        kw: Dict[str, Any] = {self.rate: self.value}
        if self.data_range is not None:
            kw["data_range"] = self.data_range
        return kw

    def encode(self, buf: Any) -> bytes:
        a = ensure_ndarray_like(buf)
        a = np.ascontiguousarray(a).reshape(coded_shape(a.shape))
        return encode(
            a,
            scheme=self.scheme,
            boundary=self.boundary,
            levels=self.levels,
            **self._rate_kwargs(),
        )

    def decode(self, buf: Any, out: Any = None) -> Any:
        data = ensure_contiguous_ndarray_like(buf).view(np.uint8).reshape(-1)
        dec = decode(data)
        return ndarray_copy(dec, out) if out is not None else dec

    def __repr__(self) -> str:
        v = "" if self.rate == "lossless" else f"={self.value!r}"
        extra = "" if self.data_range is None else f", data_range={self.data_range!r}"
        return (
            f"Mra({self.rate}{v}{extra}, scheme={self.scheme!r}, "
            f"boundary={self.boundary!r}, levels={self.levels})"
        )
