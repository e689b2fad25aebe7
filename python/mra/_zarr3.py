"""The ``mra`` codec for Zarr v3 (an array → bytes codec), registered through the
``zarr.codecs`` entry point under the name ``mra``; its configuration is the numcodecs
config of :class:`mra._numcodecs.Mra` without ``id``. Each chunk is coded by the
numcodecs codec in a worker thread (the GIL is released while it codes).
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Dict

import numpy as np
from zarr.abc.codec import ArrayBytesCodec
from zarr.core.common import parse_named_configuration

from ._numcodecs import Mra as _Numcodec

if TYPE_CHECKING:
    from zarr.core.array_spec import ArraySpec
    from zarr.core.buffer import Buffer, NDBuffer


@dataclass(frozen=True)
class Mra(ArrayBytesCodec):
    """Zarr v3 codec ``mra``: ``zarr.create_array(..., serializer=Mra(max_error=1))``.
    Keywords as :class:`mra._numcodecs.Mra` (default lossless)."""

    is_fixed_size = False

    config: Dict[str, Any]

    def __init__(self, **kwargs: Any) -> None:
        codec = _Numcodec(**kwargs)
        cfg = codec.get_config()
        cfg.pop("id")
        object.__setattr__(self, "config", cfg)

    @property
    def _codec(self) -> _Numcodec:
        return _Numcodec(**self.config)

    @classmethod
    def from_dict(cls, data: Dict[str, Any]) -> "Mra":
        _, cfg = parse_named_configuration(data, "mra")
        return cls(**cfg)

    def to_dict(self) -> Dict[str, Any]:
        return {"name": "mra", "configuration": dict(self.config)}

    def __hash__(self) -> int:
        return hash(tuple(sorted(self.config.items())))

    async def _decode_single(self, chunk_bytes: "Buffer", chunk_spec: "ArraySpec") -> "NDBuffer":
        data = chunk_bytes.as_numpy_array()
        out = await asyncio.to_thread(self._codec.decode, data)
        dtype = chunk_spec.dtype.to_native_dtype()
        if out.dtype != dtype:
            raise ValueError(f"mra chunk of type {out.dtype} (expected {dtype})")
        out = np.asarray(out).reshape(chunk_spec.shape)
        return chunk_spec.prototype.nd_buffer.from_numpy_array(out)

    async def _encode_single(self, chunk_array: "NDBuffer", chunk_spec: "ArraySpec") -> "Buffer":
        a = chunk_array.as_numpy_array()
        b = await asyncio.to_thread(self._codec.encode, a)
        return chunk_spec.prototype.buffer.from_bytes(b)

    def compute_encoded_size(self, _input_byte_length: int, _chunk_spec: "ArraySpec") -> int:
        raise NotImplementedError
