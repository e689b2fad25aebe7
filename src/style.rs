//! Curve style transfer (notes §9.7.1, Figure 9.18): the details of a style stroke,
//! expressed in the local frame of its own coarse curve, are added to the
//! reconstruction of a new base curve, so that the style follows the new path.
//!
//! 1. Decompose the style `S` over `L` levels: `C_k = A C_{k−1}`, `D_k = B C_{k−1}`.
//! 2. Detail `j` of level `k` sits at parameter `u = (j + ½)(n_k − 1)/d_k` of the coarse
//!    polygon `C_k` (`n_k` coarse points, `d_k` details). With the unit tangent `t(u)`
//!    (central difference of `C_k` at the nearest vertex) and normal `n = t` turned 90°,
//!    keep `(α, β) = (D_j·t, D_j·n)`.
//! 3. The base is resampled by arc length to `n_L` points (its ends kept): the new `C_L`.
//! 4. Level by level, `C_{k−1} = P C_k + Q D'_k` with `D'_j = α t'(u) + β n'(u)` in the
//!    frame of the *new* coarse curve.
//!
//! Planar curves (2-D points); the interpolating boundary for open strokes, periodic
//! for closed ones.

use crate::scheme::{max_levels, Boundary, Scheme, TwoScale};
use crate::{Error, Result};

/// Unit tangent of the polygon `c` (2-D points) at the vertex nearest to parameter `u`.
fn frame(c: &[f64], closed: bool, u: f64) -> ([f64; 2], [f64; 2]) {
    let n = c.len() / 2;
    let i = (u.round().max(0.0) as usize).min(n - 1);
    let (a, b) = if closed {
        ((i + n - 1) % n, (i + 1) % n)
    } else {
        (i.saturating_sub(1), (i + 1).min(n - 1))
    };
    let (tx, ty) = (c[2 * b] - c[2 * a], c[2 * b + 1] - c[2 * a + 1]);
    let len = (tx * tx + ty * ty).sqrt();
    let t = if len > 0.0 {
        [tx / len, ty / len]
    } else {
        [1.0, 0.0]
    };
    (t, [-t[1], t[0]])
}

fn param(j: usize, n: usize, d: usize) -> f64 {
    (j as f64 + 0.5) * (n.max(2) - 1) as f64 / d.max(1) as f64
}

/// `n` points along the polyline `p` (2-D), equally spaced in arc length; the ends kept
/// for open curves, the closing edge included for closed ones.
pub fn resample_arc(p: &[f64], n: usize, closed: bool) -> Vec<f64> {
    let m = p.len() / 2;
    let pt = |i: usize| [p[2 * (i % m)], p[2 * (i % m) + 1]];
    let segs = if closed { m } else { m - 1 };
    let mut cum = vec![0.0];
    for i in 0..segs {
        let (a, b) = (pt(i), pt(i + 1));
        cum.push(cum[i] + ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt());
    }
    let total = cum[segs];
    let steps = if closed { n } else { n - 1 };
    let mut out = Vec::with_capacity(2 * n);
    let mut s = 0;
    for k in 0..n {
        let target = total * k as f64 / steps.max(1) as f64;
        while s + 1 < segs && cum[s + 1] < target {
            s += 1;
        }
        let len = cum[s + 1] - cum[s];
        let f = if len > 0.0 {
            ((target - cum[s]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (pt(s), pt(s + 1));
        out.push(a[0] + f * (b[0] - a[0]));
        out.push(a[1] + f * (b[1] - a[1]));
    }
    out
}

/// Apply the style of `style` (2-D points) to `base` (2-D points) over `levels` levels.
/// The result has as many points as the style.
pub fn transfer_style(
    style: &[f64],
    base: &[f64],
    scheme: Scheme,
    levels: usize,
    closed: bool,
) -> Result<Vec<f64>> {
    let boundary = if closed {
        Boundary::Periodic
    } else {
        Boundary::Interpolating
    };
    let m = style.len() / 2;
    if !style.len().is_multiple_of(2) || !base.len().is_multiple_of(2) || base.len() < 4 {
        return Err(Error::parameter(
            "points",
            format!("{} style and {} base coordinates", style.len(), base.len()),
            "2-D point lists, the base with at least 2 points",
        ));
    }
    let max = max_levels(scheme, boundary, m);
    if levels == 0 || levels > max {
        return Err(Error::parameter(
            "levels",
            format!("{levels} for a style of {m} points"),
            "1 to the levels the style's length allows for the scheme",
        ));
    }
    // 1–2: the style's pyramid, details in local frames
    let mut c = style.to_vec();
    let mut local: Vec<Vec<[f64; 2]>> = Vec::with_capacity(levels);
    let mut lengths = vec![m];
    for _ in 0..levels {
        let mm = c.len() / 2;
        let lv = TwoScale::new(scheme, boundary, mm);
        let mut packed = vec![0.0; c.len()];
        lv.decompose(&c, 2, &mut packed);
        let (n, d) = (lv.coarse, lv.details());
        let coarse = packed[..2 * n].to_vec();
        let dets = (0..d)
            .map(|j| {
                let (t, nn) = frame(&coarse, closed, param(j, n, d));
                let (dx, dy) = (packed[2 * (n + j)], packed[2 * (n + j) + 1]);
                [dx * t[0] + dy * t[1], dx * nn[0] + dy * nn[1]]
            })
            .collect();
        local.push(dets);
        c = coarse;
        lengths.push(n);
    }
    // 3: the base as the new coarsest curve
    let mut cur = resample_arc(base, lengths[levels], closed);
    // 4: reconstruct with the details in the new frames
    for k in (1..=levels).rev() {
        let mm = lengths[k - 1];
        let lv = TwoScale::new(scheme, boundary, mm);
        let (n, d) = (lv.coarse, lv.details());
        let mut packed = vec![0.0; 2 * mm];
        packed[..2 * n].copy_from_slice(&cur);
        for (j, ab) in local[k - 1].iter().enumerate() {
            let (t, nn) = frame(&cur, closed, param(j, n, d));
            packed[2 * (n + j)] = ab[0] * t[0] + ab[1] * nn[0];
            packed[2 * (n + j) + 1] = ab[0] * t[1] + ab[1] * nn[1];
        }
        let mut fine = vec![0.0; 2 * mm];
        lv.reconstruct(&packed, 2, &mut fine);
        cur = fine;
    }
    Ok(cur)
}
