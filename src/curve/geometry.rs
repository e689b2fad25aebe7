//! Differential geometry of curves shared by every representation: unit tangent (§1.2), the
//! 2D normal as the tangent turned by 90° (§1.3), and curvature.

use super::Curve;
use crate::{Error, Result};

/// Unit tangent `T(u)/|T(u)|`; an error where the derivative vanishes.
pub fn unit_tangent(c: &dyn Curve, u: f64) -> Result<Vec<f64>> {
    let t = c.derivative(u, 1)?;
    let len = norm(&t);
    if len == 0.0 {
        return Err(Error::parameter(
            "parameter u",
            u,
            "a regular point (non-zero derivative)",
        ));
    }
    Ok(t.iter().map(|x| x / len).collect())
}

/// The 2D normal `N(u) = (−y'(u), x'(u))` of §1.3 (not normalised), for planar curves.
pub fn normal_2d(c: &dyn Curve, u: f64) -> Result<[f64; 2]> {
    if c.dim() != 2 {
        return Err(Error::parameter(
            "dimension",
            c.dim(),
            "2 for a planar normal",
        ));
    }
    let t = c.derivative(u, 1)?;
    Ok([-t[1], t[0]])
}

/// Curvature `κ = |Q' × Q''| / |Q'|³` in any dimension (via `|a×b|² = |a|²|b|² − (a·b)²`);
/// signed `(x'y'' − y'x'')/|Q'|³` for planar curves.
pub fn curvature(c: &dyn Curve, u: f64) -> Result<f64> {
    let d1 = c.derivative(u, 1)?;
    let d2 = c.derivative(u, 2)?;
    let l = norm(&d1);
    if l == 0.0 {
        return Err(Error::parameter(
            "parameter u",
            u,
            "a regular point (non-zero derivative)",
        ));
    }
    if c.dim() == 2 {
        return Ok((d1[0] * d2[1] - d1[1] * d2[0]) / (l * l * l));
    }
    let a2 = dot(&d1, &d1);
    let b2 = dot(&d2, &d2);
    let ab = dot(&d1, &d2);
    Ok((a2 * b2 - ab * ab).max(0.0).sqrt() / (l * l * l))
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(crate) fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}
