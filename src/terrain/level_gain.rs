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
//! so `g = (−b + √(b² − c (a − T)))/c`. The slope at the scale of each level is so the
//! example's, while `A Q = 0` keeps the coarse points.
//!
//! **The limit.** The smoothing only approximates what refinement keeps: a smooth base
//! leaves the coarsest level's slope to its details alone, whose gain (2.1–2.4 on the
//! bench) then makes every finer level's coarse part steeper than the example's (1.7× at
//! the next level), and the finer details cannot take it back. So above the finest level
//! the gain is limited by a measured one: `F_{k−1}` is refined once more (no details) and
//! the limit is the gain at which that coarse part's mean squared gradient,
//! `a' + 2 g b' + g² c'`, is the example's own coarse part's at that level (`P C_{k−1}` of
//! the example's pyramid, measured alike). Where the example is steeper than the base at
//! every scale the limit is high; where the base or the coarser details already carry
//! the example's slope it is low ([`level_gain`]).

use super::finest_gain::{sub_axis, sub_block};
use super::Grid;
use crate::scheme::{Boundary, Scheme};
use crate::Result;

/// The least `g_k`: a level keeps at least half of the example's band (the bench's
/// targets are the same with 0.2).
pub const GAIN_FLOOR: f64 = 0.5;

/// The largest `g_k`, a bound for absurd inputs (the measured limit of [`level_gain`]
/// is below it on the bench and the tests).
pub const GAIN_CEIL: f64 = 4.0;

/// How much steeper than the example's own coarse part (in mean squared gradient) the
/// next level's coarse part may be: `√1.3 ≈ 1.14` in slope, the smoothing being only
/// near what refinement keeps. With 1 the tests' diamond-square example stays too flat
/// at 4 cells (mean slope 3.56 against its 6.26) and its shallow pits too many for the
/// breaching; with 1.5 the bench's real DEM base has a W1 of 0.48 at 2 cells; 1.3 meets
/// both with margin (docs/terrain.md).
pub const LIMIT_SLACK: f64 = 1.3;

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

/// The moments `(a, b, c)` of a level and, above the finest level, its two reconstructed
/// grids `P C_k` and `Q D_k`.
pub(super) type Measured = ((f64, f64, f64), Option<(Grid, Grid)>);

/// The moments `(a, b, c)` of `P C_k` and `Q D_k` for the Mallat block `packed` (coarse
/// part `n_y × n_x`) of level `k`; `synthesize` reconstructs one level. The finest
/// level (`k = 1`) is measured on the top-left `FINEST_SIDE²` samples, reconstructed
/// from a sub-block (the same samples as the whole), the others whole and smoothed as
/// in [`mean_gradient2`]; for those the two reconstructed grids are returned too (for
/// [`refined_moments`]).
pub(super) fn level_moments(
    packed: &Grid,
    (n_y, n_x): (usize, usize),
    k: usize,
    (scheme, boundary): (Scheme, Boundary),
    synthesize: impl Fn(Grid) -> Result<Grid>,
) -> Result<Measured> {
    let (m_y, m_x) = (packed.h(), packed.w());
    let ((ay, ax), side) = measured_box(k, (m_y, m_x), (n_y, n_x), (scheme, boundary));
    let x = synthesize(sub_block(packed, (n_y, n_x), ay, ax, true))?;
    let y = synthesize(sub_block(packed, (n_y, n_x), ay, ax, false))?;
    let m = moments_at(&x, &y, k, side);
    Ok((m, (k > 1).then_some((x, y))))
}

/// The sub-block measured at level `k` of an `m_y × m_x` output from `n_y × n_x`
/// coarse samples, as [`sub_axis`] gives it per axis, and the side of the measured
/// part: at the finest level (k = 1) a top-left square of `min(m_y, m_x, FINEST_SIDE)`,
/// else the whole level.
#[allow(clippy::type_complexity)]
fn measured_box(
    k: usize,
    (m_y, m_x): (usize, usize),
    (n_y, n_x): (usize, usize),
    (scheme, boundary): (Scheme, Boundary),
) -> (((usize, usize), (usize, usize)), (usize, usize)) {
    if k == 1 {
        let s = m_y.min(m_x).min(FINEST_SIDE);
        let a = (
            sub_axis(scheme, boundary, m_y, n_y, s),
            sub_axis(scheme, boundary, m_x, n_x, s),
        );
        (a, (s, s))
    } else {
        (((m_y, n_y), (m_x, n_x)), (m_y, m_x))
    }
}

/// The moments of [`level_moments`] of two reconstructed level-`(k − 1)` grids: on the
/// top-left `side` samples unsmoothed at the finest level, else whole and smoothed.
fn moments_at(x: &Grid, y: &Grid, k: usize, side: (usize, usize)) -> (f64, f64, f64) {
    if k == 1 {
        moments_of(x.data(), y.data(), (side.0, side.1, x.w()))
    } else {
        let (h, w) = (x.h(), x.w());
        let (xs, ys) = (smooth141(x.data(), h, w), smooth141(y.data(), h, w));
        moments_of(&xs, &ys, (h, w, w))
    }
}

/// The moments `(a', b', c')` of the coarse part of level `k` (the grids `x`, `y` of
/// level `k` refined once more to `m_y × m_x` with no details), measured as
/// [`level_moments`] measures level `k`: `a' + 2 g b' + g² c'` is the mean squared
/// gradient of the next level's coarse part when level `k + 1`'s details take the gain `g`.
pub(super) fn refined_moments(
    x: &Grid,
    y: &Grid,
    (m_y, m_x): (usize, usize),
    k: usize,
    (scheme, boundary): (Scheme, Boundary),
    synthesize: impl Fn(Grid) -> Result<Grid>,
) -> Result<(f64, f64, f64)> {
    let (n_y, n_x) = (x.h(), x.w());
    let ((ay, ax), side) = measured_box(k, (m_y, m_x), (n_y, n_x), (scheme, boundary));
    let up = |g: &Grid| {
        let mut b = Grid::zeros(ay.0, ax.0, 1);
        for r in 0..ay.1 {
            for c in 0..ax.1 {
                b.data_mut()[r * ax.0 + c] = g.mean_at(r, c);
            }
        }
        synthesize(b)
    };
    let (xr, yr) = (up(x)?, up(y)?);
    Ok(moments_at(&xr, &yr, k, side))
}

/// The positive root of `c g² + 2 b g + a = t` (`None` when there is none).
fn root((a, b, c): (f64, f64, f64), t: f64) -> Option<f64> {
    let disc = b * b - c * (a - t);
    (c > 0.0 && disc > 0.0)
        .then(|| (-b + disc.sqrt()) / c)
        .filter(|g| *g > 0.0)
}

/// The slope gain `g_k` of a level from its moments `(a, b, c)` and the example's mean
/// squared gradient `t` at level `k − 1`, limited by `next`: the moments `(a', b', c')`
/// of the next level's coarse part ([`refined_moments`]) and the example's own, `t'`
/// (levels above the finest):
///
/// `g_k = clamp(min(g_t, g_n), GAIN_FLOOR, GAIN_CEIL)`, `g_t` the root of
/// `a + 2 g b + g² c = t`, `g_n` that of `a' + 2 g b' + g² c' = s t'` ([`LIMIT_SLACK`] `s`).
///
/// A level whose coarse part is already steeper than the example gets the floor (no
/// root); 1 when the details carry no gradient or the target is not finite.
pub(super) fn level_gain(
    (m, t): ((f64, f64, f64), f64),
    next: Option<((f64, f64, f64), f64)>,
) -> f64 {
    if !(m.2 > 0.0 && t.is_finite()) {
        return 1.0;
    }
    let g = root(m, t).unwrap_or(GAIN_FLOOR);
    let limit = next.map_or(GAIN_CEIL, |(n, t)| {
        root(n, LIMIT_SLACK * t).unwrap_or(GAIN_FLOOR)
    });
    g.min(limit).clamp(GAIN_FLOOR, GAIN_CEIL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gain_gives_the_target_mean_squared_gradient_within_its_limit() {
        let m = (2.0, 0.5, 3.0);
        let g = level_gain((m, 10.0), None);
        assert!((m.0 + 2.0 * g * m.1 + g * g * m.2 - 10.0).abs() < 1e-12);
        assert_eq!(level_gain((m, 1e9), None), GAIN_CEIL);
        assert_eq!(level_gain((m, 0.0), None), GAIN_FLOOR);
        // the next level's coarse part limits the gain to the root of its own equation
        let n = (1.0, 0.0, 4.0);
        let h = level_gain((m, 10.0), Some((n, 5.0)));
        assert!(
            h < g && (n.0 + h * h * n.2 - LIMIT_SLACK * 5.0).abs() < 1e-12,
            "{h} {g}"
        );
        // a next level already steeper than the example's: the floor
        assert_eq!(level_gain((m, 10.0), Some((n, 0.5))), GAIN_FLOOR);
    }
}
