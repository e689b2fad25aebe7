//! Code-blocks of format 3 (formats/MRA.md §15): a band cut into independent boxes,
//! each coded by [`super::band`] as a band of its own (fresh models, positions outside
//! the box read as 0, a coarse band's LOCO-I prediction within the box), so that blocks
//! code and decode in parallel and a region decodes only the blocks it needs.
//!
//! A block of a detail band reads its parent context from the **parent box**: on each
//! axis, the block's range `[lo, hi)` maps to `[min(lo/2, P−1), min(⌈hi/2⌉, P))` of the
//! parent band of extent `P` (block extents are even, so the parent of a position in
//! the box is the parent of the same position in the band, clamped as in §9).

use super::band::{self, Coding};
use super::block;
use super::range::Decoder;
use super::{BandKind, Parent};
use crate::format::header::CODERS;
use crate::tensor::for_each_run;
use crate::Result;
use rayon::prelude::*;
use std::ops::Range;

/// The coder of every code-block of a file: the `HEAD`'s coder byte of format 3.1
/// (formats/MRA.md §15.1; a 3.0 file is [`Coder::Context`]). The id is the byte; the
/// names are [`CODERS`]'.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Coder {
    /// 0: today's adaptive context coder ([`band`], §9 and §9.1), on `i64` indices.
    #[default]
    Context = 0,
    /// 1: the HT-style coder ([`block::ht`] with its standard codes): static prefix
    /// codes and a run coder on `i32` indices, about 4× the context coder's decode
    /// speed for 7–10% more bits.
    Ht = 1,
    /// 2: the adaptive quad coder ([`block::quad`] with [`block::Shape::coder2`]):
    /// 16-symbol adaptive CDFs from trained priors, the parent as a context, signs in
    /// the context of the W and N signs, on `i32` indices.
    Adaptive = 2,
}

/// A narrow coder's encoder of a block (values, extents, kind, parent box).
type NarrowEncode = fn(&[i32], &[usize], BandKind, Option<block::Parent>) -> Vec<u8>;
/// A narrow coder's decoder of a block (stream, extents, kind, parent box).
type NarrowDecode = fn(&[u8], &[usize], BandKind, Option<block::Parent>) -> Result<Vec<i32>>;
/// A narrow coder's rate–distortion optimised encoder of a detail block (values over
/// the step, extents, parent box, λ): its stream and the indices it chose by its own
/// costs.
type NarrowRdo = fn(&[f32], &[usize], Option<block::Parent>, f32) -> (Vec<u8>, Vec<i32>);

/// How one block is coded: by the context coder, or by a coder of `i32` blocks (its
/// encoder and decoder of a block as a band of its own, as [`block::encode_ht`]).
#[derive(Clone, Copy)]
enum PerBlock {
    Context,
    Narrow {
        encode: NarrowEncode,
        decode: NarrowDecode,
        /// `None`: the indices are chosen by the context coder's costs
        rdo: Option<NarrowRdo>,
    },
}

/// A code-block as one block of the HT coder: no inner split.
fn whole() -> block::Shape {
    block::Shape::new(1 << 30, 1 << 30, 1 << 30)
}

impl Coder {
    /// Every coder, by id.
    pub const ALL: [Coder; 3] = [Coder::Context, Coder::Ht, Coder::Adaptive];

    /// The coder byte.
    pub fn id(self) -> u8 {
        self as u8
    }

    /// The coder of byte `id`; `None` for an id this reader does not know.
    pub fn of(id: u8) -> Option<Coder> {
        Coder::ALL.into_iter().find(|c| c.id() == id)
    }

    /// Its name in formats/MRA.md's table (`mra info`).
    pub fn name(self) -> &'static str {
        CODERS[self as usize]
    }

    /// Whether the coder takes `i32` indices: a writer gives such a coder only to a
    /// file whose indices fit (indices outside are saturated).
    pub fn is_narrow(self) -> bool {
        !matches!(self.per_block(), PerBlock::Context)
    }

    /// Whether the coder chooses a detail block's indices by its own costs (coder 2,
    /// [`block::encode_rdo`]) when they are rate–distortion optimised; else the context
    /// coder's choice is coded.
    pub fn chooses_its_indices(self) -> bool {
        matches!(self.per_block(), PerBlock::Narrow { rdo: Some(_), .. })
    }

    /// The one place a coder's block functions are named: a new coder is one arm.
    fn per_block(self) -> PerBlock {
        match self {
            Coder::Context => PerBlock::Context,
            Coder::Ht => PerBlock::Narrow {
                encode: |v, d, k, p| {
                    block::encode_ht(v, d, k, p, whole(), block::ht::Tables::standard(), None)
                },
                decode: |s, d, k, p| {
                    block::decode_ht(s, d, k, p, whole(), block::ht::Tables::standard())
                },
                rdo: None,
            },
            Coder::Adaptive => PerBlock::Narrow {
                encode: |v, d, k, p| block::encode(v, d, k, p, block::Shape::coder2()),
                decode: |s, d, k, p| block::decode(s, d, k, p, block::Shape::coder2()),
                rdo: Some(|x, d, p, lambda| {
                    block::encode_rdo(x, d, p, block::Shape::coder2(), lambda)
                }),
            },
        }
    }
}

/// `v` as `i32` indices, saturated.
fn narrow(v: &[i64]) -> Vec<i32> {
    v.iter()
        .map(|&x| x.clamp(i32::MIN as i64, i32::MAX as i64) as i32)
        .collect()
}

/// Code the block of values `v` (extents `d`, parent box `par`: its indices and
/// extents) by `coder`: one block of [`encode_blocks`].
pub fn encode_one(
    coder: Coder,
    v: &[i64],
    d: &[usize],
    kind: BandKind,
    par: Option<&(Vec<i64>, Vec<usize>)>,
    coding: Coding,
) -> Vec<u8> {
    match coder.per_block() {
        PerBlock::Context => {
            let pp = par.map(|(data, dims)| Parent { data, dims });
            band::encode_stream(v, d, kind, pp, coding)
        }
        PerBlock::Narrow { encode, .. } => {
            let pn = par.map(|(data, dims)| (narrow(data), dims));
            let pp = pn.as_ref().map(|(data, dims)| block::Parent { data, dims });
            encode(&narrow(v), d, kind, pp)
        }
    }
}

/// The block extents of a band of `nd` axes for a 2-D block side `side2` and a volume
/// block `vol` (Z, Y, X): 1-D bands `side2²`, 2-D bands `side2 × side2`, bands of three
/// axes or more `vol` on the last three and 1 on the others.
pub fn block_shape(nd: usize, side2: usize, vol: [usize; 3]) -> Vec<usize> {
    match nd {
        0 => vec![],
        1 => vec![side2 * side2],
        2 => vec![side2, side2],
        _ => {
            let mut b = vec![1; nd - 3];
            b.extend_from_slice(&vol);
            b
        }
    }
}

/// The grid of code-blocks of one band: blocks of `block` extents (the last ones cut
/// by the band's edge), numbered in raster order of their grid coordinates.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Grid {
    pub dims: Vec<usize>,
    pub block: Vec<usize>,
    /// blocks per axis
    pub counts: Vec<usize>,
}

impl Grid {
    /// The grid of a band of extents `dims` (every extent of `block` ≥ 1).
    pub fn new(dims: &[usize], block: &[usize]) -> Grid {
        debug_assert_eq!(dims.len(), block.len());
        let counts = dims
            .iter()
            .zip(block)
            .map(|(&d, &b)| d.div_ceil(b.max(1)))
            .collect();
        Grid {
            dims: dims.to_vec(),
            block: block.iter().map(|&b| b.max(1)).collect(),
            counts,
        }
    }

    /// The number of blocks (0 for an empty band).
    pub fn len(&self) -> usize {
        self.counts.iter().product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The box of block `i`.
    pub fn bounds(&self, i: usize) -> Vec<Range<usize>> {
        let mut rem = i;
        let mut out = vec![0..0; self.dims.len()];
        for k in (0..self.dims.len()).rev() {
            let c = rem % self.counts[k];
            rem /= self.counts[k];
            let lo = c * self.block[k];
            out[k] = lo..(lo + self.block[k]).min(self.dims[k]);
        }
        out
    }

    /// The blocks (ascending) whose box meets `window` (one range per axis; every
    /// block when it has not one per axis).
    pub fn touching(&self, window: &[Range<usize>]) -> Vec<usize> {
        if window.len() != self.dims.len() {
            return (0..self.len()).collect();
        }
        let spans: Vec<Range<usize>> = (0..self.dims.len())
            .map(|k| {
                let w = &window[k];
                let hi = w.end.min(self.dims[k]);
                if w.start >= hi {
                    0..0
                } else {
                    w.start / self.block[k]..hi.div_ceil(self.block[k])
                }
            })
            .collect();
        let mut out = Vec::new();
        if spans.iter().any(|s| s.is_empty()) {
            return out;
        }
        let mut c: Vec<usize> = spans.iter().map(|s| s.start).collect();
        loop {
            out.push(c.iter().zip(&self.counts).fold(0, |a, (&x, &n)| a * n + x));
            let mut k = c.len();
            loop {
                if k == 0 {
                    return out;
                }
                k -= 1;
                c[k] += 1;
                if c[k] < spans[k].end {
                    break;
                }
                c[k] = spans[k].start;
            }
        }
    }
}

/// The parent box of a block box `b` in a parent band of extents `pdims` (module doc).
pub fn parent_box(b: &[Range<usize>], pdims: &[usize]) -> Vec<Range<usize>> {
    b.iter()
        .zip(pdims)
        .map(|(r, &p)| {
            let last = p.saturating_sub(1);
            (r.start / 2).min(last)..r.end.div_ceil(2).min(p)
        })
        .collect()
}

/// The values of box `b` of an array of extents `dims` (raster order).
pub fn extract<T: Copy + Default>(v: &[T], dims: &[usize], b: &[Range<usize>]) -> Vec<T> {
    let n: usize = b.iter().map(|r| r.len()).product();
    let mut out = Vec::with_capacity(n);
    for_each_run(dims, b, |at, len, _| {
        out.extend_from_slice(&v[at..at + len])
    });
    out
}

/// Write `src` (raster order over box `b`) into an array of extents `dims`.
pub fn insert<T: Copy>(v: &mut [T], dims: &[usize], b: &[Range<usize>], src: &[T]) {
    let mut from = 0;
    for_each_run(dims, b, |at, len, _| {
        v[at..at + len].copy_from_slice(&src[from..from + len]);
        from += len;
    });
}

/// The dims of a box.
pub fn box_dims(b: &[Range<usize>]) -> Vec<usize> {
    b.iter().map(|r| r.len()).collect()
}

/// The parent of block box `b` as its own band (values of the parent box).
fn parent_of(b: &[Range<usize>], parent: Option<Parent>) -> Option<(Vec<i64>, Vec<usize>)> {
    parent_in(b, parent, None)
}

/// The parent of block box `b` as its own band, from a parent band (`parent.dims` its
/// extents) whose indices `parent.data` are held over the box `held` of it (raster order
/// over the box; `None`: the whole band). `None` when the parent box is not inside `held`.
fn parent_in(
    b: &[Range<usize>],
    parent: Option<Parent>,
    held: Option<&[Range<usize>]>,
) -> Option<(Vec<i64>, Vec<usize>)> {
    let p = parent?;
    if p.dims.len() != b.len() || p.dims.contains(&0) {
        return None;
    }
    let pb = parent_box(b, p.dims);
    let Some(held) = held else {
        return Some((extract(p.data, p.dims, &pb), box_dims(&pb)));
    };
    let hd = box_dims(held);
    if held.len() != pb.len()
        || hd.iter().product::<usize>() != p.data.len()
        || pb
            .iter()
            .zip(held)
            .any(|(r, h)| r.start < h.start || r.end > h.end)
    {
        return None;
    }
    let local: Vec<Range<usize>> = pb
        .iter()
        .zip(held)
        .map(|(r, h)| r.start - h.start..r.end - h.start)
        .collect();
    Some((extract(p.data, &hd, &local), box_dims(&pb)))
}

/// Code every block of band `q` (extents `grid.dims`) in parallel: one stream per block
/// in block order ([`band::encode_stream`] of the block's values).
pub fn encode_blocks(
    q: &[i64],
    grid: &Grid,
    kind: BandKind,
    parent: Option<Parent>,
    coding: Coding,
    coder: Coder,
) -> Vec<Vec<u8>> {
    encode_blocks_by(grid, kind, parent, coding, coder, |b| {
        extract(q, &grid.dims, b)
    })
}

/// [`encode_blocks`] with the values of the block of box `b` (raster order over the
/// box) given by `values(b)`, so that the band is never copied whole.
pub fn encode_blocks_by(
    grid: &Grid,
    kind: BandKind,
    parent: Option<Parent>,
    coding: Coding,
    coder: Coder,
    values: impl Fn(&[Range<usize>]) -> Vec<i64> + Sync,
) -> Vec<Vec<u8>> {
    (0..grid.len())
        .into_par_iter()
        .map(|i| {
            let b = grid.bounds(i);
            let d = box_dims(&b);
            let v = values(&b);
            let par = if kind == BandKind::Coarse {
                None
            } else {
                parent_of(&b, parent)
            };
            encode_one(coder, &v, &d, kind, par.as_ref(), coding)
        })
        .collect()
}

/// Choose (rate–distortion optimised, [`band::encode_rdo`]) and code the indices of
/// every block of a detail band whose values divided by the step are `x`, in parallel:
/// the streams in block order and the band's indices. A coder with its own
/// rate–distortion choice (coder 2, [`block::encode_rdo`]) chooses by its own costs;
/// another coder than [`Coder::Context`] (HT) codes the indices the context coder
/// would choose.
pub fn encode_blocks_rdo(
    x: &[f32],
    grid: &Grid,
    parent: Option<Parent>,
    lambda: f32,
    coding: Coding,
    coder: Coder,
) -> (Vec<Vec<u8>>, Vec<i64>) {
    let (streams, q) = encode_blocks_rdo_by(grid, parent, lambda, coding, coder, true, |b| {
        extract(x, &grid.dims, b)
    });
    (streams, q.unwrap_or_default())
}

/// [`encode_blocks_rdo`] with the values (over the step) of the block of box `b` given
/// by `values(b)`; the band's indices only when `keep` (a band no other band reads as
/// its parent need not hold them).
pub fn encode_blocks_rdo_by(
    grid: &Grid,
    parent: Option<Parent>,
    lambda: f32,
    coding: Coding,
    coder: Coder,
    keep: bool,
    values: impl Fn(&[Range<usize>]) -> Vec<f32> + Sync,
) -> (Vec<Vec<u8>>, Option<Vec<i64>>) {
    let coded: Vec<(Vec<u8>, Vec<i64>)> = (0..grid.len())
        .into_par_iter()
        .map(|i| {
            let b = grid.bounds(i);
            let d = box_dims(&b);
            let par = parent_of(&b, parent);
            encode_one_rdo(coder, &values(&b), &d, par.as_ref(), lambda, coding, keep)
        })
        .collect();
    let mut q = keep.then(|| vec![0i64; grid.dims.iter().product()]);
    let mut streams = Vec::with_capacity(coded.len());
    for (i, (s, qb)) in coded.into_iter().enumerate() {
        if let Some(q) = q.as_mut() {
            insert(q, &grid.dims, &grid.bounds(i), &qb);
        }
        streams.push(s);
    }
    (streams, q)
}

/// Choose (rate–distortion optimised) and code the indices of the detail block whose
/// values divided by the step are `v` (extents `d`, parent box `par`: its indices and
/// extents) by `coder`: one block of [`encode_blocks_rdo`], its stream and, when
/// `keep`, its indices (else empty).
pub fn encode_one_rdo(
    coder: Coder,
    v: &[f32],
    d: &[usize],
    par: Option<&(Vec<i64>, Vec<usize>)>,
    lambda: f32,
    coding: Coding,
    keep: bool,
) -> (Vec<u8>, Vec<i64>) {
    if let PerBlock::Narrow { rdo: Some(rdo), .. } = coder.per_block() {
        let pn = par.map(|(data, dims)| (narrow(data), dims));
        let pp = pn.as_ref().map(|(data, dims)| block::Parent { data, dims });
        let (s, qb) = rdo(v, d, pp, lambda);
        let qb = if keep {
            qb.into_iter().map(i64::from).collect()
        } else {
            Vec::new()
        };
        return (s, qb);
    }
    let pp = par.map(|(data, dims)| Parent { data, dims });
    let mut e = super::range::Encoder::new();
    let cols = d.last().copied().unwrap_or(1);
    let other = coder != Coder::Context;
    let q = band::encode_rdo_with(&mut e, d, pp, lambda, coding, keep || other, |g, out| {
        out.copy_from_slice(&v[g * cols..(g + 1) * cols])
    });
    let q = q.unwrap_or_default();
    if other {
        let s = encode_one(coder, &q, d, BandKind::Detail, par, coding);
        return (s, if keep { q } else { Vec::new() });
    }
    (e.finish_short(), q)
}

/// Decode blocks `which` (ascending block numbers; their streams `streams[k]` for
/// `which[k]`) of a band straight into `out` (extents `grid.dims`; the other positions
/// are left as they are): [`decode_blocks_into`] over the rows of `out`, each index
/// copied.
// the band, its blocks and their streams, their coding: one call per band entry
#[allow(clippy::too_many_arguments)]
pub fn decode_blocks(
    out: &mut [i64],
    grid: &Grid,
    which: &[usize],
    streams: &[&[u8]],
    kind: BandKind,
    parent: Option<Parent>,
    coding: Coding,
    coder: Coder,
) -> Result<()> {
    if grid.dims.is_empty() || out.len() != grid.dims.iter().product::<usize>() || out.is_empty() {
        return Ok(());
    }
    let cols = grid.dims[grid.dims.len() - 1].max(1);
    let rows: Vec<&mut [i64]> = out.chunks_mut(cols).collect();
    let put = Put {
        wide: |o: &mut [i64], v: &[i64]| o.copy_from_slice(v),
        narrow: |o: &mut [i64], v: &[i32]| {
            for (o, &x) in o.iter_mut().zip(v) {
                *o = x as i64;
            }
        },
    };
    decode_blocks_into(
        rows,
        grid,
        which,
        streams,
        (kind, parent),
        coding,
        coder,
        &put,
    )
}

/// How [`decode_blocks_into`] writes a run of decoded indices into a run of the output
/// of the same length: `wide` from the context coder's `i64` indices, `narrow` from a
/// narrow coder's `i32` ones (a copy, or the dequantization into a plane's samples).
pub struct Put<W, N> {
    /// Writes `i64` indices.
    pub wide: W,
    /// Writes `i32` indices.
    pub narrow: N,
}

/// Decode blocks `which` (ascending block numbers; their streams `streams[k]` for
/// `which[k]`) of a band of kind and parent `(kind, parent)` into `rows`, the band's
/// rows in raster order (each as long as the band's last extent; a 1-D band is one
/// row), through `put` (the positions of other blocks are left as they are). The band is
/// cut into slabs of `block[0]` along its first axis, each its own rows: the slabs
/// decode in parallel, the blocks of a slab one after another, a detail block a row at a
/// time ([`band::decode_rows`]) into its rows of the band (a coarse block whole, its
/// LOCO-I prediction undone over the box). The parent band must hold the parent boxes
/// of those blocks. A block of a narrow coder ([`Coder::is_narrow`]) decodes whole into
/// its box. No band-sized buffer is made: a plane's rows take the indices directly.
#[allow(clippy::too_many_arguments)]
pub fn decode_blocks_into<T, W, N>(
    rows: Vec<&mut [T]>,
    grid: &Grid,
    which: &[usize],
    streams: &[&[u8]],
    (kind, parent): (BandKind, Option<Parent>),
    coding: Coding,
    coder: Coder,
    put: &Put<W, N>,
) -> Result<()>
where
    T: Send,
    W: Fn(&mut [T], &[i64]) + Sync,
    N: Fn(&mut [T], &[i32]) + Sync,
{
    let band: Vec<Range<usize>> = grid.dims.iter().map(|&e| 0..e).collect();
    let over = Over {
        rows: &band,
        parent: None,
    };
    decode_blocks_over(
        rows,
        &over,
        grid,
        which,
        streams,
        (kind, parent),
        (coding, coder),
        put,
    )
}

/// Whether a block of `which` has its parent box outside the box `held` of the parent
/// band that the parent's indices cover.
fn parent_outside(
    grid: &Grid,
    which: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    held: Option<&[Range<usize>]>,
) -> bool {
    let (Some(p), Some(held), BandKind::Detail) = (parent, held, kind) else {
        return false;
    };
    if held.len() != p.dims.len() || box_dims(held).iter().product::<usize>() != p.data.len() {
        return true;
    }
    which.iter().any(|&i| {
        parent_box(&grid.bounds(i), p.dims)
            .iter()
            .zip(held)
            .any(|(r, h)| r.start < h.start || r.end > h.end)
    })
}

/// The boxes [`decode_blocks_over`] works on (band coordinates): `rows`, the box of the
/// band its rows cover (block-aligned: its start a multiple of the block on every
/// axis), and `parent`, the box of the parent band its parent's indices hold (`None`:
/// the whole parent band).
pub struct Over<'a> {
    /// The box of the band the output rows cover.
    pub rows: &'a [Range<usize>],
    /// The box of the parent band the parent's `data` holds.
    pub parent: Option<&'a [Range<usize>]>,
}

/// [`decode_blocks_into`] over a box of the band: `rows` are the rows of `over.rows`
/// (raster order over the box, each as long as its last extent), every block of
/// `which` inside it, and the parent's indices held over `over.parent` (each block's
/// parent box inside it). Buffers the size of the blocks' boxes stand for the band's.
#[allow(clippy::too_many_arguments)]
pub fn decode_blocks_over<T, W, N>(
    rows: Vec<&mut [T]>,
    over: &Over,
    grid: &Grid,
    which: &[usize],
    streams: &[&[u8]],
    (kind, parent): (BandKind, Option<Parent>),
    (coding, coder): (Coding, Coder),
    put: &Put<W, N>,
) -> Result<()>
where
    T: Send,
    W: Fn(&mut [T], &[i64]) + Sync,
    N: Fn(&mut [T], &[i32]) + Sync,
{
    let nd = grid.dims.len();
    if nd == 0 || grid.dims.contains(&0) || over.rows.len() != nd {
        return Ok(());
    }
    let bx = over.rows;
    let bd = box_dims(bx);
    let outside = |b: &[Range<usize>]| {
        b.iter()
            .zip(bx)
            .any(|(r, o)| r.start < o.start || r.end > o.end)
    };
    if bd.contains(&0)
        || bx
            .iter()
            .zip(&grid.block)
            .zip(&grid.dims)
            .any(|((r, &b), &e)| r.start % b != 0 || r.end > e)
        || which.iter().any(|&i| outside(&grid.bounds(i)))
        || parent_outside(grid, which, kind, parent, over.parent)
    {
        return Err(crate::Error::format(
            "code-blocks outside the box decoded",
            "blocks inside a block-aligned box",
        ));
    }
    let cols = bd[nd - 1];
    // rows per plane of the first axis
    let inner: usize = bd[1.min(nd - 1)..nd - 1].iter().product();
    let nrows: usize = bd[..nd - 1].iter().product();
    if rows.len() != nrows.max(1) || rows.iter().any(|r| r.len() != cols) {
        return Ok(());
    }
    let per_slab: usize = grid.counts[1..].iter().product();
    // the first slab of the box
    let s0 = bx[0].start / grid.block[0];
    // the blocks of each slab (counted from the box's first), by their place in `which`
    let mut slabs: Vec<(usize, Vec<usize>)> = Vec::new();
    for (k, &i) in which.iter().enumerate() {
        let s = i / per_slab.max(1) - s0;
        match slabs.last_mut() {
            Some((at, v)) if *at == s => v.push(k),
            _ => slabs.push((s, vec![k])),
        }
    }
    // each slab's rows: `block[0]` planes of rows, or pieces of a 1-D band's one row
    let mut parts: Vec<Option<Vec<&mut [T]>>> = if nd == 1 {
        let row = rows.into_iter().next().expect("one row");
        row.chunks_mut(grid.block[0].max(1))
            .map(|c| Some(vec![c]))
            .collect()
    } else {
        let per = grid.block[0].max(1) * inner;
        let mut it = rows.into_iter();
        let mut parts = Vec::new();
        loop {
            let part: Vec<&mut [T]> = it.by_ref().take(per).collect();
            if part.is_empty() {
                break;
            }
            parts.push(Some(part));
        }
        parts
    };
    // each slab: its number, its rows of the output and the blocks it holds
    type Slab<'r, T> = (usize, Vec<&'r mut [T]>, Vec<usize>);
    let work: Vec<Slab<T>> = slabs
        .into_iter()
        .filter_map(|(s, ks)| Some((s, parts.get_mut(s)?.take()?, ks)))
        .collect();
    let failed: Vec<Result<()>> = work
        .into_par_iter()
        .map(|(s, mut slab, ks)| {
            // the slab's extents, its rows' length, and the row and column of an offset
            let len = slab[0].len().max(1);
            let mut shape = bd.clone();
            shape[0] = if nd == 1 {
                slab[0].len()
            } else {
                slab.len() / inner
            };
            let y0 = (s + s0) * grid.block[0];
            for k in ks {
                let b = grid.bounds(which[k]);
                let d = box_dims(&b);
                let mut local: Vec<Range<usize>> = b
                    .iter()
                    .zip(bx)
                    .map(|(r, o)| r.start - o.start..r.end - o.start)
                    .collect();
                local[0] = b[0].start - y0..b[0].end - y0;
                if let PerBlock::Narrow { decode, .. } = coder.per_block() {
                    let par = if kind == BandKind::Coarse {
                        None
                    } else {
                        parent_in(&b, parent, over.parent).map(|(data, dims)| (narrow(&data), dims))
                    };
                    let pp = par
                        .as_ref()
                        .map(|(data, dims)| block::Parent { data, dims });
                    let v = decode(streams[k], &d, kind, pp)?;
                    for_each_run(&shape, &local, |at, n, from| {
                        let (r, c) = (at / len, at % len);
                        (put.narrow)(&mut slab[r][c..c + n], &v[from..from + n]);
                    });
                    continue;
                }
                let mut dec = Decoder::new_short(streams[k]);
                if kind == BandKind::Coarse {
                    let v = band::decode(&mut dec, &d, kind, None, coding)?;
                    for_each_run(&shape, &local, |at, n, from| {
                        let (r, c) = (at / len, at % len);
                        (put.wide)(&mut slab[r][c..c + n], &v[from..from + n]);
                    });
                    continue;
                }
                let par = parent_in(&b, parent, over.parent);
                let pp = par.as_ref().map(|(data, dims)| Parent { data, dims });
                let mut starts = Vec::with_capacity(d[..nd - 1].iter().product());
                for_each_run(&shape, &local, |at, _, _| starts.push(at));
                let run = d[nd - 1].max(1);
                band::decode_rows(&mut dec, &d, pp, coding, |at, v| {
                    let o = starts[at / run];
                    let (r, c) = (o / len, o % len);
                    (put.wide)(&mut slab[r][c..c + v.len()], v);
                })?;
            }
            Ok(())
        })
        .collect();
    failed.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::entropy::walk::testing::sample;

    /// A block's parent box gives every position of the block the parent value the
    /// whole band's clamped mapping gives (§9), on odd and uneven extents.
    #[test]
    fn parent_box_maps_as_the_whole_band() {
        for (n, p, blk) in [(9, 5, 4), (5, 2, 4), (10, 4, 2), (7, 4, 6), (3, 1, 2)] {
            let g = Grid::new(&[n], &[blk]);
            for i in 0..g.len() {
                let b = g.bounds(i);
                let pb = parent_box(&b, &[p]);
                let len = pb[0].len();
                assert!(len >= 1);
                for y in b[0].clone() {
                    let local = ((y - b[0].start) / 2).min(len - 1);
                    assert_eq!(pb[0].start + local, (y / 2).min(p - 1), "{n} {p} {blk} {y}");
                }
            }
        }
    }

    /// The band shapes (1- to 4-D, odd extents, partial edge blocks) and block extents
    /// the code-block tests run on.
    fn band_shapes() -> [(Vec<usize>, Vec<usize>); 4] {
        [
            (vec![37], vec![8]),
            (vec![13, 17], vec![4, 6]),
            (vec![5, 9, 7], vec![2, 4, 4]),
            (vec![2, 3, 5, 6], vec![1, 2, 2, 4]),
        ]
    }

    /// Blocks of 1- to 4-D bands, coarse and detail, with a parent, decode to the band;
    /// decoding a subset fills exactly those boxes; `touching` finds the blocks a
    /// window meets.
    #[test]
    fn blocks_round_trip_and_subsets_fill_their_boxes() {
        for (dims, block) in band_shapes() {
            let n: usize = dims.iter().product();
            let q = sample(n, n as u64, 40);
            let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
            let pq = sample(pdims.iter().product(), 3, 3);
            let parent = Some(Parent {
                data: &pq,
                dims: &pdims,
            });
            let grid = Grid::new(&dims, &block);
            for (kind, coder) in [BandKind::Coarse, BandKind::Detail]
                .into_iter()
                .flat_map(|k| Coder::ALL.map(|c| (k, c)))
            {
                let s = encode_blocks(&q, &grid, kind, parent, Coding::Chosen, coder);
                assert_eq!(s.len(), grid.len());
                let all: Vec<usize> = (0..grid.len()).collect();
                let refs: Vec<&[u8]> = s.iter().map(|v| v.as_slice()).collect();
                let mut out = vec![0i64; n];
                let c = Coding::Chosen;
                decode_blocks(&mut out, &grid, &all, &refs, kind, parent, c, coder).unwrap();
                assert_eq!(out, q, "{dims:?} {kind:?} {coder:?}");
                let win: Vec<Range<usize>> = dims.iter().map(|&d| d / 3..d / 2 + 1).collect();
                let some = grid.touching(&win);
                assert!(!some.is_empty());
                let refs: Vec<&[u8]> = some.iter().map(|&i| s[i].as_slice()).collect();
                let mut part = vec![i64::MIN; n];
                decode_blocks(&mut part, &grid, &some, &refs, kind, parent, c, coder).unwrap();
                let mut mask = vec![false; n];
                for &i in &some {
                    let b = grid.bounds(i);
                    insert(
                        &mut mask,
                        &dims,
                        &b,
                        &vec![true; box_dims(&b).iter().product()],
                    );
                }
                for ((&m, &got), &want) in mask.iter().zip(&part).zip(&q) {
                    assert_eq!(got, if m { want } else { i64::MIN });
                }
                // every position of the window is in a touching block
                let mut inwin = vec![false; n];
                insert(
                    &mut inwin,
                    &dims,
                    &win,
                    &vec![true; box_dims(&win).iter().product()],
                );
                assert!(inwin.iter().zip(&mask).all(|(&w, &m)| !w || m));
            }
        }
    }

    /// `decode_blocks_over` decodes the blocks of a block-aligned box into a buffer of
    /// the box alone, its parent context read from a box of the parent band: the values
    /// of the same box of the whole band's decode, on 1- to 4-D bands, every coder,
    /// boxes at the start, middle and end; a block outside the box, or a parent box
    /// outside the parent's held box, is an error.
    #[test]
    fn blocks_decode_over_a_box_with_a_held_parent() {
        for (dims, block) in band_shapes() {
            let n: usize = dims.iter().product();
            let nd = dims.len();
            let q = sample(n, n as u64 + 11, 40);
            let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
            let pq = sample(pdims.iter().product(), 9, 3);
            let parent = Some(Parent {
                data: &pq,
                dims: &pdims,
            });
            let grid = Grid::new(&dims, &block);
            let copy = Put {
                wide: |o: &mut [i64], v: &[i64]| o.copy_from_slice(v),
                narrow: |o: &mut [i64], v: &[i32]| {
                    for (o, &x) in o.iter_mut().zip(v) {
                        *o = x as i64;
                    }
                },
            };
            for coder in Coder::ALL {
                let kind = BandKind::Detail;
                let s = encode_blocks(&q, &grid, kind, parent, Coding::Chosen, coder);
                let windows: Vec<Vec<Range<usize>>> = vec![
                    dims.iter().map(|_| 0..1).collect(),
                    dims.iter().map(|&d| d / 3..d / 2 + 1).collect(),
                    dims.iter().map(|&d| d - 1..d).collect(),
                ];
                for win in windows {
                    let which = grid.touching(&win);
                    let bx: Vec<Range<usize>> = win
                        .iter()
                        .zip(&block)
                        .zip(&dims)
                        .map(|((r, &b), &e)| {
                            r.start / b * b..r.end.div_ceil(b).saturating_mul(b).min(e)
                        })
                        .collect();
                    let refs: Vec<&[u8]> = which.iter().map(|&i| s[i].as_slice()).collect();
                    // the parent held over the hull of the blocks' parent boxes
                    let mut held = parent_box(&grid.bounds(which[0]), &pdims);
                    for &i in &which[1..] {
                        for (h, r) in held.iter_mut().zip(parent_box(&grid.bounds(i), &pdims)) {
                            *h = h.start.min(r.start)..h.end.max(r.end);
                        }
                    }
                    let pheld = extract(&pq, &pdims, &held);
                    let bd = box_dims(&bx);
                    let mut out = vec![i64::MIN; bd.iter().product()];
                    let rows: Vec<&mut [i64]> = out.chunks_mut(bd[nd - 1]).collect();
                    let over = Over {
                        rows: &bx,
                        parent: Some(&held),
                    };
                    let par = Some(Parent {
                        data: &pheld,
                        dims: &pdims,
                    });
                    let at = (Coding::Chosen, coder);
                    decode_blocks_over(rows, &over, &grid, &which, &refs, (kind, par), at, &copy)
                        .unwrap();
                    assert_eq!(out, extract(&q, &dims, &bx), "{dims:?} {coder:?} {win:?}");
                    // a parent box outside the held box
                    if held
                        .iter()
                        .zip(&pdims)
                        .any(|(h, &p)| h.start > 0 || h.end < p)
                    {
                        let small: Vec<Range<usize>> =
                            held.iter().map(|h| h.start..h.start + 1).collect();
                        let ps = extract(&pq, &pdims, &small);
                        let rows: Vec<&mut [i64]> = out.chunks_mut(bd[nd - 1]).collect();
                        let over = Over {
                            rows: &bx,
                            parent: Some(&small),
                        };
                        let par = Some(Parent {
                            data: &ps,
                            dims: &pdims,
                        });
                        let bad = decode_blocks_over(
                            rows,
                            &over,
                            &grid,
                            &which,
                            &refs,
                            (kind, par),
                            at,
                            &copy,
                        );
                        assert!(
                            bad.is_err()
                                || which.iter().all(|&i| {
                                    parent_box(&grid.bounds(i), &pdims)
                                        .iter()
                                        .zip(&small)
                                        .all(|(r, h)| r.start >= h.start && r.end <= h.end)
                                })
                        );
                    }
                    // a block outside the box
                    if which.len() < grid.len() {
                        let all: Vec<usize> = (0..grid.len()).collect();
                        let refs: Vec<&[u8]> = s.iter().map(|v| v.as_slice()).collect();
                        let rows: Vec<&mut [i64]> = out.chunks_mut(bd[nd - 1]).collect();
                        let over = Over {
                            rows: &bx,
                            parent: None,
                        };
                        let bad = decode_blocks_over(
                            rows,
                            &over,
                            &grid,
                            &all,
                            &refs,
                            (kind, parent),
                            at,
                            &copy,
                        );
                        assert!(bad.is_err());
                    }
                }
            }
        }
    }

    /// `decode_blocks_into` writes every index through `put` into rows that need not be
    /// contiguous (a band's rows inside a wider plane, as a decode's plane holds them),
    /// touching nothing else: the values `decode_blocks` gives, on 1- to 4-D bands.
    #[test]
    fn blocks_decode_into_rows_of_a_plane() {
        for (dims, block) in band_shapes() {
            let n: usize = dims.iter().product();
            let q = sample(n, n as u64 + 7, 40);
            let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
            let pq = sample(pdims.iter().product(), 5, 3);
            let parent = Some(Parent {
                data: &pq,
                dims: &pdims,
            });
            let grid = Grid::new(&dims, &block);
            let (cols, pad) = (dims[dims.len() - 1], 3);
            let stride = cols + 2 * pad;
            let put = Put {
                wide: |o: &mut [f64], v: &[i64]| {
                    for (o, &x) in o.iter_mut().zip(v) {
                        *o = x as f64 * 0.5;
                    }
                },
                narrow: |o: &mut [f64], v: &[i32]| {
                    for (o, &x) in o.iter_mut().zip(v) {
                        *o = x as f64 * 0.5;
                    }
                },
            };
            for (kind, coder) in [BandKind::Coarse, BandKind::Detail]
                .into_iter()
                .flat_map(|k| Coder::ALL.map(|c| (k, c)))
            {
                let s = encode_blocks(&q, &grid, kind, parent, Coding::Chosen, coder);
                let all: Vec<usize> = (0..grid.len()).collect();
                let refs: Vec<&[u8]> = s.iter().map(|v| v.as_slice()).collect();
                let mut plane = vec![f64::NAN; n / cols * stride];
                let rows: Vec<&mut [f64]> = plane
                    .chunks_mut(stride)
                    .map(|r| &mut r[pad..pad + cols])
                    .collect();
                let at = (kind, parent);
                decode_blocks_into(rows, &grid, &all, &refs, at, Coding::Chosen, coder, &put)
                    .unwrap();
                for (r, row) in plane.chunks(stride).enumerate() {
                    let mut edge = row[..pad].iter().chain(&row[pad + cols..]);
                    assert!(edge.all(|x| x.is_nan()), "{dims:?} row {r}");
                    for (c, &got) in row[pad..pad + cols].iter().enumerate() {
                        let want = q[r * cols + c] as f64 * 0.5;
                        assert_eq!(got, want, "{dims:?} {kind:?} {coder:?} at {r},{c}");
                    }
                }
            }
        }
    }
}
