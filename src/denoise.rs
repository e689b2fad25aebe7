//! Denoising by thresholded details (notes §9.7.2: "reconstruct without (or with only a
//! small portion of) the details"): decompose, shrink every detail subband, reconstruct.
//! One function serves curves (`[n, dim]`, axis 0), images (`[h, w(, c)]`), heightmaps
//! and volumes (`[d, h, w]`).
//!
//! **Noise level.** The B-spline wavelets are not orthonormal, so white noise of
//! standard deviation σ has a different deviation `σ g_b` in every subband `b`. The gains
//! `g_b` are measured once by transforming unit white noise of the same shape (a fixed
//! generator, so the result is deterministic). σ itself comes from the finest
//! all-high subband `D` by the median absolute deviation (Donoho & Johnstone):
//! `σ = median|D| / (0.6745 g_D)`.
//!
//! **Thresholds** per subband, with `σ_b = σ g_b`:
//! - BayesShrink (Chang, Yu & Vetterli 2000, the default): `T_b = σ_b² / σ_x`,
//!   `σ_x = √max(mean(D_b²) − σ_b², 0)` (all of the band removed when σ_x = 0);
//! - universal (VisuShrink): `T_b = σ_b √(2 ln N)`;
//! - a given threshold `T` (in sample units): `T_b = T g_b`.
//!
//! **Shrinkage.** Hard: `d ↦ d·[|d| > T]`; soft: `d ↦ sign(d) max(|d| − T, 0)`.
//!
//! **Scheme.** Haar is the default: measured on Kodak images and a CT volume
//! (`benches/peers/denoise_skimage.py`, docs/terrain.md), one decimated Haar transform
//! matches scikit-image's BayesShrink (db1) to 0.01 dB, and with cycle spinning it beats
//! scikit-image's sym4 everywhere. The Chaikin and cubic B-spline analysis filters are
//! not orthogonal and amplify white noise in the coarse part (`Σ a_k² = 1.25` per axis
//! for Chaikin against ½ for Haar), which is never thresholded; deep decompositions then
//! keep more noise than the details remove. For them the level count is chosen by SURE
//! (see [`denoise`]), usually 1: better than the noisy input, still below Haar.

use crate::generate::rng::SplitMix64;
use crate::scheme::{Boundary, Scheme};
use crate::tensor::{self, Array, Order, PyramidSpec};
use crate::{Error, Result};

/// Hard or soft shrinkage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    Hard,
    Soft,
}

impl std::str::FromStr for Mode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "hard" => Ok(Mode::Hard),
            "soft" => Ok(Mode::Soft),
            _ => Err(Error::parameter("mode", s, "hard or soft")),
        }
    }
}

/// How the thresholds are chosen.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Rule {
    /// Per-subband BayesShrink.
    Bayes,
    /// σ √(2 ln N) per subband.
    Universal,
    /// A fixed threshold in sample units (scaled by each band's noise gain).
    Fixed(f64),
}

/// Parameters of [`denoise`].
#[derive(Clone, Debug, PartialEq)]
pub struct DenoiseOptions {
    pub scheme: Scheme,
    pub boundary: Boundary,
    /// Levels; 0 = chosen among 1..=[`AUTO_LEVELS`] by the smallest SURE risk.
    pub levels: usize,
    pub mode: Mode,
    pub rule: Rule,
    /// Noise σ in sample units; estimated from the finest band when `None`.
    pub sigma: Option<f64>,
    /// Cycle spinning: shifts `0..shifts` along every axis (`shifts^d` runs, averaged);
    /// 1 = a single decimated transform.
    pub shifts: usize,
}

/// Largest level count tried when `levels` is 0.
pub const AUTO_LEVELS: usize = 4;

impl Default for DenoiseOptions {
    fn default() -> Self {
        DenoiseOptions {
            scheme: Scheme::Haar,
            boundary: Boundary::Symmetric,
            levels: 4,
            mode: Mode::Soft,
            rule: Rule::Bayes,
            sigma: None,
            shifts: 2,
        }
    }
}

/// What [`denoise`] did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DenoiseReport {
    /// The noise σ used (estimated or given), in sample units.
    pub sigma: f64,
    pub levels: usize,
    /// Detail coefficients set to zero ÷ all detail coefficients (mean over shifts).
    pub zeroed: f64,
    /// Shifts per axis (cycle spinning).
    pub shifts: usize,
    /// SURE risk per sample of each level count tried (`levels` = 0), 1 level first;
    /// the search stops at the first level count whose risk is not lower.
    pub sure: Vec<f64>,
}

/// Standard normal samples by Box–Muller from SplitMix64.
fn white_noise(n: usize, seed: u64) -> Vec<f64> {
    let mut r = SplitMix64::new(seed);
    let mut v = Vec::with_capacity(n + 1);
    while v.len() < n {
        let u1 = r.next_f64().max(1e-300);
        let u2 = r.next_f64();
        let rad = (-2.0 * u1.ln()).sqrt();
        let a = std::f64::consts::TAU * u2;
        v.push(rad * a.cos());
        v.push(rad * a.sin());
    }
    v.truncate(n);
    v
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    *m
}

/// The subbands of a pyramid over an array of one shape, with their noise gains `g_b`
/// (RMS of the band when unit white noise is transformed).
struct Bands {
    spec: PyramidSpec,
    depth: usize,
    bands: Vec<crate::tensor::Subband>,
    /// The array's shape (the bands' boxes are in it).
    shape: Vec<usize>,
    gains: Vec<f64>,
    /// Index of the finest all-high band (the σ estimate's).
    finest: usize,
}

impl Bands {
    fn new(shape: &[usize], axes: &[usize], o: &DenoiseOptions, levels: usize) -> Result<Bands> {
        let spec = PyramidSpec {
            scheme: o.scheme,
            boundary: o.boundary,
            levels,
            order: Order::NonStandard,
            axes: axes.to_vec(),
        };
        let n: usize = shape.iter().product();
        let mut noise = Array::from_shape_vec(shape, white_noise(n, 0x006E_6F69_7365))?;
        let pyr = tensor::analyze(&mut noise, &spec)?;
        if pyr.depth() == 0 {
            return Err(Error::parameter(
                "size",
                format!("{shape:?}"),
                "an input long enough for one level of the scheme",
            ));
        }
        let bands = pyr.subbands();
        let gains = bands
            .iter()
            .map(|b| {
                let mut s = 0.0;
                each(shape, &b.ranges, |i| s += noise.data()[i].powi(2));
                (s / box_len(&b.ranges).max(1) as f64).sqrt()
            })
            .collect();
        let finest = bands
            .iter()
            .enumerate()
            .filter(|(_, b)| b.level == 1)
            .max_by_key(|(_, b)| b.high.iter().filter(|&&h| h).count())
            .map(|(i, _)| i)
            .unwrap_or(bands.len() - 1);
        Ok(Bands {
            spec,
            depth: pyr.depth(),
            bands,
            shape: shape.to_vec(),
            gains,
            finest,
        })
    }

    /// `f(i)` for the offset `i` of every element of band `bi`, in row-major order.
    fn each(&self, bi: usize, f: impl FnMut(usize)) {
        each(&self.shape, &self.bands[bi].ranges, f);
    }
}

/// `f(i)` for the offset `i` of every element of the box `ranges` in a row-major array
/// of `shape`, in row-major order (the elements are not listed: a band of a large
/// volume would take 8 bytes per element).
fn each(shape: &[usize], ranges: &[std::ops::Range<usize>], mut f: impl FnMut(usize)) {
    crate::codec::layout::rows(shape, ranges, |off, run, _| {
        (off..off + run).for_each(&mut f)
    });
}

/// Elements in the box `ranges`.
fn box_len(ranges: &[std::ops::Range<usize>]) -> usize {
    ranges.iter().map(|r| r.len()).product()
}

/// σ from the finest all-high band: `median|D| / (0.6745 g_D)`.
fn estimate_sigma(a: &Array<f64>, axes: &[usize], o: &DenoiseOptions) -> Result<f64> {
    let b = Bands::new(a.shape(), axes, o, 1)?;
    let mut c = a.clone();
    tensor::analyze(&mut c, &b.spec)?;
    let mut d = Vec::with_capacity(box_len(&b.bands[b.finest].ranges));
    b.each(b.finest, |i| d.push(c.data()[i].abs()));
    Ok(median(d) / 0.6745 / b.gains[b.finest].max(1e-300))
}

/// Counts of one shrinkage: (details zeroed, details, coarse coefficients, details kept).
type Counts = (usize, usize, usize, usize);

/// Decompose, shrink every detail band with its own `σ_b = σ g_b`, reconstruct.
fn shrink(a: &mut Array<f64>, b: &Bands, sigma: f64, o: &DenoiseOptions) -> Result<Counts> {
    let pyr = tensor::analyze(a, &b.spec)?;
    let n_total = a.len() as f64;
    let (mut zeroed, mut total, mut coarse) = (0usize, 0usize, 0usize);
    let data = a.data_mut();
    for (bi, band) in b.bands.iter().enumerate() {
        let len = box_len(&band.ranges);
        if band.level == 0 {
            coarse += len;
            continue;
        }
        let g = b.gains[bi];
        let sb = sigma * g;
        let t = match o.rule {
            Rule::Fixed(t) => t * g,
            Rule::Universal => sb * (2.0 * n_total.ln()).sqrt(),
            Rule::Bayes => {
                let mut sum = 0.0;
                b.each(bi, |i| sum += data[i] * data[i]);
                let var = sum / len as f64;
                let sx = (var - sb * sb).max(0.0).sqrt();
                if sx > 0.0 {
                    sb * sb / sx
                } else {
                    f64::INFINITY
                }
            }
        };
        b.each(bi, |i| {
            let d = data[i];
            let v = match o.mode {
                Mode::Hard => {
                    if d.abs() > t {
                        d
                    } else {
                        0.0
                    }
                }
                Mode::Soft => d.signum() * (d.abs() - t).max(0.0),
            };
            if v == 0.0 {
                zeroed += 1;
            }
            data[i] = v;
        });
        total += len;
    }
    tensor::synthesize(a, &pyr)?;
    Ok((zeroed, total, coarse, total - zeroed))
}

/// Half-sample mirror of index `j` into `0..n` (… 1 0 | 0 1 … n−1 | n−1 n−2 …).
fn reflect(j: i64, n: usize) -> usize {
    let n = n as i64;
    let p = 2 * n;
    let m = j.rem_euclid(p);
    (if m < n { m } else { p - 1 - m }) as usize
}

/// A new array whose index `i` along `axis` (of length `len`) holds `a`'s `src(i)`.
fn reindex(
    a: &Array<f64>,
    axis: usize,
    len: usize,
    src: impl Fn(usize) -> usize,
) -> Result<Array<f64>> {
    let shape = a.shape();
    let outer: usize = shape[..axis].iter().product();
    let inner: usize = shape[axis + 1..].iter().product();
    let n = shape[axis];
    let mut out = Vec::with_capacity(outer * len * inner);
    for o in 0..outer {
        for i in 0..len {
            let s = (o * n + src(i)) * inner;
            out.extend_from_slice(&a.data()[s..s + inner]);
        }
    }
    let mut new_shape = shape.to_vec();
    new_shape[axis] = len;
    Array::from_shape_vec(&new_shape, out)
}

/// `a` shifted by `s` along `axis` (a circular shift for the periodic boundary, else
/// mirrored samples in front and `k − s` behind), and the inverse map back to `n`.
fn shift(a: &Array<f64>, axis: usize, s: usize, k: usize, periodic: bool) -> Result<Array<f64>> {
    let n = a.shape()[axis];
    if periodic {
        reindex(a, axis, n, |i| (i + n - s % n) % n)
    } else {
        reindex(a, axis, n + k, |i| reflect(i as i64 - s as i64, n))
    }
}

fn unshift(a: &Array<f64>, axis: usize, s: usize, n: usize, periodic: bool) -> Result<Array<f64>> {
    if periodic {
        reindex(a, axis, n, |i| (i + s) % n)
    } else {
        reindex(a, axis, n, |i| i + s)
    }
}

/// The estimate of `y` with `levels`, averaged over the `shifts^d` cycle spins, and its
/// divergence (for SURE): per spin `#coarse + #kept` (each kept coefficient adds
/// `b_iᵀ q_i = 1`, since `B Q = I`), scaled to `y`'s size, averaged.
fn spun(
    y: &Array<f64>,
    axes: &[usize],
    o: &DenoiseOptions,
    levels: usize,
    sigma: f64,
) -> Result<(Array<f64>, f64, f64, usize)> {
    let k = o.shifts.max(1);
    let periodic = o.boundary == Boundary::Periodic;
    let spins = k.pow(axes.len() as u32);
    let mut acc = vec![0.0; y.len()];
    let (mut zeroed_frac, mut div) = (0.0, 0.0);
    let mut bands: Option<Bands> = None;
    let mut depth = 0;
    for combo in 0..spins {
        let ss: Vec<usize> = (0..axes.len())
            .map(|j| (combo / k.pow(j as u32)) % k)
            .collect();
        let mut x = y.clone();
        if k > 1 {
            for (&ax, &s) in axes.iter().zip(&ss) {
                x = shift(&x, ax, s, k, periodic)?;
            }
        }
        // every spin has the same padded shape: one set of gains
        if bands.is_none() {
            bands = Some(Bands::new(x.shape(), axes, o, levels)?);
        }
        let b = bands.as_ref().expect("set above");
        depth = b.depth;
        let (zeroed, total, coarse, kept) = shrink(&mut x, b, sigma, o)?;
        zeroed_frac += zeroed as f64 / total.max(1) as f64;
        div += (coarse + kept) as f64 * y.len() as f64 / x.len() as f64;
        if k > 1 {
            for (&ax, &s) in axes.iter().zip(&ss) {
                x = unshift(&x, ax, s, y.shape()[ax], periodic)?;
            }
        }
        acc.iter_mut().zip(x.data()).for_each(|(a, v)| *a += v);
    }
    let inv = 1.0 / spins as f64;
    acc.iter_mut().for_each(|v| *v *= inv);
    Ok((
        Array::from_shape_vec(y.shape(), acc)?,
        zeroed_frac * inv,
        div * inv,
        depth,
    ))
}

/// Denoise `a` in place along `axes` (other axes, e.g. channels or coordinates, are
/// carried along).
///
/// **Cycle spinning** (Coifman & Donoho 1995): the decimated transform is not
/// translation invariant, so the estimate is averaged over the shifts `0..shifts` of
/// every axis (mirrored samples fill the ends; circular shifts for the periodic
/// boundary). Cost: `shifts^d` transforms.
///
/// **Level choice** (`levels` = 0): Stein's unbiased risk estimate of each level count
/// `L = 1, 2, …` (until it grows), `SURE = ‖x̂_L − y‖² − Nσ² + 2σ² div x̂_L`, with `div = #coarse + #kept details`
/// (exact for soft/hard shrinkage with fixed thresholds: `B Q = I` gives each kept
/// coefficient `b_iᵀ q_i = 1`); the smallest wins. It matters for the B-spline schemes:
/// their analysis filter `A` amplifies white noise (`Σ a_k² = 1.25` per axis for Chaikin
/// against ½ for Haar), so the coarse part of deep decompositions keeps more noise than
/// the details remove.
pub fn denoise(a: &mut Array<f64>, axes: &[usize], o: &DenoiseOptions) -> Result<DenoiseReport> {
    if o.shifts == 0 || o.shifts > 8 {
        return Err(Error::parameter("shifts", o.shifts, "1 to 8"));
    }
    if o.levels > 16 {
        return Err(Error::parameter("levels", o.levels, "0 (automatic) to 16"));
    }
    let sigma = match o.sigma {
        Some(s) if s.is_finite() && s >= 0.0 => s,
        Some(s) => {
            return Err(Error::parameter(
                "sigma",
                s,
                "a finite noise level ≥ 0 (omit it to estimate)",
            ))
        }
        None => estimate_sigma(a, axes, o)?,
    };
    let tries: Vec<usize> = if o.levels == 0 {
        (1..=AUTO_LEVELS).collect()
    } else {
        vec![o.levels]
    };
    let n = a.len() as f64;
    let mut best: Option<(f64, Array<f64>, f64, usize)> = None;
    let mut sure = Vec::new();
    for &l in &tries {
        let (x, zeroed, div, depth) = spun(a, axes, o, l, sigma)?;
        if depth < l && l > 1 && o.levels == 0 {
            break; // the input does not take more levels
        }
        let r = x
            .data()
            .iter()
            .zip(a.data())
            .map(|(p, q)| (p - q).powi(2))
            .sum::<f64>()
            - n * sigma * sigma
            + 2.0 * sigma * sigma * div;
        if o.levels == 0 {
            sure.push(r / n);
        }
        if best.as_ref().is_none_or(|b| r < b.0) {
            best = Some((r, x, zeroed, depth));
        } else {
            break; // the risk grew with one more level: deeper ones are not tried
        }
    }
    let (_, x, zeroed, depth) = best.expect("at least one level count tried");
    *a = x;
    Ok(DenoiseReport {
        sigma,
        levels: depth,
        zeroed,
        shifts: o.shifts,
        sure,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_on_a_smooth_image_is_reduced_and_sigma_estimated() {
        let (h, w) = (128, 128);
        let clean: Vec<f64> = (0..h * w)
            .map(|i| {
                let (y, x) = ((i / w) as f64, (i % w) as f64);
                100.0 + 50.0 * (x / 20.0).sin() * (y / 30.0).cos()
            })
            .collect();
        let n = white_noise(h * w, 7);
        let noisy: Vec<f64> = clean.iter().zip(&n).map(|(c, e)| c + 10.0 * e).collect();
        let mut a = Array::from_shape_vec(&[h, w], noisy.clone()).unwrap();
        let o = DenoiseOptions {
            scheme: Scheme::Haar,
            ..DenoiseOptions::default()
        };
        let r = denoise(&mut a, &[0, 1], &o).unwrap();
        assert!((r.sigma - 10.0).abs() < 1.0, "sigma {}", r.sigma);
        let mse = |v: &[f64]| {
            v.iter()
                .zip(&clean)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                / v.len() as f64
        };
        assert!(
            mse(a.data()) < 0.25 * mse(&noisy),
            "{} vs {}",
            mse(a.data()),
            mse(&noisy)
        );
    }

    /// A test image with smooth parts and edges, its noisy version (σ = 10), and MSE.
    fn scene(h: usize, w: usize) -> (Vec<f64>, Vec<f64>) {
        let clean: Vec<f64> = (0..h * w)
            .map(|i| {
                let (y, x) = ((i / w) as f64, (i % w) as f64);
                let disc = if (x - 40.0).hypot(y - 50.0) < 25.0 {
                    60.0
                } else {
                    0.0
                };
                100.0 + 50.0 * (x / 13.0).sin() * (y / 17.0).cos() + disc
            })
            .collect();
        let n = white_noise(h * w, 11);
        let noisy = clean.iter().zip(&n).map(|(c, e)| c + 10.0 * e).collect();
        (clean, noisy)
    }

    fn mse(a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64
    }

    fn run(noisy: &[f64], h: usize, w: usize, o: &DenoiseOptions) -> (Vec<f64>, DenoiseReport) {
        let mut a = Array::from_shape_vec(&[h, w], noisy.to_vec()).unwrap();
        let r = denoise(&mut a, &[0, 1], o).unwrap();
        (a.into_data(), r)
    }

    #[test]
    fn zero_threshold_gives_the_input_back_with_and_without_cycle_spinning() {
        let (h, w) = (40, 52);
        let (_, noisy) = scene(h, w);
        for scheme in [Scheme::Haar, Scheme::Chaikin, Scheme::Cubic] {
            for shifts in [1, 3] {
                let o = DenoiseOptions {
                    scheme,
                    levels: 2,
                    rule: Rule::Fixed(0.0),
                    shifts,
                    ..DenoiseOptions::default()
                };
                let (out, _) = run(&noisy, h, w, &o);
                let err = out
                    .iter()
                    .zip(&noisy)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                assert!(err < 1e-9, "{scheme:?} shifts {shifts}: {err}");
            }
        }
    }

    #[test]
    fn bspline_schemes_beat_the_noisy_input_and_sure_tracks_the_true_risk() {
        let (h, w) = (128, 128);
        let (clean, noisy) = scene(h, w);
        let before = mse(&noisy, &clean);
        for scheme in [Scheme::Chaikin, Scheme::Cubic] {
            let o = DenoiseOptions {
                scheme,
                levels: 0,
                ..DenoiseOptions::default()
            };
            let (out, r) = run(&noisy, h, w, &o);
            let after = mse(&out, &clean);
            assert!(after < 0.4 * before, "{scheme:?}: {after} vs {before}");
            // the chosen level's SURE estimates the true risk (MSE per sample)
            let chosen = r.sure.iter().cloned().fold(f64::INFINITY, f64::min);
            assert!(
                (chosen - after).abs() < 0.25 * after,
                "SURE {chosen} vs MSE {after}"
            );
        }
    }

    #[test]
    fn cycle_spinning_lowers_the_error() {
        let (h, w) = (128, 128);
        let (clean, noisy) = scene(h, w);
        for scheme in [Scheme::Haar, Scheme::Chaikin] {
            let o = |shifts| DenoiseOptions {
                scheme,
                levels: 2,
                sigma: Some(10.0),
                shifts,
                ..DenoiseOptions::default()
            };
            let one = mse(&run(&noisy, h, w, &o(1)).0, &clean);
            let spun = mse(&run(&noisy, h, w, &o(2)).0, &clean);
            assert!(spun < 0.9 * one, "{scheme:?}: {spun} vs {one}");
        }
        let mut a = Array::from_shape_vec(&[h, w], noisy).unwrap();
        let bad = DenoiseOptions {
            shifts: 0,
            ..DenoiseOptions::default()
        };
        assert!(denoise(&mut a, &[0, 1], &bad).is_err());
    }
}
