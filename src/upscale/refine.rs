//! Edge-aware refinement of the area mode: clamp the overshoot of the spline to the
//! range of the nearest input cells, then restore the cell means by back-projection;
//! how much of it to keep is learned from the input's own coarser level (detail
//! transfer across scales, §9.3: the same reduce/expand pair one level up).
//!
//! **One ×2 stage** (`U` = area upscale, `D` = 2×2(×2) block mean, `D U = I`):
//! ```text
//! u ← U s
//! repeat ITERATIONS:  u ← clamp(u, lo, hi);   u ← u + U (s − D u)
//! ```
//! `lo`, `hi`: min / max of the input over the 2^d cells nearest to each new sample
//! (along an axis, new sample `j` at `x_j` takes cells `⌊x_j⌋` and `⌈x_j⌉`; the cells
//! beyond the ends are extended by the lane's edge rule, so lines are not clipped).
//! After the last step `D u = D u + D U (s − D u) = s` exactly: the new cells still
//! average back to the input, and a constant is a fixed point (the clamp does nothing).
//! A factor `2^k · r` runs one plain area stage ×`r` (`r` odd) then `k` such stages.
//!
//! **Blend learned one level up.** With `R(s)` the refined and `B(s) = U s` the plain
//! upscale, the output is `B + t (R − B)` (still consistent: both average back to `s`),
//! where `t` is the least-squares weight that best predicts the input from its own
//! block mean `s↓ = D_F s` (cropped to a multiple of the factor `F`):
//! ```text
//! t = clamp( ⟨s − B(s↓), R(s↓) − B(s↓)⟩ / ‖R(s↓) − B(s↓)‖², 0, 1 )
//! ```
//! Images and CT volumes (edges: overshoot is error) learn `t ≈ 1`; smooth heightmaps
//! (ridges: the spline's overshoot is real) learn a smaller `t`. Measured in
//! `docs/upscale.md`.

use super::{upscale_array, AxisPlan, Edge, Geometry, Method, Mode, Prepared};
use crate::progress::Progress;
use crate::scheme::sparse::{Csr, Triplets};
use crate::tensor::resample_axis;
use crate::{Error, Result};
use rayon::prelude::*;

/// Clamp-and-project rounds per ×2 stage (1: +0.09 dB, 2: +0.10 dB, 4: +0.07 dB on
/// Kodak ×4; more rounds flatten texture).
pub const ITERATIONS: usize = 2;

/// Largest output (samples) refined: the refinement keeps about five f32 arrays of the
/// output's size; larger outputs use the plain area mode (streamed, typed output).
pub const MAX_REFINED: u64 = 1 << 27;

/// Whether the area mode clamps overshoot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clamp {
    /// Plain area mode.
    Off,
    /// Fully clamped (`t = 1`).
    On,
    /// Blend learned from the input's coarser level (default).
    Auto,
}

impl std::str::FromStr for Clamp {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "off" | "no" | "none" => Ok(Clamp::Off),
            "on" | "yes" | "full" => Ok(Clamp::On),
            "auto" | "learn" => Ok(Clamp::Auto),
            _ => Err(Error::parameter("clamp", s, "auto, on or off")),
        }
    }
}

/// Integer factor per planned axis when the refinement applies: area mode, clamping on,
/// centre geometry, every length an integer multiple with an even factor somewhere, and
/// an output of at most [`MAX_REFINED`] samples.
pub fn factors(
    method: &Method,
    shape: &[usize],
    plans: &[AxisPlan],
) -> Option<Vec<(usize, usize)>> {
    if method.mode != Mode::Area || method.clamp == Clamp::Off {
        return None;
    }
    let mut out = Vec::new();
    let mut total = shape.iter().map(|&n| n as u64).product::<u64>();
    for p in plans {
        let n = shape[p.axis];
        if p.geometry != Geometry::Centre || n == 0 || p.len % n != 0 || p.len < n {
            return None;
        }
        total = total / n as u64 * p.len as u64;
        if p.len > n {
            out.push((p.axis, p.len / n));
        }
    }
    let even = out.iter().any(|&(_, f)| f % 2 == 0);
    (even && total <= MAX_REFINED).then_some(out)
}

fn area(method: &Method) -> Method {
    Method {
        mode: Mode::Area,
        clamp: Clamp::Off,
        ..method.clone()
    }
}

fn plans_for(shape: &[usize], f: &[(usize, usize)]) -> Vec<AxisPlan> {
    f.iter()
        .map(|&(axis, g)| AxisPlan {
            axis,
            len: shape[axis] * g,
            geometry: Geometry::Centre,
        })
        .collect()
}

/// Plain area upscale by integer factors.
fn plain(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
) -> Result<(Vec<f32>, Vec<usize>)> {
    if f.is_empty() {
        return Ok((data, shape.to_vec()));
    }
    upscale_array(data, shape, &area(method), &plans_for(shape, f))
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
fn pair_gather(
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

/// An upscaled array, its shape, and optionally the plain upscale it started from.
type Staged = (Vec<f32>, Vec<usize>, Option<Vec<f32>>);

/// One ×2 clamp-and-project stage along `axes`; with `keep`, also the plain upscale
/// it starts from.
fn stage(
    low: &[f32],
    shape: &[usize],
    method: &Method,
    axes: &[usize],
    keep: bool,
) -> Result<Staged> {
    stage_with(low, shape, method, axes, keep, true)
}

/// [`stage`]; `fused` lets axes 0 and 1 take the one-pass rounds
/// ([`clamp_residual_2d`]), otherwise the general clamp / block mean / residual passes.
fn stage_with(
    low: &[f32],
    shape: &[usize],
    method: &Method,
    axes: &[usize],
    keep: bool,
    fused: bool,
) -> Result<Staged> {
    let f: Vec<(usize, usize)> = axes.iter().map(|&a| (a, 2)).collect();
    let up = Prepared::new(&area(method), shape, &plans_for(shape, &f))?;
    let hidden = Progress::hidden();
    let (mut u, fine) = up.run(low.to_vec(), &hidden, |x| x);
    let plain = keep.then(|| u.clone());
    let (mut lo, mut hi): (Option<Vec<f32>>, Option<Vec<f32>>) = (None, None);
    let mut s = shape.to_vec();
    for &a in axes {
        let (l, h) = (lo.as_deref().unwrap_or(low), hi.as_deref().unwrap_or(low));
        let l = pair_gather(l, &s, a, method.edge, |x: f32, y: f32| x.min(y));
        let h = pair_gather(h, &s, a, method.edge, |x: f32, y: f32| x.max(y));
        (lo, hi) = (Some(l), Some(h));
        s[a] *= 2;
    }
    let (lo, hi) = (
        lo.unwrap_or_else(|| low.to_vec()),
        hi.unwrap_or_else(|| low.to_vec()),
    );
    let mut sorted = axes.to_vec();
    sorted.sort_unstable();
    if fused && sorted == [0, 1] {
        // images (and the first two axes of anything): one fused pass per round
        let rows_first = axes[0] == 0;
        let mut c: Option<Vec<f32>> = None;
        for _ in 0..ITERATIONS {
            let r = clamp_residual_2d(&mut u, c.as_deref(), &lo, &hi, low, shape, rows_first);
            c = Some(up.run(r, &hidden, |x| x).0);
        }
        if let Some(c) = c {
            u.par_iter_mut()
                .zip(c.par_iter())
                .for_each(|(x, c)| *x += c);
        }
        return Ok((u, fine, plain));
    }
    for _ in 0..ITERATIONS {
        u.par_iter_mut()
            .zip(lo.par_iter().zip(hi.par_iter()))
            .for_each(|(x, (&a, &b))| *x = x.max(a).min(b));
        let (d, _) = block_mean(&u, &fine, &f);
        let r: Vec<f32> = low.iter().zip(&d).map(|(s, d)| s - d).collect();
        let (c, _) = up.run(r, &hidden, |x| x);
        u.par_iter_mut()
            .zip(c.par_iter())
            .for_each(|(x, c)| *x += c);
    }
    Ok((u, fine, plain))
}

/// One round of a ×2 stage along axes 0 and 1 in a single pass (same arithmetic as
/// the general path): `u ← clamp(u + c, lo, hi)` (no `c` in the first round), then
/// the residual `s − D u`, the 2×2 block mean `D` taken along the first stage axis
/// first (`rows_first`: axis 0) as [`block_mean`] does. `shape` is the coarse shape.
fn clamp_residual_2d(
    u: &mut [f32],
    c: Option<&[f32]>,
    lo: &[f32],
    hi: &[f32],
    low: &[f32],
    shape: &[usize],
    rows_first: bool,
) -> Vec<f32> {
    let n1 = shape[1];
    let inner: usize = shape[2..].iter().product();
    let row = n1 * inner; // one coarse row
    let fine_row = 2 * row; // one fine row
    let mut r = vec![0f32; low.len()];
    if row == 0 {
        return r;
    }
    u.par_chunks_mut(2 * fine_row)
        .zip(r.par_chunks_mut(row))
        .enumerate()
        .for_each(|(i, (uc, rc))| {
            let off = i * 2 * fine_row;
            let (l, h) = (&lo[off..off + 2 * fine_row], &hi[off..off + 2 * fine_row]);
            match c {
                Some(c) => {
                    let c = &c[off..off + 2 * fine_row];
                    for (((x, &c), &a), &b) in uc.iter_mut().zip(c).zip(l).zip(h) {
                        *x = (*x + c).max(a).min(b);
                    }
                }
                None => {
                    for ((x, &a), &b) in uc.iter_mut().zip(l).zip(h) {
                        *x = x.max(a).min(b);
                    }
                }
            }
            let (top, bottom) = uc.split_at(fine_row);
            let s = &low[i * row..(i + 1) * row];
            for j in 0..n1 {
                let (e, o) = (2 * j * inner, (2 * j + 1) * inner);
                for k in 0..inner {
                    let (a, b) = (top[e + k], top[o + k]);
                    let (p, q) = (bottom[e + k], bottom[o + k]);
                    let d = if rows_first {
                        0.5 * (0.5 * a + 0.5 * p) + 0.5 * (0.5 * b + 0.5 * q)
                    } else {
                        0.5 * (0.5 * a + 0.5 * b) + 0.5 * (0.5 * p + 0.5 * q)
                    };
                    rc[j * inner + k] = s[j * inner + k] - d;
                }
            }
        });
    r
}

/// The fully clamped upscale `R(s)`: an odd plain stage, then ×2 clamp stages. With
/// `keep` and a single ×2 stage, also the plain upscale `B(s)` (its starting point).
fn refined(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
    keep: bool,
) -> Result<Staged> {
    let odd: Vec<(usize, usize)> = f
        .iter()
        .map(|&(a, g)| (a, g >> g.trailing_zeros()))
        .filter(|&(_, r)| r > 1)
        .collect();
    let (mut u, mut s) = plain(data, shape, method, &odd)?;
    let k = f
        .iter()
        .map(|&(_, g)| g.trailing_zeros())
        .max()
        .unwrap_or(0);
    let keep = keep && k == 1 && odd.is_empty();
    let mut b = None;
    for level in 0..k {
        let axes: Vec<usize> = f
            .iter()
            .filter(|&&(_, g)| g.trailing_zeros() > level)
            .map(|&(a, _)| a)
            .collect();
        (u, s, b) = stage(&u, &s, method, &axes, keep)?;
    }
    Ok((u, s, b))
}

/// The first `len[a]` samples along every axis.
fn crop<'a>(data: &'a [f32], shape: &[usize], len: &[usize]) -> std::borrow::Cow<'a, [f32]> {
    if len == shape {
        return std::borrow::Cow::Borrowed(data);
    }
    let mut out = Vec::with_capacity(len.iter().product());
    let nd = shape.len();
    let mut idx = vec![0usize; nd];
    let total: usize = len.iter().product();
    let strides: Vec<usize> = (0..nd).map(|a| shape[a + 1..].iter().product()).collect();
    let last = len[nd - 1];
    for _ in 0..total / last.max(1) {
        let off: usize = idx.iter().zip(&strides).map(|(i, s)| i * s).sum();
        out.extend_from_slice(&data[off..off + last]);
        for a in (0..nd - 1).rev() {
            idx[a] += 1;
            if idx[a] < len[a] {
                break;
            }
            idx[a] = 0;
        }
    }
    std::borrow::Cow::Owned(out)
}

/// The blend weight `t` learned one level up (`None`: too small to learn from).
pub fn learn_weight(
    data: &[f32],
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
) -> Result<Option<f64>> {
    let mut len = shape.to_vec();
    for &(a, g) in f {
        if shape[a] / g < 2 {
            return Ok(None);
        }
        len[a] = shape[a] / g * g;
    }
    let sc = crop(data, shape, &len);
    let (coarse, cs) = block_mean(&sc, &len, f);
    // the plain upscale comes with the refined one for a single ×2 stage (no copy then)
    let single = f.iter().all(|&(_, g)| g == 2);
    let (r, _, b) = if single {
        refined(coarse, &cs, method, f, true)?
    } else {
        let (r, s, _) = refined(coarse.clone(), &cs, method, f, false)?;
        (r, s, Some(plain(coarse, &cs, method, f)?.0))
    };
    let b = b.expect("a single ×2 stage keeps its plain upscale");
    let (mut num, mut den) = (0f64, 0f64);
    for ((s, b), r) in sc.iter().zip(&b).zip(&r) {
        let d = (*r - *b) as f64;
        num += (*s - *b) as f64 * d;
        den += d * d;
    }
    if den <= 0.0 || !num.is_finite() {
        return Ok(Some(0.0));
    }
    Ok(Some((num / den).clamp(0.0, 1.0)))
}

/// Refined area upscale by integer factors `f` (from [`factors`]).
pub fn upscale_refined(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
) -> Result<(Vec<f32>, Vec<usize>)> {
    let t = match method.clamp {
        Clamp::Off => 0.0,
        Clamp::On => 1.0,
        Clamp::Auto => learn_weight(&data, shape, method, f)?.unwrap_or(0.0),
    };
    if t <= 0.0 {
        return plain(data, shape, method, f);
    }
    if t >= 1.0 {
        return refined(data, shape, method, f, false).map(|(r, s, _)| (r, s));
    }
    let (r, s, b) = refined(data.clone(), shape, method, f, true)?;
    let mut b = match b {
        Some(b) => b,
        None => plain(data, shape, method, f)?.0,
    };
    let t = t as f32;
    b.par_iter_mut()
        .zip(r.par_iter())
        .for_each(|(b, r)| *b += t * (r - *b));
    Ok((b, s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_takes_the_leading_block() {
        let d: Vec<f32> = (0..24).map(|i| i as f32).collect();
        assert_eq!(
            crop(&d, &[2, 3, 4], &[1, 2, 2]).to_vec(),
            vec![0., 1., 4., 5.]
        );
    }

    #[test]
    fn fused_rounds_match_the_general_passes_exactly() {
        for (shape, axes) in [
            (vec![5usize, 7, 3], vec![0usize, 1]),
            (vec![6, 4], vec![1, 0]),
            (vec![4, 5, 2], vec![0, 1]),
        ] {
            let n: usize = shape.iter().product();
            let low: Vec<f32> = (0..n)
                .map(|i| ((i * 7919 % 97) as f32 * 0.37).sin() * 100.0 + (i % 5) as f32)
                .collect();
            let m = Method::default();
            let a = stage_with(&low, &shape, &m, &axes, true, true).unwrap();
            let b = stage_with(&low, &shape, &m, &axes, true, false).unwrap();
            assert_eq!(a.1, b.1);
            assert_eq!(a.0.len(), b.0.len());
            for (x, y) in a.0.iter().zip(&b.0) {
                assert_eq!(x.to_bits(), y.to_bits(), "{shape:?} {axes:?}");
            }
            assert_eq!(a.2, b.2);
        }
    }

    #[test]
    fn pair_gather_matches_the_definition_on_both_paths() {
        for (shape, axis) in [
            (vec![4usize, 5, 70], 1usize),
            (vec![3, 6, 2], 1),
            (vec![5, 4], 0),
        ] {
            for edge in [Edge::Linear, Edge::Mirror] {
                let src: Vec<f32> = (0..shape.iter().product::<usize>())
                    .map(|i| ((i * 37 % 23) as f32).sqrt())
                    .collect();
                let got = pair_gather(&src, &shape, axis, edge, f32::min);
                let (outer, n) = (shape[..axis].iter().product::<usize>(), shape[axis]);
                let inner: usize = shape[axis + 1..].iter().product();
                let at = |o: usize, i: usize, k: usize| src[(o * n + i) * inner + k];
                let cell = |o: usize, c: isize, k: usize| -> f32 {
                    let (e, next) = if c < 0 { (0, 1) } else { (n - 1, n - 2) };
                    if (0..n as isize).contains(&c) {
                        at(o, c as usize, k)
                    } else if edge == Edge::Linear {
                        2.0 * at(o, e, k) - at(o, next, k)
                    } else {
                        at(o, e, k)
                    }
                };
                for o in 0..outer {
                    for j in 0..2 * n {
                        let i = (j / 2) as isize;
                        let (a, b) = if j % 2 == 0 { (i - 1, i) } else { (i, i + 1) };
                        for k in 0..inner {
                            let want = cell(o, a, k).min(cell(o, b, k));
                            assert_eq!(got[(o * 2 * n + j) * inner + k], want);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn pair_ranges_for_x2() {
        let r = pair_gather(&[1.0, 5.0, 2.0], &[3], 0, Edge::Mirror, f32::min);
        assert_eq!(r, vec![1.0, 1.0, 1.0, 2.0, 2.0, 2.0]);
        let r = pair_gather(&[1.0, 5.0, 2.0], &[3], 0, Edge::Linear, f32::max);
        assert_eq!(r, vec![1.0, 5.0, 5.0, 5.0, 5.0, 2.0]);
        let r = pair_gather(&[1.0, 5.0, 2.0], &[3], 0, Edge::Linear, f32::min);
        assert_eq!(r, vec![-3.0, 1.0, 1.0, 2.0, 2.0, -1.0]);
    }
}
