//! Knot insertion (notes §7.2–7.4): more control points, the same curve.
//!
//! Boehm's rule inserts one knot `ū` into span δ (`u_δ ≤ ū < u_{δ+1}`):
//!
//! ```text
//! F_i = P_i                                   i ≤ δ − k + 1
//! F_i = α_i P_i + (1 − α_i) P_{i−1}            δ − k + 2 ≤ i ≤ δ,  α_i = (ū − u_i)/(u_{i+k−1} − u_i)
//! F_i = P_{i−1}                               i ≥ δ + 1
//! ```
//!
//! Inserting the midpoint of every non-empty interval of the valid range is one step of
//! subdivision: on uniform knots the regular rows are the filters of Table 1 (Chaikin
//! `¼ ¾ ¾ ¼`, cubic `⅛ ½ ¾ ½ ⅛`, …), and on the standard open knots the first and last rows
//! are the end rules of §7.4 (`F_0 = C_0`, `F_1 = ½(C_0 + C_1)`, …).

use super::basis::span;
use super::{check_range, BSpline, Nurbs};
use crate::{Error, Result};

/// Insert `ū` once (Boehm). `ū` must lie in the valid range and its multiplicity stay `≤ k`.
pub fn insert(curve: &BSpline, ubar: f64) -> Result<BSpline> {
    check_range(ubar, curve.range())?;
    let (k, dim, n) = (curve.order(), curve.dim(), curve.len());
    let t = curve.knots();
    let mult = t.iter().filter(|&&x| x == ubar).count();
    if mult >= k {
        return Err(Error::Parameter {
            name: "knot multiplicity",
            value: format!("{} already at u = {}", mult, ubar),
            expected: "at most the order k after insertion",
        });
    }
    let d = span(t, n, k, ubar);
    let p = curve.points();
    let mut f = Vec::with_capacity((n + 1) * dim);
    for i in 0..=n {
        if i + k <= d + 1 {
            f.extend_from_slice(&p[i * dim..(i + 1) * dim]);
        } else if i > d {
            f.extend_from_slice(&p[(i - 1) * dim..i * dim]);
        } else {
            let a = (ubar - t[i]) / (t[i + k - 1] - t[i]);
            for c in 0..dim {
                f.push(a * p[i * dim + c] + (1.0 - a) * p[(i - 1) * dim + c]);
            }
        }
    }
    let mut knots = Vec::with_capacity(t.len() + 1);
    knots.extend_from_slice(&t[..=d]);
    knots.push(ubar);
    knots.extend_from_slice(&t[d + 1..]);
    Ok(BSpline::from_parts_unchecked(dim, k, knots, f))
}

/// Insert `ū` into a NURBS curve (Boehm on the homogeneous control points).
pub fn insert_nurbs(curve: &Nurbs, ubar: f64) -> Result<Nurbs> {
    Nurbs::from_homogeneous(insert(curve.homogeneous(), ubar)?)
}

/// Insert the midpoint of every non-empty knot interval inside the valid range (one subdivision
/// step, §7.2). The number of control points grows by the number of non-empty spans.
pub fn insert_midpoints(curve: &BSpline) -> Result<BSpline> {
    let (k, n) = (curve.order(), curve.len());
    let t = curve.knots();
    let mids: Vec<f64> = (k - 1..n)
        .filter(|&i| t[i] < t[i + 1])
        .map(|i| 0.5 * (t[i] + t[i + 1]))
        .collect();
    let mut c = curve.clone();
    for m in mids {
        c = insert(&c, m)?;
    }
    Ok(c)
}

/// Midpoint insertion on a NURBS curve (homogeneous control points).
pub fn insert_midpoints_nurbs(curve: &Nurbs) -> Result<Nurbs> {
    Nurbs::from_homogeneous(insert_midpoints(curve.homogeneous())?)
}

/// One subdivision step of a closed (periodic) uniform B-spline of order `k` with cyclic control
/// polygon `points` (`n` points): the `2n` fine control points obtained by midpoint insertion of
/// all knots. Computed on an unrolled copy (wrapped by `k` points on each side) so that every
/// returned point comes from the regular rule; `F_0` is the point whose basis function starts at
/// the same knot as that of `P_0`.
pub fn refine_periodic(points: &[f64], dim: usize, k: usize) -> Result<Vec<f64>> {
    let n = super::check_points(points, dim, 1)?;
    if k == 0 {
        return Err(Error::parameter("order", 0, "at least 1"));
    }
    let w = k; // wrap on each side
    let total = n + 2 * w;
    let mut pts = Vec::with_capacity(total * dim);
    for i in 0..total {
        let j = (i + n * (w / n + 1) - w) % n;
        pts.extend_from_slice(&points[j * dim..(j + 1) * dim]);
    }
    let c = BSpline::uniform(pts, dim, k)?;
    let f = insert_midpoints(&c)?;
    // Coarse basis i starts at knot i. After refinement the fine knots are 0..k-1 (unchanged,
    // left of the range), then half-steps from k-1. Fine basis j starts at fine knot j, which is
    // coarse parameter j for j ≤ k-1 and (k-1) + (j-(k-1))/2 after. The coarse point P_0 sits at
    // unrolled index w (start w); the fine index with start w is j = k-1 + 2(w-(k-1)).
    let j0 = k - 1 + 2 * (w - (k - 1));
    let fp = f.points();
    Ok(fp[j0 * dim..(j0 + 2 * n) * dim].to_vec())
}

/// Split a B-spline at `u` (strictly inside the valid range) into the curves on `[a, u]` and
/// `[u, b]`: insert `u` until its multiplicity is `k`, then cut the knots and control points
/// there (both halves interpolate the split point; this is the B-spline form of the de Casteljau
/// split of §2.6).
pub fn split(curve: &BSpline, u: f64) -> Result<(BSpline, BSpline)> {
    let (a, b) = curve.range();
    if !(u > a && u < b) {
        return Err(Error::Parameter {
            name: "split parameter",
            value: format!("{u} (valid range [{a}, {b}])"),
            expected: "a parameter strictly inside the valid range",
        });
    }
    let k = curve.order();
    let mut c = curve.clone();
    while c.knots().iter().filter(|&&x| x == u).count() < k {
        c = insert(&c, u)?;
    }
    let t = c.knots();
    let r = t.iter().position(|&x| x == u).expect("inserted knot");
    let dim = c.dim();
    let p = c.points();
    let left = BSpline::new(p[..r * dim].to_vec(), dim, k, t[..r + k].to_vec())?;
    let right = BSpline::new(p[r * dim..].to_vec(), dim, k, t[r..].to_vec())?;
    Ok((left, right))
}

/// Split a NURBS curve at `u` (see [`split`]).
pub fn split_nurbs(curve: &Nurbs, u: f64) -> Result<(Nurbs, Nurbs)> {
    let (l, r) = split(curve.homogeneous(), u)?;
    Ok((Nurbs::from_homogeneous(l)?, Nurbs::from_homogeneous(r)?))
}
