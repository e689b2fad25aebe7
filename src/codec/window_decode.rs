//! A region's coefficients decoded into buffers the size of its code-blocks' boxes: in
//! each band, the blocks the window's support meets ([`super::support::band_windows`])
//! decode into a buffer of their block-aligned box alone (never a band- or plane-sized
//! one), a band's parent context read from the box held of its parent band; the
//! window's synthesis ([`crate::tensor::WindowPlan::synthesize_by`], or the integer
//! lifting's [`IntWindow::synthesize`]) then reads the coefficients from those boxes
//! ([`Boxes`]). Memory and page faults scale with the boxes, not with the raster.

use super::container::Parsed;
use super::int_window::IntWindow;
use super::plan::{band_delta, coder_of, coding_of, dequantize_row};
use super::support::band_windows;
use crate::entropy::codeblocks::{box_dims, decode_blocks_over, Grid, Over, Put};
use crate::entropy::{BandKind, Parent};
use crate::tensor::WindowPlan;
use crate::{Error, Result};
use rayon::prelude::*;
use std::cell::Cell;
use std::ops::Range;

/// One band's values held over a box of the band (its own coordinates), raster order.
pub(super) struct Held<T> {
    bx: Vec<Range<usize>>,
    data: Vec<T>,
}

/// A channel's coefficients held over a box of each band: a band `j` at plane ranges
/// `R_j` holding the box `B_j` gives the coefficient at plane position `p ∈ R_j` as
/// `data_j[Σ_a (p_a − R_j,a.start − B_j,a.start) · stride_a]` inside `B_j`, and 0
/// outside it (and in the bands not held).
pub(super) struct Boxes<T> {
    bands: Vec<InPlane<T>>,
    /// The band the last position fell in (positions come in runs of one band).
    last: Cell<usize>,
}

/// A band held over a box, placed in the plane.
struct InPlane<T> {
    /// The band's ranges in the plane.
    ranges: Vec<Range<usize>>,
    /// The box held, in the plane's coordinates.
    bx: Vec<Range<usize>>,
    /// The box's strides (raster order).
    st: Vec<usize>,
    data: Vec<T>,
}

impl<T: Copy + Default> Boxes<T> {
    /// The boxes `held[j]` of the bands of plane ranges `ranges[j]`.
    fn new(ranges: &[&[Range<usize>]], held: Vec<Option<Held<T>>>) -> Boxes<T> {
        let bands = ranges
            .iter()
            .zip(held)
            .filter_map(|(r, h)| {
                let h = h?;
                let plane: Vec<Range<usize>> = r
                    .iter()
                    .zip(&h.bx)
                    .map(|(r, b)| r.start + b.start..r.start + b.end)
                    .collect();
                let d = box_dims(&h.bx);
                let mut st = vec![1usize; d.len()];
                for a in (0..d.len().saturating_sub(1)).rev() {
                    st[a] = st[a + 1] * d[a + 1];
                }
                Some(InPlane {
                    ranges: r.to_vec(),
                    bx: plane,
                    st,
                    data: h.data,
                })
            })
            .collect();
        Boxes {
            bands,
            last: Cell::new(0),
        }
    }

    /// The coefficient at plane position `p` (0 where no box holds it).
    pub(super) fn at(&self, p: &[usize]) -> T {
        let n = self.bands.len();
        let first = self.last.get().min(n.saturating_sub(1));
        for i in (first..n).chain(0..first) {
            let b = &self.bands[i];
            if !p.iter().zip(&b.ranges).all(|(x, r)| r.contains(x)) {
                continue;
            }
            self.last.set(i);
            let mut o = 0;
            for ((&x, r), s) in p.iter().zip(&b.bx).zip(&b.st) {
                if !r.contains(&x) {
                    return T::default();
                }
                o += (x - r.start) * s;
            }
            return b.data[o];
        }
        T::default()
    }
}

/// The block-aligned box of a band of extents `dims` and code-blocks `block` whose
/// blocks meet `w` (the whole band for `None`; empty when `w` is).
fn block_box(dims: &[usize], block: &[usize], w: Option<&[Range<usize>]>) -> Vec<Range<usize>> {
    match w {
        Some(w) if w.len() == dims.len() => w
            .iter()
            .zip(block)
            .zip(dims)
            .map(|((r, &b), &e)| {
                let b = b.max(1);
                if r.is_empty() || r.start >= e {
                    return 0..0;
                }
                r.start / b * b..r.end.div_ceil(b).saturating_mul(b).min(e)
            })
            .collect(),
        _ => dims.iter().map(|&e| 0..e).collect(),
    }
}

/// The values of a band's blocks inside the block-aligned box `bx` decoded from its
/// entry `data` into a buffer of the box, through `put`; `parent` the parent band's
/// indices held over a box of it.
#[allow(clippy::too_many_arguments)]
fn decode_box<T, W, N>(
    p: &Parsed,
    data: &[u8],
    j: usize,
    bx: &[Range<usize>],
    kind: BandKind,
    parent: Option<&Held<i64>>,
    put: &Put<W, N>,
) -> Result<Vec<T>>
where
    T: Copy + Default + Send,
    W: Fn(&mut [T], &[i64]) + Sync,
    N: Fn(&mut [T], &[i32]) + Sync,
{
    let plan = &p.plan;
    let (dims, block) = (&plan.dims[j], plan.block(j));
    let n: usize = box_dims(bx).iter().product();
    let mut out = vec![T::default(); n];
    if n == 0 {
        return Ok(out);
    }
    let set = crate::format::bands::parse_blocks(data, dims, block)?;
    let grid = Grid::new(dims, block);
    let which = grid.touching(bx);
    let streams: Vec<&[u8]> = which
        .iter()
        .map(|&i| &data[set.streams[i].clone()])
        .collect();
    let cols = bx.last().map_or(1, |r| r.len()).max(1);
    let rows: Vec<&mut [T]> = out.chunks_mut(cols).collect();
    let pdims = plan.parents[j].map(|pj| &plan.dims[pj]);
    let par = parent.zip(pdims).map(|(h, dims)| Parent {
        data: &h.data,
        dims,
    });
    let over = Over {
        rows: bx,
        parent: parent.map(|h| &h.bx[..]),
    };
    decode_blocks_over(
        rows,
        &over,
        &grid,
        &which,
        &streams,
        (kind, par),
        (coding_of(&p.header), coder_of(&p.header)),
        put,
    )?;
    Ok(out)
}

/// What one band of a channel decodes to: its indices (a lossless file's, or a lossy
/// band's whose values are a finer band's parent context) and its dequantized values (a
/// lossy file's).
type Decoded = (Option<Held<i64>>, Option<Held<f32>>);

/// The boxes of a decode at level `k` of `p.window` ([`band_windows`] block-aligned),
/// checked against the memory budget: `lossy` files hold `f32` values of every band
/// and `i64` indices of the bands with children, lossless ones `i64` indices.
fn boxes_of(p: &Parsed, k: usize, lossy: bool) -> Result<Vec<Vec<Range<usize>>>> {
    let plan = &p.plan;
    let wins = band_windows(p, k);
    let boxes: Vec<Vec<Range<usize>>> = wins
        .iter()
        .enumerate()
        .map(|(j, w)| {
            let l = plan.bands[j].level;
            if k > 0 && l >= 1 && l <= k {
                return vec![0..0; plan.dims[j].len()];
            }
            block_box(&plan.dims[j], plan.block(j), w.as_deref())
        })
        .collect();
    let bytes = boxes.iter().enumerate().fold(0u64, |n, (j, b)| {
        let len = box_dims(b).iter().product::<usize>() as u64;
        let per = match (lossy, plan.parents.contains(&Some(j))) {
            (false, _) => 8,
            (true, false) => 4,
            (true, true) => 12,
        };
        n.saturating_add(len.saturating_mul(per))
    });
    let bytes = bytes.saturating_mul(p.header.channels as u64);
    crate::limits::check("decoded bytes (memory budget MRA_MAX_BYTES)", bytes)?;
    Ok(boxes)
}

/// Channel `c`'s bands at level `k` decoded over `boxes` (absent bands and skipped
/// levels `None`), level by level from the coarse block down, the bands of a level in
/// parallel: a lossless file's `i64` indices; a lossy file's values dequantized
/// (`x = dequantize(q, step, δ)`), a band without children straight from its blocks.
fn decode_channel(
    p: &Parsed,
    c: usize,
    k: usize,
    boxes: &[Vec<Range<usize>>],
    lossy: bool,
) -> Result<Vec<Decoded>> {
    let (h, plan) = (&p.header, &p.plan);
    let nb = plan.bands.len();
    let mut out: Vec<Decoded> = (0..nb).map(|_| (None, None)).collect();
    for (level, js) in plan.level_groups() {
        if k > 0 && level >= 1 && level <= k {
            continue;
        }
        let kind = if level == 0 {
            BandKind::Coarse
        } else {
            BandKind::Detail
        };
        let decoded: Vec<Result<Decoded>> = js
            .par_iter()
            .map(|&j| {
                let Some(bc) = &p.bands[c][j] else {
                    return Ok((None, None));
                };
                let parent = match plan.parents[j] {
                    None => None,
                    Some(pj) => match &out[pj].0 {
                        Some(held) => Some(held),
                        None => {
                            return Err(Error::format(
                                format!("band {j} of channel {c} without its parent"),
                                "complete parents",
                            ))
                        }
                    },
                };
                let bx = &boxes[j];
                let failed = |e: Error| {
                    Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
                };
                let children = plan.parents.contains(&Some(j));
                let (step, delta) = (bc.step, band_delta(h, plan, j));
                if lossy && !children {
                    let put = super::plan::dequantizing_put(step, delta);
                    let v = decode_box(p, &bc.data, j, bx, kind, parent, &put).map_err(failed)?;
                    return Ok((
                        None,
                        Some(Held {
                            bx: bx.clone(),
                            data: v,
                        }),
                    ));
                }
                let put = Put {
                    wide: |o: &mut [i64], v: &[i64]| o.copy_from_slice(v),
                    narrow: |o: &mut [i64], v: &[i32]| {
                        for (o, &x) in o.iter_mut().zip(v) {
                            *o = x as i64;
                        }
                    },
                };
                let q: Vec<i64> =
                    decode_box(p, &bc.data, j, bx, kind, parent, &put).map_err(failed)?;
                let x = lossy.then(|| {
                    let mut x = vec![0f32; q.len()];
                    dequantize_row(&q, step, delta, &mut x);
                    Held {
                        bx: bx.clone(),
                        data: x,
                    }
                });
                Ok((
                    Some(Held {
                        bx: bx.clone(),
                        data: q,
                    }),
                    x,
                ))
            })
            .collect();
        // the first failing band in file order, as one at a time would report it
        for (&j, v) in js.iter().zip(decoded) {
            out[j] = v?;
        }
    }
    Ok(out)
}

/// The plane ranges of every band.
fn ranges(p: &Parsed) -> Vec<&[Range<usize>]> {
    p.plan.bands.iter().map(|b| &b.ranges[..]).collect()
}

/// Each channel's window `wp` of a lossy file at level `k`, from its bands decoded over
/// the code-blocks' boxes the window needs.
pub(super) fn lossy_window(p: &Parsed, k: usize, wp: &WindowPlan) -> Result<Vec<Vec<f32>>> {
    let boxes = boxes_of(p, k, true)?;
    (0..p.header.channels)
        .into_par_iter()
        .map(|ch| {
            let d = decode_channel(p, ch, k, &boxes, true)?;
            let b = Boxes::new(&ranges(p), d.into_iter().map(|(_, x)| x).collect());
            Ok(wp.synthesize_by(|pos| b.at(pos)))
        })
        .collect()
}

/// Each channel's window `iw` of a lossless file at level `k` (its `i64` samples before
/// the sample type), from its bands decoded over the code-blocks' boxes the window needs.
pub(super) fn lossless_window(p: &Parsed, k: usize, iw: &IntWindow) -> Result<Vec<Vec<i64>>> {
    let boxes = boxes_of(p, k, false)?;
    (0..p.header.channels)
        .into_par_iter()
        .map(|ch| {
            let d = decode_channel(p, ch, k, &boxes, false)?;
            let b = Boxes::new(&ranges(p), d.into_iter().map(|(q, _)| q).collect());
            Ok(iw.synthesize(&|pos| b.at(pos)))
        })
        .collect()
}
