//! Format 1 coefficient coding (read for files of major version 1): the adaptive
//! binary range coder ([`super::range`]) with single-rate [`Bit`] models driven by context models (notes §9.3.2: after quantization most details
//! are zero, and zeros cluster where the picture is smooth, at every scale).
//!
//! Each band is coded on its own (fresh models), in raster order, so a chunk decodes
//! without any other chunk except its parent band. For a coefficient `q`:
//!
//! - **zero flag** `q == 0`, context = neighbour class × parent class, where the
//!   neighbour activity is `s = 2(|W| + |N| + |Z|) + |NW| + |NE|` (W, N, Z the previous
//!   sample along the last, second-last and third-last axes) and the parent is the
//!   coefficient at half the coordinates in the same-orientation band one level coarser;
//! - **sign**, context = signs of W and N;
//! - **magnitude**: `|q| == 1` flag, then `|q| − 2` in Exp-Golomb form (unary
//!   exponent with adaptive models, top mantissa bit modelled, the rest raw).
//!
//! The coarsest block (level 0) is coded as the residual of the LOCO-I median
//! predictor `med(W, N, W + N − NW)` with the same models. Normative: formats/MRA.md §6.

use super::golomb;
use super::range::{Bit, Decoder, Encoder};
use super::walk::{classes, median_residuals, parent_fits, parent_plane, undo_median, Walk};
use super::{BandKind, Parent};
use crate::{Error, Result};

const NCLS: usize = 7;
const PCLS: usize = 3;
const PREFIX: usize = 20;

struct Models {
    zero: [Bit; NCLS * PCLS],
    one: [Bit; NCLS * 2],
    sign: [Bit; 9],
    prefix: [Bit; PREFIX * 4],
    top: [Bit; 64],
}

impl Models {
    fn new() -> Self {
        Models {
            zero: [Bit::default(); NCLS * PCLS],
            one: [Bit::default(); NCLS * 2],
            sign: [Bit::default(); 9],
            prefix: [Bit::default(); PREFIX * 4],
            top: [Bit::default(); 64],
        }
    }
}

#[inline(always)]
fn mag(v: i64) -> u64 {
    v.unsigned_abs().min(1 << 30)
}

/// Neighbour class of an activity `s`: 0, 1–2, 3–4, 5–8, 9–16, 17–40, more.
#[inline(always)]
fn ncls(s: u64) -> usize {
    const CLS: [u8; 41] = classes(&[0, 2, 4, 8, 16]);
    if s <= 40 {
        CLS[s as usize] as usize
    } else {
        6
    }
}

#[inline(always)]
fn sgn(v: i64) -> usize {
    (v.signum() + 1) as usize
}

struct Ctx<'a> {
    walk: Walk,
    parent: Option<(Parent<'a>, Walk)>,
}

impl<'a> Ctx<'a> {
    fn new(dims: &'a [usize], parent: Option<Parent<'a>>) -> Self {
        let parent = parent.filter(|p| parent_fits(p.data, p.dims, dims));
        Ctx {
            walk: Walk::new(dims),
            parent: parent.map(|p| (p, Walk::new(p.dims))),
        }
    }

    /// The offset of the parent's plane of plane `p` (0 without a parent).
    fn parent_base(&self, p: usize, dims: &[usize]) -> usize {
        match &self.parent {
            Some((par, pw)) => parent_plane(p, dims, par.dims) * pw.rows * pw.cols,
            None => 0,
        }
    }

    /// The contexts of row `y` of plane `p` (it starts at `v[at]`; everything before is
    /// known) that do not depend on the row itself, into `r` ([`Row::context`] adds the
    /// previous sample of the row, W). For the coarse band `v` holds residuals.
    fn prepare(&self, r: &mut Row, v: &[i64], at: usize, p: usize, y: usize, pbase: usize) {
        let cols = self.walk.cols;
        let plane = self.walk.rows * cols;
        // N (the row above; zeros in row 0), padded with a zero on both sides so that
        // NW and NE need no test at the ends
        let above = (y > 0).then(|| &v[at - cols..at]);
        let z = (self.walk.zdim > 0 && !p.is_multiple_of(self.walk.zdim))
            .then(|| &v[at - plane..at - plane + cols]);
        let nm = &mut r.nm[..cols + 2];
        let ns = &mut r.ns[..cols];
        nm[0] = 0;
        nm[cols + 1] = 0;
        match above {
            Some(n) => {
                for ((m, sg), &val) in nm[1..=cols].iter_mut().zip(ns.iter_mut()).zip(n) {
                    *m = mag(val);
                    *sg = sgn(val) as u8;
                }
            }
            None => {
                nm[1..=cols].fill(0);
                ns.fill(1);
            }
        }
        // base[x] = 2(|N| + |Z|) + |NW| + |NE|
        let base = &mut r.base[..cols];
        let around = base.iter_mut().zip(nm.windows(3));
        match z {
            Some(z) => {
                for ((b, w), &zv) in around.zip(z) {
                    *b = 2 * (w[1] + mag(zv)) + w[0] + w[2];
                }
            }
            None => {
                for (b, w) in around {
                    *b = 2 * w[1] + w[0] + w[2];
                }
            }
        }
        let pc = &mut r.pc[..cols];
        match &self.parent {
            Some((par, pw)) => {
                let py = (y / 2).min(pw.rows - 1);
                let prow = &par.data[pbase + py * pw.cols..pbase + (py + 1) * pw.cols];
                let cls = |v: i64| match mag(v) {
                    0 => 0,
                    1 => 1,
                    _ => 2,
                };
                // sample x reads parent x/2 (the last one past the parent's end)
                for (two, &pv) in pc.chunks_mut(2).zip(prow) {
                    two.fill(cls(pv));
                }
                let done = (2 * pw.cols).min(cols);
                pc[done..].fill(cls(prow[pw.cols - 1]));
            }
            None => pc.fill(0),
        }
    }
}

/// What [`Ctx::prepare`] works out once per row: the magnitudes of the row above
/// (padded), its signs, the neighbour sum without W, and the parent class.
struct Row {
    nm: Vec<u64>,
    ns: Vec<u8>,
    base: Vec<u64>,
    pc: Vec<u8>,
}

impl Row {
    fn new(cols: usize) -> Self {
        Row {
            nm: vec![0; cols + 2],
            ns: vec![1; cols],
            base: vec![0; cols],
            pc: vec![0; cols],
        }
    }

    /// (zero ctx, one ctx, prefix group, sign ctx) of sample `x` of the row, `w` the
    /// sample before it in the row (0 at its start): the zero context from the neighbour
    /// activity `s = 2(|W| + |N| + |Z|) + |NW| + |NE|` and the parent class, the sign
    /// context from the signs of W and N.
    #[inline(always)]
    fn context(&self, x: usize, w: i64) -> (usize, usize, usize, usize) {
        let s = self.base[x] + 2 * mag(w);
        let c = ncls(s);
        let pc = self.pc[x] as usize;
        (
            c * PCLS + pc,
            c * 2 + (pc > 0) as usize,
            (c / 2).min(3),
            sgn(w) * 3 + self.ns[x] as usize,
        )
    }
}

fn encode_value(e: &mut Encoder, m: &mut Models, q: i64, ctx: (usize, usize, usize, usize)) {
    let (cz, c1, cg, cs) = ctx;
    e.bit(&mut m.zero[cz], q != 0);
    if q == 0 {
        return;
    }
    e.bit(&mut m.sign[cs], q < 0);
    let a = q.unsigned_abs();
    e.bit(&mut m.one[c1], a > 1);
    if a == 1 {
        return;
    }
    let pre = &mut m.prefix[cg * PREFIX..(cg + 1) * PREFIX];
    golomb::encode(e, pre, &mut m.top, a - 2 + 1);
}

fn decode_value(d: &mut Decoder, m: &mut Models, ctx: (usize, usize, usize, usize)) -> Result<i64> {
    let (cz, c1, cg, cs) = ctx;
    if !d.bit(&mut m.zero[cz]) {
        return Ok(0);
    }
    let neg = d.bit(&mut m.sign[cs]);
    let a: u64 = if !d.bit(&mut m.one[c1]) {
        1
    } else {
        let pre = &mut m.prefix[cg * PREFIX..(cg + 1) * PREFIX];
        golomb::decode(d, pre, &mut m.top)? - 1 + 2
    };
    Ok(golomb::signed(a, neg))
}

/// Code one band of quantized coefficients `q` with extents `dims` (raster order).
pub fn encode_band(q: &[i64], dims: &[usize], kind: BandKind, parent: Option<Parent>) -> Vec<u8> {
    let ctx = Ctx::new(dims, parent.filter(|_| kind == BandKind::Detail));
    let mut m = Models::new();
    let mut e = Encoder::new();
    let (planes, rows, cols) = (ctx.walk.planes, ctx.walk.rows, ctx.walk.cols);
    let mut row = Row::new(cols);
    let res: Vec<i64>;
    let v: &[i64] = if kind == BandKind::Coarse {
        let r = median_residuals(q, ctx.walk);
        res = r;
        &res
    } else {
        q
    };
    for p in 0..planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..rows {
            let at = (p * rows + y) * cols;
            ctx.prepare(&mut row, v, at, p, y, pbase);
            let mut w = 0;
            for (x, &q) in v[at..at + cols].iter().enumerate() {
                encode_value(&mut e, &mut m, q, row.context(x, w));
                w = q;
            }
        }
    }
    e.finish()
}

/// Invert [`encode_band`]; `count` = product of `dims` (checked by the caller against
/// the file's limits). Fails on data that runs past its end.
pub fn decode_band(
    bytes: &[u8],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
) -> Result<Vec<i64>> {
    let ctx = Ctx::new(dims, parent.filter(|_| kind == BandKind::Detail));
    let n: usize = dims.iter().product();
    let mut v = vec![0i64; n];
    let mut m = Models::new();
    let mut d = Decoder::new(bytes);
    let (planes, rows, cols) = (ctx.walk.planes, ctx.walk.rows, ctx.walk.cols);
    let mut row = Row::new(cols);
    for p in 0..planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..rows {
            let at = (p * rows + y) * cols;
            ctx.prepare(&mut row, &v, at, p, y, pbase);
            let mut w = 0;
            for (x, out) in v[at..at + cols].iter_mut().enumerate() {
                w = decode_value(&mut d, &mut m, row.context(x, w))?;
                *out = w;
            }
            if d.overrun() > 8 {
                return Err(Error::format("band data ends early", "a complete band"));
            }
        }
    }
    if kind == BandKind::Coarse {
        undo_median(&mut v, ctx.walk);
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::super::walk::testing::{bands, sample};
    use super::*;

    #[test]
    fn bands_round_trip_in_1d_2d_3d_with_parents_and_extremes() {
        for (dims, q, pdims, pq) in bands() {
            let parent = Parent {
                data: &pq,
                dims: &pdims,
            };
            for kind in [BandKind::Coarse, BandKind::Detail] {
                let bytes = encode_band(&q, &dims, kind, Some(parent));
                let back = decode_band(&bytes, &dims, kind, Some(parent)).unwrap();
                assert_eq!(back, q, "{dims:?} {kind:?}");
            }
        }
    }

    #[test]
    fn garbage_never_panics() {
        let dims = [13usize, 17];
        for seed in 0..50u64 {
            let bytes: Vec<u8> = sample(40, seed, 128).iter().map(|&v| v as u8).collect();
            let _ = decode_band(&bytes, &dims, BandKind::Detail, None);
            let _ = decode_band(&bytes, &dims, BandKind::Coarse, None);
        }
    }
}
