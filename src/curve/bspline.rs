//! B-spline curves (notes ch. 3): `Q(u) = Σ_{i=0}^{m} P_i N_{i,k}(u)` on any non-decreasing knot
//! sequence, evaluated on the valid range `[u_{k−1}, u_{m+1}]` only.

// Index loops follow the formulas of the notes (several arrays indexed together).
#![allow(clippy::needless_range_loop)]

use super::basis::{self, basis_brute, basis_derivs, basis_funs, span, DerivWork, KnotVector};
use super::{check_out, check_points, check_range, nth_derivative, Curve};
use crate::{Error, Result};

/// A B-spline curve of order `k` with `n = m + 1` control points of dimension `dim`.
#[derive(Debug, Clone, PartialEq)]
pub struct BSpline {
    dim: usize,
    order: usize,
    knots: Vec<f64>,
    points: Vec<f64>,
}

impl BSpline {
    /// A curve from control points (row-major, `dim` each), order `k` and `n + k` knots.
    /// Errors: too few points for the order, decreasing knots, wrong knot count, empty range.
    pub fn new(points: Vec<f64>, dim: usize, k: usize, knots: Vec<f64>) -> Result<Self> {
        if k == 0 {
            return Err(Error::parameter("order", 0, "at least 1"));
        }
        let n = check_points(&points, dim, k)?;
        let kv = KnotVector::new(knots)?;
        kv.check_for(n, k)?;
        Ok(BSpline {
            dim,
            order: k,
            knots: kv.as_slice().to_vec(),
            points,
        })
    }

    /// On the uniform knots `0, 1, …, n + k − 1` (§3.4.3); valid range `[k − 1, n]`.
    pub fn uniform(points: Vec<f64>, dim: usize, k: usize) -> Result<Self> {
        let n = check_points(&points, dim, k.max(1))?;
        Self::new(
            points,
            dim,
            k,
            KnotVector::uniform(n, k).as_slice().to_vec(),
        )
    }

    /// On the standard open knots of §3.8.3 (range `[0, 1]`, end points interpolated).
    pub fn open(points: Vec<f64>, dim: usize, k: usize) -> Result<Self> {
        let n = check_points(&points, dim, k.max(1))?;
        Self::new(points, dim, k, KnotVector::open(n, k)?.as_slice().to_vec())
    }

    /// A closed (periodic) uniform curve through the cyclic control polygon `P_0 … P_{n−1}`:
    /// the first `k − 1` points are repeated at the end, knots `0, 1, …`, range `[k − 1, n + k − 1]`.
    pub fn periodic(points: &[f64], dim: usize, k: usize) -> Result<Self> {
        let n = check_points(points, dim, k.max(1))?;
        let mut pts = points.to_vec();
        for i in 0..k.saturating_sub(1) {
            let j = i % n;
            pts.extend_from_slice(&points[j * dim..(j + 1) * dim]);
        }
        Self::uniform(pts, dim, k)
    }

    /// Number of coordinates of each control point.
    pub fn dim(&self) -> usize {
        self.dim
    }
    /// Order `k` (degree + 1).
    pub fn order(&self) -> usize {
        self.order
    }
    /// Number of control points `n = m + 1`.
    pub fn len(&self) -> usize {
        self.points.len() / self.dim
    }
    /// Always false: a curve has at least `k ≥ 1` control points.
    pub fn is_empty(&self) -> bool {
        false
    }
    /// The knot sequence.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }
    /// The control points, row-major.
    pub fn points(&self) -> &[f64] {
        &self.points
    }
    /// The valid range `[u_{k−1}, u_{m+1}]`.
    pub fn range(&self) -> (f64, f64) {
        basis::domain(&self.knots, self.len(), self.order)
    }

    /// `Q(u)` by order reduction (de Boor, §3.9.4 and Algorithm 3.3): with δ the span of `u`,
    /// `E_i^{[r−1]} = ω E_i^{[r]} + (1 − ω) E_{i−1}^{[r]}`, `ω = (u − u_i)/(u_{i+r−1} − u_i)`,
    /// for `r = k … 2`, `i = δ … δ − r + 2`; the result is `E_δ^{[1]}`.
    pub fn eval(&self, u: f64) -> Result<Vec<f64>> {
        check_range(u, self.range())?;
        let mut out = vec![0.0; self.dim];
        let mut work = vec![0.0; self.order * self.dim];
        self.de_boor(u, &mut work, &mut out);
        Ok(out)
    }

    /// De Boor on a caller-provided scratch of `k·dim` values (no allocation). `u` in range.
    pub fn de_boor(&self, u: f64, work: &mut [f64], out: &mut [f64]) {
        let (k, dim, t) = (self.order, self.dim, &self.knots);
        let d = span(t, self.len(), k, u);
        // c[s] = E[d - s]
        for s in 0..k {
            work[s * dim..(s + 1) * dim]
                .copy_from_slice(&self.points[(d - s) * dim..(d - s + 1) * dim]);
        }
        for r in (2..=k).rev() {
            let mut i = d;
            for s in 0..=r - 2 {
                let omega = (u - t[i]) / (t[i + r - 1] - t[i]);
                for c in 0..dim {
                    work[s * dim + c] =
                        omega * work[s * dim + c] + (1.0 - omega) * work[(s + 1) * dim + c];
                }
                i -= 1;
            }
        }
        out.copy_from_slice(&work[..dim]);
    }

    /// `Q(u) = Σ P_i N_{i,k}(u)` with every `N_{i,k}` from the plain recursion (Algorithm 3.1):
    /// the slow test oracle.
    pub fn eval_brute(&self, u: f64) -> Result<Vec<f64>> {
        check_range(u, self.range())?;
        let n = self.len();
        let mut out = vec![0.0; self.dim];
        for i in 0..n {
            let b = basis_brute(&self.knots, n, i, self.order, u);
            for c in 0..self.dim {
                out[c] += b * self.points[i * self.dim + c];
            }
        }
        Ok(out)
    }

    /// The derivative curve: order `k − 1`, knots `u_1 … u_{m+k−1}`, control points
    /// `(k − 1)(P_{i+1} − P_i)/(u_{i+k} − u_{i+1})` (zero where the knot difference vanishes).
    /// `None` for order 1 (the derivative is zero).
    pub fn derivative_curve(&self) -> Option<BSpline> {
        let (k, dim, n) = (self.order, self.dim, self.len());
        if k < 2 || n < 2 {
            return None;
        }
        let mut pts = Vec::with_capacity((n - 1) * dim);
        for i in 0..n - 1 {
            let dt = self.knots[i + k] - self.knots[i + 1];
            for c in 0..dim {
                let v = if dt > 0.0 {
                    (k - 1) as f64 * (self.points[(i + 1) * dim + c] - self.points[i * dim + c])
                        / dt
                } else {
                    0.0
                };
                pts.push(v);
            }
        }
        Some(BSpline {
            dim,
            order: k - 1,
            knots: self.knots[1..n + k - 1].to_vec(),
            points: pts,
        })
    }

    /// Evaluate at many parameters into `out` (`params.len() · dim` values). Large batches go
    /// through the per-span power form ([`super::poly::PiecewisePoly`], Horner); small ones use
    /// [`BSpline::eval_many_de_boor`].
    pub fn eval_many(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        if params.len() >= 8 * self.len() {
            return super::poly::PiecewisePoly::from_bspline(self).eval_many(params, out);
        }
        self.eval_many_de_boor(params, out)
    }

    /// Evaluate at many parameters with the basis of §3.9: the span is found incrementally
    /// (sorted parameters hit the same or the next span, §3.9.3) and the `k` non-zero basis
    /// values are computed once per point; no allocation per point.
    pub fn eval_many_de_boor(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        let (k, dim, n) = (self.order, self.dim, self.len());
        check_out(out, params.len() * dim, "params.len() × dim")?;
        let range = self.range();
        let t = &self.knots;
        let mut nb = vec![0.0; k];
        let mut left = vec![0.0; k];
        let mut right = vec![0.0; k];
        let mut d = k - 1;
        for (j, &u) in params.iter().enumerate() {
            check_range(u, range)?;
            if !(t[d] <= u && u < t[d + 1]) {
                d = if d + 1 < n && t[d + 1] <= u && u < t[d + 2] {
                    d + 1
                } else {
                    span(t, n, k, u)
                };
            }
            basis_funs(t, d, u, k, &mut nb, &mut left, &mut right);
            let o = &mut out[j * dim..(j + 1) * dim];
            o.fill(0.0);
            for (r, b) in nb.iter().enumerate() {
                let p = &self.points[(d + 1 - k + r) * dim..(d + 2 - k + r) * dim];
                for c in 0..dim {
                    o[c] += b * p[c];
                }
            }
        }
        Ok(())
    }

    /// Derivatives `Q^{(0)}(u) … Q^{(nd)}(u)` at one parameter into `out[(j·dim)..]`, from the
    /// basis derivatives (orders `≥ k` are zero).
    pub fn derivs_into(&self, u: f64, nd: usize, out: &mut [f64]) -> Result<()> {
        check_range(u, self.range())?;
        let (k, dim, n) = (self.order, self.dim, self.len());
        let d = span(&self.knots, n, k, u);
        let mut w = DerivWork::new(k);
        let mut nd_vals = vec![0.0; (nd + 1) * k];
        basis_derivs(&self.knots, d, u, nd, &mut w, &mut nd_vals);
        out[..(nd + 1) * dim].fill(0.0);
        for j in 0..=nd {
            for r in 0..k {
                let b = nd_vals[j * k + r];
                let p = &self.points[(d + 1 - k + r) * dim..(d + 2 - k + r) * dim];
                for c in 0..dim {
                    out[j * dim + c] += b * p[c];
                }
            }
        }
        Ok(())
    }

    pub(crate) fn from_parts_unchecked(
        dim: usize,
        order: usize,
        knots: Vec<f64>,
        points: Vec<f64>,
    ) -> Self {
        BSpline {
            dim,
            order,
            knots,
            points,
        }
    }
}

impl Curve for BSpline {
    fn dim(&self) -> usize {
        self.dim
    }
    fn domain(&self) -> (f64, f64) {
        self.range()
    }
    fn eval_derivative_into(&self, u: f64, d: usize, out: &mut [f64]) -> Result<()> {
        if d > 0 {
            return nth_derivative(self.dim, d, out, |all| self.derivs_into(u, d, all));
        }
        check_out(out, self.dim, "the point dimension")?;
        check_range(u, self.range())?;
        let mut work = vec![0.0; self.order * self.dim];
        self.de_boor(u, &mut work, out);
        Ok(())
    }
}
