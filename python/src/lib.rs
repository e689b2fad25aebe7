//! `mra._mra`: the Rust half of the Python package. NumPy arrays in and out of the
//! codec ([`mra::codec`]), the pyramid ([`mra::tensor`]), the upscaler
//! ([`mra::upscale`], `up` here) and the metrics ([`mra::metrics`]).
//!
//! Conventions (the pure-Python layer `mra/__init__.py` parses keywords and calls these):
//!
//! * An array's axes are spatial, slowest first (`[H, W]`, `[D, H, W]`), 1 to 3 of them;
//!   with `channels_last` the last axis holds the channels (interleaved samples, never
//!   transformed). A result has a channel axis when it has more than one channel.
//! * Inputs are borrowed read-only: a C-contiguous array's samples are read where they
//!   are ([`RasterView`]); other layouts are gathered once in C order. `encode` and
//!   `compare` make no copy; `upscale`/`downscale` convert the samples once to their f32
//!   working buffer and `analyze`/`synthesize` copy them once into their result, on
//!   which the transform runs in place. Do not write to an array while a call reads it
//!   (the GIL is released).
//! * Every call that transforms, codes or measures runs with the GIL released.
//! * A library error becomes `MraError` (a `ValueError`) carrying the library's one-line
//!   message "what … (expected …)"; an operating-system error becomes `OSError`.
//!   A panic inside the library is caught at this boundary and raised as `MraError`
//!   starting "internal error", so that no input can take the interpreter down.

use std::borrow::Cow;
use std::panic::{catch_unwind, AssertUnwindSafe};

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::{DataKind, Metadata, Raster, RasterView, Samples, SamplesRef};
use mra::metrics::{self, CompareOptions, Convention};
use mra::progress::Progress;
use mra::scheme::subdivide::Refinement;
use mra::scheme::{Boundary, Scheme};
use mra::tensor::{self, Order, Pyramid, PyramidSpec};
use mra::upscale::{self as up, Clamp, Edge, Method, Mode};
use mra::{Error, ErrorKind};
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{
    Element, IntoPyArray, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyOSError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

pyo3::create_exception!(
    _mra,
    MraError,
    PyValueError,
    "An error reported by the mra library: bad parameters, malformed or truncated bytes, \
     unsupported input or a size over the memory budget. The message is the library's \
     one line, \"what … (expected …)\"."
);

/// The `mra compare --json` object's `axis_order` (dims are listed fastest axis first).
const AXIS_ORDER: &str = "x, y, z (fastest first)";

/// The library's error as a Python exception.
fn py_err(e: Error) -> PyErr {
    match e.kind() {
        ErrorKind::Io => PyOSError::new_err(e.to_string()),
        _ => MraError::new_err(e.to_string()),
    }
}

/// Run `f` with the GIL released; a panic becomes `MraError` ("internal error in …").
fn run<T: Send>(
    py: Python<'_>,
    what: &'static str,
    f: impl FnOnce() -> mra::Result<T> + Send,
) -> PyResult<T> {
    py.detach(|| catch_unwind(AssertUnwindSafe(f)))
        .map_err(|p| {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            MraError::new_err(format!(
                "internal error in {what}: {msg} (expected no panic)"
            ))
        })?
        .map_err(py_err)
}

fn parse<T: std::str::FromStr<Err = Error>>(s: &str) -> PyResult<T> {
    s.parse().map_err(py_err)
}

/// Samples borrowed from a NumPy array (or gathered from a non-contiguous one).
enum Input<'a> {
    U8(Cow<'a, [u8]>),
    I8(Cow<'a, [i8]>),
    U16(Cow<'a, [u16]>),
    I16(Cow<'a, [i16]>),
    U32(Cow<'a, [u32]>),
    I32(Cow<'a, [i32]>),
    F32(Cow<'a, [f32]>),
    F64(Cow<'a, [f64]>),
}

impl Input<'_> {
    /// The samples, borrowed.
    fn view(&self) -> SamplesRef<'_> {
        match self {
            Input::U8(c) => SamplesRef::U8(c),
            Input::I8(c) => SamplesRef::I8(c),
            Input::U16(c) => SamplesRef::U16(c),
            Input::I16(c) => SamplesRef::I16(c),
            Input::U32(c) => SamplesRef::U32(c),
            Input::I32(c) => SamplesRef::I32(c),
            Input::F32(c) => SamplesRef::F32(c),
            Input::F64(c) => SamplesRef::F64(c),
        }
    }
}

const DTYPES: &str = "one of uint8, int8, uint16, int16, uint32, int32, float32, float64";

/// Call `f` with the samples of array `a` borrowed read-only and its shape.
fn with_input<R>(
    a: &Bound<'_, PyAny>,
    f: impl for<'a> FnOnce(Input<'a>, Vec<usize>) -> PyResult<R>,
) -> PyResult<R> {
    macro_rules! try_type {
        ($t:ty, $v:ident) => {
            if let Ok(arr) = a.cast::<PyArrayDyn<$t>>() {
                let ro = arr
                    .try_readonly()
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                let shape = ro.shape().to_vec();
                // `as_slice` also accepts Fortran order (memory order ≠ C order)
                let cow = match ro.as_slice() {
                    Ok(s) if ro.is_c_contiguous() => Cow::Borrowed(s),
                    _ => Cow::Owned(ro.as_array().iter().copied().collect()),
                };
                return f(Input::$v(cow), shape);
            }
        };
    }
    try_type!(u8, U8);
    try_type!(i8, I8);
    try_type!(u16, U16);
    try_type!(i16, I16);
    try_type!(u32, U32);
    try_type!(i32, I32);
    try_type!(f32, F32);
    try_type!(f64, F64);
    let dtype = match a.cast::<PyUntypedArray>() {
        Ok(u) => u.dtype().to_string(),
        Err(_) => a.get_type().name()?.to_string(),
    };
    Err(PyTypeError::new_err(format!(
        "unsupported array type: {dtype} (expected {DTYPES} in native byte order)"
    )))
}

/// Spatial dims and channels of an array of `shape`.
fn layout(shape: &[usize], channels_last: bool) -> mra::Result<(Vec<usize>, usize)> {
    let (dims, channels) = match (channels_last, shape.split_last()) {
        (true, Some((&c, dims))) => (dims.to_vec(), c),
        _ => (shape.to_vec(), 1),
    };
    if !(1..=3).contains(&dims.len()) {
        return Err(Error::parameter(
            "spatial axes",
            format!("{} (array shape {shape:?})", dims.len()),
            "1 to 3, plus a last channel axis with channels_last=True",
        ));
    }
    Ok((dims, channels))
}

/// The kind of data an array of `dims` holds.
fn kind_of(dims: &[usize]) -> DataKind {
    if dims.len() == 3 {
        DataKind::Volume
    } else {
        DataKind::Image
    }
}

/// A borrowed raster over the array's samples (no copy); `dims` from [`layout`].
fn view<'a>(
    input: &'a Input<'_>,
    dims: &'a [usize],
    channels: usize,
    meta: &'a Metadata,
) -> mra::Result<RasterView<'a>> {
    RasterView::new(dims, channels, input.view(), kind_of(dims), meta)
}

fn nd<'py, T: Element>(py: Python<'py>, shape: &[usize], v: Vec<T>) -> PyResult<Bound<'py, PyAny>> {
    let a = ArrayD::from_shape_vec(IxDyn(shape), v)
        .map_err(|e| MraError::new_err(format!("{e} (expected samples for shape {shape:?})")))?;
    Ok(a.into_pyarray(py).into_any())
}

/// A raster as an array (moved, not copied): shape `dims`, plus `[channels]` when more
/// than one. f16 samples come back as float32.
fn array_of(py: Python<'_>, r: Raster) -> PyResult<Bound<'_, PyAny>> {
    let mut shape = r.dims.clone();
    if r.channels > 1 {
        shape.push(r.channels);
    }
    match r.samples {
        Samples::U8(v) => nd(py, &shape, v),
        Samples::I8(v) => nd(py, &shape, v),
        Samples::U16(v) => nd(py, &shape, v),
        Samples::I16(v) => nd(py, &shape, v),
        Samples::U32(v) => nd(py, &shape, v),
        Samples::I32(v) => nd(py, &shape, v),
        Samples::F16(v) => nd(py, &shape, v.iter().map(|x| x.to_f32()).collect()),
        Samples::F32(v) => nd(py, &shape, v),
        Samples::F64(v) => nd(py, &shape, v),
    }
}

/// The rate mode named `kind` with `value` (`data_range` for `psnr` only).
fn rate(kind: &str, value: f64, data_range: Option<f64>) -> PyResult<Rate> {
    Ok(match kind {
        "keep" => Rate::Keep(value),
        "threshold" => Rate::Threshold(value),
        "quality" => Rate::Quality(value),
        "psnr" => match data_range {
            Some(r) => Rate::PsnrRange(value, r),
            None => Rate::Psnr(value),
        },
        "bpp" => Rate::Bpp(value),
        "max_error" => Rate::MaxError(value),
        "lossless" => Rate::Lossless,
        _ => {
            return Err(py_err(Error::parameter(
                "rate",
                kind,
                "keep, threshold, quality, psnr, bpp, max_error or lossless",
            )))
        }
    })
}

/// Encode an array into the bytes of an `.mra` file.
#[pyfunction]
#[pyo3(signature = (a, rate_kind, value, data_range, scheme, boundary, levels, channels_last, tile=None, format=3, effort=None))]
#[allow(clippy::too_many_arguments)]
fn encode<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    rate_kind: &str,
    value: f64,
    data_range: Option<f64>,
    scheme: &str,
    boundary: &str,
    levels: usize,
    channels_last: bool,
    tile: Option<Vec<usize>>,
    format: usize,
    effort: Option<i64>,
) -> PyResult<Bound<'py, PyBytes>> {
    let opts = EncodeOptions {
        scheme: parse::<Scheme>(scheme)?,
        boundary: parse::<Boundary>(boundary)?,
        levels,
        rate: rate(rate_kind, value, data_range)?,
        format: codec::Format::of_major(format).map_err(py_err)?,
        // out of u8's range: 255, which the library refuses as it refuses 0 or 10
        effort: effort.map_or(codec::DEFAULT_EFFORT, |e| e.clamp(0, 255) as u8),
    };
    let bytes = with_input(a, |input, shape| {
        run(py, "encode", || {
            let (dims, channels) = layout(&shape, channels_last)?;
            let meta = Metadata::default();
            let r = view(&input, &dims, channels, &meta)?;
            match &tile {
                None => codec::encode_view(&r, &opts),
                Some(t) => {
                    if t.len() != r.dims.len() || t.contains(&0) {
                        return Err(Error::parameter(
                            "tile",
                            format!("{t:?} for spatial shape {:?}", r.dims),
                            "one extent of at least 1 per spatial axis",
                        ));
                    }
                    // a tile larger than the axis is the whole axis
                    let t: Vec<usize> = t.iter().zip(r.dims).map(|(&t, &d)| t.min(d)).collect();
                    codec::encode_tiled_view(&r, &opts, &t)
                }
            }
        })
    })?;
    Ok(PyBytes::new(py, &bytes))
}

/// The bytes of `data`: a `bytes` object, or a 1-D uint8 array (e.g. `np.frombuffer`).
fn with_bytes<R>(
    data: &Bound<'_, PyAny>,
    f: impl for<'a> FnOnce(&'a [u8]) -> PyResult<R>,
) -> PyResult<R> {
    if let Ok(b) = data.cast::<PyBytes>() {
        return f(b.as_bytes());
    }
    if let Ok(arr) = data.cast::<numpy::PyArray1<u8>>() {
        let ro = arr
            .try_readonly()
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        if let Ok(s) = ro.as_slice() {
            return f(s);
        }
        let v: Vec<u8> = ro.as_array().iter().copied().collect();
        return f(&v);
    }
    Err(PyTypeError::new_err(format!(
        "unsupported encoded data: {} (expected bytes or a 1-D uint8 array)",
        data.get_type().name()?
    )))
}

/// Decode `.mra` bytes at resolution level `level` (0 = full); with `region` (one
/// `(start, stop)` per spatial axis, slowest first, full-resolution samples) only that box,
/// reading only the tiles it meets.
#[pyfunction]
#[pyo3(signature = (data, level=0, allow_truncated=false, region=None))]
fn decode<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    level: usize,
    allow_truncated: bool,
    region: Option<Vec<(usize, usize)>>,
) -> PyResult<Bound<'py, PyAny>> {
    let r = with_bytes(data, |bytes| {
        run(py, "decode", || {
            // a level the file does not hold is the library's error (Error::Level)
            let opts = DecodeOptions {
                level,
                allow_truncated,
                // slowest axis first, as NumPy and the library
                region: region
                    .as_ref()
                    .map(|r| r.iter().map(|&(a, b)| a..b).collect()),
            };
            Ok(codec::decode(bytes, &opts)?.raster)
        })
    })?;
    array_of(py, r)
}

/// The spatial extents of `.mra` bytes (slowest axis first), from their `HEAD` alone.
#[pyfunction]
fn dims(py: Python<'_>, data: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    with_bytes(data, |bytes| {
        run(py, "dims", || Ok(codec::header_of(bytes)?.dims))
    })
}

/// The `mra info --json` object of `.mra` bytes, as JSON text.
#[pyfunction]
fn info(py: Python<'_>, data: &Bound<'_, PyAny>) -> PyResult<String> {
    let i = with_bytes(data, |bytes| run(py, "info", || codec::info(bytes)))?;
    serde_json::to_string(&i).map_err(|e| MraError::new_err(e.to_string()))
}

/// Coefficient blocks of a pyramid: `(level, high per transformed axis, [(start, stop)]
/// per array axis)`, coarse block first.
type Blocks = Vec<(usize, Vec<bool>, Vec<(usize, usize)>)>;

/// The non-standard pyramid over `axes` that [`analyze`] and [`synthesize`] share, its
/// scheme and boundary parsed from their names.
fn nonstandard_spec(
    scheme: &str,
    boundary: &str,
    levels: usize,
    axes: Vec<usize>,
) -> PyResult<PyramidSpec> {
    Ok(PyramidSpec {
        scheme: parse(scheme)?,
        boundary: parse(boundary)?,
        levels,
        order: Order::NonStandard,
        axes,
    })
}

/// Decompose a float array (Mallat layout, in a new array of the same type and shape)
/// over `axes`; returns the coefficients, every axis' lane lengths level by level and the
/// blocks.
#[pyfunction]
#[pyo3(signature = (a, scheme, boundary, levels, axes))]
fn analyze<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    scheme: &str,
    boundary: &str,
    levels: usize,
    axes: Vec<usize>,
) -> PyResult<(Bound<'py, PyAny>, Vec<Vec<usize>>, Blocks)> {
    let spec = nonstandard_spec(scheme, boundary, levels, axes)?;
    macro_rules! go {
        ($c:expr, $shape:expr) => {{
            let shape = $shape;
            let (data, pyr) = run(py, "analyze", || {
                let mut arr = tensor::Array::from_shape_vec(&shape, $c.into_owned())?;
                let pyr = tensor::analyze(&mut arr, &spec)?;
                Ok((arr.into_data(), pyr))
            })?;
            (nd(py, &shape, data)?, pyr)
        }};
    }
    let (out, pyr) = with_input(a, |input, shape| {
        Ok(match input {
            Input::F32(c) => go!(c, shape),
            Input::F64(c) => go!(c, shape),
            _ => {
                return Err(PyTypeError::new_err(
                    "analyze takes float32 or float64 arrays (expected a float array)",
                ))
            }
        })
    })?;
    let blocks = pyr
        .subbands()
        .into_iter()
        .map(|s| {
            let r = s.ranges.iter().map(|r| (r.start, r.end)).collect();
            (s.level, s.high, r)
        })
        .collect();
    Ok((out, pyr.lengths, blocks))
}

/// Invert [`analyze`]: coefficients in Mallat layout back to samples (same type).
#[pyfunction]
#[pyo3(signature = (c, scheme, boundary, levels, axes))]
fn synthesize<'py>(
    py: Python<'py>,
    c: &Bound<'py, PyAny>,
    scheme: &str,
    boundary: &str,
    levels: usize,
    axes: Vec<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let spec = nonstandard_spec(scheme, boundary, levels, axes)?;
    macro_rules! go {
        ($c:expr, $shape:expr) => {{
            let shape = $shape;
            let data = run(py, "synthesize", || {
                let mut arr = tensor::Array::from_shape_vec(&shape, $c.into_owned())?;
                let pyr = Pyramid::plan(&shape, &spec)?;
                tensor::synthesize(&mut arr, &pyr)?;
                Ok(arr.into_data())
            })?;
            nd(py, &shape, data)?
        }};
    }
    with_input(c, |input, shape| {
        Ok(match input {
            Input::F32(c) => go!(c, shape),
            Input::F64(c) => go!(c, shape),
            _ => {
                return Err(PyTypeError::new_err(
                    "synthesize takes float32 or float64 coefficients (expected a float array)",
                ))
            }
        })
    })
}

/// Upscale by `factor` along `axes` (or to `size`, one length per spatial axis).
#[pyfunction]
#[pyo3(signature = (a, factor, size, axes, scheme, mode, edge, clamp, order, channels_last))]
#[allow(clippy::too_many_arguments)]
fn upscale<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    factor: Option<usize>,
    size: Option<Vec<usize>>,
    axes: Option<Vec<usize>>,
    scheme: &str,
    mode: &str,
    edge: &str,
    clamp: &str,
    order: Option<usize>,
    channels_last: bool,
) -> PyResult<Bound<'py, PyAny>> {
    if let Some(k) = order {
        if !(1..=12).contains(&k) {
            return Err(py_err(Error::parameter("order", k, "1 to 12")));
        }
    }
    let method = Method {
        rule: parse::<Refinement>(scheme)?,
        mode: parse::<Mode>(mode)?,
        edge: parse::<Edge>(edge)?,
        order,
        clamp: parse::<Clamp>(clamp)?,
    };
    let r = with_input(a, |input, shape| {
        run(py, "upscale", || {
            let (dims, channels) = layout(&shape, channels_last)?;
            let meta = Metadata::default();
            let r = view(&input, &dims, channels, &meta)?;
            let axes = axes.unwrap_or_else(|| (0..r.dims.len()).collect());
            let plans = up::plan_raster(r.dims, &axes, factor, size.as_deref(), false)?;
            // the library checks the memory budget before anything is allocated
            up::upscale_view(&r, &method, &plans, &Progress::hidden())
        })
    })?;
    array_of(py, r)
}

/// Downscale `levels` times along `axes` by the scheme's analysis filter `A`.
#[pyfunction]
#[pyo3(signature = (a, levels, axes, scheme, boundary, channels_last))]
fn downscale<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    levels: usize,
    axes: Option<Vec<usize>>,
    scheme: &str,
    boundary: &str,
    channels_last: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let scheme = parse::<Scheme>(scheme)?;
    let boundary = parse::<Boundary>(boundary)?;
    let r = with_input(a, |input, shape| {
        run(py, "downscale", || {
            let (dims, channels) = layout(&shape, channels_last)?;
            let meta = Metadata::default();
            let r = view(&input, &dims, channels, &meta)?;
            let axes = axes.unwrap_or_else(|| (0..r.dims.len()).collect());
            up::downscale_view(&r, scheme, boundary, levels, &axes)
        })
    })?;
    array_of(py, r)
}

/// The `mra compare --json` object of reference `a` and test `b`, as JSON text.
#[pyfunction]
#[pyo3(signature = (a, b, data_range, convention, channels_last))]
fn compare(
    py: Python<'_>,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    data_range: Option<f64>,
    convention: &str,
    channels_last: bool,
) -> PyResult<String> {
    let opts = CompareOptions {
        data_range,
        convention: match convention {
            "skimage" => Convention::Skimage,
            "oiio" => Convention::Oiio,
            _ => {
                return Err(py_err(Error::parameter(
                    "convention",
                    convention,
                    "skimage or oiio",
                )))
            }
        },
    };
    let m = with_input(a, |ia, sa| {
        with_input(b, |ib, sb| {
            run(py, "compare", || {
                let meta = Metadata::default();
                let (da, ca) = layout(&sa, channels_last)?;
                let (db, cb) = layout(&sb, channels_last)?;
                let ra = view(&ia, &da, ca, &meta)?;
                let rb = view(&ib, &db, cb, &meta)?;
                metrics::compare_view(&ra, &rb, &opts)
            })
        })
    })?;
    let mut v = serde_json::to_value(&m).map_err(|e| MraError::new_err(e.to_string()))?;
    if let Some(d) = v.get_mut("dims").and_then(|d| d.as_array_mut()) {
        d.reverse();
    }
    v["axis_order"] = AXIS_ORDER.into();
    Ok(v.to_string())
}

#[pymodule]
fn _mra(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MraError", m.py().get_type::<MraError>())?;
    // the library's default effort: Python's `encode(effort=)` has no default of its own
    m.add("DEFAULT_EFFORT", codec::DEFAULT_EFFORT)?;
    m.add_function(wrap_pyfunction!(encode, m)?)?;
    m.add_function(wrap_pyfunction!(decode, m)?)?;
    m.add_function(wrap_pyfunction!(info, m)?)?;
    m.add_function(wrap_pyfunction!(dims, m)?)?;
    m.add_function(wrap_pyfunction!(analyze, m)?)?;
    m.add_function(wrap_pyfunction!(synthesize, m)?)?;
    m.add_function(wrap_pyfunction!(upscale, m)?)?;
    m.add_function(wrap_pyfunction!(downscale, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    Ok(())
}
