//! The base step of each rate mode: set, from the details, or searched on `ln(step)`
//! with a secant and a model of size and error ([`RateModel`]); and the keep-P% PSNR
//! of the notes' Figure 9.19.

use super::colour::{map3, ycocg_inverse};
use super::layout;
use super::lossy::{prepare, Prepared};
use super::options::{EncodeOptions, Ladder, Rate, BPP_LEVEL_CHOICES};
use super::plan::band_rho;
use crate::entropy::range::Encoder;
use crate::entropy::{band, codeblocks, BandKind};
use crate::format::bands::blocks_payload;
use crate::format::header::Colour;
use crate::format::Mode;
use crate::io::{Raster, RasterView, Samples};
use crate::quantize::{self, RHO};
use crate::scheme::{Boundary, Scheme};
use crate::tensor::{self, Array};
use crate::{Error, Result};
use rayon::prelude::*;

/// A lossy file at the base step the rate mode asks for: set (`--quality`), from the
/// details (`--keep`, `--threshold`), or searched (`--psnr`, `--bpp`).
///
/// `lossless()` makes the `--lossless` file: `--bpp` returns it when the budget is near
/// the lossless cost or above ([`LOSSLESS_SHARE`]) and it fits the budget (no error at
/// all); `--psnr` near the lossless cost ([`LOSSLESS_STEP`]) and `--quality 100` return
/// it when it is no larger than their lossy file.
pub(super) fn encode_lossy(
    r: &RasterView<'_>,
    opts: &EncodeOptions,
    rate: Rate,
    lossless: &dyn Fn() -> Result<Vec<u8>>,
) -> Result<Vec<u8>> {
    if matches!(rate, Rate::Bpp(_)) && opts.ladder().bpp_levels {
        return bpp_levels(r, opts, rate, lossless);
    }
    let p = prepare(r, opts, Mode::Lossy)?;
    encode_prepared(p, rate, opts.ladder(), Some(r), lossless)
}

/// Effort 9's `--bpp`: the file at each number of levels from `opts.levels` down
/// ([`BPP_LEVEL_CHOICES`] counts, at least 1), each within the budget, and the one
/// whose decode has the least squared error `Σ (x − x̂)²` over the samples that are not
/// void (the first of equal ones). Fewer levels pay on small rasters, where each
/// band's adaptive models learn from few coefficients: the Boulder grid (240×144) at
/// 0.5 bits per sample, 6 levels 44.12 dB, 2 levels 44.94 dB.
fn bpp_levels(
    r: &RasterView<'_>,
    opts: &EncodeOptions,
    rate: Rate,
    lossless: &dyn Fn() -> Result<Vec<u8>>,
) -> Result<Vec<u8>> {
    let voids = super::voids::void_mask(r);
    let most = opts.levels;
    let least = most.saturating_sub(BPP_LEVEL_CHOICES - 1).max(1).min(most);
    let mut best: Option<(f64, Vec<u8>)> = None;
    for levels in (least..=most).rev() {
        let o = EncodeOptions {
            levels,
            ..opts.clone()
        };
        let p = prepare(r, &o, Mode::Lossy)?;
        let bytes = encode_prepared(p, rate, o.ladder(), Some(r), lossless)?;
        let err = squared_error(r, &bytes, voids.as_deref())?;
        let exact = err == 0.0;
        if best.as_ref().is_none_or(|(e, _)| err < *e) {
            best = Some((err, bytes));
        }
        crate::tuning::release_freed();
        if exact {
            break; // the lossless file, or one as good
        }
    }
    Ok(best.expect("at least one level count").1)
}

/// `Σ (x − x̂)²` of the decode of `file` against `r`, over the samples that are neither
/// void (`voids`) nor, in the source, infinite or NaN: summed in runs of 2^16 samples in
/// parallel, then the runs' sums in order, so that the total (and the file kept) does not
/// depend on the thread count.
fn squared_error(r: &RasterView<'_>, file: &[u8], voids: Option<&[bool]>) -> Result<f64> {
    const RUN: usize = 1 << 16;
    let dec = super::decode::decode_untiled(
        file,
        file.len() as u64,
        &super::options::DecodeOptions::default(),
    )?
    .raster
    .samples;
    let n = r.samples.len();
    let runs: Vec<f64> = (0..n.div_ceil(RUN))
        .into_par_iter()
        .map(|k| {
            (k * RUN..((k + 1) * RUN).min(n))
                .filter(|&i| !voids.is_some_and(|m| m[i]))
                .map(|i| {
                    let x = r.samples.get_f64(i);
                    if x.is_finite() {
                        (x - dec.get_f64(i)).powi(2)
                    } else {
                        0.0
                    }
                })
                .sum::<f64>()
        })
        .collect();
    Ok(runs.iter().sum())
}

/// Check the rate mode's number: a quality from 1 to 100, a keep percentage from 0 to
/// 100, a positive threshold and bpp, a PSNR target between 0 and 400 dB and a positive,
/// finite data range.
pub(crate) fn check_rate(rate: Rate) -> Result<()> {
    match rate {
        Rate::Quality(q) if !(1.0..=100.0).contains(&q) => {
            Err(Error::parameter("quality", q, "1 to 100"))
        }
        Rate::Keep(k) if !(0.0..=100.0).contains(&k) => {
            Err(Error::parameter("keep", k, "a percentage from 0 to 100"))
        }
        Rate::Threshold(t) if !(t > 0.0 && t.is_finite()) => {
            Err(Error::parameter("threshold", t, "a positive number"))
        }
        Rate::Bpp(b) if !(b > 0.0 && b.is_finite()) => Err(Error::parameter(
            "bpp",
            b,
            "a positive number of bits per position",
        )),
        Rate::Psnr(db) | Rate::PsnrRange(db, _) if !(db > 0.0 && db < 400.0) => Err(
            Error::parameter("psnr", db, "a target in dB between 0 and 400"),
        ),
        Rate::PsnrRange(_, p) if !(p.is_finite() && p > 0.0) => Err(Error::parameter(
            "data range",
            p,
            "a positive, finite peak-to-peak range",
        )),
        _ => Ok(()),
    }
}

/// The base step of `--quality q` on data of peak-to-peak range `range`:
/// `range · 2^(−q/10)`.
pub(crate) fn quality_step(q: f64, range: f64) -> f64 {
    range * (2f64).powf(-q / 10.0)
}

/// The base step of `--keep k`: the threshold `t` of the largest `k`% of the weighted
/// details `w`, as `t / (1 − ρ)` (at least `range · 10⁻⁹`; `range · 10⁶` when nothing is
/// kept).
pub(crate) fn keep_step(w: &mut [f32], k: f64, range: f64) -> f64 {
    let t = quantize::keep_threshold(w, k);
    if t.is_infinite() {
        range * 1e6
    } else {
        (t / (1.0 - RHO)).max(range * 1e-9)
    }
}

/// [`encode_lossy`] of a transform already prepared; `r` is the raster, needed by
/// `--psnr` alone (its candidates are compared with it): without it `--psnr` is an
/// error.
pub(super) fn encode_prepared(
    mut p: Prepared,
    rate: Rate,
    ladder: Ladder,
    r: Option<&RasterView<'_>>,
    lossless: &dyn Fn() -> Result<Vec<u8>>,
) -> Result<Vec<u8>> {
    check_rate(rate)?;
    if matches!(
        rate,
        Rate::Quality(_) | Rate::Psnr(_) | Rate::PsnrRange(..) | Rate::Bpp(_)
    ) && ladder.rdo
    {
        p.optimise();
    }
    let range = (p.header.max - p.header.min).max(1e-30);
    let integer = !p.header.sample_type.is_float();
    let step = match rate {
        Rate::Keep(k) => keep_step(&mut p.weighted_details(), k, range),
        Rate::Threshold(t) => t / (1.0 - RHO),
        Rate::Quality(q) => quality_step(q, range),
        Rate::Psnr(db) | Rate::PsnrRange(db, _) => {
            let Some(r) = r else {
                return Err(Error::parameter(
                    "psnr",
                    db,
                    "a raster in memory to compare the candidates with",
                ));
            };
            return encode_psnr(&p, rate, db, r, lossless);
        }
        Rate::Bpp(b) => return encode_bpp(&p, b, ladder.bpp_floor, lossless),
        _ => unreachable!(),
    };
    let lossy = p.code(step);
    // `--quality 100` (the finest step the mode has): at a step of a few units of
    // integer samples or less it costs more than the exact file. Lower qualities keep
    // the scheme asked for (its coarse levels are what `--level` decodes)
    let near_unit = matches!(rate, Rate::Quality(q) if q >= 100.0) && step <= LOSSLESS_STEP;
    smaller_of(lossy, integer && near_unit, lossless)
}

/// `--psnr db` of the prepared transform `p` of the raster `r`: the step searched on
/// the decoded candidates' PSNR, or the lossless file when it is no larger near the
/// lossless cost.
fn encode_psnr(
    p: &Prepared,
    rate: Rate,
    db: f64,
    r: &RasterView<'_>,
    lossless: &dyn Fn() -> Result<Vec<u8>>,
) -> Result<Vec<u8>> {
    let range = (p.header.max - p.header.min).max(1e-30);
    let integer = !p.header.sample_type.is_float();
    // each candidate decoded from its quantized bands, coded only once chosen;
    // the data range `mra compare` would use, found once
    let cmp = crate::metrics::CompareOptions {
        data_range: Some(match rate {
            Rate::PsnrRange(_, range) => range,
            _ => crate::metrics::skimage_data_range(r.samples),
        }),
        ..Default::default()
    };
    let (errors, peak) = (p.rate_model(), cmp.data_range.unwrap_or(range));
    let n = (r.positions() * r.channels) as f64;
    let model = |x: f64| {
        let mse = (errors.squared_error(x.exp()) / n).max(1e-300);
        10.0 * (peak * peak / mse).log10() - db
    };
    let lossy = search(p, range, false, 0.02, Some(&model), |step| {
        let dec = p.decoded(step)?;
        let psnr = crate::metrics::psnr_view(r, &dec.view(), &cmp)?;
        Ok((psnr.unwrap_or(f64::INFINITY) - db, None))
    })?;
    // the lossless file meets every target (its PSNR is infinite)
    let near_unit = db >= unit_psnr(peak, LOSSLESS_STEP);
    smaller_of(lossy, integer && near_unit, lossless)
}

/// `--bpp b` of the prepared transform `p`: the lossless file when it fits the budget
/// near the lossless cost, else the calibrated or searched step, a file of at least
/// `floor · b` bits per position.
fn encode_bpp(
    p: &Prepared,
    b: f64,
    floor: f64,
    lossless: &dyn Fn() -> Result<Vec<u8>>,
) -> Result<Vec<u8>> {
    let range = (p.header.max - p.header.min).max(1e-30);
    let pos = p.header.dims.iter().product::<usize>() as f64;
    // v = ln b − ln bpp: met when the file is within the budget, within
    // 1% under it at −ln 0.99; the log of the size is close to a line in
    // ln(step), where the size itself bends (10 candidates at 1 bpp on
    // kodim01 against 5)
    let sizes = p.rate_model();
    let model = |x: f64| b.ln() - (sizes.bits(x.exp()) / pos).ln();
    if !p.header.sample_type.is_float() && b * pos >= LOSSLESS_SHARE * sizes.bits(1.0) {
        let bytes = lossless()?;
        if bytes.len() as f64 * 8.0 <= b * pos {
            return Ok(bytes);
        }
    }
    if let Some(bytes) = calibrated_bpp(p, range, b * pos, floor, &model) {
        return Ok(bytes);
    }
    search(p, range, true, -(floor.ln()), Some(&model), |step| {
        let bytes = p.code(step);
        Ok((b.ln() - (bytes.len() as f64 * 8.0 / pos).ln(), Some(bytes)))
    })
}

/// The base step (in units of integer samples) at or below which `--psnr` and
/// `--quality 100` also make the `--lossless` file and keep the smaller of the two: at a
/// step of 2 the lossy file's error is about a unit, so the exact file is often smaller.
const LOSSLESS_STEP: f64 = 2.0;

/// The PSNR of uniform quantization at base step `s` on data of peak-to-peak range
/// `peak`: MSE ≈ s²/12, so PSNR ≈ 10·log10(12·peak² / s²). A target at or above the
/// value for [`LOSSLESS_STEP`] is near the lossless cost.
fn unit_psnr(peak: f64, s: f64) -> f64 {
    10.0 * (12.0 * peak * peak / (s * s)).log10()
}

/// `lossy`, or the `--lossless` file when `try_lossless` and it is no larger: an exact
/// file at no more bytes beats any lossy one.
fn smaller_of(
    lossy: Vec<u8>,
    try_lossless: bool,
    lossless: &dyn Fn() -> Result<Vec<u8>>,
) -> Result<Vec<u8>> {
    if try_lossless {
        let exact = lossless()?;
        if exact.len() <= lossy.len() {
            return Ok(exact);
        }
    }
    Ok(lossy)
}

/// `--bpp` on integer samples tries the lossless file first when the budget is at least
/// this share of the rate model's size at base step 1 (the samples' unit, about the
/// lossless cost; the model is within a factor of 2.5): a lossless file within the
/// budget has no error at all, and a budget that far below it is never met by one.
const LOSSLESS_SHARE: f64 = 0.5;

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

/// The `--bpp` file found with few full encodes: `budget` in bits, `model(x)` = the
/// rate model's `ln b − ln bpp` at `x = ln(step)`. Returns the file when it is within
/// the budget and at most 1% under it, else `None` (the caller's [`search`] then codes
/// candidates in full).
///
/// The sampled size ([`Prepared::sampled_bits`], about an eighth of the work) times a
/// calibration `r` stands for the real size: `r` is first [`SAMPLED_RATIO`], then
/// `S / Ŝ(x)` measured at the last full encode (size `S` at `x`). The next `x` to code
/// in full is where `r·Ŝ` meets the aim (0.5% under the budget), found by secant steps on
/// `ln Ŝ` in `x` (the first with the model's slope), each a sampled size only. Once two
/// full encodes bracket the budget, the next is their secant in `(x, ln S)` instead
/// (regula falsi, kept inside the bracket's middle 80%), with no sampled size. The
/// calibrated first guess usually lands the first or second full encode in the window.
fn calibrated_bpp(
    p: &Prepared,
    range: f64,
    budget: f64,
    floor: f64,
    model: &dyn Fn(f64) -> f64,
) -> Option<Vec<u8>> {
    const ROUNDS: usize = 6;
    let (x_min, x_max) = ((range * 1e-7).ln(), (range * 4.0).ln());
    // the middle of the window [floor, 1] of the budget
    let mid = 0.5 * (1.0 + floor);
    let aim = (mid * budget).ln();
    // the model's ln b − ln bpp rises with x; met at the window's middle
    let x0 = model_root(model, 0.0, -(mid.ln()), 1.0, (range / 32.0).ln()).clamp(x_min, x_max);
    // where r·Ŝ meets the aim, from `x` where ln(r·Ŝ) − aim = `g`
    let sampled_root = |x: f64, g: f64, cal: f64| -> f64 {
        let (mut xa, mut ga) = (x, g);
        let h = 0.05;
        let mut slope = -(model(x + h) - model(x - h)) / (2.0 * h);
        if !(slope < -1e-3 && slope.is_finite()) {
            slope = -0.7;
        }
        for _ in 0..5 {
            let xb = (xa - ga / slope)
                .clamp(xa - 1.0, xa + 1.0)
                .clamp(x_min, x_max);
            if (xb - xa).abs() < 1e-6 {
                break;
            }
            let gb = cal + p.sampled_bits(xb.exp()).max(1.0).ln() - aim;
            let s = (gb - ga) / (xb - xa);
            if s < -1e-3 && s.is_finite() {
                slope = s;
            }
            (xa, ga) = (xb, gb);
            if ga.abs() < 0.002 {
                break;
            }
        }
        xa
    };
    // a narrow coder's static codes spend about 9% more than the context coder (which
    // codes the sample when the indices are rate–distortion optimised by its costs;
    // else the file's coder codes it, [`Prepared::sampled_bits`])
    let narrow =
        if p.plan.coder.is_narrow() && p.rdo.is_some() && !p.plan.coder.chooses_its_indices() {
            1.09
        } else {
            1.0
        };
    let cal0 = (SAMPLED_RATIO * narrow).ln();
    let s0 = p.sampled_bits(x0.exp());
    if s0.is_nan() || s0 <= 0.0 {
        return None;
    }
    let mut x = sampled_root(x0, cal0 + s0.ln() - aim, cal0);
    // the real encodes nearest the aim on either side: (x, ln S − aim)
    let mut over: Option<(f64, f64)> = None;
    let mut under: Option<(f64, f64)> = None;
    for _ in 0..ROUNDS {
        let bytes = p.code(x.exp());
        let real = bytes.len() as f64 * 8.0;
        if real <= budget && real >= floor * budget {
            return Some(bytes);
        }
        if real.is_nan() || real <= 0.0 {
            return None;
        }
        let g = real.ln() - aim;
        // the size falls as x rises
        if real > budget {
            if over.is_none_or(|(xo, _)| x > xo) {
                over = Some((x, g));
            }
        } else if under.is_none_or(|(xu, _)| x < xu) {
            under = Some((x, g));
        }
        let next = match (over, under) {
            (Some((xo, go)), Some((xu, gu))) => {
                let (lo, hi) = (xo.min(xu), xo.max(xu));
                if hi - lo < 1e-4 {
                    break;
                }
                let t = xo + go * (xu - xo) / (go - gu);
                t.clamp(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo))
            }
            _ => {
                let sampled = p.sampled_bits(x.exp());
                if sampled.is_nan() || sampled <= 0.0 {
                    return None;
                }
                sampled_root(x, g, (real / sampled).ln())
            }
        };
        if (next - x).abs() < 1e-6 {
            break;
        }
        x = next;
    }
    None
}

/// The usual ratio of a coded size to its sampled estimate ([`Prepared::sampled_bits`]
/// misses the parent context and restarts the models in every band): the calibration
/// of [`calibrated_bpp`]'s first guess.
const SAMPLED_RATIO: f64 = 0.95;

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
    /// Rows along the first (slowest) axis in each block of [`Prepared::sampled_bits`].
    const SAMPLE_BLOCK: usize = 8;
    /// One block in this many is coded.
    const SAMPLE_EVERY: usize = 8;

    /// An estimate of the coded bits at base step `step` from a fraction of the work:
    /// every band's blocks of [`Self::SAMPLE_BLOCK`] indices along its first axis (fewer
    /// in a band shorter than two such periods, at least one), one in
    /// [`Self::SAMPLE_EVERY`] (all of a band shorter than two periods of one), coded as one
    /// band of their own with no parent context (by the context coder, or, when the
    /// indices are not optimised, by a narrow coder's file's own coder in code-blocks of
    /// the file's extents, and by coder 2 by its own choice when it chooses them), the
    /// bits scaled by the band's count over
    /// the count coded. Biased (the parent context is missing, the models learn
    /// each sample afresh), but by a ratio nearly constant between nearby steps, which
    /// [`calibrated_bpp`] measures.
    pub(super) fn sampled_bits(&self, step: f64) -> f64 {
        let plan = &self.plan;
        let (b, k) = (Self::SAMPLE_BLOCK, Self::SAMPLE_EVERY);
        self.band_channels()
            .par_iter()
            .map(|&(j, c)| {
                let ranges = &plan.bands[j].ranges;
                let len0 = ranges[0].len();
                let mut picked: Vec<std::ops::Range<usize>> = Vec::new();
                // shorter blocks in shorter bands (one in k all the same)
                let b = b.min(len0 / (2 * k));
                if b > 0 {
                    let mut at = 0;
                    while at < len0 {
                        let s = ranges[0].start + at;
                        picked.push(s..(s + b).min(ranges[0].end));
                        at += b * k;
                    }
                } else {
                    picked.push(ranges[0].clone());
                }
                let mut x: Vec<f32> = Vec::new();
                let mut sub = ranges.clone();
                for r0 in &picked {
                    sub[0] = r0.clone();
                    x.extend(layout::gather(&self.coeffs[c], &plan.pyr.shape, &sub));
                }
                let kept: usize = picked.iter().map(|r| r.len()).sum();
                let mut dims = plan.dims[j].clone();
                dims[0] = kept;
                let total: usize = plan.dims[j].iter().product();
                if x.is_empty() {
                    return 0.0;
                }
                let s = self.band_step(step, j, c);
                let bytes = match (self.rdo, plan.bands[j].level) {
                    // coder 2's file: the sample chosen and coded by coder 2's own
                    // rate–distortion choice, as the file's blocks are (a third of the
                    // context coder's time)
                    (Some(lambda), l) if l > 0 && plan.coder.chooses_its_indices() => {
                        let scaled: Vec<f32> = x.iter().map(|&v| (v as f64 / s) as f32).collect();
                        let g = codeblocks::Grid::new(&dims, plan.block(j));
                        let (streams, _) = codeblocks::encode_blocks_rdo_by(
                            &g,
                            None,
                            lambda,
                            plan.coding,
                            plan.coder,
                            false,
                            |b| codeblocks::extract(&scaled, &dims, b),
                        );
                        blocks_payload(&streams).len()
                    }
                    (Some(lambda), l) if l > 0 => {
                        let scaled: Vec<f32> = x.iter().map(|&v| (v as f64 / s) as f32).collect();
                        let mut e = Encoder::new();
                        band::encode_rdo(&mut e, &scaled, &dims, None, lambda, plan.coding);
                        e.finish_short().len()
                    }
                    (_, l) => {
                        let rho = band_rho(plan, j);
                        let q: Vec<i64> = x
                            .iter()
                            .map(|&v| quantize::quantize(v as f64, s, rho))
                            .collect();
                        let kind = if l == 0 {
                            BandKind::Coarse
                        } else {
                            BandKind::Detail
                        };
                        match plan.grid(j) {
                            // a narrow coder's file: the sample coded by that coder (a
                            // fraction of the context coder's time)
                            Some(_)
                                if plan.coder.is_narrow()
                                    && (self.rdo.is_none() || plan.coder.chooses_its_indices()) =>
                            {
                                let g = codeblocks::Grid::new(&dims, plan.block(j));
                                blocks_payload(&codeblocks::encode_blocks(
                                    &q,
                                    &g,
                                    kind,
                                    None,
                                    plan.coding,
                                    plan.coder,
                                ))
                                .len()
                            }
                            _ => band::encode_stream(&q, &dims, kind, None, plan.coding).len(),
                        }
                    }
                };
                bytes as f64 * 8.0 * total as f64 / x.len() as f64
            })
            .collect::<Vec<f64>>()
            // summed in band order: the same estimate, and so the same file, on any
            // number of threads
            .into_iter()
            .sum()
    }

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
                let plane = &self.coeffs[c];
                // the band read in place, row by row (counts: any order sums the same)
                layout::rows(&plan.pyr.shape, &plan.bands[j].ranges, |off, run, _| {
                    for &v in &plane[off..off + run] {
                        let a = v.abs() * scale;
                        if !(a > 0.0 && a.is_finite()) {
                            zeros += 1.0;
                            continue;
                        }
                        // log2 from the bits: exponent plus the mantissa as a fraction
                        // (off by under 0.09 octave, about a bin)
                        let b = a.to_bits();
                        let y =
                            ((b >> 23) as i32 - 127) as f32 + (b & 0x7F_FFFF) as f32 / 8_388_608.0;
                        let k = ((y as f64 - RateModel::LOW) * RateModel::BINS_PER_OCTAVE) as isize;
                        bins[k.clamp(0, nbins as isize - 1) as usize] += 1.0;
                    }
                });
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
        format: Default::default(),
        effort: crate::codec::DEFAULT_EFFORT,
    };
    let mut p = prepare(&r.view(), &opts, Mode::Lossy)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::images;
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
        let p = prepare(&r.view(), &EncodeOptions::default(), Mode::Lossy).unwrap();
        let calls = std::cell::Cell::new(0);
        let bytes = search(&p, 1000.0, large_ok, tol, model, |step| {
            calls.set(calls.get() + 1);
            Ok((v(step.ln()), Some(step.ln().to_le_bytes().to_vec())))
        })
        .unwrap();
        let x = f64::from_le_bytes(bytes[..8].try_into().unwrap());
        (calls.get(), v(x))
    }

    /// The calibrated `--bpp` search lands within 1% under the budget on its own (no
    /// fallback to the full search) on a 3-channel picture, at low and high rates.
    #[test]
    fn calibrated_bpp_lands_within_one_percent_under_the_budget() {
        let mut f = images::strokes(384, 512, 7);
        let g = images::noise(384, 512, 1, 3);
        for (a, b) in f.values.data_mut().iter_mut().zip(g.data()) {
            *a += 0.05 * b;
        }
        let grey = f.to_raster(SampleType::U8).unwrap();
        let c = grey.samples.to_f64();
        let rgb: Vec<f64> = c
            .iter()
            .flat_map(|&v| [v, (255.0 - v) * 0.5, (v * 0.7 + 30.0).min(255.0)])
            .collect();
        let r = Raster::new(
            grey.dims.clone(),
            3,
            Samples::from_f64(&rgb, SampleType::U8),
            grey.kind,
        )
        .unwrap();
        let mut p = prepare(&r.view(), &EncodeOptions::default(), Mode::Lossy).unwrap();
        p.optimise();
        let range = p.header.max - p.header.min;
        let pos = r.positions() as f64;
        let sizes = p.rate_model();
        for b in [0.5f64, 1.0, 2.0] {
            let model = |x: f64| b.ln() - (sizes.bits(x.exp()) / pos).ln();
            let bytes = calibrated_bpp(&p, range, b * pos, 0.99, &model)
                .unwrap_or_else(|| panic!("{b} bpp: no file within 1% under the budget"));
            let got = bytes.len() as f64 * 8.0 / pos;
            assert!(got <= b && got >= 0.99 * b, "{b} bpp: {got}");
        }
    }

    /// At effort 1 (a narrow coder, indices not optimised) the sampled sizes come from
    /// the file's own coder, and the calibrated search lands in the effort's window
    /// (within 3% under the budget) on its own, on a volume of 16-bit samples.
    #[test]
    fn calibrated_bpp_at_effort_1_lands_in_its_window_on_a_volume() {
        use crate::generate::phantom;
        let mut f = phantom::shepp_logan(40, 48, 56);
        let g = images::noise(40, 48 * 56, 1, 5);
        for (a, b) in f.values.data_mut().iter_mut().zip(g.data()) {
            *a += 0.02 * b;
        }
        let r = f.to_raster(SampleType::I16).unwrap();
        let opts = EncodeOptions {
            effort: 1,
            ..EncodeOptions::default()
        };
        let ladder = opts.ladder();
        let p = prepare(&r.view(), &opts, Mode::Lossy).unwrap();
        assert!(p.plan.coder.is_narrow() && p.rdo.is_none());
        let range = p.header.max - p.header.min;
        let pos = r.positions() as f64;
        let sizes = p.rate_model();
        for b in [0.5f64, 1.0, 2.0] {
            let model = |x: f64| b.ln() - (sizes.bits(x.exp()) / pos).ln();
            let bytes = calibrated_bpp(&p, range, b * pos, ladder.bpp_floor, &model)
                .unwrap_or_else(|| panic!("{b} bpp: no file within the window"));
            let got = bytes.len() as f64 * 8.0 / pos;
            assert!(got <= b && got >= ladder.bpp_floor * b, "{b} bpp: {got}");
        }
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
        let p = prepare(&r.view(), &EncodeOptions::default(), Mode::Lossy).unwrap();
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
}
