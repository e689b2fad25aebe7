//! Format 2 band layout: one `LEVL` chunk per level (the coarse block first, then the
//! detail levels from the coarsest down), holding for every band of the level and every
//! channel the band's step as a ratio to the header's base step, the length of its
//! range-coded stream and the stream (formats/MRA.md §8; the payload's grammar is
//! [`crate::format::bands`]'s).
//!
//! Coding goes channel by channel (in parallel), level after level (a band's context is
//! its parent band, one level coarser), the bands of a level in parallel; every band has
//! its own stream, so decoding is as parallel.

use super::layout;
use super::plan::Plan;
use crate::entropy::codeblocks::{self, Grid};
use crate::entropy::range::Encoder;
use crate::entropy::{band, BandKind, Parent};
use crate::format::bands::{blocks_payload, level_payload, LevelGroups};
use crate::format::body::BandLayout;
use crate::format::{put_chunk, Tag};
use rayon::prelude::*;
use std::ops::Range;

/// One band of one channel, coded: its indices (the context of its children) and stream.
pub(super) struct CodedBand {
    pub(super) q: Vec<i64>,
    pub(super) stream: Vec<u8>,
}

/// How the indices of a band are made from its coefficients.
#[derive(Clone, Copy, Debug)]
pub(super) enum Choice {
    /// Fixed indices (integer coefficients, or quantized beforehand).
    Given,
    /// Rate–distortion optimised choice with multiplier `λ` (details; the coarse block
    /// is rounded).
    Rdo(f32),
}

impl Plan {
    /// The bands of each level in file order: the coarse block first, then the detail
    /// levels from the coarsest to the finest.
    pub(super) fn level_groups(&self) -> Vec<(usize, Vec<usize>)> {
        let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
        for (j, b) in self.bands.iter().enumerate() {
            match groups.last_mut() {
                Some((l, v)) if *l == b.level => v.push(j),
                _ => groups.push((b.level, vec![j])),
            }
        }
        groups
    }

    /// What the chunk reader needs to know of the bands ([`BandLayout`]), with `groups`
    /// this plan's [`Self::level_groups`].
    pub(super) fn band_layout<'a>(&'a self, groups: &'a LevelGroups) -> BandLayout<'a> {
        BandLayout {
            groups,
            levels: self.bands.iter().map(|b| b.level).collect(),
            parents: &self.parents,
            coefficients: self
                .dims
                .iter()
                .map(|d| d.iter().product::<usize>() as u64)
                .collect(),
        }
    }

    /// Code every band of `channels` channels; `input(c, j)` gives band `j` of channel
    /// `c` ([`BandInput`]). With [`Choice::Rdo`] the scaled coefficients of detail bands
    /// get rate–distortion optimised indices; other scaled bands are rounded.
    pub(super) fn code_levels<'a>(
        &self,
        channels: usize,
        choice: Choice,
        input: impl Fn(usize, usize) -> BandInput<'a> + Sync,
    ) -> Vec<Vec<CodedBand>> {
        self.code_levels_with(channels, choice, true, input)
    }

    /// The bands in chains along which each band is the context of the next: the
    /// coarse block alone, then for each orientation (the high-pass axes) its bands from
    /// the coarsest level to the finest. A band's parent, one level coarser with the same
    /// orientation, is the one before it in its chain, and it has no other child.
    pub(super) fn chains(&self) -> Vec<Vec<usize>> {
        let mut chains: Vec<Vec<usize>> = Vec::new();
        for (_, js) in self.level_groups() {
            for j in js {
                match chains
                    .iter_mut()
                    .find(|ch| self.bands[ch[0]].high == self.bands[j].high)
                {
                    Some(ch) => ch.push(j),
                    None => chains.push(vec![j]),
                }
            }
        }
        chains
    }

    /// [`Plan::code_levels`], keeping each band's indices only while its children are
    /// coded when `keep_indices` is false (the returned [`CodedBand::q`] are then empty):
    /// the indices of a whole image (8 bytes a sample) are never held at once. The bands
    /// are coded chain by chain ([`Plan::chains`], the chains in parallel), so that only
    /// the indices of the bands in flight and their parents are held, not those of a
    /// whole level; each band's stream depends only on its indices and its parent's, so
    /// the streams are those of any order.
    pub(super) fn code_levels_with<'a>(
        &self,
        channels: usize,
        choice: Choice,
        keep_indices: bool,
        input: impl Fn(usize, usize) -> BandInput<'a> + Sync,
    ) -> Vec<Vec<CodedBand>> {
        let chains = self.chains();
        (0..channels)
            .into_par_iter()
            .map(|c| {
                let coded: Vec<Vec<(usize, CodedBand)>> = chains
                    .par_iter()
                    .map(|chain| {
                        let mut done: Vec<(usize, CodedBand)> = Vec::with_capacity(chain.len());
                        for &j in chain {
                            let parent = self.parents[j].map(|p| {
                                let (pj, pb) = done.last().expect("a parent comes first");
                                debug_assert_eq!(*pj, p);
                                Parent {
                                    data: &pb.q,
                                    dims: &self.dims[p],
                                }
                            });
                            let cb = self.code_band(c, j, choice, keep_indices, parent, &input);
                            if !keep_indices {
                                // the parent has no other child
                                if let Some((_, pb)) = done.last_mut() {
                                    pb.q = Vec::new();
                                }
                            }
                            done.push((j, cb));
                        }
                        done
                    })
                    .collect();
                let mut out: Vec<Option<CodedBand>> = (0..self.bands.len()).map(|_| None).collect();
                for (j, cb) in coded.into_iter().flatten() {
                    out[j] = Some(cb);
                }
                out.into_iter()
                    .map(|b| b.expect("every band coded"))
                    .collect()
            })
            .collect()
    }

    /// Band `j` of channel `c` coded ([`Plan::code_levels_with`]) with context `parent`;
    /// its indices kept when `keep_indices` or when it has children.
    fn code_band<'a>(
        &self,
        c: usize,
        j: usize,
        choice: Choice,
        keep_indices: bool,
        parent: Option<Parent>,
        input: &impl Fn(usize, usize) -> BandInput<'a>,
    ) -> CodedBand {
        let level = self.bands[j].level;
        let dims = &self.dims[j];
        let stream: Vec<u8>;
        // a band without children (the finest level) is nobody's
        // context: unless asked for, its indices are not kept
        let childless = !self.parents.contains(&Some(j));
        let keep = keep_indices || !childless;
        let kind = if level == 0 {
            BandKind::Coarse
        } else {
            BandKind::Detail
        };
        let grid = self.grid(j);
        let q = match (input(c, j), choice) {
            (BandInput::Indices(q), _) => {
                stream = self.code_indices(&q, j, kind, parent);
                q
            }
            (BandInput::Quantize { plane, step, rho }, _) => match &grid {
                // nobody's context and not asked for: each block quantized as coded
                Some(g) if !keep => {
                    let shape = &self.pyr.shape;
                    stream = blocks_payload(&codeblocks::encode_blocks_by(
                        g,
                        kind,
                        parent,
                        self.coding,
                        self.coder,
                        |b| quantize_box(plane, shape, &self.in_plane(j, b), step, rho),
                    ));
                    Vec::new()
                }
                _ => {
                    let q = quantize_box(plane, &self.pyr.shape, &self.bands[j].ranges, step, rho);
                    stream = self.code_indices(&q, j, kind, parent);
                    q
                }
            },
            (BandInput::Coefficients { plane, step }, Choice::Rdo(lambda))
                if level > 0 && grid.is_some() =>
            {
                let g = grid.expect("a block grid");
                let (streams, q) = codeblocks::encode_blocks_rdo_by(
                    &g,
                    parent,
                    lambda,
                    self.coding,
                    self.coder,
                    keep,
                    |b| {
                        layout::gather(plane, &self.pyr.shape, &self.in_plane(j, b))
                            .into_iter()
                            .map(|x| (x as f64 / step) as f32)
                            .collect()
                    },
                );
                stream = blocks_payload(&streams);
                q.unwrap_or_default()
            }
            (BandInput::Coefficients { plane, step }, Choice::Rdo(lambda)) if level > 0 => {
                let offs = self.row_offsets(j);
                let cols = dims.last().copied().unwrap_or(1);
                let mut e = Encoder::new();
                let q = band::encode_rdo_with(
                    &mut e,
                    dims,
                    parent,
                    lambda,
                    self.coding,
                    keep,
                    |g, out| {
                        let row = &plane[offs[g]..offs[g] + cols];
                        for (o, &x) in out.iter_mut().zip(row) {
                            *o = (x as f64 / step) as f32;
                        }
                    },
                )
                .unwrap_or_default();
                stream = e.finish_short();
                q
            }
            (BandInput::Coefficients { plane, step }, _) => {
                let q: Vec<i64> = layout::gather(plane, &self.pyr.shape, &self.bands[j].ranges)
                    .into_iter()
                    .map(|x| round_index((x as f64 / step) as f32))
                    .collect();
                stream = self.code_indices(&q, j, kind, parent);
                q
            }
        };
        CodedBand {
            q: if keep { q } else { Vec::new() },
            stream,
        }
    }

    /// The entry of band `j` of indices `q`: its stream, or in a format 3 file its
    /// code-blocks' index and streams ([`codeblocks::encode_blocks`]).
    pub(super) fn code_indices(
        &self,
        q: &[i64],
        j: usize,
        kind: BandKind,
        parent: Option<Parent>,
    ) -> Vec<u8> {
        match self.grid(j) {
            Some(g) => blocks_payload(&codeblocks::encode_blocks(
                q,
                &g,
                kind,
                parent,
                self.coding,
                self.coder,
            )),
            None => band::encode_stream(q, &self.dims[j], kind, parent, self.coding),
        }
    }

    /// The code-block grid of band `j` in a format 3 file (its level's extents,
    /// [`Header::block_extents_at`](crate::format::Header::block_extents_at)); `None` before.
    pub(super) fn grid(&self, j: usize) -> Option<Grid> {
        self.blocks
            .as_ref()
            .map(|b| Grid::new(&self.dims[j], &b[j]))
    }

    /// The code-block extents of band `j` in a format 3 file; empty before.
    pub(super) fn block(&self, j: usize) -> &[usize] {
        self.blocks.as_ref().map_or(&[], |b| &b[j])
    }

    /// Box `b` of band `j` (in the band's coordinates) as a box of the pyramid's plane.
    pub(super) fn in_plane(&self, j: usize, b: &[Range<usize>]) -> Vec<Range<usize>> {
        self.bands[j]
            .ranges
            .iter()
            .zip(b)
            .map(|(r, x)| r.start + x.start..r.start + x.end)
            .collect()
    }

    /// The offset in the pyramid's plane of every row of band `j` (raster order).
    pub(super) fn row_offsets(&self, j: usize) -> Vec<usize> {
        let mut offs = Vec::new();
        layout::rows(&self.pyr.shape, &self.bands[j].ranges, |off, _, _| {
            offs.push(off)
        });
        offs
    }

    /// Append the `LEVL` chunks of `coded` (`[channel][band]`) to `out`; `ratio(c, j)` =
    /// band `j`'s step over the base step (as written, `f32`).
    pub(super) fn put_levels(
        &self,
        out: &mut Vec<u8>,
        coded: &[Vec<CodedBand>],
        ratio: impl Fn(usize, usize) -> f32,
    ) {
        let ratio = &ratio;
        for (level, js) in self.level_groups() {
            let streams = js.iter().flat_map(|&j| {
                coded
                    .iter()
                    .enumerate()
                    .map(move |(c, bands)| (ratio(c, j), &bands[j].stream[..]))
            });
            put_chunk(out, Tag::Levl.bytes(), &level_payload(level, streams));
        }
    }
}

/// A band handed to [`Plan::code_levels`].
pub(super) enum BandInput<'a> {
    /// Its indices.
    Indices(Vec<i64>),
    /// Its coefficients, where they sit in `plane` (laid out as the pyramid's shape),
    /// to be divided by `step` (as `f64`, then taken to `f32`) as they are coded: no
    /// copy of the band.
    Coefficients { plane: &'a [f32], step: f64 },
    /// Its indices `quantize(x, step, ρ)` of its coefficients `x` where they sit in
    /// `plane` ([`quantize_box`]): a band without children in a file of code-blocks is
    /// quantized block by block as it is coded (no `i64` band), any other band whole.
    /// The indices and so the streams are those of [`BandInput::Indices`].
    Quantize {
        plane: &'a [f32],
        step: f64,
        rho: f64,
    },
}

/// The indices `quantize(x, step, ρ)` of the coefficients `x` of box `ranges` of `plane`
/// (laid out as `shape`), in raster order over the box.
pub(super) fn quantize_box(
    plane: &[f32],
    shape: &[usize],
    ranges: &[Range<usize>],
    step: f64,
    rho: f64,
) -> Vec<i64> {
    let mut q = vec![0i64; ranges.iter().map(|r| r.len()).product()];
    layout::rows(shape, ranges, |off, run, b| {
        for (q, &x) in q[b..b + run].iter_mut().zip(&plane[off..off + run]) {
            *q = crate::quantize::quantize(x as f64, step, rho);
        }
    });
    q
}

/// `round(v)` half away from zero, 0 for values that are not finite, capped at 9·10^15.
#[inline]
pub(super) fn round_index(v: f32) -> i64 {
    if !v.is_finite() {
        return 0;
    }
    let a = (v.abs() + 0.5).min(9.0e15) as i64;
    if v < 0.0 {
        -a
    } else {
        a
    }
}
