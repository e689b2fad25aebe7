//! Comparison of two rasters of the same shape: MSE, PSNR, maximum absolute error and
//! SSIM, following scikit-image (`skimage.metrics`, checked against 0.26) or
//! OpenImageIO (`ImageBufAlgo.compare`, 3.x), see [`Convention`].
//!
//! Definitions (N = all samples of all channels, a = reference, b = test):
//!
//! * `MSE = (1/N) Σ (a − b)²`, in the data's own units. As in scikit-image, f16/f32 data
//!   is differenced and squared in f32 and summed in f64; integer data in f64.
//! * `PSNR = 10 log10(R² / MSE)` dB, `None` when MSE = 0 (identical inputs).
//! * `max_abs_error = max |a − b|`.
//! * SSIM (Wang et al. 2004, scikit-image defaults): a uniform 7 × 7 (× 7 for volumes)
//!   window, `K1 = 0.01`, `K2 = 0.03`, `C1 = (K1 R)²`, `C2 = (K2 R)²`, sample covariances
//!   (`NP/(NP−1)`, `NP = 7^d`), the map
//!   `S = (2 μa μb + C1)(2 σab + C2) / ((μa² + μb² + C1)(σa² + σb² + C2))`
//!   averaged over the positions whose window lies inside the data (scikit-image crops
//!   3 samples at every border), then over channels. `None` when a side is shorter
//!   than 7.
//!
//! Void samples (NaN, or either raster's `meta.nodata`) are left out: N counts the
//! positions valid in both, and for the SSIM windows both rasters take the reference's
//! pull-push fill at every void position ([`crate::io::nodata`]), so a void never
//! enters a filter and contributes no error.

use rayon::prelude::*;
use serde::Serialize;

use crate::io::{Raster, RasterView, SampleType, Samples, SamplesRef};
use crate::{Error, Result};

/// Whose definition of the data range R (and so of PSNR) to follow.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Convention {
    /// `skimage.metrics.peak_signal_noise_ratio`: R = `--data-range`, else from the
    /// reference's dtype: integer types R = dtype max when the reference has no negative
    /// value, else dtype max − dtype min (u8 255, u16 65535, i16 32767 or 65535); floats
    /// R = 1 for data in [0, 1], 2 for data in [−1, 1]. Outside [−1, 1] scikit-image
    /// raises; mra uses max(a) − min(a) instead and reports it. SSIM uses the same R when
    /// it was given or the data is float, else dtype max − dtype min (scikit-image's
    /// `structural_similarity` default).
    #[default]
    Skimage,
    /// `ImageBufAlgo.compare` / `oiiotool --diff`: samples are converted to float the way
    /// OpenImageIO reads them (u8 /255, u16 /65535, u32 /(2³²−1), i8 /127, i16 /32767,
    /// i32 /(2³¹−1), floats unchanged), then `PSNR = 20 log10(peak / RMS)` with
    /// `peak = max(1, largest value of either input)` and RMS over all samples. In the
    /// data's own units this is R = peak × that divisor (255 for u8, 1 for floats in
    /// [0, 1], the maximum for HDR floats); `--data-range R` replaces it by
    /// `10 log10(R² / MSE)`.
    Oiio,
}

/// Options for [`compare`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CompareOptions {
    /// Override the data range R.
    pub data_range: Option<f64>,
    pub convention: Convention,
}

/// The result of [`compare`]; serialises to the `mra compare --json` object.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    pub mse: f64,
    /// `None` (JSON null) when the inputs are identical.
    pub psnr: Option<f64>,
    pub max_abs_error: f64,
    pub ssim: Option<f64>,
    pub data_range: f64,
    pub convention: &'static str,
    pub dims: Vec<usize>,
    pub channels: usize,
    pub dtype: &'static str,
}

/// scikit-image's default PSNR data range for reference samples `a` (see [`Convention`]).
pub fn skimage_data_range(a: SamplesRef<'_>) -> f64 {
    let t = a.sample_type();
    let (dmin, dmax) = t.range();
    let (lo, hi) = a.min_max().unwrap_or((0.0, 0.0));
    if t.is_float() && (hi > dmax || lo < dmin) {
        return (hi - lo).max(f64::MIN_POSITIVE);
    }
    if lo >= 0.0 {
        dmax
    } else {
        dmax - dmin
    }
}

/// OpenImageIO's normalising divisor for a sample type (see [`Convention::Oiio`]).
pub fn oiio_scale(t: SampleType) -> f64 {
    match t {
        SampleType::U8 => 255.0,
        SampleType::U16 => 65535.0,
        SampleType::U32 => 4294967295.0,
        SampleType::I8 => 127.0,
        SampleType::I16 => 32767.0,
        SampleType::I32 => 2147483647.0,
        SampleType::F16 | SampleType::F32 | SampleType::F64 => 1.0,
    }
}

/// `Σ (a − b)²` and `max |a − b|`, computed as scikit-image does (see module doc).
fn squared_error(a: SamplesRef<'_>, b: SamplesRef<'_>) -> (f64, f64) {
    let single = matches!(a.sample_type(), SampleType::F16 | SampleType::F32)
        && matches!(b.sample_type(), SampleType::F16 | SampleType::F32);
    let mut sum = 0.0f64;
    let mut max = 0.0f64;
    for i in 0..a.len() {
        let d = if single {
            // both values are exact in f32; difference and square in f32
            let d = a.get_f64(i) as f32 - b.get_f64(i) as f32;
            sum += (d * d) as f64;
            d as f64
        } else {
            let d = a.get_f64(i) - b.get_f64(i);
            sum += d * d;
            d
        };
        max = max.max(d.abs());
    }
    (sum, max)
}

/// A sample as OpenImageIO's float iterator reads it: integers times the f32 constant
/// `1 / scale`, floats cast to f32.
fn oiio_value(s: SamplesRef<'_>, i: usize, inv: f32) -> f32 {
    match s {
        SamplesRef::F16(v) => v[i].to_f32(),
        SamplesRef::F32(v) => v[i],
        SamplesRef::F64(v) => v[i] as f32,
        other => other.get_f64(i) as f32 * inv,
    }
}

/// `(Σ d², peak)` as `ImageBufAlgo.compare` computes them: `d = a − b` and `d²` in f32,
/// summed in f64; `peak = max(1, largest value of a or b)`.
fn oiio_squared_error(a: SamplesRef<'_>, b: SamplesRef<'_>) -> (f64, f64) {
    let ia = (1.0 / oiio_scale(a.sample_type())) as f32;
    let ib = (1.0 / oiio_scale(b.sample_type())) as f32;
    let mut sum = 0.0f64;
    let mut peak = 1.0f32;
    for i in 0..a.len() {
        let x = oiio_value(a, i, ia);
        let y = oiio_value(b, i, ib);
        peak = peak.max(x).max(y);
        let d = x - y;
        sum += (d * d) as f64;
    }
    (sum, peak as f64)
}

/// Compare reference `a` with test `b` (same dims and channels).
pub fn compare(a: &Raster, b: &Raster, opts: &CompareOptions) -> Result<Comparison> {
    compare_view(&a.view(), &b.view(), opts)
}

/// [`compare`] of borrowed rasters (samples read where they are, e.g. NumPy arrays).
pub fn compare_view(
    a: &RasterView<'_>,
    b: &RasterView<'_>,
    opts: &CompareOptions,
) -> Result<Comparison> {
    check_inputs(a, b, opts)?;
    let cleaned = without_voids(a, b)?;
    let (a, b, n) = match &cleaned {
        Some((x, y, n)) => (x.view(), y.view(), *n),
        None => (*a, *b, a.samples.len()),
    };
    let (a, b) = (&a, &b);
    let e = errors(a, b, opts, n)?;
    let ssim_range = match (opts.data_range, opts.convention, a.sample_type().is_float()) {
        (Some(r), _, _) => r,
        (None, Convention::Skimage, false) => {
            let (lo, hi) = a.sample_type().range();
            hi - lo
        }
        _ => e.data_range,
    };
    let ssim = ssim_view(a, b, ssim_range);
    Ok(Comparison {
        mse: e.mse,
        psnr: e.psnr,
        max_abs_error: e.max_abs_error,
        ssim,
        data_range: e.data_range,
        convention: e.convention,
        dims: a.dims.to_vec(),
        channels: a.channels,
        dtype: a.sample_type().name(),
    })
}

/// Equal shapes, and a data range (when given) finite and positive.
fn check_inputs(a: &RasterView<'_>, b: &RasterView<'_>, opts: &CompareOptions) -> Result<()> {
    check_shapes(a, b)?;
    if let Some(r) = opts.data_range {
        if !(r.is_finite() && r > 0.0) {
            return Err(Error::parameter(
                "data range",
                r,
                "a finite peak-to-peak range > 0",
            ));
        }
    }
    Ok(())
}

/// The PSNR of `b` against the reference `a`, exactly as [`compare`] reports it (`None`
/// when identical), without the SSIM: what the encoder's `--psnr` search measures.
pub fn psnr(a: &Raster, b: &Raster, opts: &CompareOptions) -> Result<Option<f64>> {
    psnr_view(&a.view(), &b.view(), opts)
}

/// [`psnr`] of borrowed rasters.
pub fn psnr_view(
    a: &RasterView<'_>,
    b: &RasterView<'_>,
    opts: &CompareOptions,
) -> Result<Option<f64>> {
    check_inputs(a, b, opts)?;
    let cleaned = without_voids(a, b)?;
    let (a, b, n) = match &cleaned {
        Some((x, y, n)) => (x.view(), y.view(), *n),
        None => (*a, *b, a.samples.len()),
    };
    Ok(errors(&a, &b, opts, n)?.psnr)
}

fn check_shapes(a: &RasterView<'_>, b: &RasterView<'_>) -> Result<()> {
    if a.dims != b.dims || a.channels != b.channels {
        return Err(Error::parameter(
            "shapes",
            format!("{} vs {}", view_summary(a), view_summary(b)),
            "two inputs of the same dims and channels",
        ));
    }
    Ok(())
}

/// `a` and `b` with every position void in either replaced by `a`'s pull-push fill
/// (the same value in both), and the number of samples valid in both; `None` when no
/// sample is void.
fn without_voids(
    a: &RasterView<'_>,
    b: &RasterView<'_>,
) -> Result<Option<(Raster, Raster, usize)>> {
    use crate::io::nodata::{is_void, Voids};
    let n = a.samples.len();
    let (na, nb) = (a.meta.nodata, b.meta.nodata);
    let void: Vec<bool> = (0..n)
        .map(|i| is_void(a.samples.get_f64(i), na) || is_void(b.samples.get_f64(i), nb))
        .collect();
    let valid = void.iter().filter(|&&v| !v).count();
    if valid == n {
        return Ok(None);
    }
    let mut va = a.samples.to_f64();
    let voids = Voids {
        mask: void,
        marker: f64::NAN,
        range: (0.0, 0.0),
    };
    let mut shape = a.dims.to_vec();
    shape.push(a.channels);
    voids.fill(&mut va, &shape, a.dims.len())?;
    // in `a`'s type first, so that both sides hold the same value
    let filled = Samples::from_f64(&va, a.sample_type());
    let va = filled.to_f64();
    let mut vb = b.samples.to_f64();
    for (i, &v) in voids.mask.iter().enumerate() {
        if v {
            vb[i] = va[i];
        }
    }
    let x = Raster {
        samples: filled,
        ..raster_shell(a)
    };
    let y = Raster {
        samples: Samples::from_f64(&vb, b.sample_type()),
        ..raster_shell(b)
    };
    Ok(Some((x, y, valid)))
}

/// `r`'s dims, channels, kind and metadata with no samples (to be filled in).
fn raster_shell(r: &RasterView<'_>) -> Raster {
    Raster {
        dims: r.dims.to_vec(),
        channels: r.channels,
        samples: Samples::U8(Vec::new()),
        kind: r.kind,
        meta: r.meta.clone(),
    }
}

/// [`Raster::summary`] of a borrowed raster.
fn view_summary(r: &RasterView<'_>) -> String {
    crate::io::summary(r.dims, r.channels, r.sample_type(), r.kind)
}

/// What [`compare`] reports besides the SSIM.
struct Errors {
    mse: f64,
    psnr: Option<f64>,
    max_abs_error: f64,
    data_range: f64,
    convention: &'static str,
}

/// The errors over `valid` samples (the others contribute none, see [`without_voids`]).
fn errors(
    a: &RasterView<'_>,
    b: &RasterView<'_>,
    opts: &CompareOptions,
    valid: usize,
) -> Result<Errors> {
    check_shapes(a, b)?;
    if a.samples.is_empty() {
        return Err(Error::parameter("input", "empty", "at least one sample"));
    }
    let n = valid.max(1) as f64;
    let (sum, max_abs_error) = squared_error(a.samples, b.samples);
    let mse = sum / n;
    let (data_range, psnr, name) = match opts.convention {
        Convention::Skimage => {
            let r = opts
                .data_range
                .unwrap_or_else(|| skimage_data_range(a.samples));
            let psnr = (mse > 0.0).then(|| 10.0 * (r * r / mse).log10());
            (r, psnr, "skimage")
        }
        Convention::Oiio => match opts.data_range {
            Some(r) => (r, (mse > 0.0).then(|| 10.0 * (r * r / mse).log10()), "oiio"),
            None => {
                let (sq, peak) = oiio_squared_error(a.samples, b.samples);
                let rms = (sq / n).sqrt();
                let psnr = (rms > 0.0).then(|| 20.0 * (peak / rms).log10());
                (peak * oiio_scale(a.sample_type()), psnr, "oiio")
            }
        },
    };
    Ok(Errors {
        mse,
        psnr,
        max_abs_error,
        data_range,
        convention: name,
    })
}

/// Sum over a window of `w` along `axis`, keeping only full windows ("valid").
fn box_valid(data: &[f64], shape: &[usize], axis: usize, w: usize) -> (Vec<f64>, Vec<usize>) {
    let n = shape[axis];
    let m = n + 1 - w;
    let inner: usize = shape[axis + 1..].iter().product();
    let outer: usize = shape[..axis].iter().product();
    let mut out = vec![0.0; outer * m * inner];
    for o in 0..outer {
        for i in 0..inner {
            let at = |k: usize| data[(o * n + k) * inner + i];
            let mut s: f64 = (0..w).map(at).sum();
            out[(o * m) * inner + i] = s;
            for k in 1..m {
                s += at(k + w - 1) - at(k - 1);
                out[(o * m + k) * inner + i] = s;
            }
        }
    }
    let mut new_shape = shape.to_vec();
    new_shape[axis] = m;
    (out, new_shape)
}

/// Window sums (valid region) of a slab over every axis of `shape`.
fn box_sums(data: &[f64], shape: &[usize], w: usize) -> Vec<f64> {
    let mut cur = data.to_vec();
    let mut sh = shape.to_vec();
    for axis in 0..shape.len() {
        let (next, nsh) = box_valid(&cur, &sh, axis, w);
        cur = next;
        sh = nsh;
    }
    cur
}

/// Mean SSIM over channels (scikit-image `structural_similarity` defaults, see module
/// doc); `None` when any spatial side is shorter than 7.
///
/// Memory stays proportional to one slice: the window sums along the first axis are
/// kept as running sums over 7 slices (five quantities: a, b, a², b², ab), and each
/// output slab is then box-summed over the remaining axes.
pub fn ssim(a: &Raster, b: &Raster, data_range: f64) -> Option<f64> {
    ssim_view(&a.view(), &b.view(), data_range)
}

/// [`ssim`] of borrowed rasters.
// the five running sums are indexed by position together: a range loop reads best
#[allow(clippy::needless_range_loop)]
pub fn ssim_view(a: &RasterView<'_>, b: &RasterView<'_>, data_range: f64) -> Option<f64> {
    const W: usize = 7;
    if a.dims.iter().any(|&d| d < W) {
        return None;
    }
    let nd = a.dims.len();
    let np = (W as f64).powi(nd as i32);
    let cov_norm = np / (np - 1.0);
    let c1 = (0.01 * data_range).powi(2);
    let c2 = (0.03 * data_range).powi(2);
    let ch = a.channels;
    let single = a.sample_type().is_float() && a.sample_type() != SampleType::F64;
    let value = |s: SamplesRef<'_>, i: usize| {
        let v = s.get_f64(i);
        if single {
            v as f32 as f64
        } else {
            v
        }
    };
    let rest = &a.dims[1..];
    let slice_len: usize = rest.iter().product();
    let n0 = a.dims[0];
    // output slices in fixed runs, each with its own running sums (the same figures on
    // any number of threads), summed in order
    const RUN: usize = 32;
    let outputs = n0 - W + 1;
    let mut total = 0.0;
    for c in 0..ch {
        let add = |run: &mut Vec<Vec<f64>>, z: usize, sign: f64| {
            for p in 0..slice_len {
                let i = (z * slice_len + p) * ch + c;
                let (x, y) = (value(a.samples, i), value(b.samples, i));
                run[0][p] += sign * x;
                run[1][p] += sign * y;
                run[2][p] += sign * x * x;
                run[3][p] += sign * y * y;
                run[4][p] += sign * x * y;
            }
        };
        let parts: Vec<(f64, usize)> = (0..outputs.div_ceil(RUN))
            .into_par_iter()
            .map(|part| {
                let first = part * RUN;
                // running sums over W slices of the five quantities, one slice long each
                let mut run = vec![vec![0.0f64; slice_len]; 5];
                for z in first..first + W - 1 {
                    add(&mut run, z, 1.0);
                }
                let mut s = 0.0;
                let mut count = 0usize;
                for z0 in first..(first + RUN).min(outputs) {
                    add(&mut run, z0 + W - 1, 1.0);
                    let sums: Vec<Vec<f64>> = if rest.is_empty() {
                        run.clone()
                    } else {
                        run.iter().map(|q| box_sums(q, rest, W)).collect()
                    };
                    for i in 0..sums[0].len() {
                        let ux = sums[0][i] / np;
                        let uy = sums[1][i] / np;
                        let vx = cov_norm * (sums[2][i] / np - ux * ux);
                        let vy = cov_norm * (sums[3][i] / np - uy * uy);
                        let vxy = cov_norm * (sums[4][i] / np - ux * uy);
                        let num = (2.0 * ux * uy + c1) * (2.0 * vxy + c2);
                        let den = (ux * ux + uy * uy + c1) * (vx + vy + c2);
                        s += num / den;
                    }
                    count += sums[0].len();
                    add(&mut run, z0, -1.0);
                }
                (s, count)
            })
            .collect();
        let (s, count) = parts
            .iter()
            .fold((0.0, 0usize), |(s, n), &(ps, pn)| (s + ps, n + pn));
        total += s / count as f64;
    }
    Some(total / ch as f64)
}

/// The luma of a colour raster, `Y = 0.299 R + 0.587 G + 0.114 B` (ITU-R BT.601), in the same
/// sample type (rounded for integer types); other channels (alpha) are dropped. A raster with
/// fewer than three channels is returned unchanged.
pub fn luma(r: &Raster) -> Result<Raster> {
    if r.channels < 3 {
        return Ok(r.clone());
    }
    let c = r.channels;
    let v = r.to_f64();
    let y: Vec<f32> = v
        .chunks_exact(c)
        .map(|p| (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) as f32)
        .collect();
    let mut out = Raster::from_f32(r.dims.clone(), 1, &y, r.sample_type(), r.kind)?;
    out.meta = r.meta.clone();
    Ok(out)
}
