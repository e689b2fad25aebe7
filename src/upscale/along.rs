//! Smoothing along edges: the last step of the refined area mode for images, which
//! removes the staircase a ×F upscale leaves along slanted edges.
//!
//! **Why.** The input's samples along a slanted edge alias: the cells the edge crosses
//! take values that repeat with the grid, not with the edge. The area spline (which
//! undoes the cells' box average, so it boosts what lies near the input's Nyquist
//! frequency) and the clamp to the nearest cells' range turn that aliasing into notches
//! with the input's period (F output pixels) along the edge. A reconstruction that only
//! depends on the distance to the edge has none.
//!
//! **What.** With `J = G_ρ * (∇s ∇sᵀ)` the structure tensor of the input `s` (central
//! differences, summed over channels, Gaussian `ρ` = [`RHO`] cells), interpolated
//! bilinearly at each output pixel's position in input cells, `λ₁ ≥ λ₂` its eigenvalues
//! and `τ` the eigenvector of `λ₂` (the edge's direction), one round is
//! ```text
//! a(p) = Σ_k w_k u(p + k τ) / Σ_k w_k,   w_k = exp(−k² / 2σ²),  |k| ≤ ⌈2σ⌉, σ = SIGMA · F
//! v(p) = u(p) + c(p) (a(p) − u(p)),       c = (λ₁ − λ₂) / (λ₁ + λ₂)   (coherence)
//! u ← v + U (s − D v)                     (back-projection: the cell means are kept)
//! ```
//! (`u(q)` bilinear between output pixels; near the border only the pairs `±k` whose
//! both points lie inside the image, so a linear function is kept exactly; `U` the
//! plain area upscale ×F, `D` the F×F block mean, `D U = I`.) Across an edge nothing
//! moves; along it the notches average out; in texture without one direction `c ≈ 0`.
//! [`ROUNDS`] rounds; the last leaves `D u = s` exactly. Measured in `docs/upscale.md`.

use super::cells::{area, block_mean};
use super::{AxisPlan, Geometry, Method, Prepared};
use crate::progress::Progress;
use crate::Result;
use rayon::prelude::*;

/// Smooth-then-project rounds (1: the back-projection brings back part of the notches).
pub const ROUNDS: usize = 2;

/// The tangential Gaussian's σ in input cells (σ·F output pixels).
pub const SIGMA: f32 = 0.5;

/// The structure tensor's Gaussian ρ in input cells.
pub const RHO: f32 = 1.0;

/// Most channels of an image (a longer last axis is a volume's axis, not channels).
const MAX_CHANNELS: usize = 4;

/// The factor `F` when the smoothing applies: an image (`h × w`, or `h × w × c` with
/// `c ≤ 4` channels) of at least 2 × 2 upscaled by the same integer `F ≥ 2` along
/// both axes.
pub(crate) fn applies(shape: &[usize], f: &[(usize, usize)]) -> Option<usize> {
    let image = shape.len() == 2 || (shape.len() == 3 && shape[2] <= MAX_CHANNELS);
    if !image || shape[0] < 2 || shape[1] < 2 || f.len() != 2 {
        return None;
    }
    let g = |a: usize| f.iter().find(|&&(b, _)| a == b).map(|&(_, g)| g);
    match (g(0), g(1)) {
        (Some(a), Some(b)) if a == b && a >= 2 => Some(a),
        _ => None,
    }
}

/// Per output pixel: the coherence `c` and the edge direction `τ = (τ_y, τ_x)`.
struct Field {
    c: Vec<f32>,
    ty: Vec<f32>,
    tx: Vec<f32>,
}

/// Normalised Gaussian taps `exp(−k²/2σ²)`, `k = −r..=r`.
fn gaussian(sigma: f32, r: usize) -> Vec<f32> {
    let w: Vec<f32> = (-(r as isize)..=r as isize)
        .map(|k| (-(k * k) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = w.iter().sum();
    w.into_iter().map(|x| x / sum).collect()
}

/// `G_ρ * a` along both axes of an `h × w` array, indices clamped at the ends.
fn blur(a: &[f32], h: usize, w: usize, rho: f32) -> Vec<f32> {
    let r = (3.0 * rho).ceil() as usize;
    let g = gaussian(rho, r);
    let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
    let mut t = vec![0f32; h * w];
    t.par_chunks_mut(w).enumerate().for_each(|(i, row)| {
        for (j, d) in row.iter_mut().enumerate() {
            *d = g
                .iter()
                .enumerate()
                .map(|(k, &gk)| gk * a[i * w + clamp(j as isize + k as isize - r as isize, w)])
                .sum();
        }
    });
    let mut out = vec![0f32; h * w];
    out.par_chunks_mut(w).enumerate().for_each(|(i, row)| {
        for (j, d) in row.iter_mut().enumerate() {
            *d = g
                .iter()
                .enumerate()
                .map(|(k, &gk)| gk * t[clamp(i as isize + k as isize - r as isize, h) * w + j])
                .sum();
        }
    });
    out
}

/// The structure tensor `(J_xx, J_xy, J_yy)` of `s` (`h × w × c`): central differences
/// (one-sided at the ends), products summed over channels, then [`blur`] by `ρ`.
fn structure(s: &[f32], h: usize, w: usize, c: usize) -> [Vec<f32>; 3] {
    let at = |i: usize, j: usize, k: usize| s[(i * w + j) * c + k];
    let diff = |lo: usize, hi: usize| if hi - lo == 2 { 0.5 } else { 1.0 };
    let mut xx = vec![0f32; h * w];
    let mut xy = vec![0f32; h * w];
    let mut yy = vec![0f32; h * w];
    for i in 0..h {
        let (u, d) = (i.saturating_sub(1), (i + 1).min(h - 1));
        for j in 0..w {
            let (l, r) = (j.saturating_sub(1), (j + 1).min(w - 1));
            let (mut a, mut b, mut e) = (0f32, 0f32, 0f32);
            for k in 0..c {
                let gx = (at(i, r, k) - at(i, l, k)) * diff(l, r);
                let gy = (at(d, j, k) - at(u, j, k)) * diff(u, d);
                a += gx * gx;
                b += gx * gy;
                e += gy * gy;
            }
            (xx[i * w + j], xy[i * w + j], yy[i * w + j]) = (a, b, e);
        }
    }
    [xx, xy, yy].map(|v| blur(&v, h, w, RHO))
}

/// The coherence and edge direction at every output pixel of an `F`× upscale of `s`.
fn field(s: &[f32], coarse: &[usize], g: usize) -> Field {
    let (h, w) = (coarse[0], coarse[1]);
    let c = coarse.get(2).copied().unwrap_or(1);
    let [jxx, jxy, jyy] = structure(s, h, w, c);
    let (fh, fw) = (h * g, w * g);
    // bilinear weights from output pixel `q` to input cells (positions clamped)
    let axis = |q: usize, n: usize| {
        let x = ((q as f32 + 0.5) / g as f32 - 0.5).clamp(0.0, (n - 1) as f32);
        let i = (x.floor() as usize).min(n - 1);
        (i, (i + 1).min(n - 1), x - i as f32)
    };
    let mut out = Field {
        c: vec![0f32; fh * fw],
        ty: vec![0f32; fh * fw],
        tx: vec![0f32; fh * fw],
    };
    out.c
        .par_chunks_mut(fw)
        .zip(out.ty.par_chunks_mut(fw))
        .zip(out.tx.par_chunks_mut(fw))
        .enumerate()
        .for_each(|(y, ((cr, tyr), txr))| {
            let (i0, i1, fy) = axis(y, h);
            for x in 0..fw {
                let (j0, j1, fx) = axis(x, w);
                let lerp = |a: &[f32]| {
                    let top = a[i0 * w + j0] + fx * (a[i0 * w + j1] - a[i0 * w + j0]);
                    let bot = a[i1 * w + j0] + fx * (a[i1 * w + j1] - a[i1 * w + j0]);
                    top + fy * (bot - top)
                };
                let (a, b, e) = (lerp(&jxx), lerp(&jxy), lerp(&jyy));
                let tr = a + e;
                let det = ((a - e) * (a - e) + 4.0 * b * b).sqrt();
                if tr <= 0.0 || !det.is_finite() {
                    continue;
                }
                cr[x] = (det / tr).min(1.0);
                // the gradient's angle φ: tan 2φ = 2 J_xy / (J_xx − J_yy); τ ⟂ (cos φ, sin φ)
                let phi = 0.5 * (2.0 * b).atan2(a - e);
                let (sin, cos) = phi.sin_cos();
                (txr[x], tyr[x]) = (-sin, cos);
            }
        });
    out
}

/// One smoothing pass ([`ROUNDS`] of them run): `v = u + c (a − u)`, `u` of `fh × fw × ch`.
fn smooth(u: &[f32], fh: usize, fw: usize, ch: usize, f: &Field, taps: &[f32]) -> Vec<f32> {
    let r = (taps.len() / 2) as isize;
    let mut v = u.to_vec();
    let (ymax, xmax) = ((fh - 1) as f32, (fw - 1) as f32);
    v.par_chunks_mut(fw * ch).enumerate().for_each(|(y, row)| {
        let mut acc = [0f32; MAX_CHANNELS];
        for x in 0..fw {
            let p = y * fw + x;
            let c = f.c[p];
            if c < 1e-4 {
                continue;
            }
            // tap pairs ±k while both lie inside the image (symmetric: lines stay lines)
            let (ty, tx) = (f.ty[p], f.tx[p]);
            let inside = |d: f32| {
                let (qy, qx) = (y as f32 + d * ty, x as f32 + d * tx);
                (0.0..=ymax).contains(&qy) && (0.0..=xmax).contains(&qx)
            };
            let reach = (1..=r)
                .find(|&k| !inside(k as f32) || !inside(-k as f32))
                .map_or(r, |k| k - 1);
            acc[..ch].fill(0.0);
            let mut total = 0f32;
            for (k, &wk) in taps.iter().enumerate() {
                if (k as isize - r).abs() > reach {
                    continue;
                }
                total += wk;
                let d = (k as isize - r) as f32;
                let qy = (y as f32 + d * f.ty[p]).clamp(0.0, ymax);
                let qx = (x as f32 + d * f.tx[p]).clamp(0.0, xmax);
                let (y0, x0) = (qy.floor() as usize, qx.floor() as usize);
                let (y1, x1) = ((y0 + 1).min(fh - 1), (x0 + 1).min(fw - 1));
                let (ay, ax) = (qy - y0 as f32, qx - x0 as f32);
                let (w00, w01) = ((1.0 - ay) * (1.0 - ax), (1.0 - ay) * ax);
                let (w10, w11) = (ay * (1.0 - ax), ay * ax);
                let (o00, o01) = ((y0 * fw + x0) * ch, (y0 * fw + x1) * ch);
                let (o10, o11) = ((y1 * fw + x0) * ch, (y1 * fw + x1) * ch);
                for (m, a) in acc[..ch].iter_mut().enumerate() {
                    *a += wk
                        * (w00 * u[o00 + m]
                            + w01 * u[o01 + m]
                            + w10 * u[o10 + m]
                            + w11 * u[o11 + m]);
                }
            }
            for (m, a) in acc[..ch].iter().enumerate() {
                let o = &mut row[x * ch + m];
                *o += c * (a / total - *o);
            }
        }
    });
    v
}

/// [`ROUNDS`] rounds of edge smoothing and back-projection of the `F`× upscale `u`
/// (shape `fine`) of `s` (shape `coarse`, see [`applies`]).
pub(crate) fn refine(
    mut u: Vec<f32>,
    fine: &[usize],
    s: &[f32],
    coarse: &[usize],
    method: &Method,
    g: usize,
) -> Result<Vec<f32>> {
    let (fh, fw) = (fine[0], fine[1]);
    let ch = fine.get(2).copied().unwrap_or(1);
    let f = [(0usize, g), (1usize, g)];
    let plans: Vec<AxisPlan> = f
        .iter()
        .map(|&(axis, g)| AxisPlan {
            axis,
            len: coarse[axis] * g,
            geometry: Geometry::Centre,
        })
        .collect();
    let up = Prepared::new(&area(method), coarse, &plans)?;
    let field = field(s, coarse, g);
    let sigma = SIGMA * g as f32;
    let taps = gaussian(sigma, (2.0 * sigma).ceil() as usize);
    let hidden = Progress::hidden();
    for _ in 0..ROUNDS {
        let mut v = smooth(&u, fh, fw, ch, &field, &taps);
        let (d, _) = block_mean(&v, fine, &f);
        let r: Vec<f32> = s.iter().zip(&d).map(|(s, d)| s - d).collect();
        up.run_put(r, &hidden, &mut v, |d, x| *d += x);
        u = v;
    }
    Ok(u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn applies_to_images_with_equal_factors_only() {
        assert_eq!(applies(&[8, 9], &[(0, 4), (1, 4)]), Some(4));
        assert_eq!(applies(&[8, 9, 3], &[(1, 2), (0, 2)]), Some(2));
        assert_eq!(applies(&[8, 9, 3], &[(0, 4), (1, 2)]), None);
        assert_eq!(applies(&[8, 9, 30], &[(0, 2), (1, 2)]), None);
        assert_eq!(applies(&[8, 9, 3], &[(0, 2), (1, 2), (2, 2)]), None);
        assert_eq!(applies(&[1, 9], &[(0, 2), (1, 2)]), None);
        assert_eq!(applies(&[8, 9], &[(1, 2)]), None);
    }

    #[test]
    fn the_edge_direction_is_along_a_straight_edge() {
        // an edge whose normal is (cos 30°, sin 30°) in (x, y)
        let (h, w) = (16, 16);
        let (nx, ny) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
        let s: Vec<f32> = (0..h * w)
            .map(|p| {
                let (y, x) = ((p / w) as f32 - 7.5, (p % w) as f32 - 7.5);
                (2.0 * (x * nx + y * ny)).tanh() * 100.0
            })
            .collect();
        let f = field(&s, &[h, w], 4);
        let p = (32 * 64) + 32;
        assert!(f.c[p] > 0.9, "coherence {}", f.c[p]);
        let dot = f.tx[p] * nx + f.ty[p] * ny;
        // within 6° (measured 3.7°: central differences bias the direction of an edge
        // this sharp, 2 cells wide)
        assert!(dot.abs() < 0.1, "τ·n = {dot}");
    }
}
