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
//! Format 2.3 ([`Coding::Chosen`]) opens each band's stream with a bit choosing those
//! nine classes or [`Classes::Wide`]: the classes continued one per octave of `u` past
//! 130 (25 in all), the top mantissa bit modelled per class and exponent and the
//! second per exponent and top bit, for the large indices of high-bit lossless data.
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
use super::walk::{class_in, classes, median_residuals, parent_plane, undo_median, Walk};
use super::{BandKind, Parent};
use crate::Result;

mod rows;
pub use rows::{RowDecoder, RowEncoder};

const ZCLS: usize = 12;
const PCLS: usize = 3;
/// Magnitude classes of [`Classes::Wide`]: the nine of [`Classes::Narrow`], then one per
/// octave of `u` up to the largest `u` the capped magnitudes make.
const MCLS_WIDE: usize = 25;
const PREFIX: usize = 20;
const CAP: u64 = 1 << 20;

struct Models {
    zero: [Mix; ZCLS * PCLS],
    sign: [Mix; 9],
    gt1: [Mix; MCLS_WIDE],
    gt2: [Mix; MCLS_WIDE],
    prefix: [Mix; PREFIX * MCLS_WIDE],
    top: [Mix; 64],
    /// [`Classes::Wide`]: the top mantissa bit per class and exponent, the second
    /// one per exponent and top bit
    top_wide: [Mix; 64 * MCLS_WIDE],
    second: [Mix; 128],
    wide: bool,
}

impl Models {
    fn new(classes: Classes) -> Self {
        Models {
            top_wide: [Mix::default(); 64 * MCLS_WIDE],
            second: [Mix::default(); 128],
            wide: classes == Classes::Wide,
            zero: [Mix::default(); ZCLS * PCLS],
            sign: [Mix::default(); 9],
            gt1: [Mix::default(); MCLS_WIDE],
            gt2: [Mix::default(); MCLS_WIDE],
            prefix: [Mix::default(); PREFIX * MCLS_WIDE],
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
    const T: [u8; 49] = classes(&[0, 1, 2, 3, 4, 6, 8, 12, 18, 28]);
    class_in(&T, t, 11)
}

/// Class of the magnitude context `u`: 0–1, 2–3, 4–6, 7–10, 11–18, 19–34, 35–66, 67–130, more.
#[inline(always)]
fn mcls(u: u64) -> usize {
    const T: [u8; 131] = classes(&[1, 3, 6, 10, 18, 34, 66]);
    class_in(&T, u, 8)
}

/// Class of `u` in [`Classes::Wide`]: [`mcls`] up to 130, then `8 + ⌊log₂(u / 131)⌋`
/// (131–261, 262–523, …), at most 24.
#[inline(always)]
fn mcls_wide(u: u64) -> usize {
    if u <= 130 {
        mcls(u)
    } else {
        (8 + (u / 131).ilog2() as usize).min(MCLS_WIDE - 1)
    }
}

/// The coefficient coding of a file (formats/MRA.md §9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coding {
    /// Formats 2.0–2.2: every band in [`Classes::Narrow`].
    #[default]
    Narrow,
    /// Format 2.3: a band's stream opens with one bit of probability ½ choosing its
    /// classes, 0 for [`Classes::Narrow`], 1 for [`Classes::Wide`] (the encoder codes
    /// both and keeps the shorter).
    Chosen,
}

/// The magnitude classes of a band's coding (formats/MRA.md §9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Classes {
    /// Formats 2.0–2.2: nine classes of `u`, the last one `u > 130`.
    #[default]
    Narrow,
    /// Format 2.3: the nine classes up to `u = 130`, then one per octave of `u`
    /// ([`mcls_wide`], 25 in all), so that the large indices of high-bit data (16-bit
    /// lossless details reach thousands) keep their neighbourhood's scale; the top
    /// mantissa bit of the Exp-Golomb tail modelled per class and exponent, the second
    /// per exponent and top bit.
    Wide,
}

/// Write the opening of a band's stream of `coding` coded with `classes` (the selector
/// bit of [`Coding::Chosen`]; nothing in [`Coding::Narrow`], which has no wide classes).
fn open(e: &mut Encoder, coding: Coding, classes: Classes) {
    debug_assert!(coding == Coding::Chosen || classes == Classes::Narrow);
    if coding == Coding::Chosen {
        e.raw(classes == Classes::Wide);
    }
}

/// Read the opening of a band's stream of `coding`: the classes it is coded with.
fn opened(d: &mut Decoder, coding: Coding) -> Classes {
    match coding {
        Coding::Chosen if d.raw() => Classes::Wide,
        _ => Classes::Narrow,
    }
}

/// One band of indices `q` coded ([`encode`]) into a stream of its own, finished short
/// ([`Encoder::finish_short`]): in [`Coding::Chosen`] with both classes, keeping the
/// shorter stream (the narrow one on a tie).
pub fn encode_stream(
    q: &[i64],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    coding: Coding,
) -> Vec<u8> {
    let code = |classes: Classes| {
        let mut e = Encoder::new();
        open(&mut e, coding, classes);
        encode(&mut e, q, dims, kind, parent, classes);
        e.finish_short()
    };
    chosen(coding, code)
}

/// The stream `code` writes in the classes `coding` asks for: the narrow ones, or in
/// [`Coding::Chosen`] the shorter of both (coded side by side).
fn chosen(coding: Coding, code: impl Fn(Classes) -> Vec<u8> + Sync) -> Vec<u8> {
    if coding == Coding::Narrow {
        return code(Classes::Narrow);
    }
    let (narrow, wide) = rayon::join(|| code(Classes::Narrow), || code(Classes::Wide));
    if wide.len() < narrow.len() {
        wide
    } else {
        narrow
    }
}

/// [`encode_stream`] of a detail band whose indices are handed over a row at a time:
/// `row(g, out)` fills `out` with row `g` (raster order over the planes' rows). Only
/// the rows the contexts read are held ([`Window`]), not the whole band; the bytes are
/// those of [`encode_stream`] of the whole band (in [`Coding::Chosen`] each coding asks
/// for every row once).
pub fn encode_stream_rows(
    dims: &[usize],
    parent: Option<Parent>,
    coding: Coding,
    row: impl Fn(usize, &mut [i64]) + Sync,
) -> Vec<u8> {
    let code = |classes: Classes| {
        let mut e = Encoder::new();
        open(&mut e, coding, classes);
        encode_rows(&mut e, dims, parent, classes, &row);
        e.finish_short()
    };
    chosen(coding, code)
}

/// [`encode`] of a detail band handed over a row at a time (see [`encode_stream_rows`]).
fn encode_rows(
    e: &mut Encoder,
    dims: &[usize],
    parent: Option<Parent>,
    classes: Classes,
    row: impl Fn(usize, &mut [i64]),
) {
    let ctx = Ctx::new(dims, parent);
    let mut m = Models::new(classes);
    let w = ctx.walk;
    let mut r = Row::new(w.cols, classes);
    let mut q = Window::new(w, false);
    for p in 0..w.planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..w.rows {
            let g = p * w.rows + y;
            row(g, q.row_mut(g));
            ctx.prepare(&mut r, q.neighbours(&ctx, p, y, g), y, pbase);
            let (mut w1, mut w2) = (0, 0);
            for (x, &v) in q.row(g).iter().enumerate() {
                encode_value(e, &mut m, v, r.context(x, w1, w2));
                w2 = w1;
                w1 = v;
            }
        }
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
    /// magnitude classes of [`Classes::Wide`]
    wide: bool,
}

impl Row {
    fn new(cols: usize, classes: Classes) -> Self {
        Row {
            wide: classes == Classes::Wide,
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
        let cm = if self.wide {
            mcls_wide(t + 2 * pm)
        } else {
            mcls(t + 2 * pm)
        };
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

    /// The rows a row's contexts read: the two rows above it (`y > 0`, `y > 1`) and the
    /// same row of the previous plane (volumes, within one extent of the third-last
    /// axis), from a band `v` whose row `y` of plane `p` starts at `v[at]`.
    fn neighbours<'v>(&self, v: &'v [i64], at: usize, p: usize, y: usize) -> Neighbours<'v> {
        let cols = self.walk.cols;
        let plane = self.walk.rows * cols;
        Neighbours {
            n: (y > 0).then(|| &v[at - cols..at]),
            nn: (y > 1).then(|| &v[at - 2 * cols..at - cols]),
            z: self.has_z(p).then(|| &v[at - plane..at - plane + cols]),
        }
    }

    /// Whether plane `p` has a Z neighbour (a previous plane along the third-last axis).
    #[inline]
    fn has_z(&self, p: usize) -> bool {
        self.walk.zdim > 0 && !p.is_multiple_of(self.walk.zdim)
    }

    /// The contexts of row `y` (parent plane at `pbase`) that do not depend on the row
    /// itself, from its [`Neighbours`].
    fn prepare(&self, r: &mut Row, nb: Neighbours, y: usize, pbase: usize) {
        let cols = self.walk.cols;
        let n1 = &mut r.n1[..cols + 4];
        n1[..2].fill(0);
        n1[cols + 2..].fill(0);
        if let Some(above) = nb.n {
            for ((m, s), &val) in n1[2..cols + 2]
                .iter_mut()
                .zip(r.ns[..cols].iter_mut())
                .zip(above)
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
        if let Some(nn) = nb.nn {
            for (b, &val) in base.iter_mut().zip(nn) {
                *b += mag(val);
            }
        }
        if let Some(z) = nb.z {
            for (b, &zv) in base.iter_mut().zip(z) {
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

/// The already coded rows a row's contexts read (None where there is none).
#[derive(Clone, Copy)]
struct Neighbours<'v> {
    n: Option<&'v [i64]>,
    nn: Option<&'v [i64]>,
    z: Option<&'v [i64]>,
}

/// Code index `q` in context `ctx`: the zero flag inline (most indices are 0), the rest
/// in [`encode_nonzero`].
#[inline(always)]
fn encode_value(e: &mut Encoder, m: &mut Models, q: i64, ctx: (usize, usize, usize)) {
    let (cz, cm, cs) = ctx;
    e.bit(&mut m.zero[cz], q != 0);
    if q != 0 {
        encode_nonzero(e, m, q, cm, cs);
    }
}

/// The sign and magnitude of an index that is not 0.
#[inline(never)]
fn encode_nonzero(e: &mut Encoder, m: &mut Models, q: i64, cm: usize, cs: usize) {
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
    if !m.wide {
        golomb::encode(e, pre, &mut m.top, a - 3 + 1);
        return;
    }
    let v = a - 3 + 1;
    let nb = 63 - v.leading_zeros() as usize;
    for k in 0..nb {
        e.bit(&mut pre[k.min(PREFIX - 1)], true);
    }
    e.bit(&mut pre[nb.min(PREFIX - 1)], false);
    if nb > 0 {
        let t = (v >> (nb - 1)) & 1;
        e.bit(&mut m.top_wide[cm * 64 + nb], t == 1);
        if nb > 1 {
            e.bit(&mut m.second[2 * nb + t as usize], (v >> (nb - 2)) & 1 == 1);
            for j in (0..nb - 2).rev() {
                e.raw((v >> j) & 1 == 1);
            }
        }
    }
}

/// Decode the magnitude tail of [`Classes::Wide`].
fn decode_wide(d: &mut Decoder, m: &mut Models, cm: usize) -> Result<u64> {
    let pre = &mut m.prefix[cm * PREFIX..(cm + 1) * PREFIX];
    let mut nb = 0usize;
    while d.bit(&mut pre[nb.min(PREFIX - 1)]) {
        nb += 1;
        if nb > 62 {
            return Err(crate::Error::format(
                "coefficient exponent over 62",
                "a valid band",
            ));
        }
    }
    let mut v: u64 = 1;
    if nb > 0 {
        let t = d.bit(&mut m.top_wide[cm * 64 + nb]) as u64;
        v = (v << 1) | t;
        if nb > 1 {
            v = (v << 1) | d.bit(&mut m.second[2 * nb + t as usize]) as u64;
            for _ in 0..nb - 2 {
                v = (v << 1) | d.raw() as u64;
            }
        }
    }
    Ok(v)
}

/// Decode one index in context `ctx`: the zero flag inline (most indices are 0), the
/// rest in [`decode_nonzero`].
#[inline(always)]
fn decode_value(d: &mut Decoder, m: &mut Models, ctx: (usize, usize, usize)) -> Result<i64> {
    let (cz, cm, cs) = ctx;
    if !d.bit(&mut m.zero[cz]) {
        return Ok(0);
    }
    decode_nonzero(d, m, cm, cs)
}

/// The sign and magnitude of an index known not to be 0.
#[inline(never)]
fn decode_nonzero(d: &mut Decoder, m: &mut Models, cm: usize, cs: usize) -> Result<i64> {
    let neg = d.bit(&mut m.sign[cs]);
    let a: u64 = if !d.bit(&mut m.gt1[cm]) {
        1
    } else if !d.bit(&mut m.gt2[cm]) {
        2
    } else if m.wide {
        decode_wide(d, m, cm)? - 1 + 3
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
pub fn encode(
    e: &mut Encoder,
    q: &[i64],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    classes: Classes,
) {
    let coarse = kind == BandKind::Coarse;
    let ctx = Ctx::new(dims, if coarse { None } else { parent });
    let mut m = Models::new(classes);
    let w = ctx.walk;
    let mut row = Row::new(w.cols, classes);
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
            ctx.prepare(&mut row, ctx.neighbours(v, at, p, y), y, pbase);
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
    coding: Coding,
) -> Vec<i64> {
    let cols = Walk::new(dims).cols;
    encode_rdo_with(e, dims, parent, lambda, coding, true, |g, out| {
        out.copy_from_slice(&x[g * cols..(g + 1) * cols])
    })
    .unwrap_or_default()
}

/// [`encode_rdo`] with the band's values handed over a row at a time: `row(g, out)`
/// fills `out` with row `g` (raster order) of the coefficients divided by the step.
/// Returns the indices when `keep`; otherwise only the rows the contexts read are held
/// ([`Window`]), not the whole band.
pub fn encode_rdo_with(
    e: &mut Encoder,
    dims: &[usize],
    parent: Option<Parent>,
    lambda: f32,
    coding: Coding,
    keep: bool,
    mut row: impl FnMut(usize, &mut [f32]),
) -> Option<Vec<i64>> {
    // the index choice reads the narrow classes' costs
    let classes = Classes::Narrow;
    open(e, coding, classes);
    let ctx = Ctx::new(dims, parent);
    let mut m = Models::new(classes);
    let w = ctx.walk;
    let mut r = Row::new(w.cols, classes);
    let mut q = Window::new(w, keep);
    let mut x = vec![0f32; w.cols];
    for p in 0..w.planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..w.rows {
            let g = p * w.rows + y;
            row(g, &mut x);
            ctx.prepare(&mut r, q.neighbours(&ctx, p, y, g), y, pbase);
            let out = q.row_mut(g);
            let (mut w1, mut w2) = (0, 0);
            for (xi, (o, &v)) in out.iter_mut().zip(&x).enumerate() {
                let c = r.context(xi, w1, w2);
                let a = choose(&m, v, c, lambda);
                let qv = if v < 0.0 { -a } else { a };
                encode_value(e, &mut m, qv, c);
                *o = qv;
                w2 = w1;
                w1 = qv;
            }
        }
    }
    keep.then_some(q.data)
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

/// The rows of a band being coded or decoded: all of them (`keep`), or a ring of the
/// last rows the contexts read (the row being coded, the two above it and, in a volume,
/// the same row of the previous plane, `rows` rows back): three rows of a 2-D band, a
/// plane and a row of a volume's.
struct Window {
    cols: usize,
    slots: usize,
    data: Vec<i64>,
}

impl Window {
    fn new(w: Walk, keep: bool) -> Self {
        let total = w.planes * w.rows;
        let slots = if keep {
            total
        } else if w.zdim > 0 && w.planes > 1 {
            w.rows.max(2) + 1
        } else {
            3
        }
        .min(total);
        Window {
            cols: w.cols,
            slots,
            data: vec![0; slots * w.cols],
        }
    }

    /// Row `g` (raster order over the planes' rows).
    #[inline]
    fn row(&self, g: usize) -> &[i64] {
        let at = (g % self.slots) * self.cols;
        &self.data[at..at + self.cols]
    }

    #[inline]
    fn row_mut(&mut self, g: usize) -> &mut [i64] {
        let at = (g % self.slots) * self.cols;
        &mut self.data[at..at + self.cols]
    }

    /// The neighbours of row `g`, row `y` of plane `p`.
    fn neighbours(&self, ctx: &Ctx, p: usize, y: usize, g: usize) -> Neighbours<'_> {
        Neighbours {
            n: (y > 0).then(|| self.row(g - 1)),
            nn: (y > 1).then(|| self.row(g - 2)),
            z: ctx.has_z(p).then(|| self.row(g - ctx.walk.rows)),
        }
    }
}

/// Decode one band written by [`encode`] or [`encode_rdo`] from `d` (a stream may end
/// early: its trailing zero bytes are left out, so reading past the end is no damage).
/// Fails on an exponent over 62.
pub fn decode(
    d: &mut Decoder,
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    coding: Coding,
) -> Result<Vec<i64>> {
    let coarse = kind == BandKind::Coarse;
    let n: usize = dims.iter().product();
    let mut v = vec![0i64; n];
    decode_rows(
        d,
        dims,
        if coarse { None } else { parent },
        coding,
        |at, row| v[at..at + row.len()].copy_from_slice(row),
    )?;
    if coarse {
        undo_median(&mut v, Walk::new(dims));
    }
    Ok(v)
}

/// Decode one detail band written by [`encode`] or [`encode_rdo`] a row at a time:
/// `row(at, values)` receives every row in raster order (`at` = the offset of its first
/// sample in the band), and only the rows its successors' contexts read are kept (three
/// rows of a 2-D band, a plane and a row of a volume's), not the whole band. Fails on an
/// exponent over 62.
pub fn decode_rows(
    d: &mut Decoder,
    dims: &[usize],
    parent: Option<Parent>,
    coding: Coding,
    mut row: impl FnMut(usize, &[i64]),
) -> Result<()> {
    let classes = opened(d, coding);
    let ctx = Ctx::new(dims, parent);
    let mut m = Models::new(classes);
    let w = ctx.walk;
    let mut q = Window::new(w, false);
    let mut r = Row::new(w.cols, classes);
    for p in 0..w.planes {
        let pbase = ctx.parent_base(p, dims);
        for y in 0..w.rows {
            let g = p * w.rows + y;
            ctx.prepare(&mut r, q.neighbours(&ctx, p, y, g), y, pbase);
            let out = q.row_mut(g);
            let (mut w1, mut w2) = (0, 0);
            for (x, o) in out.iter_mut().enumerate() {
                let v = decode_value(d, &mut m, r.context(x, w1, w2))?;
                *o = v;
                w2 = w1;
                w1 = v;
            }
            row(g * w.cols, out);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::entropy::walk::testing::sample;

    /// Several bands of 1 to 4 axes, with parents and extreme values, share one stream
    /// and come back exactly, in the order written.
    #[test]
    fn bands_sharing_a_stream_round_trip() {
        let shapes = crate::entropy::walk::testing::shapes();
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
                encode(&mut e, &q, dims, kind, Some(parent), Classes::Narrow);
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
            let back = decode(&mut d, dims, *kind, Some(parent), Coding::Narrow).unwrap();
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
                crate::entropy::walk::testing::lcg(&mut s);
                let u = ((s >> 40) as f32 / (1u64 << 24) as f32) - 0.5;
                // Laplacian-like: mostly small, some large, smooth in places
                let mag = (-(u.abs() + 1e-3).ln()) * if i % 7 == 0 { 4.0 } else { 0.6 };
                mag.copysign(u)
            })
            .collect();
        let mut e0 = Encoder::new();
        let q0 = encode_rdo(&mut e0, &x, &dims, None, 0.0, Coding::Narrow);
        let b0 = e0.finish();
        for (qi, xi) in q0.iter().zip(&x) {
            assert_eq!(*qi, (xi.abs() + 0.5).floor().copysign(*xi) as i64);
        }
        let mut e1 = Encoder::new();
        let q1 = encode_rdo(&mut e1, &x, &dims, None, 0.1, Coding::Narrow);
        let b1 = e1.finish();
        for ((a, b), xi) in q1.iter().zip(&q0).zip(&x) {
            assert!(*a == *b || *a == b - b.signum() || *a == 0, "{xi} {a} {b}");
        }
        assert!(b1.len() < b0.len(), "{} vs {}", b1.len(), b0.len());
        for (q, b) in [(&q0, &b0), (&q1, &b1)] {
            let mut d = Decoder::new(b);
            assert_eq!(
                &decode(&mut d, &dims, BandKind::Detail, None, Coding::Narrow).unwrap(),
                q
            );
        }
    }

    /// Coding a band with only the rows its contexts read ([`Window`]: three rows, or a
    /// plane and a row of a volume) writes the same stream as with the whole band kept
    /// and as the chosen indices coded whole, and [`decode_rows`] hands back the same
    /// rows as [`decode`]: 1-D to 4-D bands with a parent, planes along one and two
    /// outer axes.
    /// A band handed over a row at a time codes to the stream of the whole band, in
    /// both codings, with and without a parent, large indices included (the wide
    /// classes win on those).
    #[test]
    fn bands_handed_over_by_rows_code_as_whole_bands() {
        for dims in [
            vec![9usize],
            vec![1, 5],
            vec![11, 6],
            vec![5, 4, 6],
            vec![3, 1, 5],
            vec![2, 3, 2, 5],
        ] {
            let n: usize = dims.iter().product();
            let cols = *dims.last().unwrap();
            let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
            let pq = sample(pdims.iter().product(), 5, 4);
            for spread in [3, 5000] {
                let q = sample(n, n as u64 + spread as u64, spread);
                for parent in [
                    None,
                    Some(Parent {
                        data: &pq,
                        dims: &pdims,
                    }),
                ] {
                    for coding in [Coding::Narrow, Coding::Chosen] {
                        let whole = encode_stream(&q, &dims, BandKind::Detail, parent, coding);
                        let rows = encode_stream_rows(&dims, parent, coding, |g, out| {
                            out.copy_from_slice(&q[g * cols..(g + 1) * cols])
                        });
                        assert_eq!(rows, whole, "{dims:?} {spread} {coding:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn row_windows_code_and_decode_as_whole_bands() {
        let shapes = [
            vec![9usize],
            vec![1, 5],
            vec![2, 7],
            vec![11, 6],
            vec![5, 4, 6],
            vec![3, 1, 5],
            vec![4, 3, 2, 5],
        ];
        for dims in &shapes {
            let n: usize = dims.iter().product();
            let cols = *dims.last().unwrap();
            let x: Vec<f32> = sample(n, n as u64 + 3, 9)
                .iter()
                .enumerate()
                .map(|(i, &v)| v as f32 * 0.7 + (i % 3) as f32 * 0.2)
                .collect();
            let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
            let pq = sample(pdims.iter().product(), 5, 4);
            let parent = Parent {
                data: &pq,
                dims: &pdims,
            };
            let code = |keep: bool| {
                let mut e = Encoder::new();
                let q = encode_rdo_with(
                    &mut e,
                    dims,
                    Some(parent),
                    0.1,
                    Coding::Narrow,
                    keep,
                    |g, out| out.copy_from_slice(&x[g * cols..(g + 1) * cols]),
                );
                (q, e.finish_short())
            };
            let (q, whole) = code(true);
            let (none, windowed) = code(false);
            let q = q.unwrap();
            assert!(none.is_none());
            assert_eq!(whole, windowed, "{dims:?}");
            assert!(q.iter().any(|&v| v != 0), "{dims:?}");
            // the chosen indices coded as given (contexts read from the whole band)
            let mut e = Encoder::new();
            encode(
                &mut e,
                &q,
                dims,
                BandKind::Detail,
                Some(parent),
                Classes::Narrow,
            );
            assert_eq!(e.finish_short(), whole, "{dims:?}");
            let back = decode(
                &mut Decoder::new_short(&whole),
                dims,
                BandKind::Detail,
                Some(parent),
                Coding::Narrow,
            )
            .unwrap();
            assert_eq!(back, q, "{dims:?}");
            let mut rows = vec![0i64; n];
            let mut seen = 0;
            decode_rows(
                &mut Decoder::new_short(&whole),
                dims,
                Some(parent),
                Coding::Narrow,
                |at, r| {
                    assert_eq!(at, seen, "{dims:?}");
                    rows[at..at + r.len()].copy_from_slice(r);
                    seen += r.len();
                },
            )
            .unwrap();
            assert_eq!(seen, n);
            assert_eq!(rows, q, "{dims:?}");
        }
    }

    /// In format 2.3's coding a band of large indices whose scale varies across it
    /// (16-bit lossless details) takes the wide classes, in fewer bytes than the narrow
    /// ones; a band of small indices keeps the narrow ones (equal streams but for the
    /// selector bit: the tie goes to narrow); both decode exactly.
    #[test]
    fn chosen_classes_are_wide_for_large_indices_and_narrow_for_small_ones() {
        let dims = [48usize, 64];
        let n = 48 * 64;
        let mut s = 5u64;
        let big: Vec<i64> = (0..n)
            .map(|i| {
                crate::entropy::walk::testing::lcg(&mut s);
                let r = (s >> 33) as i64;
                let scale = 1i64 << ((i % 64) / 6);
                (r % 9 - 4) * scale + r % 3
            })
            .collect();
        let small = sample(n, 3, 3);
        for (q, wide) in [(&big, true), (&small, false)] {
            let chosen = encode_stream(q, &dims, BandKind::Detail, None, Coding::Chosen);
            let narrow = encode_stream(q, &dims, BandKind::Detail, None, Coding::Narrow);
            assert_eq!(Decoder::new_short(&chosen).raw(), wide);
            if wide {
                assert!(
                    chosen.len() < narrow.len(),
                    "{} vs {}",
                    chosen.len(),
                    narrow.len()
                );
            } else {
                assert!(chosen.len() <= narrow.len() + 1);
            }
            let mut d = Decoder::new_short(&chosen);
            let back = decode(&mut d, &dims, BandKind::Detail, None, Coding::Chosen).unwrap();
            assert_eq!(&back, q);
            let mut d = Decoder::new_short(&narrow);
            let back = decode(&mut d, &dims, BandKind::Detail, None, Coding::Narrow).unwrap();
            assert_eq!(&back, q);
        }
    }

    #[test]
    fn garbage_never_panics() {
        let dims = [13usize, 17];
        for seed in 0..50u64 {
            let bytes: Vec<u8> = sample(40, seed, 128).iter().map(|&v| v as u8).collect();
            let _ = decode(
                &mut Decoder::new(&bytes),
                &dims,
                BandKind::Detail,
                None,
                Coding::Chosen,
            );
            let _ = decode(
                &mut Decoder::new(&bytes),
                &dims,
                BandKind::Coarse,
                None,
                Coding::Narrow,
            );
        }
    }
}
