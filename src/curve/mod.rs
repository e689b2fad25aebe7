//! Curves of the course module (notes chapters 1–4 and §7.2–7.6): Bézier, B-spline and NURBS
//! curves, knot insertion, and the eigen-analysis of curve subdivision schemes.
//!
//! Points of any dimension share one evaluator per representation: control points are stored
//! row-major in a flat `Vec<f64>`, `dim` values per point (2D, 3D, or homogeneous `dim + 1` for
//! rational forms). No code is duplicated per dimension.
//!
//! ```text
//! basis.rs    knot vectors, the δ index (§3.9.3), Cox–de Boor basis N_{i,k} (§3.4.1) and its derivatives
//! bezier.rs   Bernstein / de Casteljau (§2.1, Algorithm 2.2), derivatives, split, degree elevation
//! bspline.rs  B-spline curves, de Boor order reduction (§3.9.4, Algorithm 3.3), derivatives
//! nurbs.rs    rational curves through homogeneous coordinates (ch. 4), exact circle and arcs (§4.1)
//! poly.rs     per-span power form (Horner) for evaluating many points fast
//! knot.rs     Boehm insertion and midpoint insertion of all knots = subdivision (§7.2–7.4)
//! plot.rs     SVG / PNG pictures of a curve, its control polygon and knots
//! eigen.rs    eigenvalues of small real matrices (Hessenberg + shifted QR)
//! analysis.rs local subdivision matrix S of a mask and its spectrum (§7.5.1, §7.6.1)
//! csv.rs      control points / nets as CSV text, knot lists
//! geometry.rs tangents, 2D normals (§1.3), curvature, shared by every representation
//! ```

pub mod analysis;
pub mod basis;
pub mod bezier;
pub mod bspline;
pub mod csv;
pub mod eigen;
pub mod geometry;
pub mod knot;
pub mod nurbs;
#[cfg(feature = "geometry")]
pub mod plot;
pub mod poly;

pub use basis::KnotVector;
pub use bezier::Bezier;
pub use bspline::BSpline;
pub use nurbs::Nurbs;

use crate::{Error, Result};

/// A parametric curve of any dimension: what surfaces, plots and the CLI need from
/// Bézier, B-spline and NURBS curves alike.
pub trait Curve {
    /// Number of coordinates of each point.
    fn dim(&self) -> usize;
    /// The valid parameter range `[a, b]`.
    fn domain(&self) -> (f64, f64);
    /// Write the `d`-th derivative at `u` into `out` (`dim` values); `d = 0` is the point.
    fn eval_derivative_into(&self, u: f64, d: usize, out: &mut [f64]) -> Result<()>;

    /// The point at `u`.
    fn point(&self, u: f64) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.dim()];
        self.eval_derivative_into(u, 0, &mut out)?;
        Ok(out)
    }
    /// The `d`-th derivative at `u`.
    fn derivative(&self, u: f64, d: usize) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.dim()];
        self.eval_derivative_into(u, d, &mut out)?;
        Ok(out)
    }
}

/// The `d`-th derivative into `out` (`dim` values) from `derivs`, which writes the
/// derivatives `0..=d` (each `dim` values) into the buffer it is given.
pub(crate) fn nth_derivative(
    dim: usize,
    d: usize,
    out: &mut [f64],
    derivs: impl FnOnce(&mut [f64]) -> Result<()>,
) -> Result<()> {
    check_out(out, dim, "the point dimension")?;
    let mut all = vec![0.0; (d + 1) * dim];
    derivs(&mut all)?;
    out.copy_from_slice(&all[d * dim..]);
    Ok(())
}

/// Check that a flat point list holds whole points and at least `min` of them.
pub(crate) fn check_points(points: &[f64], dim: usize, min: usize) -> Result<usize> {
    if dim == 0 {
        return Err(Error::parameter("dimension", 0, "at least 1"));
    }
    if !points.len().is_multiple_of(dim) {
        return Err(Error::parameter(
            "number of coordinates",
            points.len(),
            "a multiple of the point dimension",
        ));
    }
    if let Some(x) = points.iter().find(|x| !x.is_finite()) {
        return Err(Error::parameter(
            "control point coordinate",
            x,
            "a finite number",
        ));
    }
    let n = points.len() / dim;
    if n < min {
        return Err(Error::parameter(
            "number of control points",
            n,
            "at least the curve order (degree + 1)",
        ));
    }
    Ok(n)
}

/// Check that an output buffer holds `want` values (`what`: how they count, e.g.
/// "the point dimension").
pub(crate) fn check_out(out: &[f64], want: usize, what: &'static str) -> Result<()> {
    if out.len() != want {
        return Err(Error::parameter("output length", out.len(), what));
    }
    Ok(())
}

/// Check that `u` lies in `[a, b]` (a clear [`Error::Parameter`] otherwise).
pub(crate) fn check_range(u: f64, (a, b): (f64, f64)) -> Result<()> {
    if !(u >= a && u <= b) {
        return Err(Error::Parameter {
            name: "parameter u",
            value: format!("{u} (valid range [{a}, {b}])"),
            expected: "u inside the valid range [u_{k-1}, u_{m+1}]",
        });
    }
    Ok(())
}
