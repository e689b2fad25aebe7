//! A throughput coder for bands of `i32` indices, cut into independent code-blocks
//! (a prototype measured against [`super::band`]; no file uses it).
//!
//! A band of extents `dims` (walked as planes × rows × columns, the planes split along
//! the third-last axis as in [`super::band`]) is cut into blocks of at most
//! [`Shape`] `z × y × x` positions (`y`, `x` even; blocks never straddle two extents of
//! the axes before the third-last). Each block is coded on its own by [`quad`]: a
//! 16-symbol adaptive range-coded stream ([`rc`]) and a raw bit stream. The band's bytes
//! are, block after block in raster order of the blocks, `varint(symbol bytes)`,
//! `varint(raw bytes)`, the symbol bytes, the raw bytes: a decoder finds every block's
//! start from the lengths alone and may decode blocks in parallel. The coarsest band is
//! coded as the residuals of the median predictor `med(W, N, W + N − NW)` (in wrapping
//! `i32` arithmetic, so every index is exact).
//!
//! The parent (one level coarser, same orientation) is a context as in
//! [`super::band`]: blocks stay independent of each other given the coarser level.
//!
//! [`encode_ht`] / [`decode_ht`] code the same blocks with the HT-style coder ([`ht`]):
//! static prefix codes ([`vlc`]) and a run coder instead of the range coder, one
//! length per block. [`encode_rans`] / [`decode_rans`] code the HT coder's quad and
//! magnitude symbols with static frequency tables and two interleaved rANS lanes
//! ([`rans`]).

pub mod ht;
mod ht_table;
pub mod prior;
pub mod quad;
pub mod rans;
pub mod rc;
pub mod vlc;

use super::walk::{median_residuals, parent_fits, parent_plane, undo_median, Walk};
use super::BandKind;
use crate::format::Cursor;
use crate::{Error, Result};
use quad::{Extent, Rows, Scratch};

/// Code-block extents (planes of 3-D and 4-D bands, rows, columns) and the models'
/// adaptation limit ([`rc::Cdf::uniform`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shape {
    pub z: usize,
    pub y: usize,
    pub x: usize,
    pub limit: u8,
    /// Start from the trained priors ([`prior`]) instead of uniform models.
    pub trained: bool,
    /// Code each sign as an adaptive bit in the context of the W and N signs
    /// ([`quad::SIGNS`]) instead of a raw bit.
    pub signs: bool,
}

impl Shape {
    /// Blocks of `z × y × x` with the default adaptation limit ([`rc::LIMIT`]).
    pub fn new(z: usize, y: usize, x: usize) -> Self {
        Shape {
            z,
            y,
            x,
            limit: rc::LIMIT,
            trained: false,
            signs: false,
        }
    }

    /// Coder 2's code-blocks (formats/MRA.md §15.4): one block over the whole box,
    /// adaptation window 2^[`LIMIT2`], models from the trained priors, signs in context.
    pub const fn coder2() -> Self {
        Shape {
            z: 1 << 30,
            y: 1 << 30,
            x: 1 << 30,
            limit: LIMIT2,
            trained: true,
            signs: true,
        }
    }

    /// The extents as given, rows and columns rounded up to even, every one at least 1.
    fn normal(self) -> Shape {
        Shape {
            z: self.z.max(1),
            y: self.y.max(2).next_multiple_of(2),
            x: self.x.max(2).next_multiple_of(2),
            limit: self.limit,
            trained: self.trained,
            signs: self.signs,
        }
    }
}

/// Coder 2's adaptation limit: windows of about 2^7 symbols.
pub const LIMIT2: u8 = 7;

/// The parent band of a detail band: its indices and extents.
#[derive(Clone, Copy, Debug)]
pub struct Parent<'a> {
    pub data: &'a [i32],
    pub dims: &'a [usize],
}

/// A block of a band: its first plane, row and column and its extents.
#[derive(Clone, Copy, Debug)]
struct Block {
    p: usize,
    y: usize,
    x: usize,
    ext: Extent,
}

/// The blocks of a band of walk `w` in coding order.
fn blocks(w: Walk, shape: Shape) -> Vec<Block> {
    let zdim = if w.zdim > 0 { w.zdim } else { w.planes.max(1) };
    let outer = w.planes / zdim;
    let mut out = Vec::new();
    for o in 0..outer {
        for z in (0..zdim).step_by(shape.z) {
            for y in (0..w.rows).step_by(shape.y) {
                for x in (0..w.cols).step_by(shape.x) {
                    out.push(Block {
                        p: o * zdim + z,
                        y,
                        x,
                        ext: Extent {
                            planes: shape.z.min(zdim - z),
                            rows: shape.y.min(w.rows - y),
                            cols: shape.x.min(w.cols - x),
                        },
                    });
                }
            }
        }
    }
    out
}

/// The band positions and parent magnitudes of one block.
struct Layout<'a> {
    w: Walk,
    b: Block,
    parent: Option<(&'a [i32], Walk, &'a [usize])>,
}

impl Rows for Layout<'_> {
    #[inline(always)]
    fn row(&self, k: usize, y: usize) -> usize {
        ((self.b.p + k) * self.w.rows + self.b.y + y) * self.w.cols + self.b.x
    }

    #[inline(always)]
    fn parent(&self, k: usize, y: usize, x: usize) -> u32 {
        match self.parent {
            Some((data, pw, pbase)) => {
                let py = ((self.b.y + y) / 2).min(pw.rows - 1);
                let px = ((self.b.x + x) / 2).min(pw.cols - 1);
                data[pbase[self.b.p + k] + py * pw.cols + px]
                    .unsigned_abs()
                    .min(1 << 20)
            }
            None => 0,
        }
    }
}

/// The parent's walk and, for each plane of the band, the offset of its parent plane;
/// None without a usable parent.
fn parent_map<'a>(
    dims: &[usize],
    w: Walk,
    parent: Option<Parent<'a>>,
) -> Option<(&'a [i32], Walk, Vec<usize>)> {
    let p = parent?;
    if !parent_fits(p.data, p.dims, dims) {
        return None;
    }
    let pw = Walk::new(p.dims);
    let bases = (0..w.planes)
        .map(|k| parent_plane(k, dims, p.dims) * pw.rows * pw.cols)
        .collect();
    Some((p.data, pw, bases))
}

/// Code a band of indices `q` (raster order, extents `dims`) in code-blocks of `shape`.
pub fn encode(
    q: &[i32],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
) -> Vec<u8> {
    encode_counting(q, dims, kind, parent, shape, None)
}

/// [`encode`], adding every coded symbol to `counts` (for training [`prior`]).
pub fn encode_counting(
    q: &[i32],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
    mut counts: Option<&mut quad::Counts>,
) -> Vec<u8> {
    let mut out = Vec::new();
    let models = (shape.limit, shape.trained, shape.signs);
    encode_walk(q, dims, kind, parent, shape, true, |v, ext, layout, s| {
        let mut e = rc::Encoder::new();
        let mut bits = rc::BitWriter::default();
        let c = counts.as_deref_mut();
        quad::encode(v, ext, layout, s, models, c, (&mut e, &mut bits));
        let (sym, raw) = (e.finish(), bits.finish());
        crate::format::put_varint(&mut out, sym.len() as u64);
        crate::format::put_varint(&mut out, raw.len() as u64);
        out.extend_from_slice(&sym);
        out.extend_from_slice(&raw);
    });
    out
}

/// Choose the indices of a detail band by rate–distortion optimisation against the
/// quad coder's own models ([`quad::encode_rdo`], Lagrange multiplier `lambda` in units
/// of the step squared per bit) and code them in code-blocks of `shape` exactly as
/// [`encode`] codes them: `x` = the band's coefficients divided by its step (raster
/// order, extents `dims`). Returns the stream and the indices chosen.
pub fn encode_rdo(
    x: &[f32],
    dims: &[usize],
    parent: Option<Parent>,
    shape: Shape,
    lambda: f32,
) -> (Vec<u8>, Vec<i32>) {
    let w = Walk::new(dims);
    let shape = shape.normal();
    let mut q = vec![0i32; x.len()];
    let mut out = Vec::new();
    if x.len() != dims.iter().product::<usize>() {
        return (out, q);
    }
    let parent = parent_map(dims, w, parent);
    let models = (shape.limit, shape.trained, shape.signs);
    let mut scratch: Option<(Extent, Scratch)> = None;
    for b in blocks(w, shape) {
        let s = scratch_for(&mut scratch, b.ext);
        let layout = Layout {
            w,
            b,
            parent: parent.as_ref().map(|(d, pw, bases)| (*d, *pw, &bases[..])),
        };
        let mut e = rc::Encoder::new();
        let mut bits = rc::BitWriter::default();
        quad::encode_rdo(
            x,
            &mut q,
            b.ext,
            &layout,
            s,
            models,
            lambda,
            (&mut e, &mut bits),
        );
        let (sym, raw) = (e.finish(), bits.finish());
        crate::format::put_varint(&mut out, sym.len() as u64);
        crate::format::put_varint(&mut out, raw.len() as u64);
        out.extend_from_slice(&sym);
        out.extend_from_slice(&raw);
    }
    (out, q)
}

/// The one band walk of every encoder: the values coded (the median residuals in the
/// coarsest band, the indices else) and, block after block of `shape` in coding
/// order, its extent, layout and scratch handed to `block`; the parent is read where
/// `uses_parent` (never in the coarsest band). [`decode_sized`] is its decoding twin.
fn encode_walk(
    q: &[i32],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
    uses_parent: bool,
    mut block: impl FnMut(&[i32], Extent, &Layout<'_>, &mut Scratch),
) {
    let w = Walk::new(dims);
    let shape = shape.normal();
    let res: Vec<i32>;
    let (v, parent) = if kind == BandKind::Coarse {
        res = median_residuals(q, w);
        (&res[..], None)
    } else if uses_parent {
        (q, parent_map(dims, w, parent))
    } else {
        (q, None)
    };
    let mut scratch: Option<(Extent, Scratch)> = None;
    for b in blocks(w, shape) {
        let s = scratch_for(&mut scratch, b.ext);
        let layout = Layout {
            w,
            b,
            parent: parent.as_ref().map(|(d, pw, bases)| (*d, *pw, &bases[..])),
        };
        block(v, b.ext, &layout, s);
    }
}

/// A scratch for a block of extents `ext`, kept while blocks keep the same extents.
fn scratch_for(keep: &mut Option<(Extent, Scratch)>, ext: Extent) -> &mut Scratch {
    let same = matches!(keep, Some((e, _)) if (e.planes, e.rows, e.cols) == (ext.planes, ext.rows, ext.cols));
    if !same {
        *keep = Some((ext, Scratch::new(ext)));
    }
    &mut keep.as_mut().expect("just set").1
}

/// Decode a band written by [`encode`] with the same `dims`, `kind`, parent and
/// `shape`. Fails when a block's declared lengths run past the data.
pub fn decode(
    data: &[u8],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
) -> Result<Vec<i32>> {
    let w = Walk::new(dims);
    let shape = shape.normal();
    let n: usize = dims.iter().product();
    let mut v = vec![0i32; n];
    let parent = if kind == BandKind::Coarse {
        None
    } else {
        parent_map(dims, w, parent)
    };
    let mut cur = Cursor::new(data, "code-block");
    let mut scratch: Option<(Extent, Scratch)> = None;
    for b in blocks(w, shape) {
        let sym_len = cur.varint()?;
        let raw_len = cur.varint()?;
        let left = data.len() as u64 - cur.pos as u64;
        if sym_len.saturating_add(raw_len) > left {
            return Err(Error::format(
                format!("a code-block declaring {sym_len} + {raw_len} bytes, {left} left"),
                "code-blocks within the band",
            ));
        }
        let sym = cur.take(sym_len as usize)?;
        let raw = cur.take(raw_len as usize)?;
        let s = scratch_for(&mut scratch, b.ext);
        let layout = Layout {
            w,
            b,
            parent: parent.as_ref().map(|(d, pw, bases)| (*d, *pw, &bases[..])),
        };
        quad::decode(
            &mut v,
            b.ext,
            &layout,
            s,
            (shape.limit, shape.trained, shape.signs),
            &mut rc::Decoder::new(sym),
            &mut rc::BitReader::new(raw),
        );
    }
    if kind == BandKind::Coarse {
        undo_median(&mut v, w);
    }
    Ok(v)
}

/// Code a band of indices `q` (raster order, extents `dims`) in code-blocks of `shape`
/// with the HT-style coder ([`ht`]) and its codes `t`, adding every coded symbol to
/// `counts` when given. The band's bytes are, block after block, `varint(block bytes)`
/// and the block's bytes ([`ht`]). The coarsest band is coded as median residuals, as
/// in [`encode`]; the parent is read only when the codes' [`ht::Kind`] asks for it.
pub fn encode_ht(
    q: &[i32],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
    t: &ht::Tables,
    mut counts: Option<&mut ht::Counts>,
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut wr = ht::Writers::default();
    encode_walk(
        q,
        dims,
        kind,
        parent,
        shape,
        t.kind.parent,
        |v, ext, layout, s| {
            wr.bits.clear();
            wr.mel.clear();
            ht::encode(v, ext, layout, s, t, counts.as_deref_mut(), &mut wr);
            let (bits, mel) = (&mut wr.bits, &mut wr.mel);
            bits.flush();
            mel.finish();
            crate::format::put_varint(&mut out, (bits.out.len() + mel.w.out.len()) as u64);
            out.extend_from_slice(&bits.out);
            out.extend(mel.w.out.iter().rev());
        },
    );
    out
}

/// Decode a band written by [`encode_ht`] with the same `dims`, `kind`, `shape` and
/// codes. Fails when a block's declared length runs past the data.
pub fn decode_ht(
    data: &[u8],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
    t: &ht::Tables,
) -> Result<Vec<i32>> {
    decode_sized(
        data,
        dims,
        kind,
        parent,
        shape,
        t.kind.parent,
        |v, ext, layout, s, bytes| {
            ht::decode(v, ext, layout, s, t, bytes);
            Ok(())
        },
    )
}

/// Decode a band whose blocks are each `varint(length)` and that many bytes (the HT and
/// rANS coders' bands), handing each block's bytes to `block` with the block's layout
/// and scratch, over a band of zeros; the parent is read where `uses_parent` (never in
/// the coarsest band), whose median residuals are undone at the end. Fails when a
/// block's declared length runs past the data.
fn decode_sized(
    data: &[u8],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
    uses_parent: bool,
    mut block: impl FnMut(&mut [i32], Extent, &Layout<'_>, &mut Scratch, &[u8]) -> Result<()>,
) -> Result<Vec<i32>> {
    let w = Walk::new(dims);
    let shape = shape.normal();
    let n: usize = dims.iter().product();
    let mut v = vec![0i32; n];
    let parent = if kind == BandKind::Coarse || !uses_parent {
        None
    } else {
        parent_map(dims, w, parent)
    };
    let mut cur = Cursor::new(data, "code-block");
    let mut scratch: Option<(Extent, Scratch)> = None;
    for b in blocks(w, shape) {
        let len = cur.varint()?;
        let left = data.len() as u64 - cur.pos as u64;
        if len > left {
            return Err(Error::format(
                format!("a code-block declaring {len} bytes, {left} left"),
                "code-blocks within the band",
            ));
        }
        let bytes = cur.take(len as usize)?;
        let s = scratch_for(&mut scratch, b.ext);
        let layout = Layout {
            w,
            b,
            parent: parent.as_ref().map(|(d, pw, bases)| (*d, *pw, &bases[..])),
        };
        block(&mut v, b.ext, &layout, s, bytes)?;
    }
    if kind == BandKind::Coarse {
        undo_median(&mut v, w);
    }
    Ok(v)
}

/// Code a band of indices `q` (raster order, extents `dims`) in code-blocks of `shape`
/// with the rANS quad coder ([`rans`]) and its tables `t`, adding every coded symbol to
/// `counts` when given. The band's bytes are, block after block, `varint(block bytes)`
/// and the block's bytes ([`rans::encode`]). The coarsest band is coded as median
/// residuals, as in [`encode`]; the parent is read only when the tables' kind asks.
pub fn encode_rans(
    q: &[i32],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
    t: &rans::Tables,
    mut counts: Option<&mut rans::Counts>,
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut blk = Vec::new();
    let mut wr = rans::Writers::default();
    encode_walk(
        q,
        dims,
        kind,
        parent,
        shape,
        t.kind.parent,
        |v, ext, layout, s| {
            blk.clear();
            let c = counts.as_deref_mut();
            rans::encode(v, ext, layout, s, t, c, &mut wr, &mut blk);
            crate::format::put_varint(&mut out, blk.len() as u64);
            out.extend_from_slice(&blk);
        },
    );
    out
}

/// Decode a band written by [`encode_rans`] with the same `dims`, `kind`, `shape` and
/// tables. Fails when a block's declared lengths run past the data.
pub fn decode_rans(
    data: &[u8],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    shape: Shape,
    t: &rans::Tables,
) -> Result<Vec<i32>> {
    decode_sized(
        data,
        dims,
        kind,
        parent,
        shape,
        t.kind.parent,
        |v, ext, layout, s, bytes| rans::decode(v, ext, layout, s, t, bytes),
    )
}
