//! The last ×2 stage of the refined area mode ([`super::refine`]) worked plane by plane
//! along axis 0, so a volume's output never exists as a full-size f32 array.
//!
//! The stage's operator factors as `U = E_0 E_rest K⁻¹`: `K⁻¹` (the banded solves of
//! every stage axis) acts on coarse arrays, `E_rest` (evaluation along the stage axes
//! other than 0) on one coarse plane at a time, and `E_0` (evaluation along axis 0,
//! ≤ order + 1 taps) combines a few consecutive planes of `E_rest K⁻¹ x`. So with the
//! control points `K⁻¹ s`, `K⁻¹ r_1`, … held at the coarse size, the fine planes `2i`,
//! `2i + 1` of any round are evaluated from a window of coarse planes:
//! ```text
//! B      = U s                                   (plain upscale)
//! u_0    = B;   u_m = clamp(u_{m−1}) + U r_m      r_m = s − D clamp(u_{m−1})
//! R      = u_ITERATIONS                           (refined upscale)
//! ```
//! Round `m` needs every `r_1 … r_{m−1}`, so the stage takes `ITERATIONS + 1` passes over
//! the planes, each re-evaluating the earlier terms: about twice the arithmetic of the
//! whole-array stage, for coarse-size memory (the control points of `s` and of each
//! `r_m`) plus a few fine planes. Every value is computed with the same operators in the
//! same order as the whole-array stage, so the results are the same bits.

use super::cells::{area, block_mean, pair_gather, ITERATIONS};
use super::{AxisPlan, Edge, Geometry, Method, Prepared};
use crate::scheme::sparse::{Csr, Triplets};
use crate::tensor::resample_axis;
use crate::Result;
use rayon::prelude::*;
use std::collections::VecDeque;

/// Smallest coarse plane (samples) worked plane by plane; smaller planes (rows of an
/// image) go through the whole-array stage.
const MIN_PLANE: usize = 1 << 10;

/// Whether the stage along `axes` of arrays of `shape` is worked plane by plane: three
/// or more axes, planes of at least [`MIN_PLANE`] samples, and not the fused image
/// stage (axes 0 and 1 exactly).
pub(crate) fn applies(shape: &[usize], axes: &[usize]) -> bool {
    let mut sorted = axes.to_vec();
    sorted.sort_unstable();
    shape.len() >= 3
        && shape[1..].iter().product::<usize>() >= MIN_PLANE
        && sorted != [0, 1]
        && shape[0] >= 2
}

/// One ×2 stage along `axes` of arrays of coarse `shape`, split for plane-wise work.
pub(crate) struct Planes {
    prep: Prepared,
    /// Evaluation along axis 0 (`2 n_0 × n_0`), when axis 0 is a stage axis.
    z: Option<Csr>,
    /// Evaluation along the other stage axes, in plane coordinates (axis − 1), in the
    /// order the whole-array stage applies them.
    ops: Vec<(usize, Csr)>,
    /// Stage axes other than 0, in plane coordinates, in stage order (bounds, block mean).
    rest: Vec<usize>,
    plane: Vec<usize>,
    fine_plane: Vec<usize>,
    edge: Edge,
}

impl Planes {
    pub(crate) fn new(shape: &[usize], method: &Method, axes: &[usize]) -> Result<Planes> {
        let plans: Vec<AxisPlan> = axes
            .iter()
            .map(|&axis| AxisPlan {
                axis,
                len: shape[axis] * 2,
                geometry: Geometry::Centre,
            })
            .collect();
        let mut prep = Prepared::new(&area(method), shape, &plans)?;
        let mut z = None;
        let mut ops = Vec::new();
        for (axis, op) in std::mem::take(&mut prep.ops) {
            if axis == 0 {
                z = Some(op);
            } else {
                ops.push((axis - 1, op));
            }
        }
        let plane = shape[1..].to_vec();
        let mut fine_plane = plane.clone();
        for (a, op) in &ops {
            fine_plane[*a] = op.rows();
        }
        Ok(Planes {
            prep,
            z,
            ops,
            rest: axes.iter().filter(|&&a| a != 0).map(|&a| a - 1).collect(),
            plane,
            fine_plane,
            edge: method.edge,
        })
    }

    fn n0(&self) -> usize {
        self.prep.shape[0]
    }

    fn plane_len(&self) -> usize {
        self.plane.iter().product()
    }

    /// Samples of the fine planes made from one coarse plane.
    pub(crate) fn fine_len(&self) -> usize {
        self.fine_plane.iter().product::<usize>() * self.per()
    }

    /// Fine planes per coarse plane.
    fn per(&self) -> usize {
        if self.z.is_some() {
            2
        } else {
            1
        }
    }

    /// The control points `K⁻¹ x` (in place).
    fn control(&self, x: &mut [f32]) {
        self.prep.prefilter(x);
    }

    /// `E_rest` of coarse plane `k` of `src`.
    fn plane_up(&self, src: &[f32], k: usize) -> Vec<f32> {
        let pl = self.plane_len();
        let mut cur = src[k * pl..(k + 1) * pl].to_vec();
        let mut s = self.plane.clone();
        for (a, op) in &self.ops {
            let mut ns = s.clone();
            ns[*a] = op.rows();
            let mut next = vec![0f32; ns.iter().product()];
            resample_axis(&cur, &s, *a, op, &mut next, |x| x);
            cur = next;
            s = ns;
        }
        cur
    }

    /// The bounds (min, max) of the fine planes of coarse plane `i`, as
    /// [`pair_gather`] along the stage axes (axis 0 first) gives them.
    fn bounds(&self, low: &[f32], i: usize) -> (Vec<f32>, Vec<f32>) {
        let pl = self.plane_len();
        let coarse = |k: usize| &low[k * pl..(k + 1) * pl];
        let mut shape = vec![self.per()];
        shape.extend_from_slice(&self.plane);
        let (mut lo, mut hi) = match &self.z {
            None => (coarse(i).to_vec(), coarse(i).to_vec()),
            Some(_) => {
                let n = self.n0();
                // extended cell e (0 ..= n + 1; 0 and n + 1 beyond the ends)
                let cell = |e: usize| -> Vec<f32> {
                    if e == 0 || e == n + 1 {
                        let (a, b) = if e == 0 {
                            (coarse(0), coarse(1.min(n - 1)))
                        } else {
                            (coarse(n - 1), coarse(n.saturating_sub(2)))
                        };
                        match self.edge {
                            Edge::Linear if n > 1 => {
                                a.iter().zip(b).map(|(a, b)| 2.0 * a - b).collect()
                            }
                            _ => a.to_vec(),
                        }
                    } else {
                        coarse(e - 1).to_vec()
                    }
                };
                let (c0, c1, c2) = (cell(i), cell(i + 1), cell(i + 2));
                let mut lo = Vec::with_capacity(2 * pl);
                let mut hi = Vec::with_capacity(2 * pl);
                for (a, b) in [(&c0, &c1), (&c1, &c2)] {
                    lo.extend(a.iter().zip(b.iter()).map(|(x, y)| x.min(*y)));
                    hi.extend(a.iter().zip(b.iter()).map(|(x, y)| x.max(*y)));
                }
                (lo, hi)
            }
        };
        for &a in &self.rest {
            lo = pair_gather(&lo, &shape, a + 1, self.edge, |x: f32, y: f32| x.min(y));
            hi = pair_gather(&hi, &shape, a + 1, self.edge, |x: f32, y: f32| x.max(y));
            shape[a + 1] *= 2;
        }
        (lo, hi)
    }

    /// `s_i − D u` for the fine planes `u` of coarse plane `i` (into `r`).
    fn residual(&self, u: &[f32], s: &[f32], r: &mut [f32]) {
        let mut shape = vec![self.per()];
        shape.extend_from_slice(&self.fine_plane);
        let mut f = Vec::new();
        if self.z.is_some() {
            f.push((0, 2));
        }
        f.extend(self.rest.iter().map(|&a| (a + 1, 2)));
        let (d, _) = block_mean(u, &shape, &f);
        for ((r, s), d) in r.iter_mut().zip(s).zip(&d) {
            *r = s - d;
        }
    }

    /// Run the stage on `low`: `sink(i, b, r)` gets, for every coarse plane `i` in
    /// order, its fine planes of the plain upscale `B` and of the refined upscale `R`
    /// (`r` is `None` when `refine` is false: the plain upscale alone).
    pub(crate) fn run(
        &self,
        low: &[f32],
        refine: bool,
        mut sink: impl FnMut(usize, &[f32], Option<&[f32]>),
    ) {
        let n0 = self.n0();
        let pl = self.plane_len();
        let mut ps = low.to_vec();
        self.control(&mut ps);
        let mut rs: Vec<Vec<f32>> = Vec::new();
        let rounds = if refine { ITERATIONS } else { 0 };
        for m in 0..=rounds {
            let mut evals: Vec<Eval> = std::iter::once(&ps)
                .chain(rs.iter())
                .map(|src| Eval::new(src))
                .collect();
            let mut next = (m < rounds).then(|| vec![0f32; low.len()]);
            for i in 0..n0 {
                let b = evals[0].fine(self, i);
                let mut u = b.clone();
                let bounds = (m > 0 || m < rounds).then(|| self.bounds(low, i));
                for e in evals[1..].iter_mut() {
                    if let Some((lo, hi)) = &bounds {
                        clamp(&mut u, lo, hi);
                    }
                    let c = e.fine(self, i);
                    u.par_iter_mut()
                        .zip(c.par_iter())
                        .for_each(|(x, c)| *x += c);
                }
                match &mut next {
                    Some(r) => {
                        if let Some((lo, hi)) = &bounds {
                            clamp(&mut u, lo, hi);
                        }
                        let s = &low[i * pl..(i + 1) * pl];
                        self.residual(&u, s, &mut r[i * pl..(i + 1) * pl]);
                    }
                    None if refine => sink(i, &b, Some(&u)),
                    None => sink(i, &b, None),
                }
            }
            if let Some(mut r) = next {
                self.control(&mut r);
                rs.push(r);
            }
        }
    }
}

/// `x ← clamp(x, lo, hi)` (as `x.max(lo).min(hi)`).
fn clamp(x: &mut [f32], lo: &[f32], hi: &[f32]) {
    x.par_iter_mut()
        .zip(lo.par_iter().zip(hi.par_iter()))
        .for_each(|(x, (&a, &b))| *x = x.max(a).min(b));
}

/// The fine planes of one set of control points, with the `E_rest` planes of the
/// current window of coarse planes kept.
struct Eval<'a> {
    src: &'a [f32],
    cache: VecDeque<(usize, Vec<f32>)>,
}

impl<'a> Eval<'a> {
    fn new(src: &'a [f32]) -> Eval<'a> {
        Eval {
            src,
            cache: VecDeque::new(),
        }
    }

    fn up(&mut self, p: &Planes, k: usize) -> &[f32] {
        let at = match self.cache.iter().position(|(j, _)| *j == k) {
            Some(at) => at,
            None => {
                let v = p.plane_up(self.src, k);
                self.cache.push_back((k, v));
                self.cache.len() - 1
            }
        };
        &self.cache[at].1
    }

    /// The fine planes of coarse plane `i` (2 along a stage axis 0, else 1).
    fn fine(&mut self, p: &Planes, i: usize) -> Vec<f32> {
        let Some(z) = &p.z else {
            self.cache.retain(|(j, _)| *j >= i);
            return self.up(p, i).to_vec();
        };
        let rows = [2 * i, 2 * i + 1];
        let cols: Vec<usize> = rows
            .iter()
            .flat_map(|&r| z.row(r).map(|(c, _)| c))
            .collect();
        let (k0, k1) = (
            cols.iter().copied().min().unwrap_or(i),
            cols.iter().copied().max().unwrap_or(i),
        );
        let fp: usize = p.fine_plane.iter().product();
        let mut stack = Vec::with_capacity((k1 - k0 + 1) * fp);
        // planes below k0 are never needed again (the rows' columns go up with i)
        self.cache.retain(|(j, _)| *j >= k0);
        for k in k0..=k1 {
            stack.extend_from_slice(self.up(p, k));
        }
        let mut t = Triplets::new(2, k1 - k0 + 1);
        for (r, &row) in rows.iter().enumerate() {
            for (c, w) in z.row(row) {
                t.add(r, c - k0, w);
            }
        }
        let sub = t.into_csr();
        let mut shape = vec![k1 - k0 + 1];
        shape.extend_from_slice(&p.fine_plane);
        let mut out = vec![0f32; 2 * fp];
        resample_axis(&stack, &shape, 0, &sub, &mut out, |x| x);
        out
    }
}
