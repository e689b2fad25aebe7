//! The cell kernels the refined area mode ([`super::refine`]) and its plane-by-plane ×2
//! stage ([`super::slab`]) share: the area method, block means by integer factors, and the
//! gather of adjacent cell pairs along an axis.

use super::{Clamp, Edge, Method, Mode};
use crate::scheme::sparse::{Csr, Triplets};
use crate::tensor::resample_axis;
use rayon::prelude::*;

/// Clamp-and-project rounds per ×2 stage (1: +0.09 dB, 2: +0.10 dB, 4: +0.07 dB on
/// Kodak ×4; more rounds flatten texture).
pub const ITERATIONS: usize = 2;

pub(crate) fn area(method: &Method) -> Method {
    Method {
        mode: Mode::Area,
        clamp: Clamp::Off,
        ..method.clone()
    }
}

/// Block mean by integer factors (`shape` is the fine shape).
pub fn block_mean(data: &[f32], shape: &[usize], f: &[(usize, usize)]) -> (Vec<f32>, Vec<usize>) {
    let mut cur: Option<Vec<f32>> = None;
    let mut shape = shape.to_vec();
    for &(axis, g) in f {
        let n = shape[axis] / g;
        let mut t = Triplets::new(n, n * g);
        for i in 0..n {
            for k in 0..g {
                t.add(i, i * g + k, 1.0 / g as f64);
            }
        }
        let op: Csr = t.into_csr();
        let mut next = shape.clone();
        next[axis] = n;
        let mut out = vec![0f32; next.iter().product()];
        resample_axis(
            cur.as_deref().unwrap_or(data),
            &shape,
            axis,
            &op,
            &mut out,
            |x| x,
        );
        cur = Some(out);
        shape = next;
    }
    (cur.unwrap_or_else(|| data.to_vec()), shape)
}

/// Along `axis`, new sample `j` of `2n` takes `op` of the cells `⌊x_j⌋`, `⌈x_j⌉`
/// (`x_j = j/2 − ¼`), cells beyond the ends extended by `edge`.
///
/// With the lane extended to `e = [before, cells…, after]` (`n + 2` cells), sample `2i`
/// is `op(e_i, e_{i+1})` and `2i + 1` is `op(e_{i+1}, e_{i+2})`: each adjacent pair is
/// combined once. Long rows (`inner` large) go row by row instead, in parallel.
pub(crate) fn pair_gather(
    src: &[f32],
    shape: &[usize],
    axis: usize,
    edge: Edge,
    op: impl Fn(f32, f32) -> f32 + Sync + Send,
) -> Vec<f32> {
    let outer: usize = shape[..axis].iter().product();
    let n = shape[axis];
    let inner: usize = shape[axis + 1..].iter().product();
    let m = 2 * n;
    let mut out = vec![0f32; outer * m * inner];
    if n == 0 || inner == 0 {
        return out;
    }
    // the cell beyond the ends of lane `o`, by the edge rule, into `dst`
    let beyond = |o: usize, e: usize, next: usize, dst: &mut [f32]| {
        let lane = &src[o * n * inner..(o + 1) * n * inner];
        let row = |i: usize| &lane[i * inner..(i + 1) * inner];
        match edge {
            Edge::Linear if n > 1 => {
                for ((d, a), b) in dst.iter_mut().zip(row(e)).zip(row(next)) {
                    *d = 2.0 * a - b;
                }
            }
            _ => dst.copy_from_slice(row(e)),
        }
    };
    if inner >= 64 {
        out.par_chunks_mut(inner).enumerate().for_each(|(t, d)| {
            let (o, j) = (t / m, t % m);
            let lane = &src[o * n * inner..(o + 1) * n * inner];
            let i = (j / 2) as isize;
            let (a, b) = if j % 2 == 0 { (i - 1, i) } else { (i, i + 1) };
            let (mut ea, mut eb) = (Vec::new(), Vec::new());
            if a < 0 {
                ea.resize(inner, 0.0);
                beyond(o, 0, 1.min(n - 1), &mut ea);
            }
            if b as usize >= n {
                eb.resize(inner, 0.0);
                beyond(o, n - 1, n.saturating_sub(2), &mut eb);
            }
            let row = |c: usize| &lane[c * inner..(c + 1) * inner];
            let xa = if a < 0 { &ea[..] } else { row(a as usize) };
            let xb = if b as usize >= n {
                &eb[..]
            } else {
                row(b as usize)
            };
            for ((d, &x), &y) in d.iter_mut().zip(xa).zip(xb) {
                *d = op(x, y);
            }
        });
        return out;
    }
    out.par_chunks_mut(m * inner)
        .enumerate()
        .for_each(|(o, dst)| {
            let lane = &src[o * n * inner..(o + 1) * n * inner];
            let mut ext = vec![0f32; (n + 2) * inner];
            beyond(o, 0, 1.min(n - 1), &mut ext[..inner]);
            ext[inner..(n + 1) * inner].copy_from_slice(lane);
            beyond(o, n - 1, n.saturating_sub(2), &mut ext[(n + 1) * inner..]);
            // pair[p] = op(e_p, e_{p+1}), p = 0..=n
            let pair: Vec<f32> = ext[..(n + 1) * inner]
                .iter()
                .zip(&ext[inner..])
                .map(|(&x, &y)| op(x, y))
                .collect();
            for i in 0..n {
                dst[2 * i * inner..(2 * i + 2) * inner]
                    .copy_from_slice(&pair[i * inner..(i + 2) * inner]);
            }
        });
    out
}
