"""mra for NumPy: the multiresolution codec, pyramid, upscaler and metrics.

Arrays: the axes are spatial, slowest first (``(H, W)`` images, ``(D, H, W)`` volumes;
1 to 3 of them). With ``channels_last=True`` the last axis holds channels (RGB, RGBA,
any count up to 256), which are never transformed; a result has a channel axis when it
has more than one channel. Sample types: uint8, int8, uint16, int16, uint32, int32,
float32, float64 (other types raise ``TypeError``).

Inputs are borrowed read-only (C-contiguous arrays are not copied by NumPy); heavy calls
release the GIL, so threads run them in parallel. Errors of the library raise
:class:`MraError` (a ``ValueError``) carrying its one-line message
``"what … (expected …)"``; malformed or truncated encoded bytes raise it too.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _mra
from ._mra import MraError

__all__ = [
    "MraError",
    "Decomposition",
    "encode",
    "decode",
    "info",
    "analyze",
    "synthesize",
    "upscale",
    "downscale",
    "compare",
    "RATE_MODES",
    "Mra",
]


def __getattr__(name: str) -> Any:
    # the numcodecs codec, imported on first use (numcodecs is an optional dependency)
    if name == "Mra":
        from ._numcodecs import Mra

        return Mra
    raise AttributeError(f"module 'mra' has no attribute {name!r}")

#: The rate modes of :func:`encode`, as keyword names (one at a time).
RATE_MODES = ("lossless", "max_error", "psnr", "bpp", "quality", "keep", "threshold")


def _array(a: Any) -> np.ndarray:
    """``a`` as a C-contiguous ndarray in native byte order (no copy when it already is
    one)."""
    a = np.asarray(a)
    if a.dtype.byteorder not in ("=", "|"):
        a = a.astype(a.dtype.newbyteorder("="))
    return np.ascontiguousarray(a)


def _bytes(b: Any) -> Union[bytes, np.ndarray]:
    """Encoded data as ``bytes`` or a 1-D uint8 view (no copy of buffers)."""
    if isinstance(b, bytes):
        return b
    return np.frombuffer(memoryview(b).cast("B"), dtype=np.uint8)


def _count(name: str, value: Any) -> int:
    """``value`` as a non-negative ``int``; a negative one raises :class:`MraError` (a
    ``ValueError``, as the library's own range errors) rather than the ``OverflowError``
    of its conversion to an unsigned size."""
    n = int(value)
    if n < 0:
        raise MraError(f"invalid {name}: {n} (expected an integer ≥ 0)")
    return n


def _rate_of(
    *,
    lossless: Optional[bool] = None,
    max_error: Optional[float] = None,
    psnr: Optional[float] = None,
    bpp: Optional[float] = None,
    quality: Optional[float] = None,
    keep: Optional[float] = None,
    threshold: Optional[float] = None,
) -> Tuple[str, Optional[float]]:
    """The one rate mode given as keywords, as ``(mode, value)``; ``("quality", 50)``
    when none is given."""
    given = {
        k: v
        for k, v in (
            ("max_error", max_error),
            ("psnr", psnr),
            ("bpp", bpp),
            ("quality", quality),
            ("keep", keep),
            ("threshold", threshold),
        )
        if v is not None
    }
    if lossless:
        given["lossless"] = None
    if len(given) > 1:
        raise MraError(
            f"invalid rate: {', '.join(sorted(given))} "
            f"(expected one of {', '.join(RATE_MODES)})"
        )
    if not given:
        return ("quality", 50.0)
    mode, value = next(iter(given.items()))
    return (mode, None if value is None else float(value))


def encode(
    a: Any,
    *,
    lossless: Optional[bool] = None,
    max_error: Optional[float] = None,
    psnr: Optional[float] = None,
    bpp: Optional[float] = None,
    quality: Optional[float] = None,
    keep: Optional[float] = None,
    threshold: Optional[float] = None,
    data_range: Optional[float] = None,
    scheme: str = "cdf97",
    boundary: str = "symmetric",
    levels: int = 6,
    channels_last: bool = False,
    tile: Optional[Sequence[int]] = None,
    format: int = 3,
    effort: int = _mra.DEFAULT_EFFORT,
) -> bytes:
    """Encode ``a`` into the bytes of an ``.mra`` file (the ``mra encode`` format).

    Rate, one of: ``lossless=True`` (bit-exact), ``max_error=E`` (every decoded sample
    within E), ``psnr=DB`` (smallest file reaching it, as :func:`compare` measures; the
    peak-to-peak ``data_range`` may be given), ``bpp=B`` (largest file within B bits
    per position), ``quality=Q`` (1..100, step ``(max − min)·2^(−Q/10)``; the default,
    50), ``keep=P`` (largest P % of details), ``threshold=T``.

    ``tile`` cuts the array into tiles of these extents (one per spatial axis, NumPy
    order), each coded on its own at one quality for the whole array, so that
    ``decode(..., region=)`` reads only the tiles a block meets. Without it, arrays up
    to 2^24 positions or 2^26 samples are one tile, larger ones tiles of 1024² (2-D)
    or 128³ (3-D).

    ``format`` is that of a one-piece file: 3 (the default, every band cut into
    independent code-blocks) or 2 (one stream per band, for readers older than format
    3). Tiled files are format 2 either way.

    ``effort`` (1..9, as ``mra encode --effort``) trades speed for size: 1–3 code the
    blocks with the HT-style coder (format 3.1, about 4× faster decode for 7–10% more
    bits) without rate–distortion optimisation, 4–6 with it and the adaptive quad coder
    (format 3.2, between the two in bits and speed; ``lossless=True`` keeps the context
    coder), 7–9 with the adaptive context coder. The default is the library's
    (``mra._mra.DEFAULT_EFFORT``, 4).
    """
    mode, value = _rate_of(
        lossless=lossless,
        max_error=max_error,
        psnr=psnr,
        bpp=bpp,
        quality=quality,
        keep=keep,
        threshold=threshold,
    )
    if data_range is not None and mode != "psnr":
        raise MraError(f"invalid data_range: {data_range} (expected only with psnr=)")
    return _mra.encode(
        _array(a),
        mode,
        0.0 if value is None else value,
        None if data_range is None else float(data_range),
        scheme,
        boundary,
        _count("levels", levels),
        bool(channels_last),
        None if tile is None else [_count("tile", t) for t in tile],
        _count("format", format),
        int(effort),
    )


Region = Sequence[Union[slice, Tuple[int, int]]]


def _ranges(region: Region, shape: Sequence[int]) -> List[Tuple[int, int]]:
    """``region`` as one ``(start, stop)`` per axis of ``shape`` (axes it leaves out
    whole): a ``slice`` or ``(start, stop)`` pair per leading (spatial) axis, ends
    excluded, steps of 1, inside the array."""
    region = tuple(region)
    if len(region) > len(shape):
        raise MraError(
            f"invalid region: {len(region)} axes for shape {tuple(shape)} "
            "(expected at most one per spatial axis)"
        )
    out = []
    for axis, n in enumerate(shape):
        r = region[axis] if axis < len(region) else slice(None)
        if isinstance(r, slice):
            if r.step not in (None, 1):
                raise MraError(f"invalid region: step {r.step} on axis {axis} (expected 1)")
            start, stop = r.start, r.stop
        else:
            start, stop = r
        start = 0 if start is None else int(start)
        stop = n if stop is None else int(stop)
        if not 0 <= start < stop <= n:
            raise MraError(
                f"invalid region: {start}..{stop} on axis {axis} of length {n} "
                f"(expected 0 <= start < stop <= {n})"
            )
        out.append((start, stop))
    return out


def decode(
    b: Any,
    level: Optional[int] = None,
    region: Optional[Region] = None,
    *,
    allow_truncated: bool = False,
) -> np.ndarray:
    """Decode ``.mra`` bytes (``bytes`` or any buffer) into an array of the encoded type.

    ``level=k`` reconstructs at 1/2^k resolution from the coarse chunks only.
    ``region`` decodes one block: a ``slice`` or ``(start, stop)`` per spatial axis,
    in the coordinates of the decoded level. At full resolution a tiled file (see
    ``tile=`` in :func:`encode`) is read only where its tiles meet the block; at a
    coarser level the level is decoded whole, then cropped. ``allow_truncated``
    decodes what a cut file holds.
    """
    data = _bytes(b)
    level = _count("level", level or 0)
    if region is None:
        return _mra.decode(data, level, bool(allow_truncated))
    if level == 0:
        dims = _mra.dims(data)
        return _mra.decode(data, 0, bool(allow_truncated), _ranges(region, dims))
    out = _mra.decode(data, level, bool(allow_truncated))
    index = tuple(slice(a, b) for a, b in _ranges(region, out.shape))
    return np.ascontiguousarray(out[index])


def info(b: Any) -> Dict[str, Any]:
    """The header and chunk table of ``.mra`` bytes (the ``mra info --json`` object)."""
    return json.loads(_mra.info(_bytes(b)))


def _axes(axes: Optional[Sequence[int]], ndim: int) -> Optional[List[int]]:
    """NumPy axes (negative allowed) as indices into the first ``ndim`` axes."""
    if axes is None:
        return None
    out = []
    for ax in axes:
        ax = int(ax)
        if not -ndim <= ax < ndim:
            raise MraError(f"invalid axes: {ax} (expected an axis of {ndim} spatial axes)")
        out.append(ax % ndim)
    return out


@dataclass
class Decomposition:
    """A pyramid of :func:`analyze`: the coarse block and the details.

    ``details[0]`` holds the coarsest level's detail blocks and ``details[-1]`` the
    finest; each is a dict keyed by one letter per transformed axis, ``'a'`` (coarse,
    low-pass) or ``'d'`` (details, high-pass), as ``pywt.wavedecn`` names them.
    ``coefficients`` is the whole pyramid in place (Mallat layout: coarse block at the
    origin). :func:`synthesize` reads ``coarse`` and ``details``, so editing them
    (thresholding details, say) edits the reconstruction.
    """

    coarse: np.ndarray
    details: List[Dict[str, np.ndarray]]
    coefficients: np.ndarray
    scheme: str
    boundary: str
    levels: int
    axes: List[int]
    lengths: List[List[int]] = field(repr=False)
    blocks: List[Tuple[int, str, Tuple[slice, ...]]] = field(repr=False)


def analyze(
    a: Any,
    scheme: str = "cdf97",
    boundary: str = "symmetric",
    levels: int = 6,
    axes: Optional[Sequence[int]] = None,
) -> Decomposition:
    """Decompose ``a`` over ``axes`` (default all) into coarse + details, ``levels``
    times (each axis does what its length allows), non-standard (Mallat) order.
    float32 stays float32; other types are computed in float64."""
    a = _array(a)
    if a.dtype != np.float32:
        a = a.astype(np.float64)
    ax = _axes(axes, a.ndim)
    ax = list(range(a.ndim)) if ax is None else ax
    coeffs, lengths, raw_blocks = _mra.analyze(
        a, scheme, boundary, _count("levels", levels), ax
    )
    depth = max((len(v) - 1 for v in lengths), default=0)
    details: List[Dict[str, np.ndarray]] = [dict() for _ in range(depth)]
    blocks = []
    coarse = coeffs
    for level, high, ranges in raw_blocks:
        key = "".join("d" if h else "a" for h in high)
        index = tuple(slice(s, e) for s, e in ranges)
        blocks.append((level, key, index))
        block = coeffs[index].copy()
        if level == 0:
            coarse = block
        else:
            details[depth - level][key] = block
    return Decomposition(
        coarse=coarse,
        details=details,
        coefficients=coeffs,
        scheme=scheme,
        boundary=boundary,
        levels=int(levels),
        axes=ax,
        lengths=lengths,
        blocks=blocks,
    )


def synthesize(d: Decomposition) -> np.ndarray:
    """Invert :func:`analyze`: the samples (float32 or float64) from ``d.coarse`` and
    ``d.details``."""
    c = np.empty_like(d.coefficients)
    depth = len(d.details)
    for level, key, index in d.blocks:
        block = d.coarse if level == 0 else d.details[depth - level][key]
        c[index] = block
    return _mra.synthesize(c, d.scheme, d.boundary, d.levels, list(d.axes))


def upscale(
    a: Any,
    factor: Optional[int] = 2,
    *,
    size: Optional[Sequence[int]] = None,
    axes: Optional[Sequence[int]] = None,
    scheme: str = "chaikin",
    mode: str = "area",
    edge: str = "linear",
    clamp: str = "auto",
    order: Optional[int] = None,
    channels_last: bool = False,
) -> np.ndarray:
    """Upscale by an integer ``factor`` along ``axes`` (default every spatial axis), or
    to ``size`` (one length per spatial axis, slowest first), as ``mra upscale``.
    Schemes: box, linear, chaikin, cubic, quartic, four-point; modes: area (cell means
    kept), interpolate (through the samples), control (plain subdivision)."""
    a = _array(a)
    nsp = a.ndim - 1 if channels_last else a.ndim
    return _mra.upscale(
        a,
        None if size is not None else (None if factor is None else _count("factor", factor)),
        None if size is None else [_count("size", n) for n in size],
        _axes(axes, nsp),
        scheme,
        mode,
        edge,
        clamp,
        None if order is None else _count("order", order),
        bool(channels_last),
    )


def downscale(
    a: Any,
    levels: int = 1,
    *,
    axes: Optional[Sequence[int]] = None,
    scheme: str = "chaikin-wide",
    boundary: str = "symmetric",
    channels_last: bool = False,
) -> np.ndarray:
    """Reduce resolution ``levels`` times along ``axes`` (default every spatial axis)
    by the scheme's analysis filter ``C = A F``, keeping the sample type, as
    ``mra downscale``."""
    a = _array(a)
    nsp = a.ndim - 1 if channels_last else a.ndim
    return _mra.downscale(
        a,
        _count("levels", levels),
        _axes(axes, nsp),
        scheme,
        boundary,
        bool(channels_last),
    )


def compare(
    a: Any,
    b: Any,
    *,
    data_range: Optional[float] = None,
    convention: str = "skimage",
    channels_last: bool = False,
) -> Dict[str, Any]:
    """MSE, PSNR, max |a − b| and SSIM of test ``b`` against reference ``a``: the
    ``mra compare --json`` object (``dims`` fastest axis first, as ``axis_order``
    says; ``psnr`` None when identical, ``ssim`` None when a side is shorter than 7)."""
    return json.loads(
        _mra.compare(
            _array(a),
            _array(b),
            None if data_range is None else float(data_range),
            convention,
            bool(channels_last),
        )
    )
