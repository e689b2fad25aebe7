//! Curve-based surfaces (notes §5.2). Every input curve is reparametrised to `[0, 1]` (its valid
//! range mapped linearly), so the surfaces live on `[0, 1]²` unless stated otherwise.

use super::patch::to3;
use super::{add, cross, norm, normalize, scale, sub, Surface};
use crate::curve::Curve;
use crate::{Error, Result};

/// A curve evaluated on `t ∈ [0, 1]`, as a 3D point (planar curves get z = 0).
pub(crate) fn at(c: &dyn Curve, t: f64) -> Result<[f64; 3]> {
    let (a, b) = c.domain();
    let u = if t >= 1.0 { b } else { a + (b - a) * t };
    to3(&c.point(u)?)
}

/// `d/dt` of [`at`].
pub(crate) fn at_d(c: &dyn Curve, t: f64) -> Result<[f64; 3]> {
    let (a, b) = c.domain();
    let u = if t >= 1.0 { b } else { a + (b - a) * t };
    Ok(scale(to3(&c.derivative(u, 1)?)?, b - a))
}

/// Ruled (lofted) surface (§5.2.1): `Q(u, v) = (1 − v) P_0(u) + v P_1(u)`.
pub struct Loft {
    pub p0: Box<dyn Curve>,
    pub p1: Box<dyn Curve>,
}

impl Surface for Loft {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        ((0.0, 1.0), (0.0, 1.0))
    }
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]> {
        Ok(add(
            scale(at(&*self.p0, u)?, 1.0 - v),
            scale(at(&*self.p1, u)?, v),
        ))
    }
    fn partials(&self, u: f64, v: f64) -> Result<[[f64; 3]; 3]> {
        let (a, b) = (at(&*self.p0, u)?, at(&*self.p1, u)?);
        let (da, db) = (at_d(&*self.p0, u)?, at_d(&*self.p1, u)?);
        Ok([
            add(scale(a, 1.0 - v), scale(b, v)),
            add(scale(da, 1.0 - v), scale(db, v)),
            sub(b, a),
        ])
    }
}

/// Bilinearly blended Coons patch (§5.2.2) from four boundary curves:
/// `P_0(u) = Q(u, 0)`, `P_1(u) = Q(u, 1)`, `Q_0(v) = Q(0, v)`, `Q_1(v) = Q(1, v)`:
///
/// ```text
/// Q(u,v) = (1−u) Q_0(v) + u Q_1(v) + (1−v) P_0(u) + v P_1(u)
///        − [(1−u)(1−v) P00 + u(1−v) P10 + (1−u) v P01 + u v P11]
/// ```
///
/// with the corners `P00 = P_0(0)`, `P10 = P_0(1)`, `P01 = P_1(0)`, `P11 = P_1(1)`.
pub struct Coons {
    p0: Box<dyn Curve>,
    p1: Box<dyn Curve>,
    q0: Box<dyn Curve>,
    q1: Box<dyn Curve>,
    c: [[f64; 3]; 4],
}

impl Coons {
    /// Checks that the four curves meet at the corners (to 1e-9 of the patch size).
    pub fn new(
        p0: Box<dyn Curve>,
        p1: Box<dyn Curve>,
        q0: Box<dyn Curve>,
        q1: Box<dyn Curve>,
    ) -> Result<Self> {
        let c = [
            at(&*p0, 0.0)?,
            at(&*p0, 1.0)?,
            at(&*p1, 0.0)?,
            at(&*p1, 1.0)?,
        ];
        let other = [
            at(&*q0, 0.0)?,
            at(&*q1, 0.0)?,
            at(&*q0, 1.0)?,
            at(&*q1, 1.0)?,
        ];
        let size = c.iter().chain(&other).map(|p| norm(*p)).fold(1.0, f64::max);
        let names = [
            "P0(0) = Q0(0)",
            "P0(1) = Q1(0)",
            "P1(0) = Q0(1)",
            "P1(1) = Q1(1)",
        ];
        for k in 0..4 {
            if norm(sub(c[k], other[k])) > 1e-9 * size {
                return Err(Error::Parameter {
                    name: "Coons boundary corner",
                    value: format!("{}: {:?} vs {:?}", names[k], c[k], other[k]),
                    expected: "four boundary curves that meet at the corners",
                });
            }
        }
        Ok(Coons { p0, p1, q0, q1, c })
    }
}

impl Surface for Coons {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        ((0.0, 1.0), (0.0, 1.0))
    }
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]> {
        Ok(self.partials(u, v)?[0])
    }
    fn partials(&self, u: f64, v: f64) -> Result<[[f64; 3]; 3]> {
        let (p0, p1) = (at(&*self.p0, u)?, at(&*self.p1, u)?);
        let (q0, q1) = (at(&*self.q0, v)?, at(&*self.q1, v)?);
        let (dp0, dp1) = (at_d(&*self.p0, u)?, at_d(&*self.p1, u)?);
        let (dq0, dq1) = (at_d(&*self.q0, v)?, at_d(&*self.q1, v)?);
        let [c00, c10, c01, c11] = self.c;
        let mut q = [0.0; 3];
        let mut qu = [0.0; 3];
        let mut qv = [0.0; 3];
        for k in 0..3 {
            let bil = (1.0 - u) * (1.0 - v) * c00[k]
                + u * (1.0 - v) * c10[k]
                + (1.0 - u) * v * c01[k]
                + u * v * c11[k];
            q[k] = (1.0 - u) * q0[k] + u * q1[k] + (1.0 - v) * p0[k] + v * p1[k] - bil;
            let bu = -(1.0 - v) * c00[k] + (1.0 - v) * c10[k] - v * c01[k] + v * c11[k];
            qu[k] = q1[k] - q0[k] + (1.0 - v) * dp0[k] + v * dp1[k] - bu;
            let bv = -(1.0 - u) * c00[k] - u * c10[k] + (1.0 - u) * c01[k] + u * c11[k];
            qv[k] = (1.0 - u) * dq0[k] + u * dq1[k] + p1[k] - p0[k] - bv;
        }
        Ok([q, qu, qv])
    }
}

/// Surface of revolution (§5.2.3) of a planar profile `C(v) = (x(v), z(v))` about the z axis:
/// `Q(u, v) = (x(v) cos u, x(v) sin u, z(v))`, `u ∈ [0, angle]`. (For the exact rational form
/// see [`super::TensorPatch::revolve`].)
pub struct Revolution {
    pub profile: Box<dyn Curve>,
    pub angle: f64,
}

impl Surface for Revolution {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        ((0.0, self.angle), (0.0, 1.0))
    }
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]> {
        Ok(self.partials(u, v)?[0])
    }
    fn partials(&self, u: f64, v: f64) -> Result<[[f64; 3]; 3]> {
        let p = at(&*self.profile, v)?;
        let d = at_d(&*self.profile, v)?;
        let (s, c) = u.sin_cos();
        Ok([
            [p[0] * c, p[0] * s, p[1]],
            [-p[0] * s, p[0] * c, 0.0],
            [d[0] * c, d[0] * s, d[1]],
        ])
    }
}

/// Unit normal of the plane of two planar curves: z for 2D input, otherwise Newell's normal of the
/// closed polygon `ql(0..1)` followed by `qr(1..0)`.
pub(crate) fn plane_normal(ql: &dyn Curve, qr: &dyn Curve) -> Result<[f64; 3]> {
    if ql.dim() == 2 && qr.dim() == 2 {
        return Ok([0.0, 0.0, 1.0]);
    }
    let m = 64;
    let mut poly = Vec::with_capacity(2 * m + 2);
    for i in 0..=m {
        poly.push(at(ql, i as f64 / m as f64)?);
    }
    for i in (0..=m).rev() {
        poly.push(at(qr, i as f64 / m as f64)?);
    }
    let mut n = [0.0; 3];
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        n = add(n, cross(a, b));
    }
    normalize(n).ok_or_else(|| {
        Error::parameter(
            "constructive curves",
            "collinear",
            "two curves spanning a plane (or 2D curves)",
        )
    })
}

/// Rotational blending surface (§5.2.4): circles perpendicular to the plane of the two
/// constructive curves, through `q_l(u)` and `q_r(u)` with centre `c(u) = ½(q_l + q_r)`:
/// `S(u, v) = c(u) + cos v (q_l(u) − c(u)) + sin v · ½|q_r(u) − q_l(u)| · z`, `v ∈ [0, 2π]`,
/// so `S(u, 0) = q_l(u)` and `S(u, π) = q_r(u)`. Here `z = −n` with `n` the normal of the sketch
/// plane facing the viewer (+z for 2D strokes): the circle first passes behind the sketch, so that
/// with u running up the strokes and `q_l` on the left the normals `∂S/∂u × ∂S/∂v` point outward.
pub struct RotationalBlend {
    ql: Box<dyn Curve>,
    qr: Box<dyn Curve>,
    z: [f64; 3],
}

impl RotationalBlend {
    pub fn new(ql: Box<dyn Curve>, qr: Box<dyn Curve>) -> Result<Self> {
        let z = scale(plane_normal(&*ql, &*qr)?, -1.0);
        Ok(RotationalBlend { ql, qr, z })
    }
}

impl Surface for RotationalBlend {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        ((0.0, 1.0), (0.0, std::f64::consts::TAU))
    }
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]> {
        let (l, r) = (at(&*self.ql, u)?, at(&*self.qr, u)?);
        let c = scale(add(l, r), 0.5);
        let rad = 0.5 * norm(sub(r, l));
        Ok(add(
            add(c, scale(sub(l, c), v.cos())),
            scale(self.z, rad * v.sin()),
        ))
    }
}

/// Cross-sectional blending surface (§5.2.6): a user-drawn planar section `s(v)` from `s(0)` to
/// `s(1)` replaces the half circle of the rotational blend. In the section's own frame
/// (`e1` along the chord `s(1) − s(0)`, `e2` turned by 90°), `a(v)` and `b(v)` are its coordinates
/// divided by the chord length; then
/// `S(u, v) = q_l(u) + a(v) (q_r(u) − q_l(u)) + b(v) |q_r(u) − q_l(u)| z`.
/// With `mirror`, `v ∈ [1, 2]` runs back from `q_r` to `q_l` on the mirrored section (b → −b),
/// closing the surface. A half circle section gives the rotational blend; as there, `z` is the
/// sketch-plane normal turned away from the viewer (a section bulging up in its drawing bulges
/// behind the sketch plane).
pub struct CrossBlend {
    ql: Box<dyn Curve>,
    qr: Box<dyn Curve>,
    section: Box<dyn Curve>,
    z: [f64; 3],
    s0: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
    len: f64,
    mirror: bool,
}

impl CrossBlend {
    pub fn new(
        ql: Box<dyn Curve>,
        qr: Box<dyn Curve>,
        section: Box<dyn Curve>,
        mirror: bool,
    ) -> Result<Self> {
        if section.dim() != 2 {
            return Err(Error::parameter(
                "section dimension",
                section.dim(),
                "2 (a planar stroke)",
            ));
        }
        let z = scale(plane_normal(&*ql, &*qr)?, -1.0);
        let s0 = at(&*section, 0.0)?;
        let s1 = at(&*section, 1.0)?;
        let chord = sub(s1, s0);
        let len = norm(chord);
        if len == 0.0 {
            return Err(Error::parameter(
                "section",
                "closed",
                "a stroke from one end point to another",
            ));
        }
        let e1 = scale(chord, 1.0 / len);
        let e2 = [-e1[1], e1[0], 0.0];
        Ok(CrossBlend {
            ql,
            qr,
            section,
            z,
            s0,
            e1,
            e2,
            len,
            mirror,
        })
    }
}

impl Surface for CrossBlend {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        ((0.0, 1.0), (0.0, if self.mirror { 2.0 } else { 1.0 }))
    }
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]> {
        let (t, sign) = if v > 1.0 { (2.0 - v, -1.0) } else { (v, 1.0) };
        let s = sub(at(&*self.section, t)?, self.s0);
        let (a, b) = (
            super::dot(s, self.e1) / self.len,
            sign * super::dot(s, self.e2) / self.len,
        );
        let (l, r) = (at(&*self.ql, u)?, at(&*self.qr, u)?);
        let d = sub(r, l);
        Ok(add(add(l, scale(d, a)), scale(self.z, b * norm(d))))
    }
}
