//! NURBS curves (notes ch. 4): `R(u) = Σ w_i P_i N_{i,k}(u) / Σ w_i N_{i,k}(u)`.
//!
//! Evaluated by lift–project (§4.5): the control points are lifted to homogeneous coordinates
//! `(w_i P_i, w_i)` (dimension `dim + 1`), the B-spline evaluator of that dimension runs once,
//! and the result is projected by dividing by its last coordinate.

use super::bezier::binomial;
use super::{check_out, check_points, nth_derivative, BSpline, Curve};
use crate::{Error, Result};

/// A rational B-spline curve: a B-spline in homogeneous coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Nurbs {
    dim: usize,
    hom: BSpline,
}

impl Nurbs {
    /// From Euclidean control points (`dim` each), positive weights, order `k` and knots.
    pub fn new(
        points: &[f64],
        weights: &[f64],
        dim: usize,
        k: usize,
        knots: Vec<f64>,
    ) -> Result<Self> {
        let n = check_points(points, dim, k.max(1))?;
        if weights.len() != n {
            return Err(Error::Parameter {
                name: "number of weights",
                value: format!("{} for {} control points", weights.len(), n),
                expected: "one weight per control point",
            });
        }
        if let Some(w) = weights.iter().find(|w| !(**w > 0.0 && w.is_finite())) {
            return Err(Error::parameter("weight", w, "a positive finite number"));
        }
        let mut hom = Vec::with_capacity(n * (dim + 1));
        for i in 0..n {
            for c in 0..dim {
                hom.push(points[i * dim + c] * weights[i]);
            }
            hom.push(weights[i]);
        }
        Ok(Nurbs {
            dim,
            hom: BSpline::new(hom, dim + 1, k, knots)?,
        })
    }

    /// From a B-spline already in homogeneous coordinates (last coordinate = weight > 0).
    pub fn from_homogeneous(hom: BSpline) -> Result<Self> {
        let d1 = hom.dim();
        if d1 < 2 {
            return Err(Error::parameter("homogeneous dimension", d1, "at least 2"));
        }
        if let Some(w) = hom
            .points()
            .chunks(d1)
            .map(|p| p[d1 - 1])
            .find(|w| !(w.is_finite() && *w > 0.0))
        {
            return Err(Error::parameter("weight", w, "a positive finite number"));
        }
        Ok(Nurbs { dim: d1 - 1, hom })
    }

    /// The exact unit-free circle of §4.1 (9 control points, order 3, knots
    /// `{0,0,0,¼,¼,½,½,¾,¾,1,1,1}`, weights `1, √2/2, 1, …`), centre `c`, radius `r`, in the plane.
    pub fn circle(center: [f64; 2], radius: f64) -> Result<Self> {
        Self::arc(center, radius, 0.0, std::f64::consts::TAU)
    }

    /// An exact circular arc from angle `a0` to `a1` (radians, `0 < a1 − a0 ≤ 2π`): quadratic
    /// rational pieces of at most 90°, each with middle weight `cos(Δ/2)`, double interior knots.
    /// For the full circle this is exactly the control net of §4.1.
    pub fn arc(center: [f64; 2], radius: f64, a0: f64, a1: f64) -> Result<Self> {
        let sweep = a1 - a0;
        if !(sweep > 0.0 && sweep <= std::f64::consts::TAU + 1e-12) {
            return Err(Error::parameter("arc sweep", sweep, "0 < a1 − a0 ≤ 2π"));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(Error::parameter(
                "radius",
                radius,
                "a positive finite number",
            ));
        }
        let (pts, w, knots) = arc_net(sweep);
        let (s0, c0) = a0.sin_cos();
        let mut p = Vec::with_capacity(pts.len());
        for q in pts.chunks(2) {
            // rotate by a0, scale, translate
            p.push(center[0] + radius * (c0 * q[0] - s0 * q[1]));
            p.push(center[1] + radius * (s0 * q[0] + c0 * q[1]));
        }
        Self::new(&p, &w, 2, 3, knots)
    }

    /// Order `k`.
    pub fn order(&self) -> usize {
        self.hom.order()
    }
    /// Number of control points.
    pub fn len(&self) -> usize {
        self.hom.len()
    }
    /// Always false.
    pub fn is_empty(&self) -> bool {
        false
    }
    /// The knots.
    pub fn knots(&self) -> &[f64] {
        self.hom.knots()
    }
    /// The homogeneous B-spline `(w P, w)`.
    pub fn homogeneous(&self) -> &BSpline {
        &self.hom
    }
    /// The weights.
    pub fn weights(&self) -> Vec<f64> {
        let d1 = self.dim + 1;
        self.hom.points().chunks(d1).map(|p| p[self.dim]).collect()
    }
    /// The Euclidean control points (row-major).
    pub fn points(&self) -> Vec<f64> {
        let d1 = self.dim + 1;
        let mut out = Vec::with_capacity(self.len() * self.dim);
        for p in self.hom.points().chunks(d1) {
            out.extend(p[..self.dim].iter().map(|x| x / p[self.dim]));
        }
        out
    }
    /// The valid range.
    pub fn range(&self) -> (f64, f64) {
        self.hom.range()
    }

    /// `R(u)` by lift–project (§4.5).
    pub fn eval(&self, u: f64) -> Result<Vec<f64>> {
        let h = self.hom.eval(u)?;
        Ok(project(&h))
    }

    /// `R(u) = Σ P_i R_{i,k}(u)` with the rational basis `R_{i,k} = w_i N_{i,k}/Σ_j w_j N_{j,k}`
    /// (§4.2), every `N` from the plain recursion: the test oracle.
    pub fn eval_brute(&self, u: f64) -> Result<Vec<f64>> {
        let h = self.hom.eval_brute(u)?;
        Ok(project(&h))
    }

    /// The rational basis `R_{i,k}(u) = w_i N_{i,k}(u) / Σ_j w_j N_{j,k}(u)` of §4.2, all `n` values
    /// (zero outside the local support): non-negative, summing to one (§4.3).
    pub fn rational_basis(&self, u: f64) -> Result<Vec<f64>> {
        let hom = &self.hom;
        super::check_range(u, hom.range())?;
        let (k, n) = (hom.order(), hom.len());
        let t = hom.knots();
        let d = super::basis::span(t, n, k, u);
        let (mut nb, mut l, mut r) = (vec![0.0; k], vec![0.0; k], vec![0.0; k]);
        super::basis::basis_funs(t, d, u, k, &mut nb, &mut l, &mut r);
        let w = self.weights();
        let mut out = vec![0.0; n];
        let mut den = 0.0;
        for (j, b) in nb.iter().enumerate() {
            let i = d + 1 - k + j;
            out[i] = w[i] * b;
            den += out[i];
        }
        out.iter_mut().for_each(|x| *x /= den);
        Ok(out)
    }

    /// Evaluate at many parameters (lift–project on [`BSpline::eval_many`]).
    pub fn eval_many(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        let d1 = self.dim + 1;
        check_out(out, params.len() * self.dim, "params.len() × dim")?;
        if params.len() >= 8 * self.len() {
            return super::poly::PiecewisePoly::from_bspline(&self.hom)
                .eval_many_projected(params, out);
        }
        let mut h = vec![0.0; params.len() * d1];
        self.hom.eval_many(params, &mut h)?;
        for (o, p) in out.chunks_mut(self.dim).zip(h.chunks(d1)) {
            let inv = 1.0 / p[self.dim];
            for c in 0..self.dim {
                o[c] = p[c] * inv;
            }
        }
        Ok(())
    }

    /// Derivatives `R^{(0)} … R^{(nd)}` at `u` into `out` (`(nd+1)·dim` values), from the
    /// homogeneous derivatives `A^{(j)}, w^{(j)}` by the quotient rule
    /// `R^{(j)} = (A^{(j)} − Σ_{i=1}^{j} C(j,i) w^{(i)} R^{(j−i)}) / w`.
    pub fn derivs_into(&self, u: f64, nd: usize, out: &mut [f64]) -> Result<()> {
        let (dim, d1) = (self.dim, self.dim + 1);
        let mut h = vec![0.0; (nd + 1) * d1];
        self.hom.derivs_into(u, nd, &mut h)?;
        let w0 = h[dim];
        for j in 0..=nd {
            for c in 0..dim {
                let mut v = h[j * d1 + c];
                for i in 1..=j {
                    v -= binomial(j, i) * h[i * d1 + dim] * out[(j - i) * dim + c];
                }
                out[j * dim + c] = v / w0;
            }
        }
        Ok(())
    }
}

fn project(h: &[f64]) -> Vec<f64> {
    let d = h.len() - 1;
    h[..d].iter().map(|x| x / h[d]).collect()
}

/// Control net of a unit arc from angle 0 to `sweep`: 2D points, weights, knots (order 3).
fn arc_net(sweep: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let quarter = std::f64::consts::FRAC_PI_2;
    let narcs = ((sweep / quarter) - 1e-12).ceil().max(1.0) as usize;
    let delta = sweep / narcs as f64;
    let wm = (delta / 2.0).cos();
    let mut pts = vec![1.0, 0.0];
    let mut w = vec![1.0];
    for a in 0..narcs {
        let t0 = a as f64 * delta;
        let t1 = t0 + delta;
        let tm = t0 + delta / 2.0;
        // middle point: intersection of the end tangents, at distance 1/cos(Δ/2) along the bisector
        let r = 1.0 / wm;
        pts.extend_from_slice(&[r * tm.cos(), r * tm.sin()]);
        w.push(wm);
        let (s1, c1) = if a + 1 == narcs && (sweep - std::f64::consts::TAU).abs() < 1e-12 {
            (0.0, 1.0) // close the full circle exactly
        } else {
            t1.sin_cos()
        };
        pts.extend_from_slice(&[c1, s1]);
        w.push(1.0);
    }
    let mut knots = vec![0.0; 3];
    for a in 1..narcs {
        let t = a as f64 / narcs as f64;
        knots.push(t);
        knots.push(t);
    }
    knots.extend_from_slice(&[1.0; 3]);
    (pts, w, knots)
}

impl Curve for Nurbs {
    fn dim(&self) -> usize {
        self.dim
    }
    fn domain(&self) -> (f64, f64) {
        self.range()
    }
    fn eval_derivative_into(&self, u: f64, d: usize, out: &mut [f64]) -> Result<()> {
        nth_derivative(self.dim, d, out, |all| self.derivs_into(u, d, all))
    }
}
