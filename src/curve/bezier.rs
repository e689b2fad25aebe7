//! Bézier curves (notes ch. 2): `Q(u) = Σ_{i=0}^{d} B_{i,d}(u) P_i`, `0 ≤ u ≤ 1`, with the
//! Bernstein polynomials `B_{i,d}(u) = C(d,i) u^i (1 − u)^{d−i}` (§2.1).

use super::{check_out, check_points, check_range, Curve};
use crate::Result;

/// A Bézier curve of degree `d` with `d + 1` control points of dimension `dim`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bezier {
    dim: usize,
    points: Vec<f64>,
}

impl Bezier {
    /// A curve from `d + 1 ≥ 1` control points, `dim` coordinates each, row-major.
    pub fn new(points: Vec<f64>, dim: usize) -> Result<Self> {
        check_points(&points, dim, 1)?;
        Ok(Bezier { dim, points })
    }

    /// The degree `d` (number of control points − 1).
    pub fn degree(&self) -> usize {
        self.points.len() / self.dim - 1
    }

    /// The control points, row-major.
    pub fn points(&self) -> &[f64] {
        &self.points
    }

    /// `Q(u)` by de Casteljau (Algorithm 2.2): `P_j ← (1 − u) P_j + u P_{j+1}`, `d` rounds.
    /// Numerically stable (convex combinations only for `u ∈ [0, 1]`).
    pub fn eval(&self, u: f64) -> Result<Vec<f64>> {
        check_range(u, (0.0, 1.0))?;
        let mut work = self.points.clone();
        Ok(de_casteljau(&mut work, self.dim, u).to_vec())
    }

    /// `Q(u)` by the definition `Σ B_{i,d}(u) P_i` (Algorithm 2.1): the test oracle.
    pub fn eval_bernstein(&self, u: f64) -> Result<Vec<f64>> {
        check_range(u, (0.0, 1.0))?;
        let d = self.degree();
        let mut out = vec![0.0; self.dim];
        for i in 0..=d {
            let b = bernstein(i, d, u);
            for (o, p) in out
                .iter_mut()
                .zip(&self.points[i * self.dim..(i + 1) * self.dim])
            {
                *o += b * p;
            }
        }
        Ok(out)
    }

    /// The derivative curve (hodograph, §2.2): degree `d − 1`, control points `d (P_{i+1} − P_i)`.
    /// The derivative of a degree-0 curve is the zero point.
    pub fn hodograph(&self) -> Bezier {
        let d = self.degree();
        let dim = self.dim;
        if d == 0 {
            return Bezier {
                dim,
                points: vec![0.0; dim],
            };
        }
        let mut pts = Vec::with_capacity(d * dim);
        for i in 0..d {
            for c in 0..dim {
                pts.push(d as f64 * (self.points[(i + 1) * dim + c] - self.points[i * dim + c]));
            }
        }
        Bezier { dim, points: pts }
    }

    /// Split at `u` into the two curves on `[0, u]` and `[u, 1]` (each reparametrised to
    /// `[0, 1]`): the left and right edges of the de Casteljau triangle (§2.6).
    pub fn split(&self, u: f64) -> Result<(Bezier, Bezier)> {
        check_range(u, (0.0, 1.0))?;
        let dim = self.dim;
        let n = self.degree() + 1;
        let mut work = self.points.clone();
        let mut left = Vec::with_capacity(n * dim);
        let mut right = vec![0.0; n * dim];
        for r in 0..n {
            let m = n - r; // points in this column
            left.extend_from_slice(&work[..dim]);
            right[(n - 1 - r) * dim..(n - r) * dim].copy_from_slice(&work[(m - 1) * dim..m * dim]);
            for j in 0..m - 1 {
                for c in 0..dim {
                    work[j * dim + c] = (1.0 - u) * work[j * dim + c] + u * work[(j + 1) * dim + c];
                }
            }
        }
        Ok((Bezier { dim, points: left }, Bezier { dim, points: right }))
    }

    /// Degree elevation: the same curve with `d + 2` control points,
    /// `P'_i = (i/(d+1)) P_{i−1} + (1 − i/(d+1)) P_i`, `i = 0 … d + 1`.
    pub fn elevate(&self) -> Bezier {
        let d = self.degree();
        let dim = self.dim;
        let mut pts = vec![0.0; (d + 2) * dim];
        for i in 0..=d + 1 {
            let a = i as f64 / (d + 1) as f64;
            for c in 0..dim {
                let prev = if i > 0 {
                    self.points[(i - 1) * dim + c]
                } else {
                    0.0
                };
                let cur = if i <= d {
                    self.points[i * dim + c]
                } else {
                    0.0
                };
                pts[i * dim + c] = a * prev + (1.0 - a) * cur;
            }
        }
        Bezier { dim, points: pts }
    }

    /// The same curve as a B-spline of order `d + 1` on `{0,…,0, 1,…,1}` (§3.8.4).
    pub fn to_bspline(&self) -> super::BSpline {
        let k = self.degree() + 1;
        let mut knots = vec![0.0; k];
        knots.extend(std::iter::repeat_n(1.0, k));
        super::BSpline::new(self.points.clone(), self.dim, k, knots)
            .expect("a Bézier curve is a valid B-spline")
    }
}

/// In-place de Casteljau on `work` (`d + 1` points of `dim`); returns the point `work[..dim]`.
pub fn de_casteljau(work: &mut [f64], dim: usize, u: f64) -> &[f64] {
    let n = work.len() / dim;
    for r in 1..n {
        for j in 0..n - r {
            for c in 0..dim {
                work[j * dim + c] = (1.0 - u) * work[j * dim + c] + u * work[(j + 1) * dim + c];
            }
        }
    }
    &work[..dim]
}

/// `B_{i,d}(u) = C(d, i) u^i (1 − u)^{d−i}`.
pub fn bernstein(i: usize, d: usize, u: f64) -> f64 {
    if i > d {
        return 0.0;
    }
    binomial(d, i) * u.powi(i as i32) * (1.0 - u).powi((d - i) as i32)
}

/// `C(n, r)` as a float (exact for the degrees used here).
pub fn binomial(n: usize, r: usize) -> f64 {
    let r = r.min(n - r);
    let mut b = 1.0;
    for j in 0..r {
        b = b * (n - j) as f64 / (j + 1) as f64;
    }
    b.round()
}

impl Curve for Bezier {
    fn dim(&self) -> usize {
        self.dim
    }
    fn domain(&self) -> (f64, f64) {
        (0.0, 1.0)
    }
    fn eval_derivative_into(&self, u: f64, d: usize, out: &mut [f64]) -> Result<()> {
        check_range(u, (0.0, 1.0))?;
        check_out(out, self.dim, "the point dimension")?;
        let mut c = self.clone();
        for _ in 0..d {
            c = c.hodograph();
        }
        let mut work = c.points;
        out.copy_from_slice(de_casteljau(&mut work, self.dim, u));
        Ok(())
    }
}
