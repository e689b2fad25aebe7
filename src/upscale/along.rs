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
//! [`ROUNDS`] rounds ([`ROUNDS_X2`] at ×2); the last leaves `D u = s` exactly.
//!
//! **How.** `τ` is rounded to the nearest of [`BUCKETS`] directions, and each
//! direction's `2r + 1` bilinear taps are merged once into a stencil of whole-pixel
//! offsets and weights (entries below [`MIN_WEIGHT`] dropped, the rest rescaled to sum
//! 1), applied without index clamps `r + 1` pixels or more from the border; nearer the
//! border the taps are summed pairwise as above. A pass runs over input rows in parallel
//! and also writes its row's residual `s − D v`; every value depends only on the previous
//! round, so the bits do not depend on the thread count. Measured in `docs/upscale.md`.

use super::cells::area;
use super::{AxisPlan, Geometry, Method, Prepared};
use crate::progress::Progress;
use crate::Result;
use rayon::prelude::*;

/// Smooth-then-project rounds at ×4 and above (1: the back-projection brings back part
/// of the notches); [`ROUNDS_X2`] at ×2.
pub const ROUNDS: usize = 2;

/// Smooth-then-project rounds at ×2 (a second round adds little there, see `docs/upscale.md`).
pub const ROUNDS_X2: usize = 1;

/// The rounds at factor `g`.
fn rounds(g: usize) -> usize {
    if g == 2 {
        ROUNDS_X2
    } else {
        ROUNDS
    }
}

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

/// Directions the edge's direction `τ` is quantised to, evenly over `[0, π)`: bucket `k`
/// is `τ_k = (τ_y, τ_x) = (sin(kπ/B), cos(kπ/B))`, `B` = [`BUCKETS`].
pub const BUCKETS: usize = 32;

/// Pixels whose coherence is below this are left as they are (the change `c (a − u)`
/// is negligible there).
pub const MIN_COHERENCE: f32 = 1e-4;

/// A direction's stencil drops the pixels whose weight is below this (about a quarter
/// of its pixels, 1–4 % of its weight) and rescales the rest to sum 1.
pub const MIN_WEIGHT: f32 = 0.01;

/// Per output pixel: the coherence `c` (0: left as it is) and the bucket of the edge
/// direction `τ`.
struct Field {
    c: Vec<f32>,
    bucket: Vec<u8>,
}

/// Normalised Gaussian taps `exp(−k²/2σ²)`, `k = −r..=r`.
fn gaussian(sigma: f32, r: usize) -> Vec<f32> {
    let w: Vec<f32> = (-(r as isize)..=r as isize)
        .map(|k| (-(k * k) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = w.iter().sum();
    w.into_iter().map(|x| x / sum).collect()
}

/// `G_ρ * a` along both axes of an `h × w` array, indices clamped at the ends (the
/// clamp once per row: a padded copy of the row, and the source rows of each output row).
fn blur(a: &[f32], h: usize, w: usize, rho: f32) -> Vec<f32> {
    let r = (3.0 * rho).ceil() as usize;
    let g = gaussian(rho, r);
    let mut t = vec![0f32; h * w];
    t.par_chunks_mut(w).zip(a.par_chunks(w)).for_each_init(
        || vec![0f32; w + 2 * r],
        |pad, (row, src)| {
            pad[..r].fill(src[0]);
            pad[r..r + w].copy_from_slice(src);
            pad[r + w..].fill(src[w - 1]);
            for (j, d) in row.iter_mut().enumerate() {
                *d = g
                    .iter()
                    .zip(&pad[j..j + 2 * r + 1])
                    .map(|(g, a)| g * a)
                    .sum();
            }
        },
    );
    let mut out = vec![0f32; h * w];
    out.par_chunks_mut(w).enumerate().for_each(|(i, row)| {
        for (k, &gk) in g.iter().enumerate() {
            let src = (i + k).saturating_sub(r).min(h - 1);
            for (d, &x) in row.iter_mut().zip(&t[src * w..(src + 1) * w]) {
                *d += gk * x;
            }
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

/// `atan2(y, x)` within 1e-5 rad (a minimax polynomial of `atan` on `[0, 1]`).
fn atan2(y: f32, x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    if hi == 0.0 {
        return 0.0;
    }
    let t = lo / hi;
    let t2 = t * t;
    let mut a = t
        * (0.999_977_23
            + t2 * (-0.332_623_48
                + t2 * (0.193_543_46
                    + t2 * (-0.116_432_87 + t2 * (0.052_653_32 - 0.011_721_2 * t2)))));
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if y < 0.0 {
        -a
    } else {
        a
    }
}

/// The bucket of the edge direction of the tensor `(J_xx, J_xy, J_yy) = (a, b, e)`: the
/// gradient's angle is `φ = ½ atan2(2b, a − e)`, `τ ⟂ (cos φ, sin φ)` is at `φ + π/2`,
/// so bucket `round((2φ + π) B / 2π) mod B`.
fn bucket(a: f32, b: f32, e: f32) -> u8 {
    let t = atan2(2.0 * b, a - e) + std::f32::consts::PI;
    // t ≥ 0, so `+ 0.5` then truncation rounds
    ((t * (BUCKETS as f32 / std::f32::consts::TAU) + 0.5) as usize % BUCKETS) as u8
}

/// The direction `(τ_y, τ_x)` of bucket `k`.
fn direction(k: usize) -> (f32, f32) {
    (k as f32 * std::f32::consts::PI / BUCKETS as f32).sin_cos()
}

/// The coherence and edge-direction bucket at every output pixel of an `F`× upscale of
/// `s`: the tensor interpolated bilinearly at the pixel's position in input cells
/// (positions clamped), `c = (λ₁ − λ₂)/(λ₁ + λ₂) = √((a − e)² + 4b²)/(a + e)`.
fn field(s: &[f32], coarse: &[usize], g: usize) -> Field {
    let (h, w) = (coarse[0], coarse[1]);
    let c = coarse.get(2).copied().unwrap_or(1);
    let [jxx, jxy, jyy] = structure(s, h, w, c);
    let (fh, fw) = (h * g, w * g);
    let axis = |q: usize, n: usize| {
        let x = ((q as f32 + 0.5) / g as f32 - 0.5).clamp(0.0, (n - 1) as f32);
        let i = (x.floor() as usize).min(n - 1);
        (i, (i + 1).min(n - 1), x - i as f32)
    };
    let cols: Vec<(usize, usize, f32)> = (0..fw).map(|x| axis(x, w)).collect();
    let mut out = Field {
        c: vec![0f32; fh * fw],
        bucket: vec![0u8; fh * fw],
    };
    out.c
        .par_chunks_mut(fw)
        .zip(out.bucket.par_chunks_mut(fw))
        .enumerate()
        .for_each_init(
            || vec![[0f32; 3]; w],
            |rowt, (y, (cr, br))| {
                // the tensor along the output row's position between input rows i0, i1
                let (i0, i1, fy) = axis(y, h);
                for (j, t) in rowt.iter_mut().enumerate() {
                    let lerp = |a: &[f32]| a[i0 * w + j] + fy * (a[i1 * w + j] - a[i0 * w + j]);
                    *t = [lerp(&jxx), lerp(&jxy), lerp(&jyy)];
                }
                for ((cx, bx), &(j0, j1, fx)) in cr.iter_mut().zip(br.iter_mut()).zip(&cols) {
                    let (t0, t1) = (rowt[j0], rowt[j1]);
                    let [a, b, e] = [0, 1, 2].map(|m| t0[m] + fx * (t1[m] - t0[m]));
                    let tr = a + e;
                    let det = ((a - e) * (a - e) + 4.0 * b * b).sqrt();
                    if tr <= 0.0 || !det.is_finite() {
                        continue;
                    }
                    let coh = (det / tr).min(1.0);
                    if coh >= MIN_COHERENCE {
                        *cx = coh;
                        *bx = bucket(a, b, e);
                    }
                }
            },
        );
    out
}

/// The averaging along each bucket's direction: `a(p) = Σ_k w_k u(p + k τ)` with
/// `u(q)` bilinear, written as weights on whole-pixel offsets.
struct Stencils {
    /// Gaussian taps `w_k`, `k = −r..=r`.
    taps: Vec<f32>,
    /// Per bucket: `(offset into the fine array, weight)`, offset `(dy·fw + dx)·ch`.
    lin: Vec<Vec<(isize, f32)>>,
    /// Pixels at least this far from every border use `lin` (all taps inside, no clamp).
    margin: usize,
}

impl Stencils {
    fn new(taps: Vec<f32>, fw: usize, ch: usize, min_weight: f32) -> Stencils {
        let r = (taps.len() / 2) as isize;
        let lin = (0..BUCKETS)
            .map(|b| {
                let (ty, tx) = direction(b);
                let mut acc: Vec<((isize, isize), f32)> = Vec::new();
                for (k, &wk) in taps.iter().enumerate() {
                    let d = (k as isize - r) as f32;
                    let (qy, qx) = (d * ty, d * tx);
                    let (y0, x0) = (qy.floor(), qx.floor());
                    let (ay, ax) = (qy - y0, qx - x0);
                    for (dy, dx, wt) in [
                        (0, 0, (1.0 - ay) * (1.0 - ax)),
                        (0, 1, (1.0 - ay) * ax),
                        (1, 0, ay * (1.0 - ax)),
                        (1, 1, ay * ax),
                    ] {
                        if wt == 0.0 {
                            continue;
                        }
                        let at = (y0 as isize + dy, x0 as isize + dx);
                        match acc.iter_mut().find(|(o, _)| *o == at) {
                            Some((_, w)) => *w += wk * wt,
                            None => acc.push((at, wk * wt)),
                        }
                    }
                }
                // drop the corners of least weight, keep the sum 1
                acc.retain(|&(_, w)| w >= min_weight);
                let total: f32 = acc.iter().map(|&(_, w)| w).sum();
                for (_, w) in acc.iter_mut() {
                    *w /= total;
                }
                acc.sort_by_key(|&(o, _)| o);
                acc.into_iter()
                    .map(|((dy, dx), w)| ((dy * fw as isize + dx) * ch as isize, w))
                    .collect()
            })
            .collect();
        Stencils {
            taps,
            lin,
            margin: r as usize + 1,
        }
    }
}

/// `a(p)` at a pixel near the border: only the pairs `±k` whose both points lie inside
/// the image (symmetric: lines stay lines), bilinear with clamped indices.
fn border<const CH: usize>(
    u: &[f32],
    (fh, fw): (usize, usize),
    (y, x): (usize, usize),
    (ty, tx): (f32, f32),
    taps: &[f32],
) -> [f32; CH] {
    let r = (taps.len() / 2) as isize;
    let (ymax, xmax) = ((fh - 1) as f32, (fw - 1) as f32);
    let inside = |d: f32| {
        let (qy, qx) = (y as f32 + d * ty, x as f32 + d * tx);
        (0.0..=ymax).contains(&qy) && (0.0..=xmax).contains(&qx)
    };
    let reach = (1..=r)
        .find(|&k| !inside(k as f32) || !inside(-k as f32))
        .map_or(r, |k| k - 1);
    let mut acc = [0f32; CH];
    let mut total = 0f32;
    for (k, &wk) in taps.iter().enumerate() {
        if (k as isize - r).abs() > reach {
            continue;
        }
        total += wk;
        let d = (k as isize - r) as f32;
        let qy = (y as f32 + d * ty).clamp(0.0, ymax);
        let qx = (x as f32 + d * tx).clamp(0.0, xmax);
        let (y0, x0) = (qy.floor() as usize, qx.floor() as usize);
        let (y1, x1) = ((y0 + 1).min(fh - 1), (x0 + 1).min(fw - 1));
        let (ay, ax) = (qy - y0 as f32, qx - x0 as f32);
        let (w00, w01) = ((1.0 - ay) * (1.0 - ax), (1.0 - ay) * ax);
        let (w10, w11) = (ay * (1.0 - ax), ay * ax);
        let (o00, o01) = ((y0 * fw + x0) * CH, (y0 * fw + x1) * CH);
        let (o10, o11) = ((y1 * fw + x0) * CH, (y1 * fw + x1) * CH);
        for (m, a) in acc.iter_mut().enumerate() {
            *a += wk * (w00 * u[o00 + m] + w01 * u[o01 + m] + w10 * u[o10 + m] + w11 * u[o11 + m]);
        }
    }
    acc.map(|a| a / total)
}

/// One smoothing pass over the `g` output rows of input row `i`, written to `band`:
/// `v = u + c (a − u)` (`u` of `fh × fw × CH`), then the residual of the band's cells
/// `r = s − D v` (`s_row`, `r_row`: input row `i`).
#[allow(clippy::too_many_arguments)]
fn smooth_band<const CH: usize>(
    u: &[f32],
    (fh, fw): (usize, usize),
    g: usize,
    i: usize,
    band: &mut [f32],
    f: &Field,
    st: &Stencils,
    s_row: &[f32],
    r_row: &mut [f32],
) {
    let m = st.margin;
    for dy in 0..g {
        let y = i * g + dy;
        let row = &mut band[dy * fw * CH..(dy + 1) * fw * CH];
        row.copy_from_slice(&u[y * fw * CH..(y + 1) * fw * CH]);
        let inner = y >= m && y + m < fh;
        let (cs, bs) = (&f.c[y * fw..(y + 1) * fw], &f.bucket[y * fw..(y + 1) * fw]);
        for (x, (&c, &b)) in cs.iter().zip(bs).enumerate() {
            if c == 0.0 {
                continue;
            }
            let a: [f32; CH] = if inner && x >= m && x + m < fw {
                let base = ((y * fw + x) * CH) as isize;
                let mut acc = [0f32; CH];
                for &(off, wt) in &st.lin[b as usize] {
                    if let Some(px) = u[(base + off) as usize..].first_chunk::<CH>() {
                        for (a, &v) in acc.iter_mut().zip(px) {
                            *a += wt * v;
                        }
                    }
                }
                acc
            } else {
                border::<CH>(u, (fh, fw), (y, x), direction(b as usize), &st.taps)
            };
            for (o, a) in row[x * CH..(x + 1) * CH].iter_mut().zip(a) {
                *o += c * (a - *o);
            }
        }
    }
    let norm = 1.0 / (g * g) as f32;
    for (j, (r, s)) in r_row
        .chunks_exact_mut(CH)
        .zip(s_row.chunks_exact(CH))
        .enumerate()
    {
        let mut sum = [0f32; CH];
        for dy in 0..g {
            let cells = &band[(dy * fw + j * g) * CH..(dy * fw + (j + 1) * g) * CH];
            for px in cells.chunks_exact(CH) {
                for (a, &v) in sum.iter_mut().zip(px) {
                    *a += v;
                }
            }
        }
        for ((r, s), a) in r.iter_mut().zip(s).zip(sum) {
            *r = s - a * norm;
        }
    }
}

/// One smoothing pass `v = u + c (a − u)` of the whole image, rayon over input rows (each
/// output value depends only on `u`, so the bits do not depend on the thread count);
/// returns the residual `s − D v` at the input's size.
fn smooth<const CH: usize>(
    u: &[f32],
    v: &mut [f32],
    (fh, fw): (usize, usize),
    g: usize,
    f: &Field,
    st: &Stencils,
    s: &[f32],
) -> Vec<f32> {
    let w = fw / g;
    let mut r = vec![0f32; s.len()];
    v.par_chunks_mut(g * fw * CH)
        .zip(r.par_chunks_mut(w * CH))
        .zip(s.par_chunks(w * CH))
        .enumerate()
        .for_each(|(i, ((band, r_row), s_row))| {
            smooth_band::<CH>(u, (fh, fw), g, i, band, f, st, s_row, r_row)
        });
    r
}

/// [`ROUNDS`] rounds of edge smoothing and back-projection of the `F`× upscale `u`
/// (shape `fine`) of `s` (shape `coarse`, see [`applies`]). Two buffers of the output's
/// size, used in turn.
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
    let st = Stencils::new(
        gaussian(sigma, (2.0 * sigma).ceil() as usize),
        fw,
        ch,
        MIN_WEIGHT,
    );
    let hidden = Progress::hidden();
    let mut v = vec![0f32; u.len()];
    for _ in 0..rounds(g) {
        let r = match ch {
            1 => smooth::<1>(&u, &mut v, (fh, fw), g, &field, &st, s),
            2 => smooth::<2>(&u, &mut v, (fh, fw), g, &field, &st, s),
            3 => smooth::<3>(&u, &mut v, (fh, fw), g, &field, &st, s),
            _ => smooth::<4>(&u, &mut v, (fh, fw), g, &field, &st, s),
        };
        up.run_put(r, &hidden, &mut v, |d, x| *d += x);
        std::mem::swap(&mut u, &mut v);
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
        let (ty, tx) = direction(f.bucket[p] as usize);
        let dot = tx * nx + ty * ny;
        // within 6° (measured 3.7°: central differences bias the direction of an edge
        // this sharp, 2 cells wide; the bucket then rounds it to the nearest π/32)
        assert!(dot.abs() < 0.1, "τ·n = {dot}");
    }

    #[test]
    fn the_fast_atan2_is_within_1e_5_rad() {
        for k in 0..720 {
            let t = k as f32 * std::f32::consts::TAU / 720.0;
            for r in [1e-3f32, 1.0, 3e4] {
                let (y, x) = (r * t.sin(), r * t.cos());
                let d = (atan2(y, x) - y.atan2(x)).abs();
                // ±π are the same angle
                let d = d.min((d - std::f32::consts::TAU).abs());
                assert!(
                    d < 1e-5,
                    "atan2({y}, {x}): {} vs {}",
                    atan2(y, x),
                    y.atan2(x)
                );
            }
        }
        assert_eq!(atan2(0.0, 0.0), 0.0);
    }

    #[test]
    fn the_bucket_is_the_nearest_direction() {
        // a tensor whose gradient is at angle φ: J = n nᵀ, n = (cos φ, sin φ) in (x, y)
        for k in 0..360 {
            let phi = (k as f32 - 180.0).to_radians() * 0.5 + 0.001;
            let (s, c) = phi.sin_cos();
            let (ty, tx) = direction(bucket(c * c, c * s, s * s) as usize);
            // τ ⟂ n, so |τ·n| = |sin(error)| ≤ sin(π/2B)
            let err = (tx * c + ty * s).abs();
            let half = (std::f32::consts::PI / (2.0 * BUCKETS as f32)).sin();
            assert!(err <= half + 1e-4, "φ {phi}: |τ·n| {err} > {half}");
        }
    }

    #[test]
    fn the_interior_stencil_is_the_bilinear_average_along_the_direction() {
        // a smooth non-polynomial image, 3 channels; the whole-pixel stencil of every
        // bucket against the per-tap bilinear sum of `border` at an interior pixel
        let (fh, fw) = (40, 44);
        let u: Vec<f32> = (0..fh * fw * 3)
            .map(|i| {
                let (p, m) = (i / 3, i % 3);
                let (y, x) = ((p / fw) as f32, (p % fw) as f32);
                (0.3 * x + 0.2 * y * (m as f32 + 1.0)).sin() * 50.0 + x * y * 0.1
            })
            .collect();
        let st = Stencils::new(gaussian(2.0, 4), fw, 3, 0.0);
        let (y, x) = (20, 21);
        for b in 0..BUCKETS {
            let slow = border::<3>(&u, (fh, fw), (y, x), direction(b), &st.taps);
            let base = ((y * fw + x) * 3) as isize;
            let total: f32 = st.lin[b].iter().map(|&(_, w)| w).sum();
            assert!(
                (total - 1.0).abs() < 1e-5,
                "bucket {b}: weights sum to {total}"
            );
            for (m, s) in slow.iter().enumerate() {
                let fast: f32 = st.lin[b]
                    .iter()
                    .map(|&(o, w)| w * u[(base + o) as usize + m])
                    .sum();
                assert!(
                    (fast - s).abs() < 1e-3,
                    "bucket {b} channel {m}: {fast} vs {s}"
                );
            }
        }
    }
}
