//! The slope gain of a synthesized level (with `--base-scale` above the base's own scale).
//!
//! When the base is trusted only down to a coarse scale, it is usually smoother there than
//! the example (a sketch, a coarse global DEM): the example's band RMS alone then leaves
//! the result flatter than the example at every scale. Each level `k ≥ 2` is therefore
//! reconstructed as `F_{k−1} = P C_k + g_k Q D_k`, with `g_k` chosen so that the mean
//! squared gradient of `F_{k−1}` (central differences on its lattice, as the slope of
//! block means is measured; above the finest level after a `[1 4 1]/6` smoothing, since
//! refinement by `P` and block means pass little of the lattice's highest frequencies)
//! is that of the example's own level-`(k−1)` grid `E_{k−1}`, measured the same way:
//!
//! `G(X + g Y) = a + 2 g b + g² c = T`, with `X = P C_k`, `Y = Q D_k`,
//! `a = G(X)`, `b = ⟨∇X, ∇Y⟩`, `c = G(Y)`, `T = G(E_{k−1})`,
//!
//! so `g = (−b + √(b² − c (a − T)))/c`, clamped to [`GAIN_RANGE`]. The slope at the
//! scale of each level is so the example's, while `A Q = 0` keeps the coarse points.

use super::finest_gain::{sub_axis, sub_block};
use super::Grid;
use crate::scheme::{Boundary, Scheme};
use crate::Result;

/// The range of `g_k`. A narrower (0.2, 1.8) meets the bench's landform targets with
/// margin (docs/terrain.md) but leaves the tests' diamond-square example too flat at 4
/// cells, so it is not the default.
pub const GAIN_RANGE: (f64, f64) = (0.5, 4.0);

/// The side of the top-left square on which the finest level's moments are taken (the
/// finest level is the output's size; its mean gradient is a local statistic).
const FINEST_SIDE: usize = 512;

/// Mean squared central difference `(f[i+1] − f[i−1])/2` along both axes of the channel
/// means of `g`, after a `[1 4 1]/6` smoothing along both axes when `smooth` (levels
/// above the finest, whose lattice is later refined by `P` and seen through block means:
/// both pass little of the lattice's highest frequencies).
pub(super) fn mean_gradient2(g: &Grid, smooth: bool) -> f64 {
    let m: Vec<f64> = (0..g.h() * g.w())
        .map(|i| g.mean_at(i / g.w(), i % g.w()))
        .collect();
    let m = if smooth {
        smooth141(&m, g.h(), g.w())
    } else {
        m
    };
    moments_of(&m, &m, (g.h(), g.w(), g.w())).0
}

/// Separable `[1 4 1]/6` smoothing of an `h × w` field (ends repeated). Its response
/// `(2 + cos ω)/3` is near that of refining by Chaikin's `P` and taking block means
/// (about `sinc⁴(ω/2)`: 0.67 against 0.66 at half the lattice's Nyquist frequency);
/// `[1 2 1]/4` (0.5 there) over-corrected on the bench: the coarsest gain reached 3 and
/// the finer levels' slopes overshot.
fn smooth141(f: &[f64], h: usize, w: usize) -> Vec<f64> {
    let mut a = vec![0.0; h * w];
    for y in 0..h {
        for x in 0..w {
            let (l, r) = (x.saturating_sub(1), (x + 1).min(w - 1));
            a[y * w + x] = (f[y * w + l] + 4.0 * f[y * w + x] + f[y * w + r]) / 6.0;
        }
    }
    let mut b = vec![0.0; h * w];
    for y in 0..h {
        let (u, d) = (y.saturating_sub(1), (y + 1).min(h - 1));
        for x in 0..w {
            b[y * w + x] = (a[u * w + x] + 4.0 * a[y * w + x] + a[d * w + x]) / 6.0;
        }
    }
    b
}

/// Means of `∇x·∇x`, `∇x·∇y` and `∇y·∇y` over central differences of two fields, on
/// their top-left `h × w` samples (rows `stride` apart).
fn moments_of(xd: &[f64], yd: &[f64], (h, w, stride): (usize, usize, usize)) -> (f64, f64, f64) {
    let (mut a, mut b, mut c, mut n) = (0.0, 0.0, 0.0, 0usize);
    let mut add = |i: usize, j: usize| {
        let (dx, dy) = (0.5 * (xd[j] - xd[i]), 0.5 * (yd[j] - yd[i]));
        a += dx * dx;
        b += dx * dy;
        c += dy * dy;
        n += 1;
    };
    for r in 0..h {
        for col in 0..w {
            let i = r * stride + col;
            if col + 2 < w {
                add(i, i + 2);
            }
            if r + 2 < h {
                add(i, i + 2 * stride);
            }
        }
    }
    let n = n.max(1) as f64;
    (a / n, b / n, c / n)
}

/// The gain `g_k` for the Mallat block `packed` (coarse part `n_y × n_x`) of level `k`
/// whose result's mean squared gradient should be `target`; `synthesize` reconstructs
/// one level. The finest level (`k = 1`) is measured on the top-left
/// `FINEST_SIDE²` samples, reconstructed from a sub-block (the same samples as the
/// whole), the others whole and smoothed as in [`mean_gradient2`].
pub(super) fn fit_level_gain(
    packed: &Grid,
    (n_y, n_x): (usize, usize),
    (target, k): (f64, usize),
    (scheme, boundary): (Scheme, Boundary),
    synthesize: impl Fn(Grid) -> Result<Grid>,
) -> Result<f64> {
    let (m_y, m_x) = (packed.h(), packed.w());
    let ((ay, ax), side) = if k == 1 {
        let s = m_y.min(m_x).min(FINEST_SIDE);
        let a = (
            sub_axis(scheme, boundary, m_y, n_y, s),
            sub_axis(scheme, boundary, m_x, n_x, s),
        );
        (a, (s, s))
    } else {
        (((m_y, n_y), (m_x, n_x)), (m_y, m_x))
    };
    let x = synthesize(sub_block(packed, (n_y, n_x), ay, ax, true))?;
    let y = synthesize(sub_block(packed, (n_y, n_x), ay, ax, false))?;
    let (a, b, c) = if k == 1 {
        moments_of(x.data(), y.data(), (side.0, side.1, x.w()))
    } else {
        let (h, w) = (x.h(), x.w());
        let (xs, ys) = (smooth141(x.data(), h, w), smooth141(y.data(), h, w));
        moments_of(&xs, &ys, (h, w, w))
    };
    Ok(solve(a, b, c, target))
}

/// The positive root of `c g² + 2 b g + a = t`, clamped to [`GAIN_RANGE`] (1 when the
/// details carry no gradient or the target is not finite).
pub(super) fn solve(a: f64, b: f64, c: f64, t: f64) -> f64 {
    if !(c > 0.0 && t.is_finite()) {
        return 1.0;
    }
    let disc = b * b - c * (a - t);
    let g = if disc > 0.0 {
        (-b + disc.sqrt()) / c
    } else {
        GAIN_RANGE.0
    };
    g.clamp(GAIN_RANGE.0, GAIN_RANGE.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gain_gives_the_target_mean_squared_gradient() {
        let (a, b, c) = (2.0, 0.5, 3.0);
        let g = solve(a, b, c, 10.0);
        assert!((a + 2.0 * g * b + g * g * c - 10.0).abs() < 1e-12);
        assert_eq!(solve(a, b, c, 1e9), GAIN_RANGE.1);
        assert_eq!(solve(a, b, c, 0.0), GAIN_RANGE.0);
    }
}
