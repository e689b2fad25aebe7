//! Piecewise-polynomial (power basis) form of a B-spline, for evaluating many points fast.
//!
//! Speed note: on each non-empty span `[u_δ, u_{δ+1})` the curve is one polynomial of degree
//! `k − 1`. Writing it once per span as a Taylor expansion at the span start,
//! `Q(u) = Σ_j c_j s^j`, `s = u − u_δ`, `c_j = Q^{(j)}(u_δ⁺)/j!` (from the basis derivatives,
//! §3.9), turns every further evaluation into `k − 1` multiply-adds per coordinate (Horner)
//! instead of the `k(k − 1)/2` divisions and lerps of de Boor. The local variable `s` keeps the
//! expansion well conditioned for the low degrees used here; results agree with de Boor to
//! round-off. Nothing is snapped: `u` picks its span by exact comparison with the knots.

#![allow(clippy::needless_range_loop)]

use super::basis::{basis_derivs, DerivWork};
use super::{check_out, BSpline};
use crate::{Error, Result};

/// The spans of a B-spline as polynomials in power form.
#[derive(Debug, Clone)]
pub struct PiecewisePoly {
    dim: usize,
    k: usize,
    /// Start of each non-empty span, then the end of the valid range.
    breaks: Vec<f64>,
    /// Per span: `k` coefficient rows of `dim` values (`c_0 … c_{k−1}`).
    coeffs: Vec<f64>,
}

impl PiecewisePoly {
    /// Convert every non-empty span of the valid range.
    pub fn from_bspline(c: &BSpline) -> Self {
        let (k, dim, n) = (c.order(), c.dim(), c.len());
        let t = c.knots();
        let mut breaks = Vec::new();
        let mut coeffs = Vec::new();
        let mut w = DerivWork::new(k);
        let mut d = vec![0.0; k * k];
        let p = c.points();
        for span in k - 1..n {
            if t[span] >= t[span + 1] {
                continue;
            }
            breaks.push(t[span]);
            basis_derivs(t, span, t[span], k - 1, &mut w, &mut d);
            let mut fact = 1.0;
            for j in 0..k {
                if j > 0 {
                    fact *= j as f64;
                }
                for cc in 0..dim {
                    let mut s = 0.0;
                    for r in 0..k {
                        s += d[j * k + r] * p[(span + 1 - k + r) * dim + cc];
                    }
                    coeffs.push(s / fact);
                }
            }
        }
        breaks.push(t[n]);
        PiecewisePoly {
            dim,
            k,
            breaks,
            coeffs,
        }
    }

    /// Evaluate at `params` (any order; sorted input is fastest) into `out` (`dim` per point).
    pub fn eval_many(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        check_out(out, params.len() * self.dim, "params.len() × dim")?;
        match (self.k, self.dim) {
            (4, 3) => self.run::<4, 3>(params, out),
            (4, 2) => self.run::<4, 2>(params, out),
            (4, 4) => self.run::<4, 4>(params, out),
            (3, 3) => self.run::<3, 3>(params, out),
            (3, 2) => self.run::<3, 2>(params, out),
            (3, 4) => self.run::<3, 4>(params, out),
            _ => self.run_dyn(params, out),
        }
    }

    /// Rational evaluation: the polynomial is homogeneous `(w P, w)`; writes the projected
    /// points (`dim − 1` per point) into `out` in the same pass (lift–project, §4.5).
    pub fn eval_many_projected(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        let d = self.dim - 1;
        if d == 0 || out.len() != params.len() * d {
            return Err(Error::parameter(
                "output length",
                out.len(),
                "params.len() × (dim − 1)",
            ));
        }
        match (self.k, self.dim) {
            (3, 3) => self.run_projected::<3, 3>(params, out),
            (3, 4) => self.run_projected::<3, 4>(params, out),
            (4, 3) => self.run_projected::<4, 3>(params, out),
            (4, 4) => self.run_projected::<4, 4>(params, out),
            _ => {
                let mut h = vec![0.0; params.len() * self.dim];
                self.run_dyn(params, &mut h)?;
                for (o, p) in out.chunks_exact_mut(d).zip(h.chunks_exact(self.dim)) {
                    for c in 0..d {
                        o[c] = p[c] / p[d];
                    }
                }
                Ok(())
            }
        }
    }

    fn run_projected<const K: usize, const D: usize>(
        &self,
        params: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        let mut s = 0usize;
        for (u, o) in params.iter().zip(out.chunks_exact_mut(D - 1)) {
            self.locate(*u, &mut s)?;
            let acc = self.horner::<K, D>(s, u - self.breaks[s]);
            let inv = 1.0 / acc[D - 1];
            for d in 0..D - 1 {
                o[d] = acc[d] * inv;
            }
        }
        Ok(())
    }

    /// Piece `s` at local variable `x` by Horner's rule: `Σ_j c_j x^j`, `D` coordinates.
    #[inline(always)]
    fn horner<const K: usize, const D: usize>(&self, s: usize, x: f64) -> [f64; D] {
        let c = &self.coeffs[s * K * D..(s + 1) * K * D];
        let mut acc = [0.0; D];
        acc.copy_from_slice(&c[(K - 1) * D..]);
        for j in (0..K - 1).rev() {
            for d in 0..D {
                acc[d] = acc[d] * x + c[j * D + d];
            }
        }
        acc
    }

    #[inline]
    fn locate(&self, u: f64, s: &mut usize) -> Result<()> {
        let b = &self.breaks;
        let last = b.len() - 2;
        if !(u >= b[0] && u <= b[last + 1]) {
            return super::check_range(u, (b[0], b[last + 1]));
        }
        // incremental search first (sorted parameters stay on the same or the next span)
        if u >= b[*s] && (u < b[*s + 1] || *s == last) {
            return Ok(());
        }
        if *s < last && u >= b[*s + 1] && (u < b[*s + 2] || *s + 1 == last) {
            *s += 1;
            return Ok(());
        }
        // binary search: largest s ≤ last with b[s] ≤ u
        let (mut lo, mut hi) = (0, last + 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if b[mid] <= u {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        *s = lo;
        Ok(())
    }

    fn run<const K: usize, const D: usize>(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        let mut s = 0usize;
        for (u, o) in params.iter().zip(out.chunks_exact_mut(D)) {
            self.locate(*u, &mut s)?;
            let acc = self.horner::<K, D>(s, u - self.breaks[s]);
            o.copy_from_slice(&acc);
        }
        Ok(())
    }

    fn run_dyn(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        let (k, dim) = (self.k, self.dim);
        let mut s = 0usize;
        for (u, o) in params.iter().zip(out.chunks_exact_mut(dim)) {
            self.locate(*u, &mut s)?;
            let x = u - self.breaks[s];
            let c = &self.coeffs[s * k * dim..(s + 1) * k * dim];
            for d in 0..dim {
                let mut acc = c[(k - 1) * dim + d];
                for j in (0..k - 1).rev() {
                    acc = acc * x + c[j * dim + d];
                }
                o[d] = acc;
            }
        }
        Ok(())
    }
}
