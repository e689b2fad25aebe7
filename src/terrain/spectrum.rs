//! Radially averaged power spectra, their slope over the finest octave, and the gain of a
//! field's fine part that gives a wanted slope.
//!
//! **Spectral slope** of an `s × s` square `f` (the definition of
//! `benches/terrain_quality.py`): the mean is removed, the square is multiplied by the
//! Hann window `w_i = ½ − ½ cos(2π i/(s − 1))` along both axes, transformed (2-D DFT),
//! and the power `|F̂(u, v)|²` is averaged over the rings `r = ⌊√(u² + v²)⌋` (signed
//! frequencies, `|u|, |v| ≤ s/2`); the slope is the least-squares slope of `ln P(r)`
//! against `ln r` over `s/4 ≤ r ≤ s/2` (the finest octave).
//!
//! **Gain.** For `F = X + g Y` the transform is linear, so each ring's power is quadratic
//! in `g`: `P(r; g) = a_r + 2g b_r + g² c_r` with `a = ⟨|X̂|²⟩`, `b = ⟨Re X̂ Ŷ*⟩`,
//! `c = ⟨|Ŷ|²⟩`. Both real squares are transformed at once as `Z = X + iY`
//! (`X̂(k) = (Ẑ(k) + Ẑ(−k)*)/2`, `Ŷ(k) = (Ẑ(k) − Ẑ(−k)*)/(2i)`).
//!
//! The DFT is `rustfft`'s, from its scalar planner (the same bits on every CPU); rows of a
//! square are transformed in parallel, and every sum is taken in a fixed order (the same
//! bits for any thread count).

use rayon::prelude::*;
use rustfft::{Fft, FftPlannerScalar};
use std::sync::Arc;

/// A complex number `re + i·im` in f32 (a square of 512² takes 2 MB; the slope of the
/// finest octave agrees with an f64 transform to 1e-6 on the bench's DEMs).
pub type Complex = rustfft::num_complex::Complex<f32>;

/// `|z|²`, in f64.
#[inline]
fn norm2(z: Complex) -> f64 {
    (z.re as f64).powi(2) + (z.im as f64).powi(2)
}

/// The forward DFT `X_k = Σ_j x_j e^{−2πi jk/n}` of length `n`.
fn plan(n: usize) -> Arc<dyn Fft<f32>> {
    FftPlannerScalar::new().plan_fft_forward(n)
}

/// In-place 2-D DFT of a row-major `s × s` square, left transposed (`z[v·s + u] =
/// Ẑ(u, v)` for input `z[y·s + x]`, `u` along `y`): rows are transformed, the square is
/// transposed in place, and rows are transformed again. Ring sums do not depend on the order.
fn dft2_transposed(z: &mut [Complex], s: usize) {
    let fft = plan(s);
    let scratch = fft.get_inplace_scratch_len();
    let pass = |z: &mut [Complex]| {
        z.par_chunks_mut(s).for_each_init(
            || vec![Complex::default(); scratch],
            |scratch, row| fft.process_with_scratch(row, scratch),
        );
    };
    pass(z);
    for y in 0..s {
        for x in y + 1..s {
            z.swap(y * s + x, x * s + y);
        }
    }
    pass(z);
}

/// Numpy's `hanning(s)`: `½ − ½ cos(2π i/(s − 1))`.
fn hann(s: usize) -> Vec<f64> {
    if s == 1 {
        return vec![1.0];
    }
    (0..s)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / (s - 1) as f64).cos())
        .collect()
}

/// Ring sums of the finest octave of `F = X + gY`: per ring `r` in `s/4 ..= s/2`,
/// `(ln r, a_r, b_r, c_r)` with `P(r; g) = a_r + 2g b_r + g² c_r` the mean power.
#[derive(Clone, Debug)]
pub struct Rings {
    rings: Vec<(f64, f64, f64, f64)>,
}

impl Rings {
    /// The rings of the two `s × s` squares `x` and `y` (row-major; `y` may be all zeros).
    pub fn new(x: &[f64], y: &[f64], s: usize) -> Rings {
        assert!(x.len() == s * s && y.len() == s * s, "square sizes");
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (mx, my) = (mean(x), mean(y));
        let z = x
            .iter()
            .zip(y)
            .map(|(&a, &b)| Complex::new((a - mx) as f32, (b - my) as f32))
            .collect();
        Rings::packed(z, s)
    }

    /// The rings of the two `s × s` squares packed as `z = x + i y` (row-major; best with
    /// the means already taken out, as f32 keeps 24 bits).
    pub fn packed(mut z: Vec<Complex>, s: usize) -> Rings {
        assert_eq!(z.len(), s * s, "square size");
        let n = (s * s) as f64;
        let (mx, my) = z
            .iter()
            .fold((0.0, 0.0), |(a, b), v| (a + v.re as f64, b + v.im as f64));
        let (mx, my) = (mx / n, my / n);
        let w = hann(s);
        for (i, v) in z.iter_mut().enumerate() {
            let h = w[i / s] * w[i % s];
            *v = Complex::new(
                ((v.re as f64 - mx) * h) as f32,
                ((v.im as f64 - my) * h) as f32,
            );
        }
        dft2_transposed(&mut z, s);
        let (lo, hi) = (s / 4, s / 2);
        let mut sums = vec![(0.0, 0.0, 0.0, 0usize); hi + 1];
        let signed = |u: usize| -> f64 {
            if u < s.div_ceil(2) {
                u as f64
            } else {
                u as f64 - s as f64
            }
        };
        for v in 0..s {
            for u in 0..s {
                let r = signed(u).hypot(signed(v)) as usize;
                if r < lo || r > hi {
                    continue;
                }
                let zk = z[v * s + u];
                let zm = z[((s - v) % s) * s + (s - u) % s].conj();
                let xk = Complex::new(0.5 * (zk.re + zm.re), 0.5 * (zk.im + zm.im));
                // (zk − zm)/(2i) = −i (zk − zm)/2
                let d = zk - zm;
                let yk = Complex::new(0.5 * d.im, -0.5 * d.re);
                let t = &mut sums[r];
                t.0 += norm2(xk);
                t.1 += xk.re as f64 * yk.re as f64 + xk.im as f64 * yk.im as f64;
                t.2 += norm2(yk);
                t.3 += 1;
            }
        }
        let rings = sums
            .iter()
            .enumerate()
            .filter(|(r, t)| *r >= lo.max(1) && t.3 > 0)
            .map(|(r, t)| {
                let n = t.3 as f64;
                ((r as f64).ln(), t.0 / n, t.1 / n, t.2 / n)
            })
            .collect();
        Rings { rings }
    }

    /// The least-squares slope of `ln P(r; g)` against `ln r` (NaN when undefined).
    pub fn slope(&self, g: f64) -> f64 {
        let pts: Vec<(f64, f64)> = self
            .rings
            .iter()
            .map(|&(lr, a, b, c)| (lr, (a + 2.0 * g * b + g * g * c).max(1e-300).ln()))
            .collect();
        if pts.len() < 2 {
            return f64::NAN;
        }
        let n = pts.len() as f64;
        let (mx, my) = pts
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for &(x, y) in &pts {
            sxy += (x - mx) * (y - my);
            sxx += (x - mx) * (x - mx);
        }
        sxy / sxx
    }

    /// The gain `g` on the grid `G_MIN + i/1024` within `[G_MIN, G_MAX]` whose slope is
    /// nearest `target` (the first such on ties; 1 when no slope is defined).
    pub fn fit_gain(&self, target: f64) -> f64 {
        let steps = ((GAIN_RANGE.1 - GAIN_RANGE.0) * 1024.0).round() as usize;
        let mut best = (f64::INFINITY, 1.0);
        for i in 0..=steps {
            let g = GAIN_RANGE.0 + i as f64 / 1024.0;
            let e = (self.slope(g) - target).abs();
            if e < best.0 {
                best = (e, g);
            }
        }
        best.1
    }
}

/// The range `[min, max]` of the fitted finest-level gain.
pub const GAIN_RANGE: (f64, f64) = (0.5, 2.0);

/// The side of the square the spectral slope is taken on: `min(h, w, MAX_SIDE)`.
pub const MAX_SIDE: usize = 512;

/// The spectral slope of the top-left `s × s` square of a row-major `h × w` field,
/// `s = min(h, w, MAX_SIDE)` (see the module's definition).
pub fn spectral_slope(f: &[f64], h: usize, w: usize) -> f64 {
    let s = h.min(w).min(MAX_SIDE);
    let at = |i: usize| f[(i / s) * w + i % s];
    let mean = (0..s * s).map(at).sum::<f64>() / (s * s) as f64;
    let z = (0..s * s)
        .map(|i| Complex::new((at(i) - mean) as f32, 0.0))
        .collect();
    Rings::packed(z, s).slope(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The DFT by its definition, in f64.
    fn direct(x: &[Complex]) -> Vec<(f64, f64)> {
        let n = x.len();
        (0..n)
            .map(|k| {
                x.iter().enumerate().fold((0.0, 0.0), |acc, (j, v)| {
                    let th = -2.0 * std::f64::consts::PI * ((j * k) % n) as f64 / n as f64;
                    let (c, s) = (th.cos(), th.sin());
                    let (re, im) = (v.re as f64, v.im as f64);
                    (acc.0 + re * c - im * s, acc.1 + re * s + im * c)
                })
            })
            .collect()
    }

    #[test]
    fn the_planned_dft_agrees_with_the_direct_dft() {
        for n in [1usize, 2, 3, 5, 8, 12, 64, 97, 144, 256] {
            let x: Vec<Complex> = (0..n)
                .map(|i| Complex::new((i as f32 * 0.37).sin(), (i as f32 * 1.3).cos() - 0.2))
                .collect();
            let want = direct(&x);
            let mut got = x.clone();
            plan(n).process(&mut got);
            let err = got
                .iter()
                .zip(&want)
                .map(|(a, b)| (a.re as f64 - b.0).hypot(a.im as f64 - b.1))
                .fold(0.0, f64::max);
            // f32 rounding: a few ulps of the largest output per stage
            assert!(err < 1e-6 * n as f64, "n {n}: error {err}");
        }
    }

    #[test]
    fn the_packed_pair_gives_the_power_of_their_sum() {
        // P(r; g) from the packed transform equals the ring power of x + g·y itself
        let s = 48;
        let x: Vec<f64> = (0..s * s)
            .map(|i| ((i / s) as f64 * 0.9).sin() + ((i % s) as f64 * 2.1).cos())
            .collect();
        let y: Vec<f64> = (0..s * s)
            .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let pair = Rings::new(&x, &y, s);
        for g in [0.5, 1.0, 1.7] {
            let sum: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a + g * b).collect();
            let one = Rings::new(&sum, &vec![0.0; s * s], s);
            assert!((pair.slope(g) - one.slope(1.0)).abs() < 1e-5);
        }
    }
}
