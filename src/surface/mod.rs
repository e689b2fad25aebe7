//! Surfaces of the course module (notes ch. 5), each tessellated to a triangle or quad mesh with
//! vertex normals `N = ∂Q/∂u × ∂Q/∂v` (§5.1.1).
//!
//! ```text
//! patch.rs    tensor-product Bézier / B-spline / NURBS patches; exact NURBS sphere, torus, cylinder
//! common.rs   curve-based surfaces (§5.2): loft, Coons, revolution, rotational and cross-sectional blends
//! sweep.rs    sweep surfaces with a rotation-minimising (parallel transport) frame (§5.2.5, Alg. 5.2)
//! tessellate.rs  sampling a surface on a grid into a `crate::mesh::Mesh` with analytic normals
//! raster.rs   tiny RGB canvas (anti-aliased lines and discs) for curve pictures
//! ```
//!
//! Mesh files and pictures go through `crate::mesh`: `mesh::io::{read, write}` (OBJ / PLY /
//! OFF) and `mesh::render`.

pub mod common;
pub mod patch;
pub mod raster;
pub mod sweep;
pub mod tessellate;

pub use common::{Coons, CrossBlend, Loft, Revolution, RotationalBlend};
pub use patch::TensorPatch;
pub use sweep::Sweep;
pub use tessellate::{tessellate, FaceKind};

use crate::Result;

/// A parametric surface `Q(u, v)` in 3D.
pub trait Surface {
    /// Parameter ranges `([u0, u1], [v0, v1])`.
    fn ranges(&self) -> ((f64, f64), (f64, f64));
    /// The point `Q(u, v)`.
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]>;
    /// `[Q, ∂Q/∂u, ∂Q/∂v]`. The default uses central differences (one-sided at the ends of the
    /// ranges) with a step of 1e-6 of the range; exact forms override it.
    fn partials(&self, u: f64, v: f64) -> Result<[[f64; 3]; 3]> {
        let ((u0, u1), (v0, v1)) = self.ranges();
        let q = self.point(u, v)?;
        let diff =
            |a: f64, b: f64, x: f64, f: &dyn Fn(f64) -> Result<[f64; 3]>| -> Result<[f64; 3]> {
                let h = 1e-6 * (b - a);
                let (lo, hi) = ((x - h).max(a), (x + h).min(b));
                let (p, m) = (f(hi)?, f(lo)?);
                Ok([
                    (p[0] - m[0]) / (hi - lo),
                    (p[1] - m[1]) / (hi - lo),
                    (p[2] - m[2]) / (hi - lo),
                ])
            };
        let qu = diff(u0, u1, u, &|x| self.point(x, v))?;
        let qv = diff(v0, v1, v, &|y| self.point(u, y))?;
        Ok([q, qu, qv])
    }
}

pub(crate) use crate::mesh::vec3::{add, cross, dot, norm, scale, sub};

/// `a / |a|`, or `None` for a zero or non-finite length.
pub(crate) fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let l = norm(a);
    if l > 0.0 && l.is_finite() {
        Some(scale(a, 1.0 / l))
    } else {
        None
    }
}
