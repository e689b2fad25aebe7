"""Types of the extension module ``mra._mra`` (the Rust half; see ``mra/__init__.py``)."""

from typing import List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

class MraError(ValueError):
    """An error of the mra library; the message is its one line "what … (expected …)"."""

_Bytes = Union[bytes, npt.NDArray[np.uint8]]
_Blocks = List[Tuple[int, List[bool], List[Tuple[int, int]]]]

def encode(
    a: npt.NDArray[np.generic],
    rate_kind: str,
    value: float,
    data_range: Optional[float],
    scheme: str,
    boundary: str,
    levels: int,
    channels_last: bool,
    tile: Optional[List[int]] = None,
    format: int = 3,
    effort: int = 7,
) -> bytes: ...
def decode(
    data: _Bytes,
    level: int = 0,
    allow_truncated: bool = False,
    region: Optional[List[Tuple[int, int]]] = None,
) -> npt.NDArray[np.generic]: ...
def dims(data: _Bytes) -> List[int]: ...
def info(data: _Bytes) -> str: ...
def analyze(
    a: npt.NDArray[np.floating],
    scheme: str,
    boundary: str,
    levels: int,
    axes: List[int],
) -> Tuple[npt.NDArray[np.floating], List[List[int]], _Blocks]: ...
def synthesize(
    c: npt.NDArray[np.floating],
    scheme: str,
    boundary: str,
    levels: int,
    axes: List[int],
) -> npt.NDArray[np.floating]: ...
def upscale(
    a: npt.NDArray[np.generic],
    factor: Optional[int],
    size: Optional[List[int]],
    axes: Optional[List[int]],
    scheme: str,
    mode: str,
    edge: str,
    clamp: str,
    order: Optional[int],
    channels_last: bool,
) -> npt.NDArray[np.generic]: ...
def downscale(
    a: npt.NDArray[np.generic],
    levels: int,
    axes: Optional[List[int]],
    scheme: str,
    boundary: str,
    channels_last: bool,
) -> npt.NDArray[np.generic]: ...
def compare(
    a: npt.NDArray[np.generic],
    b: npt.NDArray[np.generic],
    data_range: Optional[float],
    convention: str,
    channels_last: bool,
) -> str: ...
