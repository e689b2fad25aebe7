//! Format 2 coefficient coding of one band (formats/MRA.md §9).
//!
//! A band is coded with fresh [`Mix`] models in raster order, into a range-coder stream
//! that the bands of one level and channel share. For a detail coefficient `q` with
//! already coded neighbours W, WW (same row), N, NN, NW, NE (rows above), Z (previous
//! plane, volumes only) and the parent P (half the coordinates, one level coarser, same
//! orientation):
//!
//! - activity `t = 2(|W| + |N| + |Z|) + |NW| + |NE| + |WW| + |NN|`;
//! - **zero flag** `q == 0`: context = class of `t` (12) × class of `|P|` (0, 1, ≥ 2);
//! - **sign**: context = signs of W and N;
//! - **magnitude**: `|q| > 1`, then `|q| > 2` flags, then `|q| − 3` in Exp-Golomb form
//!   (unary exponent with adaptive models, top mantissa bit modelled, the rest raw), all
//!   in the class of `u = t + 2|P|` (9 classes).
//!
//! The coarsest block is coded as the residual of the LOCO-I median predictor
//! `med(W, N, W + N − NW)` with the same models and no parent.
//!
//! The encoder may choose the indices itself ([`encode_rdo`]): each coefficient `x`
//! (in units of the band's step) gets the index among `round(|x|)`, `round(|x|) − 1` and
//! 0 that minimises `(|x| − |q|)² + λ·bits(q)`, the bits read from the models' current
//! state — rate–distortion optimised quantization, invisible to the decoder.

use super::golomb;
use super::range::{Decoder, Encoder, Mix, Model};
use super::walk::{median_residuals, parent_plane, undo_median, Walk};
use super::{BandKind, Parent};
use crate::Result;

const ZCLS: usize = 12;
const PCLS: usize = 3;
const MCLS: usize = 9;
const PREFIX: usize = 20;
const CAP: u64 = 1 << 20;

struct Models {
    zero: [Mix; ZCLS * PCLS],
    sign: [Mix; 9],
    gt1: [Mix; MCLS],
    gt2: [Mix; MCLS],
    prefix: [Mix; PREFIX * MCLS],
    top: [Mix; 64],
}

impl Models {
    fn new() -> Self {
        Models {
            zero: [Mix::default(); ZCLS * PCLS],
            sign: [Mix::default(); 9],
            gt1: [Mix::default(); MCLS],
            gt2: [Mix::default(); MCLS],
            prefix: [Mix::default(); PREFIX * MCLS],
            top: [Mix::default(); 64],
        }
    }
}

#[inline(always)]
fn mag(v: i64) -> u64 {
    v.unsigned_abs().min(CAP)
}

#[inline(always)]
fn sgn(v: i64) -> usize {
    (v.signum() + 1) as usize
}

/// Class of the activity `t`: 0, 1, 2, 3, 4, 5–6, 7–8, 9–12, 13–18, 19–28, 29–48, more.
#[inline(always)]
fn zcls(t: u64) -> usize {
    const T: [u8; 49] = {
        let mut t = [0u8; 49];
        let mut s = 0;
        while s <= 48 {
            t[s] = match s {
                0..=4 => s as u8,
                5..=6 => 5,
                7..=8 => 6,
                9..=12 => 7,
                13..=18 => 8,
                19..=28 => 9,
                _ => 10,
            };
            s += 1;
        }
        t
    };
    if t <= 48 {
        T[t as usize] as usize
    } else {
        11
    }
}

/// Class of the magnitude context `u`: 0–1, 2–3, 4–6, 7–10, 11–18, 19–34, 35–66, 67–130, more.
#[inline(always)]
fn mcls(u: u64) -> usize {
    match u {
        0..=1 => 0,
        2..=3 => 1,
        4..=6 => 2,
        7..=10 => 3,
        11..=18 => 4,
        19..=34 => 5,
        35..=66 => 6,
        67..=130 => 7,
        _ => 8,
    }
}

#[inline(always)]
fn cls3(m: u64) -> usize {
    m.min(2) as usize
}

struct Ctx<'a> {
    walk: Walk,
    parent: Option<(Parent<'a>, Walk)>,
}

/// What [`Ctx::prepare`] works out once per row.
struct Row {
    /// magnitudes of the row above, padded with two zeros on each side
    n1: Vec<u64>,
    /// signs of the row above
    ns: Vec<u8>,
    /// activity without W and WW
    base: Vec<u64>,
    /// parent magnitude (capped)
    pm: Vec<u64>,
}

impl Row {
    fn new(cols: usize) -> Self {
        Row {
            n1: vec![0; cols + 4],
            ns: vec![1; cols],
            base: vec![0; cols],
            pm: vec![0; cols],
        }
    }

    /// (zero ctx, magnitude class, sign ctx) of sample `x`; `w`, `ww` the two samples
    /// before it in the row (0 past its start).
    #[inline(always)]
    fn context(&self, x: usize, w: i64, ww: i64) -> (usize, usize, usize) {
        let t = self.base[x] + 2 * mag(w) + mag(ww);
        let pm = self.pm[x];
        let cz = zcls(t) * PCLS + cls3(pm);
        let cm = mcls(t + 2 * pm);
        (cz, cm, sgn(w) * 3 + self.ns[x] as usize)
    }
}

impl<'a> Ctx<'a> {
    /// Offset of the parent plane of plane `p` in the parent's data.
    fn parent_base(&self, p: usize, dims: &[usize]) -> usize {
        match &self.parent {
            Some((par, pw)) => parent_plane(p, dims, par.dims) * pw.rows * pw.cols,
            None => 0,
        }
    }

    fn new(dims: &'a [usize], parent: Option<Parent<'a>>) -> Self {
        let parent = parent.filter(|p| {
            p.dims.len() == dims.len()
                && p.dims.iter().all(|&d| d > 0)
                && p.data.len() == p.dims.iter().product::<usize>()
        });
        Ctx {
            walk: Walk::new(dims),
            parent: parent.map(|p| (p, Walk::new(p.dims))),
        }
    }

    /// The contexts of row `y` of plane `p` (it starts at `v[at]`; everything before is
    /// known) that do not depend on the row itself.
    fn prepare(&self, r: &mut Row, v: &[i64], at: usize, p: usize, y: usize, pbase: usize) {
        let cols = self.walk.cols;
        let plane = self.walk.rows * cols;
        let n1 = &mut r.n1[..cols + 4];
        n1[..2].fill(0);
        n1[cols + 2..].fill(0);
        if y > 0 {
            for ((m, s), &val) in n1[2..cols + 2]
                .iter_mut()
                .zip(r.ns[..cols].iter_mut())
                .zip(&v[at - cols..at])
            {
                *m = mag(val);
                *s = sgn(val) as u8;
            }
        } else {
            n1[2..cols + 2].fill(0);
            r.ns[..cols].fill(1);
        }
        let base = &mut r.base[..cols];
        for (b, w) in base.iter_mut().zip(n1.windows(5)) {
            *b = 2 * w[2] + w[1] + w[3];
        }
        if y > 1 {
            for (b, &val) in base.iter_mut().zip(&v[at - 2 * cols..at - cols]) {
                *b += mag(val);
            }
        }
        if self.walk.zdim > 0 && !p.is_multiple_of(self.walk.zdim) {
            for (b, &zv) in base.iter_mut().zip(&v[at - plane..at - plane + cols]) {
                *b += 2 * mag(zv);
            }
        }
        let pm = &mut r.pm[..cols];
        match &self.parent {
            Some((par, pw)) => {
                let py = (y / 2).min(pw.rows - 1);
                let prow = &par.data[pbase + py * pw.cols..pbase + (py + 1) * pw.cols];
                for (two, &pv) in pm.chunks_mut(2).zip(prow) {
                    two.fill(mag(pv));
                }
                let done = (2 * pw.cols).min(cols);
                pm[done..].fill(mag(prow[pw.cols - 1]));
            }
            None => pm.fill(0),
        }
    }
}

fn encode_value(e: &mut Encoder, m: &mut Models, q: i64, ctx: (usize, usize, usize)) {
    let (cz, cm, cs) = ctx;
    e.bit(&mut m.zero[cz], q != 0);
    if q == 0 {
        return;
    }
    e.bit(&mut m.sign[cs], q < 0);
    let a = q.unsigned_abs();
    e.bit(&mut m.gt1[cm], a > 1);
    if a == 1 {
        return;
    }
    e.bit(&mut m.gt2[cm], a > 2);
    if a == 2 {
        return;
    }
    let pre = &mut m.prefix[cm * PREFIX..(cm + 1) * PREFIX];
    golomb::encode(e, pre, &mut m.top, a - 3 + 1);
}

fn decode_value(d: &mut Decoder, m: &mut Models, ctx: (usize, usize, usize)) -> Result<i64> {
    let (cz, cm, cs) = ctx;
    if !d.bit(&mut m.zero[cz]) {
        return Ok(0);
    }
    let neg = d.bit(&mut m.sign[cs]);
    let a: u64 = if !d.bit(&mut m.gt1[cm]) {
        1
    } else if !d.bit(&mut m.gt2[cm]) {
        2
    } else {
        let pre = &mut m.prefix[cm * PREFIX..(cm + 1) * PREFIX];
        golomb::decode(d, pre, &mut m.top)? - 1 + 3
    };
    Ok(if neg {
        0u64.wrapping_sub(a) as i64
    } else {
        a as i64
    })
}

/// Code one band of indices `q` with extents `dims` (raster order) into `e`.
pub fn encode(e: &mut Encoder, q: &[i64], dims: &[usize], kind: BandKind, parent: Option<Parent>) {
    let coarse = kind == BandKind::Coarse;
    let ctx = Ctx::new(dims, if coarse { None } else { parent });
    let mut m = Models::new();
    let w = ctx.walk;
    let mut row = Row::new(w.cols);
    let res: Vec<i64>;
    let v: &[i64] = if coarse {
        res = median_residuals(q, w);
        &res
    } else {
        q
    };
    for p in 0..w.planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..w.rows {
            let at = (p * w.rows + y) * w.cols;
            ctx.prepare(&mut row, v, at, p, y, pbase);
            let (mut w1, mut w2) = (0, 0);
            for (x, &q) in v[at..at + w.cols].iter().enumerate() {
                encode_value(e, &mut m, q, row.context(x, w1, w2));
                w2 = w1;
                w1 = q;
            }
        }
    }
}

/// Choose and code the indices of a detail band: `x` = its coefficients divided by the
/// band's step; returns the indices chosen (see the module doc; `λ = 0` rounds).
pub fn encode_rdo(
    e: &mut Encoder,
    x: &[f32],
    dims: &[usize],
    parent: Option<Parent>,
    lambda: f32,
) -> Vec<i64> {
    let ctx = Ctx::new(dims, parent);
    let mut m = Models::new();
    let w = ctx.walk;
    let mut row = Row::new(w.cols);
    let mut q = vec![0i64; x.len()];
    for p in 0..w.planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..w.rows {
            let at = (p * w.rows + y) * w.cols;
            ctx.prepare(&mut row, &q, at, p, y, pbase);
            let (mut w1, mut w2) = (0, 0);
            for xi in 0..w.cols {
                let v = x[at + xi];
                let c = row.context(xi, w1, w2);
                let a = choose(&m, v, c, lambda);
                let qv = if v < 0.0 { -a } else { a };
                encode_value(e, &mut m, qv, c);
                q[at + xi] = qv;
                w2 = w1;
                w1 = qv;
            }
        }
    }
    q
}

/// The index magnitude among `round(|v|)`, `round(|v|) − 1` and 0 with the least
/// `(|v| − a)² + λ·bits(a)`.
#[inline(always)]
fn choose(m: &Models, v: f32, c: (usize, usize, usize), lambda: f32) -> i64 {
    let ax = v.abs();
    if !ax.is_finite() {
        return 0;
    }
    let a0 = (ax + 0.5).min(9.0e15) as u64;
    if lambda <= 0.0 || a0 == 0 {
        return a0 as i64;
    }
    let neg = v < 0.0;
    let mut best = (f32::INFINITY, 0u64);
    let tries = if a0 >= 2 { 3 } else { 2 };
    for a in [a0, a0 - 1, 0].into_iter().take(tries) {
        let d = ax - a as f32;
        let j = d * d + lambda * value_cost(m, a, c, neg);
        if j < best.0 {
            best = (j, a);
        }
    }
    best.1 as i64
}

/// Estimated cost in bits of coding magnitude `a` (sign included) in `ctx`.
#[inline(always)]
fn value_cost(m: &Models, a: u64, ctx: (usize, usize, usize), neg: bool) -> f32 {
    let (cz, cm, cs) = ctx;
    let mut c = m.zero[cz].cost(a != 0);
    if a == 0 {
        return c;
    }
    c += m.sign[cs].cost(neg) + m.gt1[cm].cost(a > 1);
    if a == 1 {
        return c;
    }
    c += m.gt2[cm].cost(a > 2);
    if a == 2 {
        return c;
    }
    let v = a - 3 + 1;
    let nb = 63 - v.leading_zeros() as usize;
    let pre = &m.prefix[cm * PREFIX..(cm + 1) * PREFIX];
    for k in 0..nb {
        c += pre[k.min(PREFIX - 1)].cost(true);
    }
    c += pre[nb.min(PREFIX - 1)].cost(false);
    if nb > 0 {
        c += m.top[nb].cost((v >> (nb - 1)) & 1 == 1) + (nb - 1) as f32;
    }
    c
}

/// Decode one band written by [`encode`] or [`encode_rdo`] from `d` (a stream may end
/// early: its trailing zero bytes are left out, so reading past the end is no damage).
/// Fails on an exponent over 62.
pub fn decode(
    d: &mut Decoder,
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
) -> Result<Vec<i64>> {
    let coarse = kind == BandKind::Coarse;
    let ctx = Ctx::new(dims, if coarse { None } else { parent });
    let n: usize = dims.iter().product();
    let mut v = vec![0i64; n];
    let mut m = Models::new();
    let w = ctx.walk;
    let mut row = Row::new(w.cols);
    for p in 0..w.planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..w.rows {
            let at = (p * w.rows + y) * w.cols;
            ctx.prepare(&mut row, &v, at, p, y, pbase);
            let (mut w1, mut w2) = (0, 0);
            for (x, out) in v[at..at + w.cols].iter_mut().enumerate() {
                let q = decode_value(d, &mut m, row.context(x, w1, w2))?;
                *out = q;
                w2 = w1;
                w1 = q;
            }
        }
    }
    if coarse {
        undo_median(&mut v, w);
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(n: usize, seed: u64, spread: i64) -> Vec<i64> {
        let mut x = seed;
        (0..n)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let r = (x >> 33) as i64;
                if r % 3 == 0 {
                    (r % (2 * spread + 1)) - spread
                } else {
                    0
                }
            })
            .collect()
    }

    /// Several bands of 1 to 4 axes, with parents and extreme values, share one stream
    /// and come back exactly, in the order written.
    #[test]
    fn bands_sharing_a_stream_round_trip() {
        let shapes = [
            vec![1usize],
            vec![7],
            vec![5, 9],
            vec![1, 1],
            vec![3, 4, 5],
            vec![2, 2, 3, 3],
        ];
        let mut e = Encoder::new();
        let mut written = Vec::new();
        for dims in &shapes {
            let n: usize = dims.iter().product();
            let mut q = sample(n, n as u64, 300);
            q[0] = i64::MIN;
            if n > 1 {
                q[n - 1] = i64::MAX;
            }
            let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
            let pq = sample(pdims.iter().product(), 9, 3);
            for kind in [BandKind::Coarse, BandKind::Detail] {
                let parent = Parent {
                    data: &pq,
                    dims: &pdims,
                };
                encode(&mut e, &q, dims, kind, Some(parent));
                written.push((dims.clone(), kind, q.clone(), pq.clone(), pdims.clone()));
            }
        }
        let bytes = e.finish();
        let mut d = Decoder::new(&bytes);
        for (dims, kind, q, pq, pdims) in &written {
            let parent = Parent {
                data: pq,
                dims: pdims,
            };
            let back = decode(&mut d, dims, *kind, Some(parent)).unwrap();
            assert_eq!(&back, q, "{dims:?} {kind:?}");
        }
    }

    /// The indices [`encode_rdo`] chooses decode exactly; with λ = 0 they are the
    /// rounded values, and with λ > 0 each is round(|x|), one less, or 0, and the
    /// stream is smaller than the rounded one's.
    #[test]
    fn rdo_indices_decode_and_save_bits() {
        let dims = [48usize, 40];
        let n = 48 * 40;
        let mut s = 7u64;
        let x: Vec<f32> = (0..n)
            .map(|i| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = ((s >> 40) as f32 / (1u64 << 24) as f32) - 0.5;
                // Laplacian-like: mostly small, some large, smooth in places
                let mag = (-(u.abs() + 1e-3).ln()) * if i % 7 == 0 { 4.0 } else { 0.6 };
                mag.copysign(u)
            })
            .collect();
        let mut e0 = Encoder::new();
        let q0 = encode_rdo(&mut e0, &x, &dims, None, 0.0);
        let b0 = e0.finish();
        for (qi, xi) in q0.iter().zip(&x) {
            assert_eq!(*qi, (xi.abs() + 0.5).floor().copysign(*xi) as i64);
        }
        let mut e1 = Encoder::new();
        let q1 = encode_rdo(&mut e1, &x, &dims, None, 0.1);
        let b1 = e1.finish();
        for ((a, b), xi) in q1.iter().zip(&q0).zip(&x) {
            assert!(*a == *b || *a == b - b.signum() || *a == 0, "{xi} {a} {b}");
        }
        assert!(b1.len() < b0.len(), "{} vs {}", b1.len(), b0.len());
        for (q, b) in [(&q0, &b0), (&q1, &b1)] {
            let mut d = Decoder::new(b);
            assert_eq!(&decode(&mut d, &dims, BandKind::Detail, None).unwrap(), q);
        }
    }

    #[test]
    fn garbage_never_panics() {
        let dims = [13usize, 17];
        for seed in 0..50u64 {
            let bytes: Vec<u8> = sample(40, seed, 128).iter().map(|&v| v as u8).collect();
            let _ = decode(&mut Decoder::new(&bytes), &dims, BandKind::Detail, None);
            let _ = decode(&mut Decoder::new(&bytes), &dims, BandKind::Coarse, None);
        }
    }
}
