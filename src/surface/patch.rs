//! Tensor-product patches (notes §5.3): `Q(u, v) = Σ_i Σ_j P_{i,j} N_{i,k}(u) N_{j,k'}(v)`, with
//! Bézier (§5.3.1) and NURBS (§5.3.3, homogeneous net `(w P, w)`) as special cases, and the exact
//! NURBS sphere, torus and cylinder as surfaces of revolution of rational profiles (§5.2.3 with
//! the NURBS circle `(c(u), s(u))` of §4.1).

use super::Surface;
use crate::curve::basis::{basis_derivs, basis_funs, span, DerivWork, KnotVector};
use crate::curve::{check_range, Nurbs};
use crate::{Error, Result};

/// A tensor-product B-spline or NURBS patch with a net of `nu × nv` points (`nu` along u).
#[derive(Debug, Clone, PartialEq)]
pub struct TensorPatch {
    ku: usize,
    kv: usize,
    tu: Vec<f64>,
    tv: Vec<f64>,
    nu: usize,
    nv: usize,
    dim: usize,
    rational: bool,
    /// Row-major net, point (i, j) at `(i·nv + j)·cdim`; `cdim = dim + 1` when rational
    /// (homogeneous `(w P, w)`).
    net: Vec<f64>,
}

impl TensorPatch {
    /// A B-spline patch: net of `nu × nv` points (`dim` each, point (i, j) at `(i·nv + j)·dim`),
    /// orders `(ku, kv)` and knot sequences of `nu + ku` and `nv + kv` values.
    pub fn bspline(
        net: Vec<f64>,
        dim: usize,
        (nu, nv): (usize, usize),
        (ku, kv): (usize, usize),
        tu: Vec<f64>,
        tv: Vec<f64>,
    ) -> Result<Self> {
        check_net(&net, dim, nu, nv)?;
        KnotVector::new(tu.clone())?.check_for(nu, ku)?;
        KnotVector::new(tv.clone())?.check_for(nv, kv)?;
        Ok(TensorPatch {
            ku,
            kv,
            tu,
            tv,
            nu,
            nv,
            dim,
            rational: false,
            net,
        })
    }

    /// A NURBS patch: as [`TensorPatch::bspline`] plus one positive weight per net point.
    pub fn nurbs(
        net: &[f64],
        weights: &[f64],
        dim: usize,
        sizes: (usize, usize),
        orders: (usize, usize),
        tu: Vec<f64>,
        tv: Vec<f64>,
    ) -> Result<Self> {
        let (nu, nv) = sizes;
        check_net(net, dim, nu, nv)?;
        if weights.len() != nu * nv {
            return Err(Error::Parameter {
                name: "number of weights",
                value: format!("{} for a {}×{} net", weights.len(), nu, nv),
                expected: "one weight per net point",
            });
        }
        if let Some(w) = weights.iter().find(|w| !(**w > 0.0 && w.is_finite())) {
            return Err(Error::parameter("weight", w, "a positive finite number"));
        }
        let mut hom = Vec::with_capacity(nu * nv * (dim + 1));
        for (p, &w) in net.chunks(dim).zip(weights) {
            hom.extend(p.iter().map(|x| x * w));
            hom.push(w);
        }
        let mut s = Self::bspline(hom, dim + 1, sizes, orders, tu, tv)?;
        s.dim = dim;
        s.rational = true;
        Ok(s)
    }

    /// A Bézier patch of degrees `(nu − 1, nv − 1)` (§5.3.1): knots `{0…0, 1…1}` in both directions.
    pub fn bezier(net: Vec<f64>, dim: usize, (nu, nv): (usize, usize)) -> Result<Self> {
        if nu == 0 || nv == 0 {
            return Err(Error::parameter(
                "net size",
                format!("{nu}×{nv}"),
                "at least 1×1",
            ));
        }
        let clamp = |n: usize| {
            let mut t = vec![0.0; n];
            t.extend(std::iter::repeat_n(1.0, n));
            t
        };
        Self::bspline(net, dim, (nu, nv), (nu, nv), clamp(nu), clamp(nv))
    }

    /// The exact surface of revolution of a planar NURBS profile `(x(v), z(v))` about the z axis
    /// through `sweep` radians: `P_{ij} = (x_j c_i, x_j s_i, z_j)`, `w_{ij} = w_i w_j`, where
    /// `(c_i, s_i), w_i` is the NURBS arc of §4.1. u runs around the axis, v along the profile.
    pub fn revolve(profile: &Nurbs, sweep: f64) -> Result<Self> {
        if profile.points().len() / profile.len() != 2 {
            return Err(Error::parameter(
                "profile dimension",
                profile.points().len() / profile.len(),
                "2 (radius x, height z)",
            ));
        }
        let arc = Nurbs::arc([0.0, 0.0], 1.0, 0.0, sweep)?;
        let (cp, cw) = (arc.points(), arc.weights());
        let (pp, pw) = (profile.points(), profile.weights());
        let (nu, nv) = (arc.len(), profile.len());
        let mut net = Vec::with_capacity(nu * nv * 3);
        let mut w = Vec::with_capacity(nu * nv);
        for i in 0..nu {
            for j in 0..nv {
                let (x, z) = (pp[2 * j], pp[2 * j + 1]);
                net.extend_from_slice(&[x * cp[2 * i], x * cp[2 * i + 1], z]);
                w.push(cw[i] * pw[j]);
            }
        }
        Self::nurbs(
            &net,
            &w,
            3,
            (nu, nv),
            (arc.order(), profile.order()),
            arc.knots().to_vec(),
            profile.knots().to_vec(),
        )
    }

    /// The exact sphere of radius `r` centred at the origin (half-circle profile revolved).
    pub fn sphere(r: f64) -> Result<Self> {
        let half = Nurbs::arc(
            [0.0, 0.0],
            r,
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
        )?;
        Self::revolve(&half, std::f64::consts::TAU)
    }

    /// The exact torus: tube radius `r` around a circle of radius `big_r > r` in the xy plane.
    pub fn torus(big_r: f64, r: f64) -> Result<Self> {
        if !(big_r > r && r > 0.0) {
            return Err(Error::parameter(
                "torus radii",
                format!("R = {big_r}, r = {r}"),
                "R > r > 0",
            ));
        }
        let tube = Nurbs::circle([big_r, 0.0], r)?;
        Self::revolve(&tube, std::f64::consts::TAU)
    }

    /// The exact cylinder of radius `r` from z = 0 to z = `h` (a straight profile revolved).
    pub fn cylinder(r: f64, h: f64) -> Result<Self> {
        if !(r > 0.0 && h > 0.0 && h.is_finite()) {
            return Err(Error::parameter(
                "cylinder size",
                format!("r = {r}, h = {h}"),
                "r > 0, h > 0",
            ));
        }
        let line = Nurbs::new(&[r, 0.0, r, h], &[1.0, 1.0], 2, 2, vec![0.0, 0.0, 1.0, 1.0])?;
        Self::revolve(&line, std::f64::consts::TAU)
    }

    /// Net size `(nu, nv)`.
    pub fn size(&self) -> (usize, usize) {
        (self.nu, self.nv)
    }
    /// Orders `(ku, kv)`.
    pub fn orders(&self) -> (usize, usize) {
        (self.ku, self.kv)
    }
    /// True for a NURBS patch.
    pub fn is_rational(&self) -> bool {
        self.rational
    }
    /// Point dimension (Euclidean).
    pub fn dim(&self) -> usize {
        self.dim
    }
    fn cdim(&self) -> usize {
        self.dim + self.rational as usize
    }
    /// Valid ranges in u and v.
    pub fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        (
            (self.tu[self.ku - 1], self.tu[self.nu]),
            (self.tv[self.kv - 1], self.tv[self.nv]),
        )
    }

    /// The knot spans holding `(u, v)`, after checking both are in range.
    fn spans_at(&self, u: f64, v: f64) -> Result<(usize, usize)> {
        let (ru, rv) = self.ranges();
        check_range(u, ru)?;
        check_range(v, rv)?;
        Ok((
            span(&self.tu, self.nu, self.ku, u),
            span(&self.tv, self.nv, self.kv, v),
        ))
    }

    /// Per non-empty v-span: its knot index, its start knot `t` and the `kv × kv` Taylor
    /// matrix `M[j][r] = N_r^{(j)}(t)/j!` (all matrices in one array).
    fn v_span_taylor(&self) -> (Vec<usize>, Vec<f64>, Vec<f64>) {
        let (kv, nv) = (self.kv, self.nv);
        let mut spans = Vec::new();
        let mut starts = Vec::new();
        let mut mats = Vec::new();
        let mut w = DerivWork::new(kv);
        let mut d = vec![0.0; kv * kv];
        for sp in kv - 1..nv {
            if self.tv[sp] >= self.tv[sp + 1] {
                continue;
            }
            basis_derivs(&self.tv, sp, self.tv[sp], kv - 1, &mut w, &mut d);
            let mut fact = 1.0;
            for j in 0..kv {
                if j > 0 {
                    fact *= j as f64;
                }
                mats.extend(d[j * kv..(j + 1) * kv].iter().map(|x| x / fact));
            }
            spans.push(sp);
            starts.push(self.tv[sp]);
        }
        (spans, starts, mats)
    }

    /// `Q(u, v)` (any dimension): `Σ_i Σ_j N_i(u) N_j(v) P_{ij}`, only the `ku × kv` non-zero terms.
    pub fn eval(&self, u: f64, v: f64) -> Result<Vec<f64>> {
        let cd = self.cdim();
        let (su, sv) = self.spans_at(u, v)?;
        let mut bu = vec![0.0; self.ku];
        let mut bv = vec![0.0; self.kv];
        let k = self.ku.max(self.kv);
        let (mut l, mut r) = (vec![0.0; k], vec![0.0; k]);
        basis_funs(&self.tu, su, u, self.ku, &mut bu, &mut l, &mut r);
        basis_funs(&self.tv, sv, v, self.kv, &mut bv, &mut l, &mut r);
        let mut h = vec![0.0; cd];
        for (a, nu_) in bu.iter().enumerate() {
            let i = su + 1 - self.ku + a;
            for (b, nv_) in bv.iter().enumerate() {
                let j = sv + 1 - self.kv + b;
                let p = &self.net[(i * self.nv + j) * cd..(i * self.nv + j + 1) * cd];
                let w = nu_ * nv_;
                for c in 0..cd {
                    h[c] += w * p[c];
                }
            }
        }
        if self.rational {
            let w = h[self.dim];
            h.truncate(self.dim);
            h.iter_mut().for_each(|x| *x /= w);
        }
        Ok(h)
    }

    /// `Q`, `∂Q/∂u`, `∂Q/∂v` at `(u, v)` from first basis derivatives; rational patches by the
    /// quotient rule `Q_u = (A_u − w_u Q)/w`.
    pub fn eval_partials(&self, u: f64, v: f64) -> Result<[Vec<f64>; 3]> {
        let cd = self.cdim();
        let (su, sv) = self.spans_at(u, v)?;
        let mut du = vec![0.0; 2 * self.ku];
        let mut dv = vec![0.0; 2 * self.kv];
        basis_derivs(&self.tu, su, u, 1, &mut DerivWork::new(self.ku), &mut du);
        basis_derivs(&self.tv, sv, v, 1, &mut DerivWork::new(self.kv), &mut dv);
        let mut h = [vec![0.0; cd], vec![0.0; cd], vec![0.0; cd]];
        for a in 0..self.ku {
            let i = su + 1 - self.ku + a;
            for b in 0..self.kv {
                let j = sv + 1 - self.kv + b;
                let p = &self.net[(i * self.nv + j) * cd..(i * self.nv + j + 1) * cd];
                let (w0, wu, wv) = (
                    du[a] * dv[b],
                    du[self.ku + a] * dv[b],
                    du[a] * dv[self.kv + b],
                );
                for c in 0..cd {
                    h[0][c] += w0 * p[c];
                    h[1][c] += wu * p[c];
                    h[2][c] += wv * p[c];
                }
            }
        }
        if self.rational {
            let d = self.dim;
            let (w, wu, wv) = (h[0][d], h[1][d], h[2][d]);
            let q: Vec<f64> = h[0][..d].iter().map(|x| x / w).collect();
            let qu: Vec<f64> = (0..d).map(|c| (h[1][c] - wu * q[c]) / w).collect();
            let qv: Vec<f64> = (0..d).map(|c| (h[2][c] - wv * q[c]) / w).collect();
            return Ok([q, qu, qv]);
        }
        Ok(h)
    }

    /// Evaluate the grid `us × vs` into `out` (`us.len() · vs.len() · dim` values, row `i` for
    /// `us[i]`), using the row-curve factorisation of §5.3.1: for each u the `nv` control points
    /// `C_j(u) = Σ_i N_i(u) P_{ij}` of the v-curve are formed once; that curve is then written per
    /// v-span in power form (Taylor coefficients from basis derivatives precomputed once per span,
    /// see `crate::curve::poly`) and every v costs `kv − 1` multiply-adds per coordinate (Horner).
    /// Rational patches run the same on homogeneous points and divide.
    pub fn eval_grid(&self, us: &[f64], vs: &[f64], out: &mut [f64]) -> Result<()> {
        let (ru, rv) = self.ranges();
        let (dim, cd, kv, nv) = (self.dim, self.cdim(), self.kv, self.nv);
        if out.len() != us.len() * vs.len() * dim {
            return Err(Error::parameter(
                "output length",
                out.len(),
                "us.len() × vs.len() × dim",
            ));
        }
        let (spans, starts, mats) = self.v_span_taylor();
        // per v: which span (index into `spans`) and the local variable
        let mut vsig = Vec::with_capacity(vs.len());
        let mut vx = Vec::with_capacity(vs.len());
        for &v in vs {
            check_range(v, rv)?;
            let sp = span(&self.tv, nv, kv, v);
            let sig = spans.partition_point(|&x| x < sp);
            vsig.push(sig);
            vx.push(v - starts[sig]);
        }
        let k = self.ku.max(kv);
        let (mut l, mut r) = (vec![0.0; k], vec![0.0; k]);
        let mut bu = vec![0.0; self.ku];
        let mut row = vec![0.0; nv * cd];
        let mut rc = vec![0.0; spans.len() * kv * cd];
        for (i, &u) in us.iter().enumerate() {
            check_range(u, ru)?;
            let s = span(&self.tu, self.nu, self.ku, u);
            basis_funs(&self.tu, s, u, self.ku, &mut bu, &mut l, &mut r);
            row.fill(0.0);
            for (a, b) in bu.iter().enumerate() {
                let ii = s + 1 - self.ku + a;
                let src = &self.net[ii * nv * cd..(ii + 1) * nv * cd];
                for (dst, x) in row.iter_mut().zip(src) {
                    *dst += b * x;
                }
            }
            // Taylor coefficients of the row curve on every v-span
            for (sig, &sp) in spans.iter().enumerate() {
                let m = &mats[sig * kv * kv..(sig + 1) * kv * kv];
                let first = sp + 1 - kv;
                for j in 0..kv {
                    for c in 0..cd {
                        let mut acc = 0.0;
                        for rr in 0..kv {
                            acc += m[j * kv + rr] * row[(first + rr) * cd + c];
                        }
                        rc[(sig * kv + j) * cd + c] = acc;
                    }
                }
            }
            let orow = &mut out[i * vs.len() * dim..(i + 1) * vs.len() * dim];
            match (kv, cd, self.rational) {
                (4, 3, false) => horner_row::<4, 3>(&rc, &vsig, &vx, orow, false),
                (3, 3, false) => horner_row::<3, 3>(&rc, &vsig, &vx, orow, false),
                (4, 4, true) => horner_row::<4, 4>(&rc, &vsig, &vx, orow, true),
                (3, 4, true) => horner_row::<3, 4>(&rc, &vsig, &vx, orow, true),
                _ => {
                    let mut h = vec![0.0; cd];
                    for (j, o) in orow.chunks_exact_mut(dim).enumerate() {
                        let c = &rc[vsig[j] * kv * cd..(vsig[j] + 1) * kv * cd];
                        h.copy_from_slice(&c[(kv - 1) * cd..]);
                        for jj in (0..kv - 1).rev() {
                            for q in 0..cd {
                                h[q] = h[q] * vx[j] + c[jj * cd + q];
                            }
                        }
                        if self.rational {
                            for q in 0..dim {
                                o[q] = h[q] / h[dim];
                            }
                        } else {
                            o.copy_from_slice(&h);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// Horner along one grid row with fixed sizes (order `K`, `D` stored coordinates); `project`
/// divides by the last (weight) coordinate.
fn horner_row<const K: usize, const D: usize>(
    rc: &[f64],
    sig: &[usize],
    x: &[f64],
    out: &mut [f64],
    project: bool,
) {
    let od = if project { D - 1 } else { D };
    for ((o, &s), &t) in out.chunks_exact_mut(od).zip(sig).zip(x) {
        let c = &rc[s * K * D..(s + 1) * K * D];
        let mut h = [0.0; D];
        h.copy_from_slice(&c[(K - 1) * D..]);
        for j in (0..K - 1).rev() {
            for q in 0..D {
                h[q] = h[q] * t + c[j * D + q];
            }
        }
        if project {
            let inv = 1.0 / h[D - 1];
            for q in 0..D - 1 {
                o[q] = h[q] * inv;
            }
        } else {
            o.copy_from_slice(&h);
        }
    }
}

fn check_net(net: &[f64], dim: usize, nu: usize, nv: usize) -> Result<()> {
    if dim == 0 {
        return Err(Error::parameter("dimension", 0, "at least 1"));
    }
    if net.len() != nu * nv * dim {
        return Err(Error::Parameter {
            name: "net size",
            value: format!(
                "{} coordinates for a {}×{} net of dimension {}",
                net.len(),
                nu,
                nv,
                dim
            ),
            expected: "nu × nv × dim coordinates",
        });
    }
    if let Some(x) = net.iter().find(|x| !x.is_finite()) {
        return Err(Error::parameter(
            "control point coordinate",
            x,
            "a finite number",
        ));
    }
    Ok(())
}

impl Surface for TensorPatch {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        TensorPatch::ranges(self)
    }
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]> {
        to3(&self.eval(u, v)?)
    }
    fn partials(&self, u: f64, v: f64) -> Result<[[f64; 3]; 3]> {
        let [q, qu, qv] = self.eval_partials(u, v)?;
        Ok([to3(&q)?, to3(&qu)?, to3(&qv)?])
    }
}

/// A point of dimension 2 or 3 as 3D (z = 0 for planar nets).
pub(crate) fn to3(p: &[f64]) -> Result<[f64; 3]> {
    match p.len() {
        2 => Ok([p[0], p[1], 0.0]),
        3 => Ok([p[0], p[1], p[2]]),
        d => Err(Error::parameter(
            "point dimension",
            d,
            "2 or 3 for a surface",
        )),
    }
}
