//! Trivariate B-spline hyper-patches (notes §10.2, equation (1)): a tensor-product volume
//!
//! ```text
//! Q(u, v, w) = Σ_i Σ_j Σ_k P_{i,j,k} N_{i,ku}(u) N_{j,kv}(v) N_{k,kw}(w)
//! ```
//!
//! a deformation of the parameter cuboid into space. The basis is the curve module's Cox–de Boor
//! basis ([`crate::curve::basis`], §3.4.1); only the `ku·kv·kw` terms that can be non-zero on the
//! spans of `(u, v, w)` are summed. Control point `(i, j, k)` is stored at `i + nu·(j + nv·k)`
//! (`i` fastest). Because the basis sums to one on the valid range (§3.5) the patch is affine
//! invariant: moving every control point by an affine map moves every point of `Q` by that map.

// Index loops over the three axes follow the formulas (several arrays indexed together).
#![allow(clippy::needless_range_loop)]
use crate::curve::basis::{basis_derivs, basis_funs, span, DerivWork, KnotVector};
use crate::curve::check_range;
use crate::{Error, Result};

/// The most control points a hyper-patch may have (per patch, all three directions).
pub const MAX_POINTS: usize = 1 << 24;

/// A trivariate tensor-product B-spline volume with `nu × nv × nw` control points.
#[derive(Debug, Clone, PartialEq)]
pub struct HyperPatch {
    dims: [usize; 3],
    orders: [usize; 3],
    knots: [Vec<f64>; 3],
    points: Vec<[f64; 3]>,
}

/// Per-evaluation scratch (basis values and Cox–de Boor work arrays), so evaluating many points
/// allocates once.
#[derive(Debug, Clone)]
pub struct Scratch {
    basis: [Vec<f64>; 3],
    left: Vec<f64>,
    right: Vec<f64>,
}

/// `nu · nv · nw`, refused above [`MAX_POINTS`] (before anything is allocated).
pub(crate) fn checked_count(dims: [usize; 3], what: &'static str) -> Result<usize> {
    let total = dims
        .iter()
        .try_fold(1usize, |a, &n| a.checked_mul(n))
        .unwrap_or(usize::MAX);
    if total > MAX_POINTS {
        return Err(Error::LimitsExceeded {
            what,
            requested: total as u64,
            limit: MAX_POINTS as u64,
        });
    }
    Ok(total)
}

impl HyperPatch {
    /// A patch from control points (`i` fastest), `dims = [nu, nv, nw]`, orders `k = degree + 1`
    /// and knot sequences of `n + k` values each.
    pub fn new(
        points: Vec<[f64; 3]>,
        dims: [usize; 3],
        orders: [usize; 3],
        knots: [KnotVector; 3],
    ) -> Result<Self> {
        let total = checked_count(dims, "hyper-patch control points")?;
        if points.len() != total {
            return Err(Error::Parameter {
                name: "number of control points",
                value: format!("{} for a {:?} lattice", points.len(), dims),
                expected: "nu · nv · nw points",
            });
        }
        if let Some(p) = points.iter().find(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(Error::parameter(
                "control point",
                format!("{p:?}"),
                "finite coordinates",
            ));
        }
        for d in 0..3 {
            knots[d].check_for(dims[d], orders[d])?;
        }
        let [a, b, c] = knots;
        Ok(HyperPatch {
            dims,
            orders,
            knots: [
                a.as_slice().to_vec(),
                b.as_slice().to_vec(),
                c.as_slice().to_vec(),
            ],
            points,
        })
    }

    /// A patch with the standard open (clamped) knot sequences of §3.8.3 on `[0, 1]³` and the
    /// given degrees (order = degree + 1; each `n ≥ degree + 1`).
    pub fn clamped(points: Vec<[f64; 3]>, dims: [usize; 3], degrees: [usize; 3]) -> Result<Self> {
        let orders = degrees.map(|d| d + 1);
        let knots = [
            KnotVector::open(dims[0], orders[0])?,
            KnotVector::open(dims[1], orders[1])?,
            KnotVector::open(dims[2], orders[2])?,
        ];
        HyperPatch::new(points, dims, orders, knots)
    }

    /// Number of control points along u, v, w.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Orders (degree + 1) along u, v, w.
    pub fn orders(&self) -> [usize; 3] {
        self.orders
    }

    /// The knot sequence along direction `d` (0 = u, 1 = v, 2 = w).
    pub fn knots(&self, d: usize) -> &[f64] {
        &self.knots[d]
    }

    /// The control points, `i` fastest.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// Flat index of control point `(i, j, k)`.
    #[inline]
    pub fn index(&self, [i, j, k]: [usize; 3]) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Control point `(i, j, k)`, mutable.
    pub fn point_mut(&mut self, ijk: [usize; 3]) -> Result<&mut [f64; 3]> {
        for d in 0..3 {
            if ijk[d] >= self.dims[d] {
                return Err(Error::Parameter {
                    name: "control point index",
                    value: format!("{ijk:?} in a {:?} lattice", self.dims),
                    expected: "each index below the lattice size",
                });
            }
        }
        let at = self.index(ijk);
        Ok(&mut self.points[at])
    }

    /// The valid parameter range `[u_{k−1}, u_n]` along direction `d` (§3.5).
    pub fn range(&self, d: usize) -> (f64, f64) {
        (
            self.knots[d][self.orders[d] - 1],
            self.knots[d][self.dims[d]],
        )
    }

    /// Scratch space sized for this patch.
    pub fn scratch(&self) -> Scratch {
        let k = self.orders.iter().copied().max().unwrap_or(1);
        Scratch {
            basis: self.orders.map(|o| vec![0.0; o]),
            left: vec![0.0; k],
            right: vec![0.0; k],
        }
    }

    /// `Q(u, v, w)`; each parameter must lie in its valid range.
    pub fn eval(&self, uvw: [f64; 3]) -> Result<[f64; 3]> {
        for d in 0..3 {
            check_range(uvw[d], self.range(d))?;
        }
        Ok(self.eval_with(uvw, &mut self.scratch()))
    }

    /// `Q(u, v, w)` with caller-provided scratch; the parameters must lie in the valid ranges
    /// (not checked; values outside are evaluated on the end spans, i.e. extrapolated).
    pub fn eval_with(&self, uvw: [f64; 3], s: &mut Scratch) -> [f64; 3] {
        let mut first = [0usize; 3];
        for d in 0..3 {
            let (n, k, t) = (self.dims[d], self.orders[d], &self.knots[d]);
            let sp = span(t, n, k, uvw[d]);
            basis_funs(t, sp, uvw[d], k, &mut s.basis[d], &mut s.left, &mut s.right);
            first[d] = sp + 1 - k;
        }
        let [bu, bv, bw] = &s.basis;
        let mut q = [0.0; 3];
        for (c, &nw) in bw.iter().enumerate() {
            for (b, &nv) in bv.iter().enumerate() {
                let row = self.index([first[0], first[1] + b, first[2] + c]);
                let mut acc = [0.0; 3];
                for (a, &nu) in bu.iter().enumerate() {
                    let p = &self.points[row + a];
                    acc[0] += nu * p[0];
                    acc[1] += nu * p[1];
                    acc[2] += nu * p[2];
                }
                let wvw = nv * nw;
                q[0] += wvw * acc[0];
                q[1] += wvw * acc[1];
                q[2] += wvw * acc[2];
            }
        }
        q
    }

    /// `Q` and its Jacobian `[∂Q/∂u, ∂Q/∂v, ∂Q/∂w]` at `(u, v, w)`, from the first derivatives
    /// of the basis ([`basis_derivs`]).
    pub fn eval_jacobian(&self, uvw: [f64; 3]) -> Result<([f64; 3], [[f64; 3]; 3])> {
        for d in 0..3 {
            check_range(uvw[d], self.range(d))?;
        }
        // nd[d] = [N_0..N_{k-1}, N'_0..N'_{k-1}]
        let mut nd: [Vec<f64>; 3] = [Vec::new(), Vec::new(), Vec::new()];
        let mut first = [0usize; 3];
        for d in 0..3 {
            let (n, k, t) = (self.dims[d], self.orders[d], &self.knots[d]);
            let sp = span(t, n, k, uvw[d]);
            let mut w = DerivWork::new(k);
            nd[d] = vec![0.0; 2 * k];
            basis_derivs(t, sp, uvw[d], 1, &mut w, &mut nd[d]);
            first[d] = sp + 1 - k;
        }
        let [ku, kv, kw] = self.orders;
        let mut q = [0.0; 3];
        let mut jac = [[0.0; 3]; 3];
        for c in 0..kw {
            for b in 0..kv {
                for a in 0..ku {
                    let p = self.points[self.index([first[0] + a, first[1] + b, first[2] + c])];
                    let (nu, nv, nw) = (nd[0][a], nd[1][b], nd[2][c]);
                    let (du, dv, dw) = (nd[0][ku + a], nd[1][kv + b], nd[2][kw + c]);
                    let weights = [nu * nv * nw, du * nv * nw, nu * dv * nw, nu * nv * dw];
                    for x in 0..3 {
                        q[x] += weights[0] * p[x];
                        jac[0][x] += weights[1] * p[x];
                        jac[1][x] += weights[2] * p[x];
                        jac[2][x] += weights[3] * p[x];
                    }
                }
            }
        }
        Ok((q, jac))
    }
}

/// Greville abscissae `ξ_i = (t_{i+1} + … + t_{i+k−1}) / (k − 1)` of `n` control points of order
/// `k ≥ 2`. Control values `ξ_i` reproduce the identity: `Σ_i ξ_i N_{i,k}(u) = u` (linear
/// precision of B-splines), which makes the undeformed free-form deformation lattice.
pub fn greville(knots: &[f64], n: usize, k: usize) -> Vec<f64> {
    let p = (k - 1).max(1) as f64;
    (0..n)
        .map(|i| knots[i + 1..i + k].iter().sum::<f64>() / p)
        .collect()
}
