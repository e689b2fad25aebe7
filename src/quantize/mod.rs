//! Quantization of pyramid coefficients (notes §9.3.2, §9.7.3).
//!
//! The bases are not orthonormal, so a unit of error in a coefficient costs a different
//! squared error in the picture in every band. The *synthesis gain* of a band is the
//! mean squared norm of its synthesis basis functions,
//! `G²_b = (1/|b|) Σ_{k∈b} ‖S e_k‖²`, a product over axes of 1-D gains computed here
//! numerically from the schemes' own synthesis operators (impulse through `P`, `Q`
//! level by level). Uniform noise of step `Δ_b` in band `b` adds `G²_b Δ_b²/12` per
//! coefficient to the squared error, so the steps `Δ_b = Δ / G_b` spend the error
//! evenly (the gains: [`band_gains`]).
//!
//! The quantizer is a dead-zone uniform quantizer: `q = sign(c)·⌊|c|/Δ_b + ρ⌋`, and
//! the decoder returns `sign(q)·(|q| + δ)·Δ_b` (`δ` recorded in the file). The
//! coarsest block uses plain rounding (`ρ = ½`, `δ = 0`).

use crate::scheme::{Boundary, Scheme, TwoScale};
use crate::tensor::{Pyramid, Subband};

/// Multiplier `λ` of rate–distortion optimised quantization, in units of the squared
/// step: an index costs `(x − q)² + λ·bits` with `x` the coefficient over its band's
/// step (the weighted bands make one `λ` right for all of them). High-rate theory puts
/// the slope of a uniform quantizer at `2 ln 2 / 12 ≈ 0.116`; 0.1 measured best on
/// photographs (0.05–0.15 within 0.05 dB).
pub const LAMBDA: f32 = 0.1;

/// Encoder rounding offset of detail bands (dead zone `|c| < (1 − ρ)Δ`).
pub const RHO: f64 = 0.34;
/// Reconstruction offset of detail bands (written into the file).
pub const DELTA: f64 = 0.12;

/// Mean squared norm of the 1-D synthesis functions of the coefficients that sit at
/// `start..end` of the packed lane of level `level` (0 = the full-length lane, i.e. a
/// coefficient of the finest packed lane), synthesized through the levels below.
/// `lengths` = the axis' lane lengths by level (`lengths[0]` = full length).
pub fn gain_1d(
    scheme: Scheme,
    boundary: Boundary,
    lengths: &[usize],
    level: usize,
    high: bool,
) -> f64 {
    let ops: Vec<TwoScale> = (0..level)
        .map(|l| TwoScale::new(scheme, boundary, lengths[l]))
        .collect();
    gain_1d_with(&ops, lengths, level, high)
}

/// [`gain_1d`] with the axis' operators already built: `ops[l]` = the two-scale
/// operator of level `l` (lanes of `lengths[l]`), at least `level` of them.
fn gain_1d_with(ops: &[TwoScale], lengths: &[usize], level: usize, high: bool) -> f64 {
    // the coefficient lives in the packed lane of length lengths[level-1] (detail, or
    // coarse block after `level` steps); level 0 means an untransformed axis
    if level == 0 {
        return 1.0;
    }
    let fine_len = lengths[level - 1];
    let coarse_len = lengths[level];
    let (start, end) = if high {
        (coarse_len, fine_len)
    } else {
        (0, coarse_len)
    };
    let count = end - start;
    if count == 0 {
        return 1.0;
    }
    // sample at most 64 coefficients evenly; their impulses are synthesized together,
    // impulse t in lane t of elements `picks` wide (the operators work on whole
    // elements, each lane with the arithmetic of a lone one)
    let picks = count.min(64);
    let mut lane = vec![0.0f64; fine_len * picks];
    for t in 0..picks {
        let k = start + t * count / picks;
        lane[k * picks + t] = 1.0;
    }
    for l in (0..level).rev() {
        let mut fine = vec![0.0f64; lengths[l] * picks];
        let mut packed = vec![0.0f64; lengths[l] * picks];
        packed[..lane.len()].copy_from_slice(&lane);
        ops[l].reconstruct(&packed, picks, &mut fine);
        lane = fine;
    }
    let mut total = 0.0;
    for t in 0..picks {
        total += lane
            .iter()
            .skip(t)
            .step_by(picks)
            .map(|v| v * v)
            .sum::<f64>();
    }
    total / picks as f64
}

/// The synthesis gain `G_b` (square root of the mean squared norm) of every band of
/// `pyr`, in [`Pyramid::subbands`] order: the product over axes of the 1-D gains
/// ([`gain_1d`]) of the band's level and pass along each axis. Each distinct 1-D gain is
/// computed once, and they (and every axis' operators before them) are computed in
/// parallel: each is a pure function of its axis, level and pass, so the gains are the
/// same numbers on any number of threads.
pub fn band_gains(pyr: &Pyramid, bands: &[Subband]) -> Vec<f64> {
    use rayon::prelude::*;
    let (scheme, boundary) = (pyr.spec.scheme, pyr.spec.boundary);
    // the level of a band's coefficients along axis i and whether it is high-pass there
    let key = |b: &Subband, i: usize| {
        let al = pyr.axis_levels(i);
        if b.level == 0 || b.level > al {
            (i, al, false)
        } else {
            (i, b.level, b.high[i])
        }
    };
    let naxes = pyr.spec.axes.len();
    let mut keys: Vec<(usize, usize, bool)> = bands
        .iter()
        .flat_map(|b| (0..naxes).map(move |i| key(b, i)))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    // every axis' operators built once, for all the levels a gain needs (not once a band)
    let mut need = vec![0usize; naxes];
    for &(i, l, _) in &keys {
        need[i] = need[i].max(l);
    }
    let built: Vec<TwoScale> = need
        .iter()
        .enumerate()
        .flat_map(|(i, &n)| (0..n).map(move |l| (i, l)))
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|(i, l)| TwoScale::new(scheme, boundary, pyr.lengths[i][l]))
        .collect();
    let mut ops: Vec<&[TwoScale]> = Vec::with_capacity(naxes);
    let mut at = 0;
    for &n in &need {
        ops.push(&built[at..at + n]);
        at += n;
    }
    let gains: Vec<f64> = keys
        .par_iter()
        .map(|&(i, l, high)| gain_1d_with(ops[i], &pyr.lengths[i], l, high))
        .collect();
    let gain = |k: (usize, usize, bool)| gains[keys.binary_search(&k).expect("a key")];
    bands
        .iter()
        .map(|b| {
            let mut g2 = 1.0;
            for i in 0..naxes {
                g2 *= gain(key(b, i));
            }
            g2.sqrt()
        })
        .collect()
}

/// Dead-zone quantization of one value.
#[inline(always)]
pub fn quantize(c: f64, step: f64, rho: f64) -> i64 {
    // ⌊|c|/Δ + ρ⌋ capped at 9·10^15 (exact in f64), 0 when not finite; for the
    // non-negative values it is always given (ρ ≥ 0), the floor is a truncating
    // conversion, not a libm call (the call took 9% of an encode)
    let x = c.abs() / step + rho;
    let a = if !x.is_finite() {
        0
    } else if x >= 0.0 {
        x.min(9.0e15) as i64
    } else {
        x.floor() as i64
    };
    if c < 0.0 {
        -a
    } else {
        a
    }
}

/// Reconstruction of one index.
#[inline(always)]
pub fn dequantize(q: i64, step: f64, delta: f64) -> f64 {
    if q == 0 {
        0.0
    } else if q < 0 {
        (q as f64 - delta) * step
    } else {
        (q as f64 + delta) * step
    }
}

/// The threshold `T` such that `keep` percent of the weighted detail magnitudes
/// `|c|·G_b` are at least `T` (the notes' keep-P% protocol, Figure 9.19).
pub fn keep_threshold(weighted: &mut [f32], keep: f64) -> f64 {
    if weighted.is_empty() {
        return 1.0;
    }
    let n = weighted.len();
    let k = ((keep / 100.0) * n as f64).round() as usize;
    if k == 0 {
        return f64::INFINITY;
    }
    if k >= n {
        return 0.0;
    }
    let idx = n - k;
    let (_, t, _) = weighted.select_nth_unstable_by(idx, |a, b| a.total_cmp(b));
    (*t as f64).max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn haar_gains_follow_the_averaging_normalisation() {
        // Haar analysis averages: C = (a+b)/2, D = (a−b)/2; synthesis a = C + D,
        // b = C − D: every synthesis function has squared norm 2 at one level.
        let lengths = [8, 4, 2];
        let g = gain_1d(Scheme::Haar, Boundary::Interpolating, &lengths, 1, true);
        let g2 = gain_1d(Scheme::Haar, Boundary::Interpolating, &lengths, 2, false);
        assert!(g > 0.0 && g2 > g, "{g} {g2}");
    }

    /// The impulses synthesized together give the gains of one impulse at a time, to
    /// the bit, for every scheme, boundary, level and both halves.
    #[test]
    fn batched_gains_are_those_of_lone_impulses() {
        fn lone(s: Scheme, b: Boundary, lengths: &[usize], level: usize, high: bool) -> f64 {
            let (fine_len, coarse_len) = (lengths[level - 1], lengths[level]);
            let (start, end) = if high {
                (coarse_len, fine_len)
            } else {
                (0, coarse_len)
            };
            let count = end - start;
            let picks = count.min(64);
            let mut total = 0.0;
            for t in 0..picks {
                let mut lane = vec![0.0f64; fine_len];
                lane[start + t * count / picks] = 1.0;
                for l in (0..level).rev() {
                    let mut fine = vec![0.0f64; lengths[l]];
                    let mut packed = vec![0.0f64; lengths[l]];
                    packed[..lane.len()].copy_from_slice(&lane);
                    TwoScale::new(s, b, lengths[l]).reconstruct(&packed, 1, &mut fine);
                    lane = fine;
                }
                total += lane.iter().map(|v| v * v).sum::<f64>();
            }
            total / picks as f64
        }
        for scheme in Scheme::ALL {
            for boundary in [Boundary::Symmetric, Boundary::Interpolating] {
                let spec = crate::tensor::PyramidSpec {
                    scheme,
                    boundary,
                    levels: 4,
                    order: crate::tensor::Order::NonStandard,
                    axes: vec![0],
                };
                let pyr = Pyramid::plan(&[300], &spec).unwrap();
                let lengths = &pyr.lengths[0];
                for level in 1..lengths.len() {
                    for high in [false, true] {
                        let a = gain_1d(scheme, boundary, lengths, level, high);
                        let b = lone(scheme, boundary, lengths, level, high);
                        assert_eq!(
                            a.to_bits(),
                            b.to_bits(),
                            "{scheme:?} {boundary:?} {level} {high}"
                        );
                    }
                }
            }
        }
    }

    /// Every band's gain is the product over its axes of the 1-D gains, each computed
    /// alone ([`gain_1d`]), to the bit: on images and volumes of uneven extents, with
    /// axes of different level counts, standard and non-standard orders, and the same
    /// on one and two threads.
    #[test]
    fn band_gains_are_the_products_of_lone_axis_gains() {
        let cases: [(&[usize], &[usize], crate::tensor::Order); 4] = [
            (&[151, 226], &[0, 1], crate::tensor::Order::NonStandard),
            (&[9, 300], &[0, 1], crate::tensor::Order::NonStandard),
            (&[17, 40, 33], &[0, 1, 2], crate::tensor::Order::NonStandard),
            (&[40, 57], &[0, 1], crate::tensor::Order::Standard),
        ];
        for (shape, axes, order) in cases {
            for scheme in [Scheme::Cdf97, Scheme::Haar] {
                let spec = crate::tensor::PyramidSpec {
                    scheme,
                    boundary: Boundary::Symmetric,
                    levels: 5,
                    order,
                    axes: axes.to_vec(),
                };
                let pyr = Pyramid::plan(shape, &spec).unwrap();
                let bands = pyr.subbands();
                let want: Vec<f64> = bands
                    .iter()
                    .map(|b| {
                        let mut g2 = 1.0;
                        for i in 0..axes.len() {
                            let al = pyr.axis_levels(i);
                            let (lvl, high) = if b.level == 0 || b.level > al {
                                (al, false)
                            } else {
                                (b.level, b.high[i])
                            };
                            g2 *= gain_1d(scheme, Boundary::Symmetric, &pyr.lengths[i], lvl, high);
                        }
                        g2.sqrt()
                    })
                    .collect();
                for threads in [1, 2] {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    let got = pool.install(|| band_gains(&pyr, &bands));
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(
                        bits(&got),
                        bits(&want),
                        "{shape:?} {scheme:?} {order:?} {threads}"
                    );
                }
            }
        }
    }

    /// The conversion in [`quantize`] is the floor it replaces, on values around every
    /// integer, huge, tiny, infinite and NaN inputs, and either sign.
    #[test]
    fn quantize_is_the_floor_of_the_scaled_magnitude() {
        fn by_floor(c: f64, step: f64, rho: f64) -> i64 {
            let a = (c.abs() / step + rho).floor();
            let a = if a.is_finite() { a.min(9.0e15) } else { 0.0 };
            if c < 0.0 {
                -(a as i64)
            } else {
                a as i64
            }
        }
        let mut cs = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            1e300,
            -1e300,
            8.9e15,
            9.1e15,
        ];
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for k in 0..20000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            let near = (k % 200) as f64 + (u - 0.5) * 1e-12;
            cs.push(if k % 2 == 0 { near } else { -(u * 1e6) });
        }
        for &c in &cs {
            for step in [1.0, 0.37, 3.0, 1e-9] {
                for rho in [0.0, 0.34, 0.5] {
                    assert_eq!(
                        quantize(c, step, rho),
                        by_floor(c, step, rho),
                        "{c} {step} {rho}"
                    );
                }
            }
        }
    }

    #[test]
    fn quantizer_inverts_within_a_step() {
        for &c in &[-10.3, -0.2, 0.0, 0.49, 3.7, 100.0] {
            let q = quantize(c, 0.5, RHO);
            let r = dequantize(q, 0.5, DELTA);
            assert!((r - c).abs() <= 0.5, "{c} {q} {r}");
        }
    }

    #[test]
    fn keep_threshold_keeps_the_requested_share() {
        let mut v: Vec<f32> = (0..1000).map(|i| i as f32).collect();
        let t = keep_threshold(&mut v, 10.0);
        let kept = (0..1000).filter(|&i| i as f64 >= t).count();
        assert_eq!(kept, 100);
    }
}
