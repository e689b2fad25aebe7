//! Sweep surfaces (notes §5.2.5): a planar profile `c(v) = (c_x, c_y)` carried along a 3D
//! trajectory `t(u)` in a moving frame `(T, N, B)`:
//! `Q(u, v) = t(u) + c_x(v) N(u) + c_y(v) B(u)`.
//!
//! The frame is the rotation-minimising (parallel transport) frame of Algorithm 5.2: along
//! samples of the unit tangent, `N_{i+1} = R(T_i × T_{i+1}, θ_i) N_i` with `θ_i` the angle between
//! `T_i` and `T_{i+1}` — the smallest rotation taking one tangent to the next, so N never flips
//! at inflection points where the Frenet frame (eqs. 6–8) is undefined or turns over.
//! `B = T × N` as in the notes; the normals `∂Q/∂u × ∂Q/∂v` point away from the path when the
//! profile runs clockwise in its (x = N, y = B) plane.

use super::common::{at, at_d};
use super::patch::to3;
use super::{add, cross, dot, norm, normalize, scale, sub, Surface};
use crate::curve::Curve;
use crate::{Error, Result};

/// Rodrigues: rotate `x` about the unit `axis` by the angle with cosine `c` and sine `s`.
fn rotate(x: [f64; 3], axis: [f64; 3], c: f64, s: f64) -> [f64; 3] {
    add(
        add(scale(x, c), scale(cross(axis, x), s)),
        scale(axis, dot(axis, x) * (1.0 - c)),
    )
}

/// Transport `n` (⊥ `ta`) to the tangent `tb` by the minimal rotation taking `ta` to `tb`, then
/// re-orthogonalise against `tb` (Gram–Schmidt) so round-off cannot accumulate.
pub fn transport(n: [f64; 3], ta: [f64; 3], tb: [f64; 3]) -> [f64; 3] {
    let b = cross(ta, tb);
    let s = norm(b);
    let out = if s > 1e-15 {
        rotate(n, scale(b, 1.0 / s), dot(ta, tb), s)
    } else {
        n // ‖B‖ = 0: N_{i+1} = N_i (Algorithm 5.2, line 4)
    };
    normalize(sub(out, scale(tb, dot(out, tb)))).unwrap_or(n)
}

/// A sweep surface with a precomputed rotation-minimising frame.
pub struct Sweep {
    profile: Box<dyn Curve>,
    path: Box<dyn Curve>,
    /// Unit tangents and normals at `samples + 1` evenly spaced `u`.
    tangents: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
}

impl Sweep {
    /// `samples` frame samples along the trajectory (≥ 1; 1024 is plenty for tessellation).
    /// `up`, when given, fixes the initial normal `N_0` (projected to ⊥ T_0); otherwise the
    /// coordinate axis least aligned with `T_0` is used.
    pub fn new(
        profile: Box<dyn Curve>,
        path: Box<dyn Curve>,
        samples: usize,
        up: Option<[f64; 3]>,
    ) -> Result<Self> {
        if profile.dim() != 2 {
            return Err(Error::parameter(
                "profile dimension",
                profile.dim(),
                "2 (a planar section)",
            ));
        }
        let samples = samples.max(1);
        let mut tangents = Vec::with_capacity(samples + 1);
        for i in 0..=samples {
            let t = i as f64 / samples as f64;
            tangents.push(unit_tangent(&*path, t)?);
        }
        let t0 = tangents[0];
        let seed = match up {
            Some(v) => v,
            None => {
                let ax = (0..3)
                    .min_by(|&a, &b| t0[a].abs().partial_cmp(&t0[b].abs()).unwrap())
                    .unwrap();
                let mut e = [0.0; 3];
                e[ax] = 1.0;
                e
            }
        };
        let n0 = normalize(sub(seed, scale(t0, dot(seed, t0)))).ok_or_else(|| {
            Error::parameter(
                "up vector",
                format!("{seed:?}"),
                "a vector not parallel to the start tangent",
            )
        })?;
        let mut normals = Vec::with_capacity(samples + 1);
        normals.push(n0);
        for i in 0..samples {
            let n = transport(normals[i], tangents[i], tangents[i + 1]);
            normals.push(n);
        }
        Ok(Sweep {
            profile,
            path,
            tangents,
            normals,
        })
    }

    /// The frame `(T, N, B)` at `u ∈ [0, 1]`: the nearest sample's normal transported to `T(u)`.
    pub fn frame(&self, u: f64) -> Result<[[f64; 3]; 3]> {
        let m = self.tangents.len() - 1;
        let i = ((u.clamp(0.0, 1.0) * m as f64).round() as usize).min(m);
        let t = unit_tangent(&*self.path, u)?;
        let n = transport(self.normals[i], self.tangents[i], t);
        Ok([t, n, cross(t, n)])
    }

    /// The sampled normals (for tests and plots).
    pub fn sampled_frames(&self) -> Vec<[[f64; 3]; 3]> {
        self.tangents
            .iter()
            .zip(&self.normals)
            .map(|(&t, &n)| [t, n, cross(t, n)])
            .collect()
    }
}

fn unit_tangent(path: &dyn Curve, t: f64) -> Result<[f64; 3]> {
    let d = at_d(path, t)?;
    normalize(d).ok_or_else(|| {
        Error::parameter(
            "trajectory",
            format!("zero tangent at {t}"),
            "a regular curve",
        )
    })
}

impl Surface for Sweep {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        ((0.0, 1.0), (0.0, 1.0))
    }
    fn point(&self, u: f64, v: f64) -> Result<[f64; 3]> {
        let [_, n, b] = self.frame(u)?;
        let c = to3(&self.profile.point(profile_param(&*self.profile, v))?)?;
        Ok(add(
            add(at(&*self.path, u)?, scale(n, c[0])),
            scale(b, c[1]),
        ))
    }
}

fn profile_param(c: &dyn Curve, v: f64) -> f64 {
    let (a, b) = c.domain();
    if v >= 1.0 {
        b
    } else {
        a + (b - a) * v
    }
}
