//! Knot vectors and the B-spline basis (notes §3.4–3.9).
//!
//! Notation of the notes: order `k` (degree `k − 1`), control points `P_0 … P_m` (so `n = m + 1`
//! of them), knots `u_0 ≤ u_1 ≤ … ≤ u_{m+k}` (`n + k` values). The basis is the Cox–de Boor
//! recursion (§3.4.1)
//!
//! ```text
//! N_{i,1}(u) = 1 if u_i ≤ u < u_{i+1}, else 0
//! N_{i,r}(u) = (u − u_i)/(u_{i+r−1} − u_i) N_{i,r−1}(u) + (u_{i+r} − u)/(u_{i+r} − u_{i+1}) N_{i+1,r−1}(u)
//! ```
//!
//! with every fraction whose denominator vanishes (multiple knots, §3.8.2) taken as zero. The
//! basis sums to one on the valid range `[u_{k−1}, u_{m+1}]` (§3.5), which every evaluator enforces.
//! At the right end of the range the last non-empty span is used (half-open spans otherwise), so
//! the curve is defined, and continuous, on the closed range. Nothing is snapped: a parameter
//! 1e-12 away from a knot is evaluated on its own span.

// Index loops follow the formulas of the notes (several arrays indexed together).
#![allow(clippy::needless_range_loop)]

use crate::{Error, Result};

/// A validated non-decreasing knot sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct KnotVector {
    knots: Vec<f64>,
}

impl KnotVector {
    /// Any finite non-decreasing sequence.
    pub fn new(knots: Vec<f64>) -> Result<Self> {
        if let Some(x) = knots.iter().find(|x| !x.is_finite()) {
            return Err(Error::parameter("knot", x, "a finite number"));
        }
        if let Some(i) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
            return Err(Error::Parameter {
                name: "knot sequence",
                value: format!("u_{} = {} < u_{} = {}", i, knots[i], i - 1, knots[i - 1]),
                expected: "non-decreasing knots",
            });
        }
        Ok(KnotVector { knots })
    }

    /// The uniform sequence `0, 1, 2, …, n + k − 1` of §3.4.3 (valid range `[k − 1, n]`).
    pub fn uniform(n: usize, k: usize) -> Self {
        KnotVector {
            knots: (0..n + k).map(|i| i as f64).collect(),
        }
    }

    /// The standard (open, clamped) sequence of §3.8.3 on `[0, 1]`: `k` zeros, `n − k` interior
    /// knots with uniform step `1/(m − k + 2) = 1/(n − k + 1)`, `k` ones. End points are interpolated.
    pub fn open(n: usize, k: usize) -> Result<Self> {
        if k == 0 || n < k {
            return Err(Error::parameter(
                "number of control points",
                n,
                "at least the curve order (degree + 1)",
            ));
        }
        let segments = n - k + 1;
        let mut knots = vec![0.0; k];
        knots.extend((1..segments).map(|i| i as f64 / segments as f64));
        knots.extend(std::iter::repeat_n(1.0, k));
        Ok(KnotVector { knots })
    }

    /// The knots as a slice.
    pub fn as_slice(&self) -> &[f64] {
        &self.knots
    }

    /// Number of knots.
    pub fn len(&self) -> usize {
        self.knots.len()
    }

    /// True for an empty sequence.
    pub fn is_empty(&self) -> bool {
        self.knots.is_empty()
    }

    /// Check this sequence against `n` control points of order `k`: `n + k` knots, `n ≥ k ≥ 1`
    /// and a non-empty valid range `u_{k−1} < u_n`.
    pub fn check_for(&self, n: usize, k: usize) -> Result<()> {
        if k == 0 {
            return Err(Error::parameter("order", 0, "at least 1"));
        }
        if n < k {
            return Err(Error::parameter(
                "number of control points",
                n,
                "at least the curve order (degree + 1)",
            ));
        }
        if self.knots.len() != n + k {
            return Err(Error::Parameter {
                name: "number of knots",
                value: format!(
                    "{} for {} control points of order {}",
                    self.knots.len(),
                    n,
                    k
                ),
                expected: "number of control points + order",
            });
        }
        if self.knots[k - 1] >= self.knots[n] {
            return Err(Error::Parameter {
                name: "knot sequence",
                value: format!("u_{} = {} = u_{}", k - 1, self.knots[k - 1], n),
                expected: "a non-empty valid range u_{k-1} < u_{m+1}",
            });
        }
        Ok(())
    }
}

/// The valid range `[u_{k−1}, u_n]` for `n` control points of order `k` (§3.5).
#[inline]
pub fn domain(knots: &[f64], n: usize, k: usize) -> (f64, f64) {
    (knots[k - 1], knots[n])
}

/// The δ index of §3.9.3: the `δ ∈ [k − 1, n − 1]` with `u_δ ≤ u < u_{δ+1}`; at the right end
/// of the valid range, the last non-empty span. `u` must lie in the valid range.
/// Binary search, O(log n).
#[inline]
pub fn span(knots: &[f64], n: usize, k: usize, u: f64) -> usize {
    if u >= knots[n] {
        // right end: last non-empty span (the range is non-empty, so one exists)
        let mut d = n - 1;
        while knots[d] >= knots[d + 1] {
            d -= 1;
        }
        return d;
    }
    // largest d in [k-1, n-1] with knots[d] <= u
    let (mut lo, mut hi) = (k - 1, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if knots[mid] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The `k` basis functions `N_{δ−k+1,k}(u) … N_{δ,k}(u)` that can be non-zero on span `δ`,
/// written to `out[0..k]`. The triangular form of the Cox–de Boor recursion (each `N_{i,r}`
/// computed once, §3.9.4); `left`/`right` are scratch of length `k`. All denominators are
/// differences of knots around a non-empty span, hence positive.
#[inline]
pub fn basis_funs(
    knots: &[f64],
    span: usize,
    u: f64,
    k: usize,
    out: &mut [f64],
    left: &mut [f64],
    right: &mut [f64],
) {
    out[0] = 1.0;
    for j in 1..k {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = out[r] / (right[r + 1] + left[j - r]);
            out[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        out[j] = saved;
    }
}

/// Scratch space for [`basis_derivs`], allocated once per order.
#[derive(Debug, Clone)]
pub struct DerivWork {
    k: usize,
    left: Vec<f64>,
    right: Vec<f64>,
    ndu: Vec<f64>,
    a: Vec<f64>,
}

impl DerivWork {
    pub fn new(k: usize) -> Self {
        DerivWork {
            k,
            left: vec![0.0; k + 1],
            right: vec![0.0; k + 1],
            ndu: vec![0.0; k * k],
            a: vec![0.0; 2 * k],
        }
    }
}

/// Derivatives `d^j/du^j N_{δ−k+1+r,k}(u)` for `j = 0..=nd`, `r = 0..k`, written row by row to
/// `out[j * k + r]`. Derivatives of order `≥ k` are zero. Uses the differentiated recursion
/// `N'_{i,r} = (r−1) [N_{i,r−1}/(u_{i+r−1} − u_i) − N_{i+1,r−1}/(u_{i+r} − u_{i+1})]`
/// applied to the triangular table of lower-order basis values.
pub fn basis_derivs(
    knots: &[f64],
    span: usize,
    u: f64,
    nd: usize,
    w: &mut DerivWork,
    out: &mut [f64],
) {
    let k = w.k;
    let p = k - 1;
    let idx = |row: usize, col: usize| row * k + col;
    // ndu[j][r]: upper triangle basis values N (col = degree), lower triangle knot differences
    w.ndu[idx(0, 0)] = 1.0;
    for j in 1..=p {
        w.left[j] = u - knots[span + 1 - j];
        w.right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            w.ndu[idx(j, r)] = w.right[r + 1] + w.left[j - r];
            let temp = w.ndu[idx(r, j - 1)] / w.ndu[idx(j, r)];
            w.ndu[idx(r, j)] = saved + w.right[r + 1] * temp;
            saved = w.left[j - r] * temp;
        }
        w.ndu[idx(j, j)] = saved;
    }
    for v in out[..(nd + 1) * k].iter_mut() {
        *v = 0.0;
    }
    for j in 0..=p {
        out[j] = w.ndu[idx(j, p)];
    }
    let nmax = nd.min(p);
    for r in 0..=p {
        let (mut s1, mut s2) = (0usize, k);
        w.a[s1] = 1.0;
        for kk in 1..=nmax {
            let mut d = 0.0;
            let rk = r as isize - kk as isize;
            let pk = p - kk;
            if rk >= 0 {
                let rk = rk as usize;
                w.a[s2] = w.a[s1] / w.ndu[idx(pk + 1, rk)];
                d = w.a[s2] * w.ndu[idx(rk, pk)];
            }
            let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2 = if r as isize - 1 <= pk as isize {
                kk - 1
            } else {
                p - r
            };
            for j in j1..=j2 {
                let c = (rk + j as isize) as usize;
                w.a[s2 + j] = (w.a[s1 + j] - w.a[s1 + j - 1]) / w.ndu[idx(pk + 1, c)];
                d += w.a[s2 + j] * w.ndu[idx(c, pk)];
            }
            if r <= pk {
                w.a[s2 + kk] = -w.a[s1 + kk - 1] / w.ndu[idx(pk + 1, r)];
                d += w.a[s2 + kk] * w.ndu[idx(r, pk)];
            }
            out[kk * k + r] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let mut fac = p as f64;
    for kk in 1..=nmax {
        for j in 0..=p {
            out[kk * k + j] *= fac;
        }
        fac *= (p - kk) as f64;
    }
}

/// One basis function `N_{i,k}(u)` by the plain recursion of §3.4.1 (the brute force of
/// Algorithm 3.1): the test oracle for [`basis_funs`]. `n` (number of control points) fixes the
/// right end of the valid range, where the last non-empty first-order span is closed.
pub fn basis_brute(knots: &[f64], n: usize, i: usize, k: usize, u: f64) -> f64 {
    if k == 1 {
        let end = knots[n];
        if u == end {
            // right end of the valid range: the value is the limit from the left, so only the
            // last non-empty span of the range counts (closed there)
            return (i < n && knots[i] < knots[i + 1] && knots[i + 1] == end) as u8 as f64;
        }
        return (knots[i] <= u && u < knots[i + 1]) as u8 as f64;
    }
    let mut s = 0.0;
    let d1 = knots[i + k - 1] - knots[i];
    if d1 > 0.0 {
        s += (u - knots[i]) / d1 * basis_brute(knots, n, i, k - 1, u);
    }
    let d2 = knots[i + k] - knots[i + 1];
    if d2 > 0.0 {
        s += (knots[i + k] - u) / d2 * basis_brute(knots, n, i + 1, k - 1, u);
    }
    s
}
