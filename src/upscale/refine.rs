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

use super::along;
pub use super::cells::ITERATIONS;
use super::cells::{area, block_mean, pair_gather};
use super::slab::{self, Planes};
use super::{upscale_array, AxisPlan, Edge, Geometry, Method, Mode, Prepared};
use crate::progress::Progress;
use crate::{Error, Result};
use rayon::prelude::*;

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

/// A refined upscale `u + c` whose last correction `c` is not added yet (the final pass
/// adds it together with the blend and the store: one pass instead of three), its
/// shape, and optionally the plain upscale it started from.
struct Staged {
    u: Vec<f32>,
    c: Option<Vec<f32>>,
    shape: Vec<usize>,
    plain: Option<Vec<f32>>,
}

impl Staged {
    /// `u + c` as one array.
    fn settle(&mut self) {
        if let Some(c) = self.c.take() {
            self.u
                .par_iter_mut()
                .zip(c.par_iter())
                .for_each(|(x, c)| *x += c);
        }
    }
}

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
/// ([`clamp_residual_2d`]: the clamp bounds computed per row from the input, no
/// full-size bound arrays), otherwise the general clamp / block mean / residual passes.
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
    let mut sorted = axes.to_vec();
    sorted.sort_unstable();
    if fused && sorted == [0, 1] {
        // images (and the first two axes of anything): one fused pass per round; with
        // `keep` the first round reads the plain upscale and writes a new array; the
        // correction `U r` is added straight into `u` by the last axis' resampling
        let rows_first = axes[0] == 0;
        let mut plain = None;
        for round in 0..ITERATIONS {
            let r = if round == 0 && keep {
                let mut v = vec![0f32; u.len()];
                let prev = Prev::From(&u);
                let r = clamp_residual_2d(&mut v, prev, low, shape, rows_first, method.edge);
                plain = Some(std::mem::replace(&mut u, v));
                r
            } else {
                clamp_residual_2d(&mut u, Prev::InPlace, low, shape, rows_first, method.edge)
            };
            up.run_put(r, &hidden, &mut u, |d, x| *d += x);
        }
        return Ok(Staged {
            u,
            c: None,
            shape: fine,
            plain,
        });
    }
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
    let mut c: Option<Vec<f32>> = None;
    for _ in 0..ITERATIONS {
        let mut st = Staged {
            u,
            c: c.take(),
            shape: Vec::new(),
            plain: None,
        };
        st.settle();
        u = st.u;
        u.par_iter_mut()
            .zip(lo.par_iter().zip(hi.par_iter()))
            .for_each(|(x, (&a, &b))| *x = x.max(a).min(b));
        let (d, _) = block_mean(&u, &fine, &f);
        let r: Vec<f32> = low.iter().zip(&d).map(|(s, d)| s - d).collect();
        c = Some(up.run(r, &hidden, |x| x).0);
    }
    Ok(Staged {
        u,
        c,
        shape: fine,
        plain,
    })
}

/// What a fused round clamps: `u` itself or another array (the plain upscale, kept).
#[derive(Clone, Copy)]
enum Prev<'a> {
    InPlace,
    From(&'a [f32]),
}

/// The extension of a lane beyond its end `e` by the edge rule (`next` the sample
/// inside): `2 a − b` (linear, lanes of two or more) or `a`.
fn beyond(a: &[f32], b: &[f32], edge: Edge, long: bool, dst: &mut [f32]) {
    match edge {
        Edge::Linear if long => {
            for ((d, a), b) in dst.iter_mut().zip(a).zip(b) {
                *d = 2.0 * a - b;
            }
        }
        _ => dst.copy_from_slice(a),
    }
}

/// The pairs of one lane of [`pair_gather`], compact: `pair[p] = op(e_p, e_{p+1})`,
/// `p = 0..=n` (`e` the lane of `n` elements of `w` samples extended by `edge`, `e_0`
/// beyond the first element; same arithmetic). New element `2i` of the gathered lane is
/// `pair[i]`, `2i + 1` is `pair[i + 1]`. `ext` (`(n + 2) w`) is scratch.
#[allow(clippy::too_many_arguments)]
fn pair_lane(
    src: &[f32],
    n: usize,
    w: usize,
    edge: Edge,
    op: impl Fn(f32, f32) -> f32 + Copy,
    ext: &mut [f32],
    pair: &mut [f32],
) {
    let ext = &mut ext[..(n + 2) * w];
    let row = |i: usize| &src[i * w..(i + 1) * w];
    let (head, rest) = ext.split_at_mut(w);
    let (mid, tail) = rest.split_at_mut(n * w);
    beyond(row(0), row(1.min(n - 1)), edge, n > 1, head);
    mid.copy_from_slice(src);
    beyond(row(n - 1), row(n.saturating_sub(2)), edge, n > 1, tail);
    let pair = &mut pair[..(n + 1) * w];
    for ((p, &x), &y) in pair.iter_mut().zip(&ext[..(n + 1) * w]).zip(&ext[w..]) {
        *p = op(x, y);
    }
}

/// Scratch of one worker of [`clamp_residual_2d`]: the bounds of two fine rows in the
/// compact pair form of [`pair_lane`] (`(w + 1) · inner` each) and the rows they are
/// made of.
struct Bounds {
    lo: Pair,
    hi: Pair,
    work: Work,
    /// Vertical (or horizontal) pair means of the block mean.
    half: Vec<f32>,
}

/// The bounds of two fine rows.
type Pair = [Vec<f32>; 2];

/// What the bounds of two fine rows are made of: three rows, their pair and the
/// extended lane of [`pair_lane`].
struct Work {
    rows: [Vec<f32>; 3],
    pair: Vec<f32>,
    ext: Vec<f32>,
}

impl Bounds {
    fn new(row: usize, inner: usize) -> Bounds {
        let compact = vec![0f32; row + inner];
        Bounds {
            lo: [compact.clone(), compact.clone()],
            hi: [compact.clone(), compact.clone()],
            work: Work {
                rows: [compact.clone(), compact.clone(), compact.clone()],
                pair: compact,
                ext: vec![0f32; row + 2 * inner],
            },
            half: vec![0f32; 2 * row],
        }
    }

    /// The bounds (min into `lo`, max into `hi`) of fine rows `2i`, `2i + 1` of a ×2
    /// stage along axes 0 and 1 of `low` (`h` rows of `w` elements of `inner`), as
    /// [`pair_gather`] along the first stage axis then the second would give them
    /// (compact along axis 1: the gather's copies commute with the elementwise steps).
    #[allow(clippy::too_many_arguments)]
    fn fill(
        &mut self,
        low: &[f32],
        h: usize,
        w: usize,
        inner: usize,
        i: usize,
        edge: Edge,
        rows_first: bool,
    ) {
        let g = Geom {
            low,
            h,
            w,
            inner,
            i,
            edge,
        };
        let w = &mut self.work;
        if rows_first {
            g.rows_first(|x: f32, y: f32| x.min(y), w, &mut self.lo);
            g.rows_first(|x: f32, y: f32| x.max(y), w, &mut self.hi);
        } else {
            g.cols_first(|x: f32, y: f32| x.min(y), w, &mut self.lo);
            g.cols_first(|x: f32, y: f32| x.max(y), w, &mut self.hi);
        }
    }
}

/// The input of [`Bounds::fill`] and the coarse row `i` being worked on.
struct Geom<'a> {
    low: &'a [f32],
    h: usize,
    w: usize,
    inner: usize,
    i: usize,
    edge: Edge,
}

impl Geom<'_> {
    fn coarse(&self, r: usize) -> &[f32] {
        let row = self.w * self.inner;
        &self.low[r * row..(r + 1) * row]
    }

    /// Along axis 0 first (on the input rows), then along axis 1.
    fn rows_first(&self, op: impl Fn(f32, f32) -> f32 + Copy, w: &mut Work, out: &mut Pair) {
        let Work { rows, pair, ext } = w;
        let (h, row) = (self.h, self.w * self.inner);
        for (k, dst) in rows.iter_mut().enumerate() {
            // input row i − 1 + k, beyond the ends by the edge rule
            let q = (self.i + k) as isize - 1;
            let dst = &mut dst[..row];
            if q < 0 {
                beyond(
                    self.coarse(0),
                    self.coarse(1.min(h - 1)),
                    self.edge,
                    h > 1,
                    dst,
                );
            } else if q as usize >= h {
                let (e, next) = (self.coarse(h - 1), self.coarse(h.saturating_sub(2)));
                beyond(e, next, self.edge, h > 1, dst);
            } else {
                dst.copy_from_slice(self.coarse(q as usize));
            }
        }
        for (t, out) in out.iter_mut().enumerate() {
            for ((p, &x), &y) in pair[..row]
                .iter_mut()
                .zip(&rows[t][..row])
                .zip(&rows[t + 1][..row])
            {
                *p = op(x, y);
            }
            pair_lane(&pair[..row], self.w, self.inner, self.edge, op, ext, out);
        }
    }

    /// Along axis 1 first (every input row, compact), then along axis 0.
    fn cols_first(&self, op: impl Fn(f32, f32) -> f32 + Copy, w: &mut Work, out: &mut Pair) {
        let Work { rows, pair, ext } = w;
        let (h, i, edge) = (self.h, self.i, self.edge);
        let mut g = |r: usize, dst: &mut [f32]| {
            pair_lane(self.coarse(r), self.w, self.inner, edge, op, ext, dst)
        };
        let [r0, r1, r2] = rows;
        g(i, r1);
        if i == 0 {
            // beyond the first row: 2 G(0) − G(1) (linear), G(0) (mirror)
            if h > 1 {
                g(1, r2);
                beyond(r1, r2, edge, true, r0);
            } else {
                r0.copy_from_slice(r1);
            }
        } else {
            g(i - 1, r0);
        }
        if i + 1 == h {
            if h > 1 {
                g(h - 2, pair);
                beyond(r1, pair, edge, true, r2);
            } else {
                r2.copy_from_slice(r1);
            }
        } else {
            g(i + 1, r2);
        }
        for (t, out) in out.iter_mut().enumerate() {
            for ((d, &x), &y) in out.iter_mut().zip(&rows[t]).zip(&rows[t + 1]) {
                *d = op(x, y);
            }
        }
    }
}

/// `x ← clamp(prev, lo, hi)` along one fine row, the bounds compact ([`pair_lane`]):
/// fine element `2j + t` (`w` samples, `C` = `w` known at compile time, or 0) takes
/// bound element `j + t`, so element pair `j` reads the window `lo[j w .. (j + 2) w]`.
fn clamp_row<const C: usize>(
    x: &mut [f32],
    prev: Option<&[f32]>,
    lo: &[f32],
    hi: &[f32],
    w: usize,
) {
    let w = if C == 0 { w } else { C };
    match prev {
        Some(p) => {
            for (j, (xc, pc)) in x
                .chunks_exact_mut(2 * w)
                .zip(p.chunks_exact(2 * w))
                .enumerate()
            {
                let (l, h) = (&lo[j * w..j * w + 2 * w], &hi[j * w..j * w + 2 * w]);
                for t in 0..2 * w {
                    xc[t] = pc[t].max(l[t]).min(h[t]);
                }
            }
        }
        None => {
            for (j, xc) in x.chunks_exact_mut(2 * w).enumerate() {
                let (l, h) = (&lo[j * w..j * w + 2 * w], &hi[j * w..j * w + 2 * w]);
                for t in 0..2 * w {
                    xc[t] = xc[t].max(l[t]).min(h[t]);
                }
            }
        }
    }
}

/// One round of a ×2 stage along axes 0 and 1 in a single pass (same arithmetic as
/// the general path): `u ← clamp(prev, lo, hi)` with the bounds of the nearest input
/// cells computed row by row ([`Bounds::fill`]), then the residual `s − D u`, the 2×2
/// block mean `D` taken along the first stage axis first (`rows_first`: axis 0) as
/// [`block_mean`] does. `shape` is the coarse shape.
fn clamp_residual_2d(
    u: &mut [f32],
    prev: Prev,
    low: &[f32],
    shape: &[usize],
    rows_first: bool,
    edge: Edge,
) -> Vec<f32> {
    let (h, n1) = (shape[0], shape[1]);
    let inner: usize = shape[2..].iter().product();
    let row = n1 * inner; // one coarse row
    let fine_row = 2 * row; // one fine row
    let mut r = vec![0f32; low.len()];
    if row == 0 {
        return r;
    }
    let body = |i: usize, uc: &mut [f32], rc: &mut [f32], b: &mut Bounds| {
        b.fill(low, h, n1, inner, i, edge, rows_first);
        let off = i * 2 * fine_row;
        for (t, uc) in uc.chunks_mut(fine_row).enumerate() {
            let (l, hh) = (&b.lo[t][..], &b.hi[t][..]);
            let at = off + t * fine_row;
            let p = match prev {
                Prev::From(p) => Some(&p[at..at + fine_row]),
                Prev::InPlace => None,
            };
            match inner {
                1 => clamp_row::<1>(uc, p, l, hh, inner),
                3 => clamp_row::<3>(uc, p, l, hh, inner),
                4 => clamp_row::<4>(uc, p, l, hh, inner),
                _ => clamp_row::<0>(uc, p, l, hh, inner),
            }
        }
        let (top, bottom) = uc.split_at(fine_row);
        let s = &low[i * row..(i + 1) * row];
        match inner {
            1 => block_residual::<1>(top, bottom, s, rc, inner, rows_first, &mut b.half),
            3 => block_residual::<3>(top, bottom, s, rc, inner, rows_first, &mut b.half),
            4 => block_residual::<4>(top, bottom, s, rc, inner, rows_first, &mut b.half),
            _ => block_residual::<0>(top, bottom, s, rc, inner, rows_first, &mut b.half),
        }
    };
    u.par_chunks_mut(2 * fine_row)
        .zip(r.par_chunks_mut(row))
        .enumerate()
        .for_each_init(
            || Bounds::new(row, inner),
            |b, (i, (uc, rc))| body(i, uc, rc, b),
        );
    r
}

/// `r = s − D u` for one coarse row: `top`, `bottom` the two fine rows, elements of
/// `w` samples (`C` = `w` known at compile time, or 0); `D` along axis 0 first when
/// `rows_first` (`½(½a + ½p) + ½(½b + ½q)`, `a b` / `p q` the top / bottom pairs),
/// else along axis 1 first (`½(½a + ½b) + ½(½p + ½q)`), as [`block_mean`] computes it.
fn block_residual<const C: usize>(
    top: &[f32],
    bottom: &[f32],
    s: &[f32],
    r: &mut [f32],
    w: usize,
    rows_first: bool,
    half: &mut [f32],
) {
    let w = if C == 0 { w } else { C };
    if rows_first {
        let half = &mut half[..top.len()];
        for ((v, &a), &p) in half.iter_mut().zip(top).zip(bottom) {
            *v = 0.5 * a + 0.5 * p;
        }
        for ((r, s), v) in r
            .chunks_exact_mut(w)
            .zip(s.chunks_exact(w))
            .zip(half.chunks_exact(2 * w))
        {
            let (e, o) = v.split_at(w);
            for k in 0..w {
                r[k] = s[k] - (0.5 * e[k] + 0.5 * o[k]);
            }
        }
    } else {
        for (((r, s), t), b) in r
            .chunks_exact_mut(w)
            .zip(s.chunks_exact(w))
            .zip(top.chunks_exact(2 * w))
            .zip(bottom.chunks_exact(2 * w))
        {
            let ((te, to), (be, bo)) = (t.split_at(w), b.split_at(w));
            for k in 0..w {
                let (ht, hb) = (0.5 * te[k] + 0.5 * to[k], 0.5 * be[k] + 0.5 * bo[k]);
                r[k] = s[k] - (0.5 * ht + 0.5 * hb);
            }
        }
    }
}

/// The stage axes of ×2 stage `level` (the axes whose factor has more than `level`
/// factors 2).
fn stage_axes(f: &[(usize, usize)], level: u32) -> Vec<usize> {
    f.iter()
        .filter(|&&(_, g)| g.trailing_zeros() > level)
        .map(|&(a, _)| a)
        .collect()
}

/// The last ×2 stage's input, its shape, the stage's axes, and whether it is the only
/// stage (nothing ran before it).
type LastStage = (Vec<f32>, Vec<usize>, Vec<usize>, bool);

/// Everything before the last ×2 stage: the odd plain stage and the earlier ×2 stages
/// (settled).
fn before_last(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
) -> Result<LastStage> {
    let odd: Vec<(usize, usize)> = f
        .iter()
        .map(|&(a, g)| (a, g >> g.trailing_zeros()))
        .filter(|&(_, r)| r > 1)
        .collect();
    let (u, s) = plain(data, shape, method, &odd)?;
    let k = f
        .iter()
        .map(|&(_, g)| g.trailing_zeros())
        .max()
        .unwrap_or(0)
        .max(1);
    let mut st = Staged {
        u,
        c: None,
        shape: s,
        plain: None,
    };
    for level in 0..k - 1 {
        st.settle();
        st = stage(&st.u, &st.shape, method, &stage_axes(f, level), false)?;
    }
    st.settle();
    Ok((
        st.u,
        st.shape,
        stage_axes(f, k - 1),
        k == 1 && odd.is_empty(),
    ))
}

/// The fully clamped upscale `R(s)`: an odd plain stage, then ×2 clamp stages, the
/// last correction left pending. With `keep` and a single ×2 stage, also the plain
/// upscale `B(s)` (its starting point).
fn refined(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
    keep: bool,
) -> Result<Staged> {
    let (u, s, axes, only) = before_last(data, shape, method, f)?;
    stage(&u, &s, method, &axes, keep && only)
}

/// For a single ×2 stage worked plane by plane ([`slab`]): its planes.
fn planes(shape: &[usize], method: &Method, f: &[(usize, usize)]) -> Result<Option<Planes>> {
    let axes: Vec<usize> = f.iter().map(|&(a, _)| a).collect();
    if !single_stage(f) || !slab::applies(shape, &axes) {
        return Ok(None);
    }
    Planes::new(shape, method, &axes).map(Some)
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
    learn_weight_with(data, shape, method, f, true)
}

/// [`learn_weight`]; `slabs` lets a volume's stage run plane by plane.
fn learn_weight_with(
    data: &[f32],
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
    slabs: bool,
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
    let (mut num, mut den) = (0f64, 0f64);
    let mut acc = |s: f32, b: f32, r: f32| {
        let d = (r - b) as f64;
        num += (s - b) as f64 * d;
        den += d * d;
    };
    if let Some(p) = planes(&cs, method, f)?.filter(|_| slabs) {
        let fl = p.fine_len();
        p.run(&coarse, true, |i, b, r| {
            let s = &sc[i * fl..(i + 1) * fl];
            for ((s, b), r) in s.iter().zip(b).zip(r.unwrap_or(b)) {
                acc(*s, *b, *r);
            }
        });
        return Ok(Some(weight(num, den)));
    }
    // the plain upscale comes with the refined one for a single ×2 stage (no copy then)
    let b = (!single_stage(f))
        .then(|| plain(coarse.clone(), &cs, method, f))
        .transpose()?
        .map(|p| p.0);
    let st = refined(coarse, &cs, method, f, true)?;
    let Some(b) = b.or(st.plain) else {
        unreachable!("a single ×2 stage keeps its plain upscale")
    };
    match &st.c {
        Some(c) => {
            for (((s, b), u), c) in sc.iter().zip(&b).zip(&st.u).zip(c) {
                acc(*s, *b, *u + *c);
            }
        }
        None => {
            for ((s, b), r) in sc.iter().zip(&b).zip(&st.u) {
                acc(*s, *b, *r);
            }
        }
    }
    Ok(Some(weight(num, den)))
}

/// `clamp(num / den, 0, 1)`, 0 when `den` is 0 or `num` is not finite.
fn weight(num: f64, den: f64) -> f64 {
    if den <= 0.0 || !num.is_finite() {
        return 0.0;
    }
    (num / den).clamp(0.0, 1.0)
}

/// Whether the factors are one ×2 stage (whose plain upscale [`refined`] keeps).
fn single_stage(f: &[(usize, usize)]) -> bool {
    f.iter().all(|&(_, g)| g == 2)
}

/// Refined area upscale by integer factors `f` (from [`factors`]).
pub fn upscale_refined(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
) -> Result<(Vec<f32>, Vec<usize>)> {
    upscale_refined_into(data, shape, method, f, |x| x)
}

/// [`upscale_refined`] with every output sample stored through `store` in the same
/// pass that adds the last correction and blends (`B + t (R − B)`).
pub(crate) fn upscale_refined_into<U: Copy + Default + Send + Sync + 'static>(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
    store: impl Fn(f32) -> U + Sync + Send,
) -> Result<(Vec<U>, Vec<usize>)> {
    if let Some(g) = along::applies(shape, f) {
        // images: smoothed along edges ([`along`]), then stored
        let s = data.clone();
        let (u, fine) = upscale_refined_with(data, shape, method, f, |x| x, true)?;
        let u = along::refine(u, &fine, &s, shape, method, g)?;
        return Ok((u.into_par_iter().map(store).collect(), fine));
    }
    upscale_refined_with(data, shape, method, f, store, true)
}

/// [`upscale_refined_into`]; `slabs` lets a volume's last stage run plane by plane.
fn upscale_refined_with<U: Copy + Default + Send + Sync + 'static>(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    f: &[(usize, usize)],
    store: impl Fn(f32) -> U + Sync + Send,
    slabs: bool,
) -> Result<(Vec<U>, Vec<usize>)> {
    let t = match method.clamp {
        Clamp::Off => 0.0,
        Clamp::On => 1.0,
        Clamp::Auto => learn_weight_with(&data, shape, method, f, slabs)?.unwrap_or(0.0),
    };
    if let Some(p) = planes(shape, method, f)?.filter(|_| slabs) {
        return Ok(by_planes(&p, data, shape, f, t, store));
    }
    if t <= 0.0 {
        let up = Prepared::new(&area(method), shape, &plans_for(shape, f))?;
        return Ok(up.run(data, &Progress::hidden(), store));
    }
    fn add(c: &[f32]) -> impl Fn(usize, &mut [f32]) + Sync + Send + '_ {
        move |off, ch| {
            let n = ch.len();
            for (x, c) in ch.iter_mut().zip(&c[off..off + n]) {
                *x += c;
            }
        }
    }
    if t >= 1.0 {
        let st = refined(data, shape, method, f, false)?;
        let out = match &st.c {
            Some(c) => finish(st.u, add(c), store),
            None => finish(st.u, |_, _| {}, store),
        };
        return Ok((out, st.shape));
    }
    // the plain upscale: kept by a single ×2 stage, else computed first (no copy of data)
    let b = (!single_stage(f))
        .then(|| plain(data.clone(), shape, method, f))
        .transpose()?
        .map(|p| p.0);
    let st = refined(data, shape, method, f, true)?;
    let Some(b) = b.or(st.plain) else {
        unreachable!("a single ×2 stage keeps its plain upscale")
    };
    let t = t as f32;
    let u = &st.u;
    let out = match &st.c {
        Some(c) => finish(
            b,
            |off, ch: &mut [f32]| {
                let n = ch.len();
                for ((b, &u), &c) in ch.iter_mut().zip(&u[off..off + n]).zip(&c[off..off + n]) {
                    let r = u + c;
                    *b += t * (r - *b);
                }
            },
            store,
        ),
        None => finish(
            b,
            |off, ch: &mut [f32]| {
                let n = ch.len();
                for (b, &r) in ch.iter_mut().zip(&u[off..off + n]) {
                    *b += t * (r - *b);
                }
            },
            store,
        ),
    };
    Ok((out, st.shape))
}

/// [`upscale_refined_with`] plane by plane with `p`: the control points of s and of the
/// residuals at the input's size, a few fine planes, and the typed output
/// `b + t·(r − b)` of the plain upscale `b` and the refined one `r`.
fn by_planes<U: Copy + Default + Send + Sync + 'static>(
    p: &Planes,
    data: Vec<f32>,
    shape: &[usize],
    f: &[(usize, usize)],
    t: f64,
    store: impl Fn(f32) -> U + Sync + Send,
) -> (Vec<U>, Vec<usize>) {
    let mut fine = shape.to_vec();
    for &(a, g) in f {
        fine[a] *= g;
    }
    let mut out = vec![U::default(); fine.iter().product()];
    let fl = p.fine_len();
    let tf = t as f32;
    p.run(&data, t > 0.0, |i, b, r| {
        let o = &mut out[i * fl..(i + 1) * fl];
        match r {
            Some(r) if t >= 1.0 => o
                .par_iter_mut()
                .zip(r.par_iter())
                .for_each(|(o, &r)| *o = store(r)),
            Some(r) => o
                .par_iter_mut()
                .zip(b.par_iter().zip(r.par_iter()))
                .for_each(|(o, (&b, &r))| {
                    let mut x = b;
                    x += tf * (r - x);
                    *o = store(x);
                }),
            None => o
                .par_iter_mut()
                .zip(b.par_iter())
                .for_each(|(o, &b)| *o = store(b)),
        }
    });
    drop(data);
    (out, fine)
}

/// Samples per chunk of the final pass.
const CHUNK: usize = 1 << 12;

/// The final pass: `fill(offset, chunk)` turns a chunk of `buf` into output values, then
/// `store` converts them; f32 outputs are written over `buf` (no new array).
fn finish<U: Copy + Default + Send + Sync + 'static>(
    mut buf: Vec<f32>,
    fill: impl Fn(usize, &mut [f32]) + Sync + Send,
    store: impl Fn(f32) -> U + Sync + Send,
) -> Vec<U> {
    use std::any::{Any, TypeId};
    if TypeId::of::<U>() == TypeId::of::<f32>() {
        buf.par_chunks_mut(CHUNK).enumerate().for_each(|(k, ch)| {
            fill(k * CHUNK, ch);
            for x in ch.iter_mut() {
                let y = store(*x);
                *x = (&y as &dyn Any)
                    .downcast_ref::<f32>()
                    .copied()
                    .unwrap_or(f32::NAN);
            }
        });
        let any: Box<dyn Any> = Box::new(buf);
        return match any.downcast::<Vec<U>>() {
            Ok(v) => *v,
            Err(_) => unreachable!("U is f32 (checked above)"),
        };
    }
    let mut out = vec![U::default(); buf.len()];
    buf.par_chunks_mut(CHUNK)
        .zip(out.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(k, (ch, o))| {
            fill(k * CHUNK, ch);
            for (o, &x) in o.iter_mut().zip(ch.iter()) {
                *o = store(x);
            }
        });
    out
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
            (vec![3, 4, 4], vec![1, 0]),
            (vec![1, 5, 4], vec![0, 1]),
            (vec![4, 1, 3], vec![1, 0]),
            (vec![2, 3, 5], vec![0, 1]),
        ] {
            let n: usize = shape.iter().product();
            let low: Vec<f32> = (0..n)
                .map(|i| ((i * 7919 % 97) as f32 * 0.37).sin() * 100.0 + (i % 5) as f32)
                .collect();
            for (edge, keep) in [
                (Edge::Linear, true),
                (Edge::Linear, false),
                (Edge::Mirror, true),
            ] {
                let m = Method {
                    edge,
                    ..Method::default()
                };
                let mut a = stage_with(&low, &shape, &m, &axes, keep, true).unwrap();
                let mut b = stage_with(&low, &shape, &m, &axes, keep, false).unwrap();
                a.settle();
                b.settle();
                assert_eq!(a.shape, b.shape);
                assert_eq!(a.u.len(), b.u.len());
                for (x, y) in a.u.iter().zip(&b.u) {
                    assert_eq!(
                        x.to_bits(),
                        y.to_bits(),
                        "{shape:?} {axes:?} {edge:?} {keep}"
                    );
                }
                assert_eq!(a.plain, b.plain);
            }
        }
    }

    /// The final pass (last correction, blend, store) gives the same samples whether
    /// it writes f32 over its buffer or converts into a new array.
    #[test]
    fn typed_output_is_the_stored_f32_output() {
        let shape = [8usize, 12, 3];
        let data: Vec<f32> = (0..shape.iter().product::<usize>())
            .map(|i| (((i * 7919) % 251) as f32 * 0.9).min(255.0))
            .collect();
        let store = |x: f32| x.round() as u8;
        for f in [
            vec![(0usize, 2usize), (1, 2)],
            vec![(0, 4), (1, 4)],
            vec![(1, 2)],
        ] {
            for clamp in [Clamp::Auto, Clamp::On, Clamp::Off] {
                let m = Method {
                    clamp,
                    ..Method::default()
                };
                let (a, sa) = upscale_refined(data.clone(), &shape, &m, &f).unwrap();
                let (b, sb) = upscale_refined_into(data.clone(), &shape, &m, &f, store).unwrap();
                assert_eq!(sa, sb);
                let want: Vec<u8> = a.iter().map(|&x| store(x)).collect();
                assert_eq!(b, want, "{f:?} {clamp:?}");
            }
        }
    }

    /// A volume's last stage worked plane by plane gives the same bits as the
    /// whole-array stage, for the output and for the learned weight.
    #[test]
    fn plane_by_plane_stage_is_the_whole_array_stage_exactly() {
        for (shape, f) in [
            (vec![6usize, 66, 64], vec![(0usize, 2usize), (1, 2), (2, 2)]),
            (vec![6, 64, 72], vec![(1, 2), (2, 2)]),
            (vec![7, 64, 64], vec![(0, 2)]),
            (vec![4, 40, 36, 3], vec![(0, 2), (1, 2), (2, 2)]),
            (vec![4, 66, 64], vec![(0, 2), (2, 2)]),
        ] {
            // both the output's stage and the learning stage (at half size) by planes
            let half: Vec<usize> = shape
                .iter()
                .enumerate()
                .map(|(a, &n)| {
                    if f.iter().any(|&(b, _)| a == b) {
                        n / 2
                    } else {
                        n
                    }
                })
                .collect();
            assert!(planes(&shape, &Method::default(), &f).unwrap().is_some());
            assert!(planes(&half, &Method::default(), &f).unwrap().is_some());
            let n: usize = shape.iter().product();
            let data: Vec<f32> = (0..n)
                .map(|i| {
                    let v = ((i * 7919 % 211) as f32 * 0.37).sin() * 900.0;
                    if i % 13 < 6 {
                        v
                    } else {
                        -v * 0.5 + (i % 7) as f32
                    }
                })
                .collect();
            for edge in [Edge::Linear, Edge::Mirror] {
                for clamp in [Clamp::Auto, Clamp::On, Clamp::Off] {
                    let m = Method {
                        edge,
                        clamp,
                        ..Method::default()
                    };
                    let store = |x: f32| x;
                    let (a, sa) =
                        upscale_refined_with(data.clone(), &shape, &m, &f, store, true).unwrap();
                    let (b, sb) =
                        upscale_refined_with(data.clone(), &shape, &m, &f, store, false).unwrap();
                    assert_eq!(sa, sb);
                    assert_eq!(a.len(), b.len());
                    let differ = a
                        .iter()
                        .zip(&b)
                        .filter(|(x, y)| x.to_bits() != y.to_bits())
                        .count();
                    assert_eq!(differ, 0, "{shape:?} {f:?} {edge:?} {clamp:?}");
                }
                let m = Method {
                    edge,
                    ..Method::default()
                };
                let ta = learn_weight_with(&data, &shape, &m, &f, true).unwrap();
                let tb = learn_weight_with(&data, &shape, &m, &f, false).unwrap();
                assert!(ta.is_some(), "{shape:?}");
                assert_eq!(ta, tb, "{shape:?} {f:?} {edge:?}");
            }
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
