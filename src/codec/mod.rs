//! The codec: raster → colour transform → pyramid (notes §9.3) → per-band dead-zone
//! quantization weighted by synthesis gain ([`crate::quantize`]) → context-modelled
//! range coding ([`crate::entropy`]) → `.mra` chunks ([`crate::format`]), and back.
//!
//! Rate modes ([`Rate`]): keep P% of details, threshold, quality, target PSNR, target
//! bits per position (a search on the step), guaranteed maximum error (lossy base plus
//! a spatial residual layer quantized with step `2E`), and lossless (integer
//! S-transform, integer YCoCg-R).

pub mod demo;
pub mod layout;
pub mod lossless;
pub mod meta;

use crate::entropy::{self, BandKind, Parent};
use crate::format::header::Colour;
use crate::format::{self, put_chunk, ChunkEnd, ChunkReader, Cursor, Header, Mode};
use crate::io::{DataKind, Raster, SampleType, Samples};
use crate::quantize::{self, DELTA, RHO};
use crate::scheme::{Boundary, Scheme};
use crate::tensor::{self, Array, Order, Pyramid, PyramidSpec, Subband};
use crate::{Error, Result};
use rayon::prelude::*;
use std::io::Read;
use std::path::Path;

/// How to spend bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rate {
    /// Keep the largest P percent of the (gain-weighted) details.
    Keep(f64),
    /// Zero the details whose gain-weighted magnitude is below T.
    Threshold(f64),
    /// 1..100: step `Δ = (max − min) · 2^(−Q/10)`.
    Quality(f64),
    /// Target PSNR in dB (skimage convention of `mra compare`).
    Psnr(f64),
    /// Target PSNR in dB with the peak-to-peak data range `R` of
    /// `PSNR = 10 log10(R² / MSE)` given (as `mra compare --data-range R`).
    PsnrRange(f64, f64),
    /// Target bits per position (pixel / voxel), all channels together.
    Bpp(f64),
    /// Every decoded sample within E of the source.
    MaxError(f64),
    /// Bit-exact.
    Lossless,
}

/// Encoder settings.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeOptions {
    pub scheme: Scheme,
    pub boundary: Boundary,
    pub levels: usize,
    pub rate: Rate,
}

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions {
            scheme: Scheme::Haar,
            boundary: Boundary::Symmetric,
            levels: 6,
            rate: Rate::Quality(50.0),
        }
    }
}

/// Decoder settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DecodeOptions {
    /// Reconstruct at 1/2^level resolution, reading only the chunks needed.
    pub level: usize,
    /// Decode what a truncated file holds instead of failing.
    pub allow_truncated: bool,
}

/// A decoded file.
#[derive(Clone, Debug)]
pub struct Decoded {
    pub raster: Raster,
    pub header: Header,
    /// False when the file ended before its `MEND` chunk (only with `allow_truncated`).
    pub complete: bool,
}

const BAND: &[u8; 4] = b"BAND";
const HEAD: &[u8; 4] = b"HEAD";
const RESI: &[u8; 4] = b"RESI";
const MEND: &[u8; 4] = b"MEND";
const META: &[u8; 4] = b"mETA";

/// Pyramid, bands, their parents and extents for a header.
struct Plan {
    pyr: Pyramid,
    bands: Vec<Subband>,
    parents: Vec<Option<usize>>,
    dims: Vec<Vec<usize>>,
}

impl Plan {
    /// Range-code every `(band, channel)` job's quantized indices `q[job]` (jobs band-major,
    /// `channels` per band), each band with its parent band of the same channel (§9).
    fn code_bands(&self, jobs: &[(usize, usize)], q: &[Vec<i64>], channels: usize) -> Vec<Vec<u8>> {
        jobs.par_iter()
            .enumerate()
            .map(|(i, &(j, c))| {
                let kind = if self.bands[j].level == 0 {
                    BandKind::Coarse
                } else {
                    BandKind::Detail
                };
                let parent = self.parents[j].map(|p| Parent {
                    data: &q[p * channels + c],
                    dims: &self.dims[p],
                });
                entropy::encode_band(&q[i], &self.dims[j], kind, parent)
            })
            .collect()
    }

    fn new(h: &Header) -> Result<Plan> {
        let pyr = if h.mode == Mode::Lossless {
            lossless::plan(&h.dims, h.levels)
        } else {
            let spec = PyramidSpec {
                scheme: h.scheme,
                boundary: h.boundary,
                levels: h.levels,
                order: Order::NonStandard,
                axes: (0..h.dims.len()).collect(),
            };
            Pyramid::plan(&h.dims, &spec)?
        };
        let bands = pyr.subbands();
        let parents = bands
            .iter()
            .map(|b| {
                if b.level == 0 {
                    return None;
                }
                bands
                    .iter()
                    .position(|p| p.level == b.level + 1 && p.high == b.high)
            })
            .collect();
        let dims = bands
            .iter()
            .map(|b| b.ranges.iter().map(|r| r.len()).collect())
            .collect();
        Ok(Plan {
            pyr,
            bands,
            parents,
            dims,
        })
    }

    /// Extents of the coarse block left after `k` levels (k = 0: full size).
    fn region(&self, k: usize) -> Vec<usize> {
        let mut r = self.pyr.shape.clone();
        for (i, &a) in self.pyr.spec.axes.iter().enumerate() {
            r[a] = self.pyr.lengths[i][k.min(self.pyr.axis_levels(i))];
        }
        r
    }

    /// The pyramid of the coarse block after `k` levels.
    fn sub(&self, k: usize) -> Pyramid {
        let p = &self.pyr;
        Pyramid {
            spec: PyramidSpec {
                levels: p.spec.levels.saturating_sub(k),
                ..p.spec.clone()
            },
            shape: self.region(k),
            lengths: (0..p.lengths.len())
                .map(|i| p.lengths[i][k.min(p.axis_levels(i))..].to_vec())
                .collect(),
        }
    }
}

/// Squared synthesis gain of each channel after the colour transform (inverse YCoCg
/// columns: Y → (1,1,1), Co → (½,0,−½), Cg → (−½,½,−½)).
fn channel_weights(colour: Colour, channels: usize) -> Vec<f64> {
    let mut w = vec![1.0; channels];
    if colour == Colour::YCoCg {
        w[0] = 3.0f64.sqrt();
        w[1] = 0.5f64.sqrt();
        w[2] = 0.75f64.sqrt();
    }
    w
}

fn finite_range(s: &Samples) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for i in 0..s.len() {
        let x = s.get_f64(i);
        if x.is_finite() {
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    if lo > hi {
        (0.0, 0.0)
    } else {
        (lo, hi)
    }
}

/// `(p0, p1, p2)[i] = f(p0[i], p1[i], p2[i])` on the first three planes (a colour
/// transform, one pixel at a time).
fn map3<T: Copy>(planes: &mut [Vec<T>], f: impl Fn(T, T, T) -> (T, T, T)) {
    let [a, b, c, ..] = planes else {
        panic!("a colour transform on fewer than 3 planes")
    };
    for ((x, y), z) in a.iter_mut().zip(b.iter_mut()).zip(c.iter_mut()) {
        (*x, *y, *z) = f(*x, *y, *z);
    }
}

/// Inverse YCoCg in real arithmetic: `(Y, Co, Cg) → (R, G, B)`.
fn ycocg_inverse(y: f32, co: f32, cg: f32) -> (f32, f32, f32) {
    let t = y - cg * 0.5;
    let g = cg + t;
    let b = t - co * 0.5;
    (b + co, g, b)
}

/// Split interleaved samples into per-channel f32 planes, NaN/∞ → 0, colour applied.
fn planes_f32(r: &Raster, colour: Colour) -> Vec<Vec<f32>> {
    let c = r.channels;
    let n = r.positions();
    let mut planes = vec![vec![0f32; n]; c];
    for i in 0..n {
        for (k, p) in planes.iter_mut().enumerate() {
            let x = r.samples.get_f64(i * c + k);
            p[i] = if x.is_finite() { x as f32 } else { 0.0 };
        }
    }
    if colour == Colour::YCoCg {
        map3(&mut planes, |r, g, b| {
            let co = r - b;
            let t = b + co * 0.5;
            let cg = g - t;
            (t + cg * 0.5, co, cg)
        });
    }
    planes
}

/// The transform of a lossy encode, computed once and quantized at any step.
struct Prepared {
    header: Header,
    plan: Plan,
    gains: Vec<f64>,
    weights: Vec<f64>,
    coeffs: Vec<Vec<f32>>,
    meta: Vec<u8>,
}

fn header_for(r: &Raster, opts: &EncodeOptions, mode: Mode, colour: Colour) -> Result<Header> {
    if r.dims.is_empty() || r.dims.len() > format::header::MAX_AXES {
        return Err(Error::parameter(
            "dims",
            format!("{:?}", r.dims),
            "1 to 4 spatial axes",
        ));
    }
    if r.dims.iter().any(|&d| d == 0 || d > u32::MAX as usize) {
        return Err(Error::parameter(
            "dims",
            format!("{:?}", r.dims),
            "extents from 1 to 2^32−1",
        ));
    }
    if r.channels == 0 || r.channels > format::header::MAX_CHANNELS {
        return Err(Error::parameter("channels", r.channels, "1 to 256"));
    }
    if opts.levels > format::header::MAX_LEVELS {
        return Err(Error::parameter("levels", opts.levels, "0 to 32"));
    }
    let (min, max) = finite_range(&r.samples);
    Ok(Header {
        major: format::MAJOR,
        minor: format::MINOR,
        kind: r.kind,
        sample_type: r.sample_type(),
        dims: r.dims.clone(),
        channels: r.channels,
        colour,
        mode,
        scheme: opts.scheme,
        boundary: opts.boundary,
        levels: opts.levels,
        step: 1.0,
        delta: if mode == Mode::Lossless { 0.0 } else { DELTA },
        max_error: 0.0,
        min,
        max,
        tile: r.dims.clone(),
    })
}

fn prepare(r: &Raster, opts: &EncodeOptions, mode: Mode) -> Result<Prepared> {
    let colour = if r.channels >= 3 {
        Colour::YCoCg
    } else {
        Colour::None
    };
    let header = header_for(r, opts, mode, colour)?;
    let plan = Plan::new(&header)?;
    let gains = quantize::band_gains(&plan.pyr, &plan.bands);
    let weights = channel_weights(colour, r.channels);
    let spec = plan.pyr.spec.clone();
    let coeffs = planes_f32(r, colour)
        .into_par_iter()
        .map(|p| {
            let mut a = Array::from_shape_vec(&r.dims, p)?;
            tensor::analyze(&mut a, &spec)?;
            Ok(a.into_data())
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Prepared {
        header,
        plan,
        gains,
        weights,
        coeffs,
        meta: meta::to_bytes(&r.meta),
    })
}

fn band_payload(channel: usize, band: usize, step: f64, coded: &[u8]) -> Vec<u8> {
    let mut p = Vec::with_capacity(12 + coded.len());
    p.extend_from_slice(&(channel as u16).to_le_bytes());
    p.extend_from_slice(&(band as u16).to_le_bytes());
    p.extend_from_slice(&step.to_le_bytes());
    p.extend_from_slice(coded);
    p
}

impl Prepared {
    fn band_step(&self, step: f64, band: usize, channel: usize) -> f64 {
        step / (self.gains[band] * self.weights[channel])
    }

    /// Band `j` of channel `c` quantized at base step `step`: its indices.
    fn quantized(&self, step: f64, j: usize, c: usize) -> Vec<i64> {
        let plan = &self.plan;
        let (s, rho) = (self.band_step(step, j, c), band_rho(plan, j));
        layout::gather(&self.coeffs[c], &plan.pyr.shape, &plan.bands[j].ranges)
            .into_iter()
            .map(|x| quantize::quantize(x as f64, s, rho))
            .collect()
    }

    /// What a decoder makes of [`Prepared::code`]`(step)`, at full size, computed from the
    /// quantized bands without coding them (the coding is lossless): the same samples.
    fn decoded(&self, step: f64) -> Result<Raster> {
        let (h, plan) = (&self.header, &self.plan);
        let values = lossy_values(h, plan, 0, |c| {
            Ok((0..plan.bands.len())
                .into_par_iter()
                .map(|j| {
                    let q = self.quantized(step, j, c);
                    Some(dequantized(h, plan, j, &q, self.band_step(step, j, c)))
                })
                .collect())
        })?;
        Raster::new(
            h.dims.clone(),
            h.channels,
            Samples::from_f64(&values, h.sample_type),
            h.kind,
        )
    }

    /// Every (band, channel) in file order: bands in order, the channels of each.
    fn band_channels(&self) -> Vec<(usize, usize)> {
        let nc = self.coeffs.len();
        (0..self.plan.bands.len())
            .flat_map(|j| (0..nc).map(move |c| (j, c)))
            .collect()
    }

    /// Quantize and code at base step `step`; the whole file.
    fn code(&self, step: f64) -> Vec<u8> {
        let plan = &self.plan;
        let nc = self.coeffs.len();
        let jobs = self.band_channels();
        let q: Vec<Vec<i64>> = jobs
            .par_iter()
            .map(|&(j, c)| self.quantized(step, j, c))
            .collect();
        let coded = plan.code_bands(&jobs, &q, nc);
        let mut h = self.header.clone();
        h.step = step;
        let mut out = format::SIGNATURE.to_vec();
        put_chunk(&mut out, HEAD, &h.to_bytes());
        if !self.meta.is_empty() {
            put_chunk(&mut out, META, &self.meta);
        }
        for (k, &(j, c)) in jobs.iter().enumerate() {
            let s = if plan.bands[j].level == 0 || h.mode != Mode::Lossless {
                self.band_step(step, j, c)
            } else {
                1.0
            };
            put_chunk(&mut out, BAND, &band_payload(c, j, s, &coded[k]));
        }
        put_chunk(&mut out, MEND, &[]);
        out
    }

    /// Gain-weighted magnitudes of all detail coefficients.
    fn weighted_details(&self) -> Vec<f32> {
        let mut v = Vec::new();
        for (j, b) in self.plan.bands.iter().enumerate() {
            if b.level == 0 {
                continue;
            }
            for (c, plane) in self.coeffs.iter().enumerate() {
                let w = (self.gains[j] * self.weights[c]) as f32;
                layout::rows(&self.plan.pyr.shape, &b.ranges, |off, run, _| {
                    v.extend(plane[off..off + run].iter().map(|x| x.abs() * w));
                });
            }
        }
        v
    }
}

/// The `meta.extra` key listing the void samples of an encoded raster as runs
/// `start:length` (sample indices, channels interleaved).
const VOID_RUNS: &str = "nodata.voids";

/// `r` with its void samples ([`crate::io::nodata`]) filled by pull-push and their runs
/// kept in [`VOID_RUNS`]; `None` when no sample (or every sample) is void.
fn with_voids_filled(r: &Raster) -> Result<Option<Raster>> {
    let mut v = r.to_f64();
    let Some(voids) = crate::io::nodata::Voids::find(&v, r.meta.nodata) else {
        return Ok(None);
    };
    if voids.count() == v.len() {
        return Ok(None);
    }
    let mut shape = r.dims.clone();
    shape.push(r.channels);
    voids.fill(&mut v, &shape, r.dims.len())?;
    let mut runs = Vec::new();
    let mut i = 0;
    while i < voids.mask.len() {
        if voids.mask[i] {
            let start = i;
            while i < voids.mask.len() && voids.mask[i] {
                i += 1;
            }
            runs.push(format!("{start}:{}", i - start));
        } else {
            i += 1;
        }
    }
    let mut out = Raster::new(
        r.dims.clone(),
        r.channels,
        Samples::from_f64(&v, r.sample_type()),
        r.kind,
    )?;
    out.meta = r.meta.clone();
    out.meta.extra.insert(VOID_RUNS.into(), runs.join(" "));
    Ok(Some(out))
}

/// Mark the voids listed in `meta.extra[VOID_RUNS]` on a raster decoded at level `k`
/// (an output sample is void when its whole footprint on the full grid is) and drop
/// the key. Malformed runs are ignored.
fn mark_voids(r: &mut Raster, full: &[usize], maps: &[crate::io::AxisMap]) {
    let Some(runs) = r.meta.extra.remove(VOID_RUNS) else {
        return;
    };
    let Ok(n) = crate::io::bytes::sample_count(full, r.channels) else {
        return;
    };
    let mut mask = vec![false; n];
    for run in runs.split_whitespace() {
        let Some((a, l)) = run.split_once(':') else {
            return;
        };
        let (Ok(a), Ok(l)) = (a.parse::<usize>(), l.parse::<usize>()) else {
            return;
        };
        match a.checked_add(l).filter(|&e| e <= n) {
            Some(e) => mask[a..e].iter_mut().for_each(|m| *m = true),
            None => return,
        }
    }
    let voids = crate::io::nodata::Voids {
        mask,
        marker: r.meta.nodata.unwrap_or(f64::NAN),
        range: (f64::NEG_INFINITY, f64::INFINITY),
    };
    let mut shape = full.to_vec();
    shape.push(r.channels);
    let m = voids.footprint(&shape, &r.dims, maps);
    crate::io::with_samples!(&mut r.samples, v => voids.restore(v, &m, false));
}

/// Encode a raster into the bytes of an `.mra` file. Void samples (NaN, `meta.nodata`)
/// are filled by pull-push before the transform and listed in the metadata, so that the
/// decoder marks them again ([`crate::io::nodata`]).
pub fn encode(r: &Raster, opts: &EncodeOptions) -> Result<Vec<u8>> {
    let n = crate::io::bytes::sample_count(&r.dims, r.channels)?;
    if n != r.samples.len() {
        return Err(Error::parameter(
            "samples",
            r.samples.len(),
            "dims × channels samples",
        ));
    }
    match with_voids_filled(r)? {
        Some(filled) => encode_filled(&filled, opts),
        None => encode_filled(r, opts),
    }
}

fn encode_filled(r: &Raster, opts: &EncodeOptions) -> Result<Vec<u8>> {
    match opts.rate {
        Rate::Lossless => encode_lossless(r, opts),
        Rate::MaxError(e) => encode_max_error(r, opts, e),
        rate => {
            let p = prepare(r, opts, Mode::Lossy)?;
            let range = (p.header.max - p.header.min).max(1e-30);
            let step = match rate {
                Rate::Keep(k) => {
                    if !(0.0..=100.0).contains(&k) {
                        return Err(Error::parameter("keep", k, "a percentage from 0 to 100"));
                    }
                    let mut w = p.weighted_details();
                    let t = quantize::keep_threshold(&mut w, k);
                    if t.is_infinite() {
                        range * 1e6
                    } else {
                        (t / (1.0 - RHO)).max(range * 1e-9)
                    }
                }
                Rate::Threshold(t) => {
                    if !(t > 0.0 && t.is_finite()) {
                        return Err(Error::parameter("threshold", t, "a positive number"));
                    }
                    t / (1.0 - RHO)
                }
                Rate::Quality(q) => {
                    if !(1.0..=100.0).contains(&q) {
                        return Err(Error::parameter("quality", q, "1 to 100"));
                    }
                    range * (2f64).powf(-q / 10.0)
                }
                Rate::Psnr(db) | Rate::PsnrRange(db, _) => {
                    if let Rate::PsnrRange(_, r) = rate {
                        if !(r.is_finite() && r > 0.0) {
                            return Err(Error::parameter(
                                "data range",
                                r,
                                "a positive, finite peak-to-peak range",
                            ));
                        }
                    }
                    if !(db > 0.0 && db < 400.0) {
                        return Err(Error::parameter(
                            "psnr",
                            db,
                            "a target in dB between 0 and 400",
                        ));
                    }
                    // each candidate decoded from its quantized bands, coded only once chosen;
                    // the data range `mra compare` would use, found once
                    let cmp = crate::metrics::CompareOptions {
                        data_range: Some(match rate {
                            Rate::PsnrRange(_, range) => range,
                            _ => crate::metrics::skimage_data_range(&r.samples),
                        }),
                        ..Default::default()
                    };
                    let (errors, peak) = (p.rate_model(), cmp.data_range.unwrap_or(range));
                    let n = (r.positions() * r.channels) as f64;
                    let model = |x: f64| {
                        let mse = (errors.squared_error(x.exp()) / n).max(1e-300);
                        10.0 * (peak * peak / mse).log10() - db
                    };
                    return search(&p, range, false, 0.02, Some(&model), |step| {
                        let dec = p.decoded(step)?;
                        let psnr = crate::metrics::psnr(r, &dec, &cmp)?;
                        Ok((psnr.unwrap_or(f64::INFINITY) - db, None))
                    });
                }
                Rate::Bpp(b) => {
                    if !(b > 0.0 && b.is_finite()) {
                        return Err(Error::parameter(
                            "bpp",
                            b,
                            "a positive number of bits per position",
                        ));
                    }
                    let pos = r.positions() as f64;
                    // v = ln b − ln bpp: met when the file is within the budget, within
                    // 1% under it at −ln 0.99; the log of the size is close to a line in
                    // ln(step), where the size itself bends (10 candidates at 1 bpp on
                    // kodim01 against 5)
                    let sizes = p.rate_model();
                    let model = |x: f64| b.ln() - (sizes.bits(x.exp()) / pos).ln();
                    return search(&p, range, true, -(0.99f64.ln()), Some(&model), |step| {
                        let bytes = p.code(step);
                        Ok((b.ln() - (bytes.len() as f64 * 8.0 / pos).ln(), Some(bytes)))
                    });
                }
                _ => unreachable!(),
            };
            Ok(p.code(step))
        }
    }
}

/// Search on `x = ln(step)` for the file closest to a target: `f(step)` gives `v ≥ 0`
/// when the target is met (PSNR reached, or size within budget), which holds for large
/// steps when `large_ok` (size) and for small steps otherwise (PSNR), and the coded file
/// if it made it. Returns the met file closest to the target; stops at the first met
/// file within `tol` of it.
///
/// `v` is close to linear in `x` (PSNR falls by 20/ln 10 ≈ 8.7 dB per unit of `x`; the
/// size by up to 1/ln 2 bits per sample), so each step is a secant: through the last two
/// points until the target is bracketed, then between the bracket's ends (regula falsi,
/// aiming at `tol / 2` above the target), kept inside the bracket's middle 80%, and a
/// bisection whenever the bracket did not halve. A handful of candidates instead of the
/// 15–25 of a bisection over the whole range.
///
/// With a `model` (an estimate of `v` at any `x`, roughly right in shape), the first
/// candidate is where the model meets the target, and the steps before the target is
/// bracketed go to where the model, shifted to agree with the last candidate, meets it,
/// instead of along the secant.
fn search(
    p: &Prepared,
    range: f64,
    large_ok: bool,
    tol: f64,
    model: Option<&dyn Fn(f64) -> f64>,
    f: impl Fn(f64) -> Result<(f64, Option<Vec<u8>>)>,
) -> Result<Vec<u8>> {
    let (x_min, x_max) = ((range * 1e-7).ln(), (range * 4.0).ln());
    // v as a function rising with x, so that "met" is one side of its root
    let sign = if large_ok { 1.0 } else { -1.0 };
    // default slope of sign·v per unit of x until two points give one
    let slope0 = if large_ok {
        1.0
    } else {
        20.0 / std::f64::consts::LN_10
    };
    let aim = 0.5 * tol;
    let mut met: Option<(f64, f64)> = None; // (x, v) nearest the root on the met side
    let mut unmet: Option<(f64, f64)> = None;
    let mut last: Option<(f64, f64)> = None;
    let mut width = x_max - x_min;
    // (v, step, file if coded)
    let mut best: Option<(f64, f64, Option<Vec<u8>>)> = None;
    let mut x = (range / 32.0).ln(); // `--quality 50`
    if let Some(m) = model {
        // where the model itself meets the target
        x = model_root(m, 0.0, aim, sign, x).clamp(x_min, x_max);
    }
    for _ in 0..48 {
        let (v, bytes) = f(x.exp())?;
        if v >= 0.0 {
            if best.as_ref().is_none_or(|(bv, _, _)| v < *bv) {
                best = Some((v, x.exp(), bytes));
            }
            if v <= tol {
                break;
            }
            met = Some((x, v));
        } else {
            unmet = Some((x, v));
        }
        let prev = last.replace((x, v));
        x = match (met, unmet) {
            (Some((xm, vm)), Some((xu, vu))) => {
                let (lo, hi) = (xm.min(xu), xm.max(xu));
                // a bracket 0.1% wide in the step changes the size and the PSNR far
                // less than the tolerances (1%, 0.02 dB): a staircase has its gap there
                if hi - lo < 1e-3 {
                    break;
                }
                let halved = hi - lo <= 0.5 * width;
                width = hi - lo;
                if !halved || !vm.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    let t = xm + (vm - aim) * (xu - xm) / (vm - vu);
                    t.clamp(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo))
                }
            }
            _ => {
                // not bracketed yet: toward the target along the secant of the last two
                // points (the default slope if they do not give a usable one)
                let slope = match prev {
                    Some((xp, vp)) if xp != x && vp.is_finite() && v.is_finite() => {
                        let s = sign * (v - vp) / (x - xp);
                        if s > 0.0 {
                            s
                        } else {
                            slope0
                        }
                    }
                    _ => slope0,
                };
                let dx = if let (Some(m), true) = (model, v.is_finite()) {
                    let off = v - m(x);
                    let dx = (model_root(m, off, aim, sign, x) - x).clamp(-3.0, 3.0);
                    dx.signum() * dx.abs().max(0.01)
                } else if v.is_finite() {
                    let dx = (sign * (aim - v) / slope).clamp(-3.0, 3.0);
                    dx.signum() * dx.abs().max(0.01)
                } else {
                    // identical to the source (PSNR without bound): a large step toward
                    // the unmet side
                    -sign * 3.0
                };
                let next = (x + dx).clamp(x_min, x_max);
                if next == x {
                    break;
                }
                next
            }
        };
    }
    Ok(match best {
        Some((_, _, Some(b))) => b,
        Some((_, step, None)) => p.code(step),
        None => p.code(if large_ok { x_max.exp() } else { x_min.exp() }),
    })
}

/// Where `m(x) + off = aim`, searched within 6 units of `x` (a bisection on the model:
/// `sign·m` rises with `x`); the nearer end when the model does not reach the target.
fn model_root(m: &dyn Fn(f64) -> f64, off: f64, aim: f64, sign: f64, x: f64) -> f64 {
    let g = |t: f64| sign * (m(t) + off - aim);
    let (mut lo, mut hi) = (x - 6.0, x + 6.0);
    if g(lo) >= 0.0 {
        return lo;
    }
    if g(hi) <= 0.0 {
        return hi;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A rough size and error of the coded file at any base step, for [`search`], from a
/// histogram of the coefficients' `log2(|c|·G_b·w_c)` (a coefficient quantizes to
/// `t = |c|·G_b·w_c / Δ`; its error times `G_b·w_c` is about its error in the samples):
/// below the dead zone's edge `1 − ρ` a coefficient costs [`RateModel::ZERO_BITS`] and
/// its whole value in error, past it about `log2 t + 2` bits and `Δ²/12`.
struct RateModel {
    /// Coefficients per bin of `BINS_PER_OCTAVE`-th octaves from `2^LOW`.
    bins: Vec<f64>,
    zeros: f64,
}

impl RateModel {
    const BINS_PER_OCTAVE: f64 = 8.0;
    const LOW: f64 = -64.0;
    /// (Zeros in zero neighbourhoods cost next to nothing; 0.02–0.1 measured alike.)
    const ZERO_BITS: f64 = 0.05;

    /// Over the coefficients that are not zero, by bin: `(count, d)` with `d = log2 t` at
    /// base step `step` and `t = |c|·G_b·w_c / Δ`, and whether `t` is past the dead zone.
    fn at(&self, step: f64) -> impl Iterator<Item = (f64, f64, bool)> + '_ {
        let (edge, s) = ((1.0 - RHO).log2(), step.log2());
        self.bins
            .iter()
            .enumerate()
            .filter(|(_, &n)| n > 0.0)
            .map(move |(k, &n)| {
                let d = Self::LOW + (k as f64 + 0.5) / Self::BINS_PER_OCTAVE - s;
                (n, d, d >= edge)
            })
    }

    /// Estimated bits at base step `step`.
    fn bits(&self, step: f64) -> f64 {
        let zb = Self::ZERO_BITS;
        let coded: f64 = self
            .at(step)
            .map(|(n, d, past)| n * if past { d + 2.0 } else { zb })
            .sum();
        (self.zeros * zb + coded).max(1.0)
    }

    /// Estimated sum of squared errors (samples × channels) at base step `step`: a
    /// coefficient in the dead zone loses `|c|·G_b·w_c = t·Δ`.
    fn squared_error(&self, step: f64) -> f64 {
        self.at(step)
            .map(|(n, d, past)| n * step * step * if past { 1.0 / 12.0 } else { (2.0 * d).exp2() })
            .sum()
    }
}

impl Prepared {
    /// The [`RateModel`] of these coefficients.
    fn rate_model(&self) -> RateModel {
        let nbins = (2.0 * -RateModel::LOW * RateModel::BINS_PER_OCTAVE) as usize;
        let plan = &self.plan;
        let (bins, zeros) = self
            .band_channels()
            .par_iter()
            .map(|&(j, c)| {
                let mut bins = vec![0.0f64; nbins];
                let mut zeros = 0.0;
                let scale = (self.gains[j] * self.weights[c]) as f32;
                let band = layout::gather(&self.coeffs[c], &plan.pyr.shape, &plan.bands[j].ranges);
                for &v in &band {
                    let a = v.abs() * scale;
                    if !(a > 0.0 && a.is_finite()) {
                        zeros += 1.0;
                        continue;
                    }
                    // log2 from the bits: exponent plus the mantissa as a fraction (off
                    // by under 0.09 octave, about a bin)
                    let b = a.to_bits();
                    let y = ((b >> 23) as i32 - 127) as f32 + (b & 0x7F_FFFF) as f32 / 8_388_608.0;
                    let k = ((y as f64 - RateModel::LOW) * RateModel::BINS_PER_OCTAVE) as isize;
                    bins[k.clamp(0, nbins as isize - 1) as usize] += 1.0;
                }
                (bins, zeros)
            })
            .reduce(
                || (vec![0.0; nbins], 0.0),
                |(mut a, za), (b, zb)| {
                    for (x, y) in a.iter_mut().zip(&b) {
                        *x += y;
                    }
                    (a, za + zb)
                },
            );
        RateModel { bins, zeros }
    }
}

fn lossless_int(x: f64, t: SampleType) -> i64 {
    let _ = t;
    x as i64
}

fn encode_lossless(r: &Raster, opts: &EncodeOptions) -> Result<Vec<u8>> {
    let ty = r.sample_type();
    let colour = if r.channels >= 3 && !ty.is_float() {
        Colour::YCoCgR
    } else {
        Colour::None
    };
    let mut o = opts.clone();
    o.scheme = Scheme::Haar;
    o.boundary = Boundary::Interpolating;
    let header = header_for(r, &o, Mode::Lossless, colour)?;
    let plan = Plan::new(&header)?;
    let c = r.channels;
    let n = r.positions();
    let mut planes = vec![vec![0i64; n]; c];
    for i in 0..n {
        for (k, p) in planes.iter_mut().enumerate() {
            p[i] = match &r.samples {
                Samples::F16(v) => lossless::float_bits_to_int(v[i * c + k].to_bits() as u64, 16),
                Samples::F32(v) => lossless::float_bits_to_int(v[i * c + k].to_bits() as u64, 32),
                Samples::F64(v) => lossless::float_bits_to_int(v[i * c + k].to_bits(), 64),
                s => lossless_int(s.get_f64(i * c + k), ty),
            };
        }
    }
    if colour == Colour::YCoCgR {
        map3(&mut planes, lossless::ycocg_r);
    }
    planes
        .par_iter_mut()
        .for_each(|p| lossless::forward(p, &plan.pyr));
    let nb = plan.bands.len();
    let jobs: Vec<(usize, usize)> = (0..nb).flat_map(|j| (0..c).map(move |k| (j, k))).collect();
    let q: Vec<Vec<i64>> = jobs
        .par_iter()
        .map(|&(j, k)| layout::gather(&planes[k], &plan.pyr.shape, &plan.bands[j].ranges))
        .collect();
    drop(planes);
    let coded = plan.code_bands(&jobs, &q, c);
    let mut out = format::SIGNATURE.to_vec();
    put_chunk(&mut out, HEAD, &header.to_bytes());
    let m = meta::to_bytes(&r.meta);
    if !m.is_empty() {
        put_chunk(&mut out, META, &m);
    }
    for (i, &(j, k)) in jobs.iter().enumerate() {
        put_chunk(&mut out, BAND, &band_payload(k, j, 1.0, &coded[i]));
    }
    put_chunk(&mut out, MEND, &[]);
    Ok(out)
}

/// Step of the residual layer for bound `e` on samples of type `t`.
fn residual_step(e: f64, t: SampleType) -> f64 {
    if t.is_float() {
        2.0 * e * (1.0 - 1e-9)
    } else {
        2.0 * e.floor() + 1.0
    }
}

fn encode_max_error(r: &Raster, opts: &EncodeOptions, e: f64) -> Result<Vec<u8>> {
    if !(e >= 0.0 && e.is_finite()) {
        return Err(Error::parameter("max-error", e, "a finite bound ≥ 0"));
    }
    let ty = r.sample_type();
    if e == 0.0 || (!ty.is_float() && e < 1.0) {
        return encode_lossless(r, opts);
    }
    let mut p = prepare(r, opts, Mode::MaxError)?;
    p.header.max_error = e;
    let base = p.code(2.0 * e);
    let dec = decode(&base, &DecodeOptions::default())?.raster;
    let s = residual_step(e, ty);
    let c = r.channels;
    let n = r.positions();
    let mut out = base[..base.len() - 12].to_vec(); // drop MEND
    let chunks: Vec<Vec<u8>> = (0..c)
        .into_par_iter()
        .map(|k| {
            let mut q = vec![0i64; n];
            let mut fixed = vec![0f64; n];
            for i in 0..n {
                let x = r.samples.get_f64(i * c + k);
                let xh = dec.samples.get_f64(i * c + k);
                let d = if x.is_finite() { x - xh } else { 0.0 };
                q[i] = (d / s).round() as i64;
                fixed[i] = xh + q[i] as f64 * s;
            }
            let back = Samples::from_f64(&fixed, ty);
            let mut exc = Vec::new();
            for i in 0..n {
                let x = r.samples.get_f64(i * c + k);
                let y = back.get_f64(i);
                // NaN differences are outside the bound, except NaN for NaN
                let within = (x - y).abs() <= e || (x.is_nan() && y.is_nan());
                if !within {
                    exc.push((i as u64, x));
                }
            }
            let coded = entropy::encode_band(&q, &r.dims, BandKind::Detail, None);
            let mut pl = Vec::new();
            pl.extend_from_slice(&(k as u16).to_le_bytes());
            pl.extend_from_slice(&s.to_le_bytes());
            pl.extend_from_slice(&(exc.len() as u32).to_le_bytes());
            for (i, v) in exc {
                pl.extend_from_slice(&i.to_le_bytes());
                pl.extend_from_slice(&v.to_le_bytes());
            }
            pl.extend_from_slice(&coded);
            pl
        })
        .collect();
    for ch in chunks {
        put_chunk(&mut out, RESI, &ch);
    }
    put_chunk(&mut out, MEND, &[]);
    Ok(out)
}

/// A BAND chunk's contents.
struct BandChunk {
    step: f64,
    data: Vec<u8>,
}

/// A RESI chunk's contents.
struct ResiChunk {
    step: f64,
    exceptions: Vec<(u64, f64)>,
    data: Vec<u8>,
}

/// One chunk as listed by [`info`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct ChunkInfo {
    pub kind: String,
    pub offset: u64,
    pub bytes: u64,
    pub channel: Option<usize>,
    pub band: Option<usize>,
    pub level: Option<usize>,
    pub coefficients: Option<u64>,
}

/// Everything read from a file before reconstruction.
struct Parsed {
    header: Header,
    meta: crate::io::Metadata,
    plan: Plan,
    bands: Vec<Vec<Option<BandChunk>>>,
    resi: Vec<Option<ResiChunk>>,
    complete: bool,
    chunks: Vec<ChunkInfo>,
}

fn read_chunks<R: Read>(
    src: R,
    len: u64,
    stop_level: usize,
    allow_truncated: bool,
) -> Result<Parsed> {
    let mut rd = ChunkReader::new(src, len)?;
    let first = match rd.next_chunk()? {
        Ok(c) => c,
        Err(_) => {
            return Err(Error::format(
                "file ends before its HEAD chunk",
                "a HEAD chunk after the signature",
            ))
        }
    };
    if &first.kind != HEAD {
        return Err(Error::format(
            format!("first chunk {}", first.name()),
            "HEAD first",
        ));
    }
    let header = Header::parse(&first.payload)?;
    let samples = header.samples()?;
    let limit = crate::io::MAX_SAMPLES.min(len.saturating_mul(12_000).max(1 << 20));
    if samples > limit {
        return Err(Error::LimitsExceeded {
            what: "declared samples",
            requested: samples,
            limit,
        });
    }
    let plan = Plan::new(&header)?;
    let nb = plan.bands.len();
    let mut bands: Vec<Vec<Option<BandChunk>>> = (0..header.channels)
        .map(|_| (0..nb).map(|_| None).collect())
        .collect();
    let mut resi: Vec<Option<ResiChunk>> = (0..header.channels).map(|_| None).collect();
    let mut meta = crate::io::Metadata::default();
    let mut chunks = vec![ChunkInfo {
        kind: "HEAD".into(),
        offset: first.offset,
        bytes: first.payload.len() as u64 + 12,
        channel: None,
        band: None,
        level: None,
        coefficients: None,
    }];
    let mut complete = false;
    let mut last = "HEAD".to_string();
    loop {
        let ch = match rd.next_chunk()? {
            Ok(c) => c,
            Err(end) => {
                if !allow_truncated {
                    let at = match end {
                        ChunkEnd::Eof => len,
                        ChunkEnd::Truncated { offset } => offset,
                    };
                    return Err(Error::format(
                        format!("file truncated after chunk {last} (byte {at} of {len})"),
                        "a complete file ending with MEND (or --allow-truncated)",
                    ));
                }
                break;
            }
        };
        let mut info = ChunkInfo {
            kind: ch.name(),
            offset: ch.offset,
            bytes: ch.payload.len() as u64 + 12,
            channel: None,
            band: None,
            level: None,
            coefficients: None,
        };
        last = ch.name();
        match &ch.kind {
            b"BAND" => {
                let mut c = Cursor::new(&ch.payload, "BAND");
                let channel = c.u16()? as usize;
                let band = c.u16()? as usize;
                let step = c.f64()?;
                if channel >= header.channels || band >= nb {
                    return Err(Error::format(
                        format!(
                            "BAND chunk at byte {} for channel {channel}, band {band}",
                            ch.offset
                        ),
                        "channel < channels and band < number of bands",
                    ));
                }
                if !(step > 0.0 && step.is_finite()) {
                    return Err(Error::format(
                        format!("BAND chunk step {step}"),
                        "a positive finite step",
                    ));
                }
                let level = plan.bands[band].level;
                if stop_level > 0 && level >= 1 && level <= stop_level {
                    complete = true;
                    break;
                }
                if let Some(p) = plan.parents[band] {
                    if bands[channel][p].is_none() {
                        return Err(Error::format(
                            format!("BAND {band} of channel {channel} before its parent band {p}"),
                            "bands in coarse-to-fine order",
                        ));
                    }
                }
                info.channel = Some(channel);
                info.band = Some(band);
                info.level = Some(level);
                info.coefficients = Some(plan.dims[band].iter().product::<usize>() as u64);
                bands[channel][band] = Some(BandChunk {
                    step,
                    data: c.rest().to_vec(),
                });
            }
            b"RESI" => {
                let mut c = Cursor::new(&ch.payload, "RESI");
                let channel = c.u16()? as usize;
                let step = c.f64()?;
                let n = c.u32()? as usize;
                if channel >= header.channels || !(step > 0.0 && step.is_finite()) {
                    return Err(Error::format(
                        format!("RESI chunk for channel {channel}, step {step}"),
                        "a valid channel and step",
                    ));
                }
                if n > (ch.payload.len() - c.pos) / 16 {
                    return Err(Error::format(
                        format!("RESI chunk declaring {n} exceptions"),
                        "exceptions that fit the chunk",
                    ));
                }
                let mut exc = Vec::with_capacity(n);
                for _ in 0..n {
                    let i = u64::from_le_bytes(c.take(8)?.try_into().unwrap());
                    let v = c.f64()?;
                    exc.push((i, v));
                }
                info.channel = Some(channel);
                resi[channel] = Some(ResiChunk {
                    step,
                    exceptions: exc,
                    data: c.rest().to_vec(),
                });
            }
            b"MEND" => {
                chunks.push(info);
                complete = true;
                break;
            }
            b"mETA" => meta = meta::parse(&ch.payload),
            b"HEAD" => return Err(Error::format("a second HEAD chunk", "one HEAD chunk")),
            k => {
                if k[0].is_ascii_uppercase() {
                    return Err(Error::Unsupported {
                        what: "critical chunk",
                        value: ch.name(),
                    });
                }
            }
        }
        chunks.push(info);
    }
    Ok(Parsed {
        header,
        meta,
        plan,
        bands,
        resi,
        complete,
        chunks,
    })
}

/// Decode one channel's bands into its coefficient indices (None = absent). A band's
/// context is its parent band (one level coarser), so the bands of one level decode
/// in parallel, level after level from the coarse block down.
fn decode_channel(p: &Parsed, c: usize, k: usize) -> Result<Vec<Option<Vec<i64>>>> {
    let plan = &p.plan;
    let nb = plan.bands.len();
    let mut q: Vec<Option<Vec<i64>>> = (0..nb).map(|_| None).collect();
    let mut levels: Vec<usize> = plan.bands.iter().map(|b| b.level).collect();
    levels.sort_unstable_by_key(|&l| (l != 0, std::cmp::Reverse(l)));
    levels.dedup();
    for level in levels {
        if k > 0 && level >= 1 && level <= k {
            continue;
        }
        let bands: Vec<usize> = (0..nb).filter(|&j| plan.bands[j].level == level).collect();
        let decoded: Vec<Result<Option<Vec<i64>>>> = bands
            .par_iter()
            .map(|&j| {
                let Some(bc) = &p.bands[c][j] else {
                    return Ok(None);
                };
                let kind = if level == 0 {
                    BandKind::Coarse
                } else {
                    BandKind::Detail
                };
                let parent = match plan.parents[j] {
                    Some(pj) => match &q[pj] {
                        Some(v) => Some(Parent {
                            data: v,
                            dims: &plan.dims[pj],
                        }),
                        None => {
                            return Err(Error::format(
                                format!("band {j} of channel {c} without its parent"),
                                "complete parents",
                            ))
                        }
                    },
                    None => None,
                };
                entropy::decode_band(&bc.data, &plan.dims[j], kind, parent)
                    .map(Some)
                    .map_err(|e| {
                        Error::format(format!("BAND {j} of channel {c}: {e}"), "a valid band")
                    })
            })
            .collect();
        // the first failing band in file order, as one at a time would report it
        for (&j, v) in bands.iter().zip(decoded) {
            q[j] = v?;
        }
    }
    Ok(q)
}

fn reconstruct(p: &Parsed, k: usize) -> Result<Raster> {
    let h = &p.header;
    let plan = &p.plan;
    let k = k.min(plan.pyr.depth());
    let region = plan.region(k);
    let npos: usize = region.iter().product();
    let c = h.channels;
    let ty = h.sample_type;
    if h.mode == Mode::Lossless {
        let planes = (0..c)
            .into_par_iter()
            .map(|ch| {
                let q = decode_channel(p, ch, k)?;
                let mut plane = vec![0i64; plan.pyr.shape.iter().product()];
                for (j, b) in q.iter().enumerate() {
                    if let Some(b) = b {
                        layout::scatter(&mut plane, &plan.pyr.shape, &plan.bands[j].ranges, b);
                    }
                }
                lossless::inverse(&mut plane, &plan.pyr, k);
                let full: Vec<std::ops::Range<usize>> = region.iter().map(|&e| 0..e).collect();
                Ok(layout::gather(&plane, &plan.pyr.shape, &full))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut planes = planes;
        if h.colour == Colour::YCoCgR {
            map3(&mut planes, lossless::ycocg_r_inv);
        }
        let samples = match ty {
            SampleType::F16 | SampleType::F32 | SampleType::F64 => {
                let w = (ty.size() * 8) as u32;
                let bits: Vec<u64> = (0..npos * c)
                    .map(|i| lossless::int_to_float_bits(planes[i % c][i / c], w))
                    .collect();
                match ty {
                    SampleType::F16 => Samples::F16(
                        bits.iter()
                            .map(|&b| half::f16::from_bits(b as u16))
                            .collect(),
                    ),
                    SampleType::F32 => {
                        Samples::F32(bits.iter().map(|&b| f32::from_bits(b as u32)).collect())
                    }
                    _ => Samples::F64(bits.iter().map(|&b| f64::from_bits(b)).collect()),
                }
            }
            _ => {
                let values: Vec<f64> = (0..npos * c).map(|i| planes[i % c][i / c] as f64).collect();
                Samples::from_f64(&values, ty)
            }
        };
        return finish(p, region, samples, k);
    }
    let mut values = lossy_values(h, plan, k, |ch| {
        let q = decode_channel(p, ch, k)?;
        Ok(q.into_iter()
            .enumerate()
            .map(|(j, b)| match (b, &p.bands[ch][j]) {
                (Some(b), Some(bc)) => Some(dequantized(h, plan, j, &b, bc.step)),
                _ => None,
            })
            .collect())
    })?;
    let mut samples = Samples::from_f64(&values, ty);
    if k == 0 && h.mode == Mode::MaxError {
        for (ch, r) in p.resi.iter().enumerate() {
            let Some(r) = r else { continue };
            let q =
                entropy::decode_band(&r.data, &h.dims, BandKind::Detail, None).map_err(|e| {
                    Error::format(format!("RESI of channel {ch}: {e}"), "a valid residual")
                })?;
            for i in 0..npos {
                values[i * c + ch] = samples.get_f64(i * c + ch) + q[i] as f64 * r.step;
            }
            let _ = ch;
        }
        samples = Samples::from_f64(&values, ty);
        let mut all: Vec<(usize, f64)> = Vec::new();
        for (ch, r) in p.resi.iter().enumerate() {
            if let Some(r) = r {
                for &(i, v) in &r.exceptions {
                    if (i as usize) < npos {
                        all.push((i as usize * c + ch, v));
                    }
                }
            }
        }
        if !all.is_empty() {
            let mut v = samples.to_f64();
            for (i, x) in all {
                v[i] = x;
            }
            samples = Samples::from_f64(&v, ty);
        }
    }
    finish(p, region, samples, k)
}

/// Quantization dead zone of band `j` (plain rounding for the coarse block).
fn band_rho(plan: &Plan, j: usize) -> f64 {
    if plan.bands[j].level == 0 {
        0.5
    } else {
        RHO
    }
}

/// Dequantization offset of band `j` (none for the coarse block).
fn band_delta(h: &Header, plan: &Plan, j: usize) -> f64 {
    if plan.bands[j].level == 0 {
        0.0
    } else {
        h.delta
    }
}

/// Band `j`'s values from its indices `q` and its step.
fn dequantized(h: &Header, plan: &Plan, j: usize, q: &[i64], step: f64) -> Vec<f32> {
    let d = band_delta(h, plan, j);
    q.iter()
        .map(|&x| quantize::dequantize(x, step, d) as f32)
        .collect()
}

/// A lossy file's samples (interleaved, clamped to the source's range, before the
/// `--max-error` residuals) of the coarse block after `k` levels (k = 0: full size):
/// per channel, its bands' dequantized values (`bands(channel)[band]`, None = absent,
/// as [`dequantized`] makes them) synthesized and taken back from YCoCg. The decoder's
/// way, and the encoder's `--psnr` search's.
fn lossy_values(
    h: &Header,
    plan: &Plan,
    k: usize,
    bands: impl Fn(usize) -> Result<Vec<Option<Vec<f32>>>> + Sync,
) -> Result<Vec<f64>> {
    let region = plan.region(k);
    let npos: usize = region.iter().product();
    let c = h.channels;
    let sub = plan.sub(k);
    let mut planes = (0..c)
        .into_par_iter()
        .map(|ch| {
            let q = bands(ch)?;
            let mut plane = vec![0f32; plan.pyr.shape.iter().product()];
            for (j, v) in q.iter().enumerate() {
                if let Some(v) = v {
                    layout::scatter(&mut plane, &plan.pyr.shape, &plan.bands[j].ranges, v);
                }
            }
            let full: Vec<std::ops::Range<usize>> = region.iter().map(|&e| 0..e).collect();
            let small = if k == 0 {
                plane
            } else {
                layout::gather(&plane, &plan.pyr.shape, &full)
            };
            let mut a = Array::from_shape_vec(&region, small)?;
            tensor::synthesize(&mut a, &sub)?;
            Ok(a.into_data())
        })
        .collect::<Result<Vec<_>>>()?;
    if h.colour == Colour::YCoCg {
        map3(&mut planes, ycocg_inverse);
    }
    let mut values = Vec::with_capacity(npos * c);
    if c == 1 {
        values.extend(planes[0].iter().map(|&x| (x as f64).clamp(h.min, h.max)));
    } else {
        for i in 0..npos {
            values.extend(planes.iter().map(|p| (p[i] as f64).clamp(h.min, h.max)));
        }
    }
    Ok(values)
}

fn finish(p: &Parsed, region: Vec<usize>, samples: Samples, k: usize) -> Result<Raster> {
    let h = &p.header;
    let mut r = Raster::new(region.clone(), h.channels, samples, h.kind)?;
    let maps = coarse_maps(p, k);
    r.meta = if k > 0 {
        p.meta.resampled(&h.dims, &region, &maps)
    } else {
        p.meta.clone()
    };
    mark_voids(&mut r, &h.dims, &maps);
    Ok(r)
}

/// Where a scheme's coarse sample `i` sits on the fine grid of one level: at fine index
/// `2i + o`. Haar (and the lossless S-transform): the mean of fine samples `2i`, `2i+1`,
/// `o = ½`. Chaikin: fine `2i`, `2i+1` are `¾ C_i + ¼ C_{i+1}` and `¼ C_i + ¾ C_{i+1}`,
/// so `C_i` sits at `o = −½`. Cubic B-spline: fine `2i` is `⅛ C_{i−1} + ¾ C_i + ⅛ C_{i+1}`,
/// `o = 0`. The schemes with an odd-length regular row (linear, linear-wide, cubic-wide, CDF
/// 9/7) centre `C_i` on fine `2i` (`o = 0`); chaikin-wide's even row, like Chaikin's, between fine
/// `2i − 1` and `2i` (`o = −½`).
pub fn coarse_offset(scheme: Scheme) -> f64 {
    match scheme {
        Scheme::Haar => 0.5,
        Scheme::Chaikin | Scheme::ChaikinWide => -0.5,
        Scheme::Cubic | Scheme::Linear | Scheme::LinearWide | Scheme::CubicWide | Scheme::Cdf97 => {
            0.0
        }
    }
}

/// Per spatial axis, where the samples of the coarse block after `k` levels sit on the
/// full grid: each level that shortens the axis maps by `step 2`, offset
/// [`coarse_offset`] (an odd length's carried last sample is off this grid by at most
/// half a coarse cell).
fn coarse_maps(p: &Parsed, k: usize) -> Vec<crate::io::AxisMap> {
    let h = &p.header;
    let o = if h.mode == Mode::Lossless {
        0.5
    } else {
        coarse_offset(h.scheme)
    };
    let pyr = &p.plan.pyr;
    (0..h.dims.len())
        .map(|a| {
            let mut m = crate::io::AxisMap::IDENTITY;
            if let Some(i) = pyr.spec.axes.iter().position(|&x| x == a) {
                let lens = &pyr.lengths[i];
                for l in 0..k.min(pyr.axis_levels(i)) {
                    if lens[l + 1] < lens[l] {
                        m = m.then(crate::io::AxisMap {
                            offset: o,
                            step: 2.0,
                        });
                    }
                }
            }
            m
        })
        .collect()
}

/// Decode from a stream of `len` bytes.
pub fn decode_stream<R: Read>(src: R, len: u64, opts: &DecodeOptions) -> Result<Decoded> {
    let p = read_chunks(src, len, opts.level, opts.allow_truncated)?;
    let raster = reconstruct(&p, opts.level)?;
    Ok(Decoded {
        raster,
        header: p.header,
        complete: p.complete,
    })
}

/// Decode the bytes of an `.mra` file.
pub fn decode(bytes: &[u8], opts: &DecodeOptions) -> Result<Decoded> {
    decode_stream(bytes, bytes.len() as u64, opts)
}

/// Decode a file, reading only the chunks needed.
pub fn decode_file(path: &Path, opts: &DecodeOptions) -> Result<Decoded> {
    let f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    decode_stream(std::io::BufReader::new(f), len, opts)
}

/// What `mra info` shows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Info {
    pub version: String,
    pub kind: String,
    pub dims: Vec<usize>,
    pub channels: usize,
    pub sample_type: String,
    pub mode: String,
    pub scheme: String,
    pub boundary: String,
    pub levels: usize,
    /// The colour transform, if any (`YCoCg`, or `YCoCg-R` in integers).
    pub colour: Option<String>,
    pub step: f64,
    /// The bound a `--max-error` file guarantees (none in other files).
    pub max_error: Option<f64>,
    pub range: [f64; 2],
    pub file_bytes: u64,
    pub bits_per_position: f64,
    pub complete: bool,
    /// Bytes and bits per position by level (0 = coarse block, then coarsest details first).
    pub levels_bytes: Vec<(usize, u64, f64)>,
    pub chunks: Vec<ChunkInfo>,
}

/// Read a file's header and chunk table (verifying every CRC).
pub fn info(bytes: &[u8]) -> Result<Info> {
    let p = read_chunks(bytes, bytes.len() as u64, 0, true)?;
    let h = &p.header;
    let pos: f64 = h.dims.iter().map(|&d| d as f64).product();
    let mut lv: std::collections::BTreeMap<usize, u64> = Default::default();
    for c in &p.chunks {
        if let Some(l) = c.level {
            *lv.entry(l).or_default() += c.bytes;
        }
    }
    let mut levels_bytes: Vec<(usize, u64, f64)> = lv
        .into_iter()
        .map(|(l, b)| (l, b, b as f64 * 8.0 / pos))
        .collect();
    levels_bytes.sort_by_key(|&(l, _, _)| if l == 0 { 0 } else { usize::MAX - l });
    Ok(Info {
        version: format!("{}.{}", h.major, h.minor),
        kind: format!("{:?}", h.kind).to_lowercase(),
        dims: h.dims.clone(),
        channels: h.channels,
        sample_type: h.sample_type.name().into(),
        mode: format!("{:?}", h.mode).to_lowercase(),
        scheme: if h.mode == Mode::Lossless {
            "integer-haar".into()
        } else {
            h.scheme.name().into()
        },
        boundary: h.boundary.name().into(),
        levels: p.plan.pyr.depth(),
        colour: match h.colour {
            Colour::None => None,
            Colour::YCoCg => Some("YCoCg".into()),
            Colour::YCoCgR => Some("YCoCg-R".into()),
        },
        step: h.step,
        // stored only by `--max-error` (0 otherwise)
        max_error: (h.max_error > 0.0).then_some(h.max_error),
        range: [h.min, h.max],
        file_bytes: bytes.len() as u64,
        bits_per_position: bytes.len() as f64 * 8.0 / pos,
        complete: p.complete,
        levels_bytes,
        chunks: p.chunks,
    })
}

/// PSNR after keeping the largest `keep` percent of details, no quantization (the
/// notes' Figure 9.19 protocol; details weighted by synthesis gain when `weighted`).
pub fn keep_psnr(
    r: &Raster,
    scheme: Scheme,
    boundary: Boundary,
    levels: usize,
    keep: f64,
    weighted: bool,
) -> Result<f64> {
    let opts = EncodeOptions {
        scheme,
        boundary,
        levels,
        rate: Rate::Keep(keep),
    };
    let mut p = prepare(r, &opts, Mode::Lossy)?;
    if !weighted {
        p.gains.iter_mut().for_each(|g| *g = 1.0);
        p.weights.iter_mut().for_each(|w| *w = 1.0);
    }
    let mut w = p.weighted_details();
    let t = quantize::keep_threshold(&mut w, keep) as f32;
    let plan = &p.plan;
    let spec = plan.pyr.spec.clone();
    let c = r.channels;
    let mut planes = Vec::new();
    for (ch, plane) in p.coeffs.iter().enumerate() {
        let mut plane = plane.clone();
        for (j, b) in plan.bands.iter().enumerate() {
            if b.level == 0 {
                continue;
            }
            let wgt = (p.gains[j] * p.weights[ch]) as f32;
            layout::rows(&plan.pyr.shape, &b.ranges, |off, run, _| {
                for x in &mut plane[off..off + run] {
                    if x.abs() * wgt < t {
                        *x = 0.0;
                    }
                }
            });
        }
        let mut a = Array::from_shape_vec(&r.dims, plane)?;
        tensor::synthesize(&mut a, &plan.pyr)?;
        planes.push(a.into_data());
    }
    let _ = spec;
    if p.header.colour == Colour::YCoCg {
        map3(&mut planes, ycocg_inverse);
    }
    let n = r.positions();
    let v: Vec<f64> = (0..n * c).map(|i| planes[i % c][i / c] as f64).collect();
    let out = Raster::new(
        r.dims.clone(),
        c,
        Samples::from_f64(&v, r.sample_type()),
        r.kind,
    )?;
    let cmp = crate::metrics::compare(r, &out, &Default::default())?;
    Ok(cmp.psnr.unwrap_or(f64::INFINITY))
}

/// Keep frames `a..b` of the slowest axis (time of an (x, y, t) sequence, slices of
/// a volume); the origin moves to frame `a` ([`crate::io::AxisMap::crop`]).
pub fn frames(r: Raster, a: usize, b: usize) -> Result<Raster> {
    let t = if r.dims.len() >= 2 { r.dims[0] } else { 0 };
    if a >= b || b > t {
        return Err(Error::parameter(
            "frames",
            format!("{a}..{b} of {t}"),
            "a non-empty range within the slowest axis of a 2-D or 3-D raster",
        ));
    }
    let per = r.samples.len() / t;
    let v = r.samples.to_f64();
    let mut dims = r.dims.clone();
    dims[0] = b - a;
    let samples = match &r.samples {
        Samples::F16(x) => Samples::F16(x[a * per..b * per].to_vec()),
        Samples::F32(x) => Samples::F32(x[a * per..b * per].to_vec()),
        _ => Samples::from_f64(&v[a * per..b * per], r.sample_type()),
    };
    let mut maps = vec![crate::io::AxisMap::IDENTITY; r.dims.len()];
    maps[0] = crate::io::AxisMap::crop(a);
    let meta = r.meta.resampled(&r.dims, &dims, &maps);
    let mut out = Raster::new(dims, r.channels, samples, r.kind)?;
    out.meta = meta;
    Ok(out)
}

/// Kind names for the CLI.
pub fn kind_name(k: DataKind) -> &'static str {
    match k {
        DataKind::Image => "image",
        DataKind::Volume => "volume",
        DataKind::Heightmap => "heightmap",
        DataKind::Sequence => "sequence",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{images, phantom};
    use crate::io::SampleType;

    /// The rate search on model curves: `(evaluations, v at the returned step)`.
    fn run_search(large_ok: bool, tol: f64, v: impl Fn(f64) -> f64) -> (usize, f64) {
        run_search_with(large_ok, tol, None, v)
    }

    /// [`run_search`] with a model of `v`.
    fn run_search_with(
        large_ok: bool,
        tol: f64,
        model: Option<&dyn Fn(f64) -> f64>,
        v: impl Fn(f64) -> f64,
    ) -> (usize, f64) {
        let r = images::zone_plate(8, 8).to_raster(SampleType::U8).unwrap();
        let p = prepare(&r, &EncodeOptions::default(), Mode::Lossy).unwrap();
        let calls = std::cell::Cell::new(0);
        let bytes = search(&p, 1000.0, large_ok, tol, model, |step| {
            calls.set(calls.get() + 1);
            Ok((v(step.ln()), Some(step.ln().to_le_bytes().to_vec())))
        })
        .unwrap();
        let x = f64::from_le_bytes(bytes[..8].try_into().unwrap());
        (calls.get(), v(x))
    }

    #[test]
    fn search_finds_the_target_in_a_few_candidates() {
        let k = 20.0 / std::f64::consts::LN_10;
        // PSNR-like (falls with the step), size-like (rises), a staircase, a curve that
        // is infinite (identical output) at small steps, one not quite linear
        // (size-like, v(ln step), most candidates)
        type Case<'a> = (bool, &'a dyn Fn(f64) -> f64, usize);
        let cases: [Case; 5] = [
            (false, &|x| 30.0 - k * x, 3),
            (true, &|x| 1.3 * x - 2.0, 4),
            (false, &|x| 30.0 - k * (x * 4.0).floor() / 4.0, 30),
            (
                false,
                &|x| {
                    if x < -3.0 {
                        f64::INFINITY
                    } else {
                        20.0 - k * x
                    }
                },
                4,
            ),
            (false, &|x| 45.0 - k * x - 0.4 * x * x.abs(), 6),
        ];
        for (i, (large_ok, v, most)) in cases.into_iter().enumerate() {
            let (n, at) = run_search(large_ok, 0.02, v);
            assert!(at >= 0.0, "case {i}: target not met ({at})");
            assert!(n <= most, "case {i}: {n} candidates");
            if i == 2 {
                // the staircase's lowest met stair (30 − 13·k/4)
                assert!((at - (30.0 - 13.0 * k / 4.0)).abs() < 1e-9, "case 2: {at}");
            } else {
                assert!(at <= 0.02, "case {i}: {at} above the tolerance");
            }
        }
    }

    /// A model of the right shape but the wrong level takes the search to the target in
    /// two candidates (the first where the model meets it, the second where the model,
    /// shifted through the first, does); a model of the wrong shape still ends within
    /// the tolerance, and the rate model of an image gives its coded sizes and squared
    /// errors within a factor of 2.5.
    #[test]
    fn search_with_a_model() {
        let v = |x: f64| 1.3 * x - 2.0;
        // (off by 3 in v, 2.3 in x: within the 3 units a step may go)
        let off = |x: f64| 1.3 * x + 1.0;
        let (n, at) = run_search_with(true, 0.01, Some(&off), v);
        assert!(
            n <= 2 && (0.0..=0.01).contains(&at),
            "{n} candidates, v = {at}"
        );
        let bent = |x: f64| 0.2 * x + 0.1 * x * x.abs();
        let (n, at) = run_search_with(true, 0.01, Some(&bent), v);
        assert!(
            n <= 10 && (0.0..=0.01).contains(&at),
            "{n} candidates, v = {at}"
        );
        // the size model against the coded sizes of a zone plate
        let r = images::zone_plate(96, 128)
            .to_raster(SampleType::U8)
            .unwrap();
        let p = prepare(&r, &EncodeOptions::default(), Mode::Lossy).unwrap();
        let m = p.rate_model();
        let src = r.samples.to_f64();
        for step in [2.0, 8.0, 32.0] {
            let real = p.code(step).len() as f64 * 8.0;
            let est = m.bits(step);
            assert!(
                est > real / 2.5 && est < real * 2.5,
                "step {step}: {est} vs {real}"
            );
            // and the squared error against the decoder's samples
            let dec = p.decoded(step).unwrap().samples.to_f64();
            let real: f64 = src.iter().zip(&dec).map(|(a, b)| (a - b) * (a - b)).sum();
            let est = m.squared_error(step);
            assert!(
                est > real / 2.5 && est < real * 2.5,
                "step {step}: squared error {est} vs {real}"
            );
        }
    }

    /// The `--psnr` search measures [`Prepared::decoded`] instead of decoding each
    /// candidate file: it must be exactly what the decoder makes of that file.
    #[test]
    fn decoded_is_what_the_decoder_makes() {
        let rasters = [
            images::zone_plate(37, 50)
                .to_raster(SampleType::U8)
                .unwrap(),
            images::gradient(20, 33, 3)
                .to_raster(SampleType::U16)
                .unwrap(),
            images::noise(17, 24, 1, 5)
                .to_raster(SampleType::F32)
                .unwrap(),
            phantom::shepp_logan(12, 10, 14)
                .to_raster(SampleType::I16)
                .unwrap(),
        ];
        for r in &rasters {
            for scheme in Scheme::ALL {
                let opts = EncodeOptions {
                    scheme,
                    boundary: Boundary::Symmetric,
                    levels: 4,
                    rate: Rate::Quality(50.0),
                };
                let p = prepare(r, &opts, Mode::Lossy).unwrap();
                let range = p.header.max - p.header.min;
                for step in [range * 1e-4, range * 0.01, range * 0.3] {
                    let file = decode(&p.code(step), &DecodeOptions::default()).unwrap();
                    let ours = p.decoded(step).unwrap();
                    assert_eq!(
                        ours.samples,
                        file.raster.samples,
                        "{} {scheme:?} step {step}",
                        r.summary()
                    );
                }
            }
        }
    }
}
