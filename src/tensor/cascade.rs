//! All levels of a non-standard pyramid in one sweep over the array ("cascade").
//!
//! Level by level, every level reads its box and writes it back: the levels after the
//! first cost one more pass over a quarter (images) or an eighth (volumes) of the array,
//! and the detail blocks written to the scratch array have to be copied back. Here the
//! levels are chained row by row along axis 0 instead: a row of level `l` is computed as
//! soon as the rows of level `l − 1` it needs exist, and those are kept in a small ring
//! (a few rows, in the caches) rather than in the array:
//!
//! - **analysis**: output row `r` of level `l` is `Σ_c A_rc · (input row c)` followed by
//!   the level along the other axes ([`Ctx::finish_row`]); its coarse part (the box of
//!   level `l + 1`) goes to level `l + 1`'s ring, the rest (details) straight to the
//!   output array. Level 0 reads the array.
//! - **synthesis**: input row `c` of level `l` is a row of level `l + 1`'s output (its
//!   coarse box) completed with the details of the array, or a detail row of the array;
//!   output rows of level 0 go to the output array.
//!
//! Every sample is read once and written once for the whole pyramid, and every output
//! is the same sums in the same order as level by level ([`super::fused`]): the same bits.
//!
//! Periodic ends: the first rows of a level read its last rows and the other way round,
//! so a ring would have to hold the whole level. For images, those rows ("wrapping"
//! rows) read "ghosts" instead: the few rows near the ends that they need, computed by
//! each part before its sweep with the same sums (a cone a few rows wide per level,
//! doubling away from the wrapping level), so the rings only ever see regular rows.
//!
//! Threads take consecutive parts of the rows of each level. A part computes what its
//! rows need, so rows near a seam between parts are computed by both (a "halo", written
//! by its owner only); [`Plan::new`] declines when the halos would cost more than
//! [`MAX_HALO`] of the work.

use super::aligned::Aligned;
use super::boxes::{copy_box_outside, strided, strided_mut};
use super::fused::{AxisOp, Ctx, STREAM_BYTES};
use super::par::SharedMut;
use super::ring::Ring;
use crate::kernel::{combine_pair_taps, combine_taps, stream_fence, Kernels, PairMemo, PairOut};
use crate::scheme::sparse::Csr;
use crate::scheme::Sample;
use rayon::prelude::*;

/// Largest extra work (rows computed twice at seams between parts) the cascade accepts.
const MAX_HALO: f64 = 0.15;

/// Most axes a cascade runs over.
const MAX_AXES: usize = 8;

/// The parts' rings and scratch may hold at most this fraction (1 / `MAX_HELD`) of the
/// array (the engine's memory stays within the array and one scratch array, plus this).
const MAX_HELD: usize = 16;

/// Most rows a level's ring may hold.
const MAX_RING: usize = 24;

/// Fewest samples per part: below this a pyramid runs in one part.
const MIN_PART: usize = 1 << 18;

/// Which way the levels go.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Way {
    Analysis,
    Synthesis,
}

/// Positions (in a level's row order) one part computes: `start..end`, of which it owns
/// (writes) `own`.
#[derive(Clone, Debug)]
struct Span {
    start: usize,
    end: usize,
    own: std::ops::Range<usize>,
}

/// How a pyramid runs as a cascade: the levels' regions, row orders, ring sizes and
/// the parts.
pub(super) struct Plan<'a> {
    way: Way,
    /// `regions[l]` = box before level `l` (leading `k` axes); `regions[levels]` = the
    /// coarsest block.
    regions: Vec<Vec<usize>>,
    /// Per level, the axes' operators.
    ops: &'a [Vec<AxisOp<'a>>],
    /// Per level, the order in which its output rows along axis 0 are computed.
    order: Vec<Vec<usize>>,
    /// Per level, slots of its input ring: (coarse rows, detail rows).
    caps: Vec<(usize, usize)>,
    /// `spans[p][l]`.
    spans: Vec<Vec<Span>>,
    e: usize,
    /// Rows along axis 0 are single lines (images): the box of a level is a prefix of
    /// the row, so rings hold whole rows and the array's rows are read in place.
    lines: bool,
    /// Per level (analysis of images with periodic ends, else empty): the rows that reach
    /// across the lane. From level 1 on they read their inputs from the ghosts, never
    /// from the ring.
    wrap: Vec<Vec<bool>>,
    /// Per part and level, increasing: the output rows the part computes first, as
    /// ghosts (the inputs of the wrapping rows it computes at the next level, and of the
    /// ghosts of that level).
    need: Vec<Vec<Vec<usize>>>,
}

/// Input rows of `op` (columns in `cols`) alive at once when its rows are computed in
/// `order` and every input is made just before its first use and dropped after its last:
/// `max_p (max col of rows ≤ p) − (min col of rows ≥ p) + 1`.
fn live_span(op: &Csr, order: &[usize], cols: std::ops::Range<usize>, skip: &[bool]) -> usize {
    let n = order.len();
    let range = |r: usize| {
        if skip.get(r) == Some(&true) {
            return None;
        }
        let (c, _) = op.row_slices(r);
        let inside = c.iter().map(|&c| c as usize).filter(|c| cols.contains(c));
        inside.fold(None, |acc: Option<(usize, usize)>, c| {
            Some(acc.map_or((c, c), |(lo, hi)| (lo.min(c), hi.max(c))))
        })
    };
    let mut suffix_min = vec![usize::MAX; n + 1];
    for p in (0..n).rev() {
        suffix_min[p] = suffix_min[p + 1].min(range(order[p]).map_or(usize::MAX, |r| r.0));
    }
    let (mut hi, mut span) = (None::<usize>, 1);
    for p in 0..n {
        if let Some((_, h)) = range(order[p]) {
            hi = Some(hi.map_or(h, |x: usize| x.max(h)));
        }
        if let (Some(h), lo) = (hi, suffix_min[p]) {
            if lo <= h {
                span = span.max(h - lo + 1);
            }
        }
    }
    span
}

/// The least and the greatest column (within `cols`) of the rows at `positions` of `order`.
fn col_range(
    op: &Csr,
    order: &[usize],
    positions: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
    skip: &[bool],
) -> Option<(usize, usize)> {
    let mut out: Option<(usize, usize)> = None;
    for &r in &order[positions] {
        if skip.get(r) == Some(&true) {
            continue;
        }
        for &c in op.row_slices(r).0 {
            let c = c as usize;
            if cols.contains(&c) {
                out = Some(out.map_or((c, c), |(lo, hi)| (lo.min(c), hi.max(c))));
            }
        }
    }
    out
}

/// The levels a [`Plan`] is built for: the steps of [`Plan::build`], each a question
/// about their rows.
struct Levels<'r, 'a> {
    way: Way,
    /// `regions[l]` = box before level `l`; `regions[levels]` = the coarsest block.
    regions: &'r [Vec<usize>],
    ops: &'a [Vec<AxisOp<'a>>],
    e: usize,
}

impl Levels<'_, '_> {
    fn count(&self) -> usize {
        self.ops.len()
    }

    /// Rows along axis 0 before level `l`.
    fn n(&self, l: usize) -> usize {
        self.regions[l][0]
    }

    /// Samples of a row of level `l`.
    fn row_len(&self, l: usize) -> usize {
        self.regions[l][1..].iter().product::<usize>() * self.e
    }

    /// Per level, the rows that reach across the lane (periodic ends): inputs more than
    /// half of it apart (synthesis: coarse inputs more than half of the coarse rows
    /// apart; the details come from the array).
    fn wrapping_rows(&self) -> Vec<Vec<bool>> {
        (0..self.count())
            .map(|l| {
                let op = self.ops[l][0].op;
                let (lim, within) = match self.way {
                    Way::Analysis => (self.n(l), self.n(l)),
                    Way::Synthesis => (self.n(l + 1), self.n(l + 1)),
                };
                (0..self.n(l))
                    .map(|r| {
                        let cs = op.row_slices(r).0.iter().map(|&c| c as usize);
                        let mut inside = cs.filter(|&c| c < within);
                        let first = inside.next();
                        let last = inside.next_back().or(first);
                        matches!((first, last), (Some(a), Some(b)) if b - a > lim / 2)
                    })
                    .collect()
            })
            .collect()
    }

    /// Per level, the order in which its rows are computed: analysis by first column
    /// (a wrapping row by its first column on its own side of the lane, the half around
    /// where its index puts it); synthesis in index order. `None` when the coarse rows of
    /// an analysis do not come in increasing order, as the next level asks for them.
    fn row_orders(&self, wrap: &[Vec<bool>], ghosts: bool) -> Option<Vec<Vec<usize>>> {
        let levels = self.count();
        let mut order: Vec<Vec<usize>> = (0..levels)
            .map(|l| match self.way {
                Way::Analysis => self.ops[l][0].order.to_vec(),
                Way::Synthesis => (0..self.n(l)).collect(),
            })
            .collect();
        if self.way == Way::Synthesis {
            return Some(order);
        }
        if ghosts {
            for (l, ord) in order.iter_mut().enumerate() {
                let (n, nc) = (self.n(l), self.n(l + 1));
                let nd = n - nc;
                let key = |r: usize| -> usize {
                    let cols = self.ops[l][0]
                        .op
                        .row_slices(r)
                        .0
                        .iter()
                        .map(|&c| c as usize);
                    if wrap[l][r] {
                        let at = if r < nc {
                            r * n / nc.max(1)
                        } else {
                            (r - nc) * n / nd.max(1)
                        };
                        cols.filter(|&c| c.abs_diff(at) <= n / 2)
                            .min()
                            .unwrap_or(at)
                    } else {
                        cols.min().unwrap_or(0)
                    }
                };
                ord.sort_by_key(|&r| (key(r), r));
            }
        }
        for (l, ord) in order.iter().enumerate().take(levels - 1) {
            let coarse: Vec<usize> = ord.iter().copied().filter(|&r| r < self.n(l + 1)).collect();
            if coarse.len() != self.n(l + 1) || coarse.windows(2).any(|w| w[0] >= w[1]) {
                return None;
            }
        }
        Some(order)
    }

    /// Per level, the slots of its input ring (coarse rows, detail rows): the input rows
    /// alive at once in `order` ([`live_span`]).
    fn ring_caps(
        &self,
        order: &[Vec<usize>],
        wrap: &[Vec<bool>],
        lines: bool,
    ) -> Vec<(usize, usize)> {
        let levels = self.count();
        (0..levels)
            .map(|l| {
                let op = self.ops[l][0].op;
                let (n, nc) = (self.n(l), self.n(l + 1));
                match self.way {
                    Way::Analysis if l == 0 => (0, 0),
                    Way::Analysis => (live_span(op, &order[l], 0..n, &wrap[l]), 0),
                    // images: the coarsest level reads the array, details come from it
                    Way::Synthesis if lines && l + 1 == levels => (0, 0),
                    Way::Synthesis if lines => (live_span(op, &order[l], 0..nc, &wrap[l]), 0),
                    Way::Synthesis => {
                        let detail = if l == 0 {
                            0
                        } else {
                            live_span(op, &order[l], nc..n, &[])
                        };
                        (live_span(op, &order[l], 0..nc, &[]), detail)
                    }
                }
            })
            .collect()
    }

    /// Samples of all levels' boxes.
    fn total(&self) -> usize {
        (0..self.count()).map(|l| self.n(l) * self.row_len(l)).sum()
    }

    /// How many parts: `parts` when `forced`, else at most one per [`MIN_PART`] samples
    /// and per row of the last level.
    fn part_count(&self, parts: usize, forced: bool) -> usize {
        if forced {
            return parts.max(1);
        }
        parts
            .clamp(1, (self.total() / MIN_PART).max(1))
            .min(self.n(self.count() - 1).max(1))
    }

    /// Per part and level, the ghosts: level `l`'s wrapping rows read rows that level
    /// `l − 1` (analysis) or `l + 1` (synthesis, its coarse inputs) makes, computed first,
    /// and so do those rows themselves (a few rows at one end or both, doubling away from
    /// the wrapping level); each part for the wrapping rows it computes. Empty without
    /// wrapping rows.
    fn ghost_needs(
        &self,
        order: &[Vec<usize>],
        wrap: &[Vec<bool>],
        spans: &[Vec<Span>],
    ) -> Vec<Vec<Vec<usize>>> {
        let levels = self.count();
        // each row's position in its level's order
        let pos: Vec<Vec<usize>> = order
            .iter()
            .map(|ord| {
                let mut at = vec![0; ord.len()];
                for (i, &r) in ord.iter().enumerate() {
                    at[r] = i;
                }
                at
            })
            .collect();
        spans
            .iter()
            .map(|sp| {
                let mine = |l: usize, r: usize| {
                    wrap[l].get(r) == Some(&true) && (sp[l].start..sp[l].end).contains(&pos[l][r])
                };
                let mut need: Vec<Vec<usize>> = vec![Vec::new(); levels];
                let inputs = |l: usize, need_l: &[usize], within: usize| {
                    let op = self.ops[l][0].op;
                    let mut rows = std::collections::BTreeSet::new();
                    for r in 0..self.n(l) {
                        if mine(l, r) || need_l.binary_search(&r).is_ok() {
                            let cs = op.row_slices(r).0.iter().map(|&c| c as usize);
                            rows.extend(cs.filter(|&c| c < within));
                        }
                    }
                    rows.into_iter().collect::<Vec<usize>>()
                };
                match self.way {
                    Way::Analysis => {
                        for l in (1..levels).rev() {
                            need[l - 1] = inputs(l, &need[l], self.n(l));
                        }
                    }
                    Way::Synthesis => {
                        // the coarsest level's inputs are the array's
                        for l in 0..levels.saturating_sub(1) {
                            need[l + 1] = inputs(l, &need[l], self.n(l + 1));
                        }
                    }
                }
                need
            })
            .collect()
    }

    /// Whether the parts' memory (rings, a few rows of scratch per level, ghosts) stays
    /// within 1/[`MAX_HELD`] of the array (a short image with very long rows would need
    /// rings as large as the image), and their work (rows computed twice at seams) within
    /// [`MAX_HALO`] more than the pyramid's.
    fn fits(&self, caps: &[(usize, usize)], spans: &[Vec<Span>], need: &[Vec<Vec<usize>>]) -> bool {
        let levels = self.count();
        // samples of a ghost row of level l: what its reader takes (analysis: the box of
        // level l + 1, a prefix of the row)
        let ghost_len = |l: usize| match self.way {
            Way::Analysis => self.row_len((l + 1).min(levels)),
            Way::Synthesis => self.row_len(l),
        };
        let work: usize = spans
            .iter()
            .flat_map(|s| s.iter().enumerate())
            .map(|(l, s)| (s.end - s.start) * self.row_len(l))
            .sum();
        let held: usize = (0..levels)
            .map(|l| {
                let row = self.row_len(l) + if l > 0 { self.row_len(l - 1) } else { 0 };
                (caps[l].0 + caps[l].1 + 8) * row
            })
            .sum::<usize>()
            * spans.len()
            + need
                .iter()
                .flat_map(|nd| nd.iter().enumerate())
                .map(|(l, rows)| rows.len() * ghost_len(l))
                .sum::<usize>();
        held * MAX_HELD <= self.n(0) * self.row_len(0)
            && work as f64 <= self.total() as f64 * (1.0 + MAX_HALO)
    }
}

/// What [`Plan::new`] asks of [`Plan::build`]: the direction, the samples per position,
/// the parts, whether they are forced, and whether rows reaching across the lane read
/// ghosts.
#[derive(Clone, Copy)]
struct Ask {
    way: Way,
    e: usize,
    parts: usize,
    forced: bool,
    ghosts: bool,
}

impl<'a> Plan<'a> {
    /// Plan `ops.len()` levels (at least 2) whose regions are `regions` (one more than
    /// levels), with up to `parts` parts; `None` when the cascade does not apply (row
    /// orders it cannot follow, rows reaching across the lane of a volume (images read
    /// ghosts for them), halos too costly for that
    /// many parts, rings above 1/[`MAX_HELD`] of the array). When `forced` (tests),
    /// exactly `parts` parts whatever the halos and the rings' size, and boxes of more
    /// than two axes too; otherwise those stay level by level (measured slower on
    /// volumes, likely because the planes of two levels and a ring of planes do not fit
    /// a 1 MB L2).
    pub fn new(
        way: Way,
        regions: Vec<Vec<usize>>,
        ops: &'a [Vec<AxisOp<'a>>],
        e: usize,
        parts: usize,
        forced: bool,
    ) -> Option<Self> {
        let ask = Ask {
            way,
            e,
            parts,
            forced,
            ghosts: false,
        };
        Self::build(regions.clone(), ops, ask).or_else(|| {
            // images with periodic ends: the rows that reach across the lane read ghosts
            let ask = Ask {
                ghosts: true,
                ..ask
            };
            (regions[0].len() == 2)
                .then(|| Self::build(regions, ops, ask))
                .flatten()
        })
    }

    /// [`Plan::new`], with ghosts for the rows that reach across the lane when `ghosts`:
    /// the rows' orders, the rings' sizes, the parts and their ghosts, then the checks of
    /// memory and halos.
    fn build(regions: Vec<Vec<usize>>, ops: &'a [Vec<AxisOp<'a>>], ask: Ask) -> Option<Self> {
        let Ask {
            way,
            e,
            parts,
            forced,
            ghosts,
        } = ask;
        let levels = ops.len();
        if levels < 2
            || regions.len() != levels + 1
            || regions[0].len() < 2
            || regions[0].len() > MAX_AXES
            || (regions[0].len() > 2 && !forced)
        {
            return None;
        }
        let g = Levels {
            way,
            regions: &regions,
            ops,
            e,
        };
        let wrap = if ghosts {
            g.wrapping_rows()
        } else {
            vec![Vec::new(); levels]
        };
        if ghosts && !wrap.iter().flatten().any(|&w| w) {
            return None;
        }
        let order = g.row_orders(&wrap, ghosts)?;
        let lines = regions[0].len() == 2;
        let caps = g.ring_caps(&order, &wrap, lines);
        // rows that reach across the lane (periodic ends) would hold a whole level
        if caps.iter().any(|&(c, d)| c + d > MAX_RING) {
            return None;
        }
        let parts = g.part_count(parts, forced);
        let spans: Vec<Vec<Span>> = (0..parts)
            .map(|p| Self::part_spans(way, &regions, ops, &order, &wrap, p, parts))
            .collect::<Option<_>>()?;
        let need = g.ghost_needs(&order, &wrap, &spans);
        if !forced && !g.fits(&caps, &spans, &need) {
            return None;
        }
        Some(Plan {
            way,
            regions,
            ops,
            order,
            caps,
            spans,
            e,
            lines,
            wrap,
            need,
        })
    }

    /// Samples of a ghost row of level `l`: what its reader takes (analysis: the box of
    /// level `l + 1`, a prefix of the row; synthesis: the row, the box of level `l`).
    fn ghost_len(&self, l: usize) -> usize {
        let row_len = |l: usize| self.regions[l][1..].iter().product::<usize>() * self.e;
        match self.way {
            Way::Analysis => row_len((l + 1).min(self.ops.len())),
            Way::Synthesis => row_len(l),
        }
    }

    /// What part `p` of `parts` computes at every level.
    fn part_spans(
        way: Way,
        regions: &[Vec<usize>],
        ops: &[Vec<AxisOp>],
        order: &[Vec<usize>],
        wrap: &[Vec<bool>],
        p: usize,
        parts: usize,
    ) -> Option<Vec<Span>> {
        let levels = ops.len();
        let n = |l: usize| regions[l][0];
        let own = |l: usize| n(l) * p / parts..n(l) * (p + 1) / parts;
        let mut spans: Vec<Span> = (0..levels)
            .map(|_| Span {
                start: 0,
                end: 0,
                own: 0..0,
            })
            .collect();
        match way {
            Way::Analysis => {
                // every level writes the rows it owns; deeper levels pull what they need
                for l in (0..levels).rev() {
                    let o = own(l);
                    let (mut start, mut end) = (o.start, o.end);
                    if l + 1 < levels {
                        let up = &spans[l + 1];
                        if up.end > up.start {
                            let (lo, hi) = col_range(
                                ops[l + 1][0].op,
                                &order[l + 1],
                                up.start..up.end,
                                0..n(l + 1),
                                &wrap[l + 1],
                            )?;
                            // positions of coarse rows lo and hi in this level's order
                            let at = |c: usize| order[l].iter().position(|&r| r == c);
                            start = start.min(at(lo)?);
                            end = end.max(at(hi)? + 1);
                        }
                    }
                    spans[l] = Span { start, end, own: o };
                }
            }
            Way::Synthesis => {
                // level 0 writes the rows it owns; the others feed it
                spans[0] = Span {
                    start: own(0).start,
                    end: own(0).end,
                    own: own(0),
                };
                for l in 1..levels {
                    let down = &spans[l - 1];
                    let (start, end) = if down.end > down.start {
                        match col_range(
                            ops[l - 1][0].op,
                            &order[l - 1],
                            down.start..down.end,
                            0..n(l),
                            &wrap[l - 1],
                        ) {
                            Some((lo, hi)) => (lo, hi + 1),
                            None => (0, 0),
                        }
                    } else {
                        (0, 0)
                    };
                    spans[l] = Span {
                        start,
                        end,
                        own: 0..0,
                    };
                }
            }
        }
        Some(spans)
    }

    /// Run the cascade: `src` (strides `strides`, leading `k`) into `dst`, every level.
    pub fn run<T: Sample>(&self, src: &[T], dst: &mut [T], strides: &[usize]) {
        let levels = self.ops.len();
        let k = self.regions[0].len();
        assert_eq!(strides.len(), k);
        assert_eq!(strides[k - 1], self.e);
        assert!(src.len() == dst.len() && strides[0] * self.regions[0][0] <= src.len());
        let bytes = self.regions[0].iter().product::<usize>() * self.e * std::mem::size_of::<T>();
        // the output goes past the caches (it is not read again in this sweep)
        let stream = bytes >= STREAM_BYTES;
        let ctxs: Vec<Ctx> = (0..levels)
            .map(|l| Ctx::new(&self.regions[l], self.e, &self.ops[l], stream))
            .collect();
        let local: Vec<Ctx> = (0..levels)
            .map(|l| Ctx::new(&self.regions[l], self.e, &self.ops[l], false))
            .collect();
        let dptr = SharedMut(dst.as_mut_ptr());
        let dst_len = dst.len();
        let run_part = |p: usize| {
            let d = dptr;
            let spans = &self.spans[p];
            let mut part = Part {
                plan: self,
                ctxs: &ctxs,
                local: &local,
                src,
                dst: d,
                dst_len,
                strides,
                spans,
                levels: level_states(self, &ctxs, spans),
                need: &self.need[p],
                ghosts: (0..levels)
                    .map(|l| vec![T::default(); self.need[p][l].len() * self.ghost_len(l)])
                    .collect(),
            };
            part.run();
            // the rows the part streamed out (`Ctx::finish_split_row`, `copy_box_outside`)
            // copied without a fence each
            stream_fence();
        };
        if self.spans.len() == 1 {
            run_part(0);
        } else {
            (0..self.spans.len()).into_par_iter().for_each(run_part);
        }
    }
}

/// Per level state of one part.
struct LevelState<T> {
    /// Next position in the level's order.
    cursor: usize,
    /// Analysis: the last coarse row made (rows come in increasing order).
    made: Option<usize>,
    /// The level's input rows (analysis: level ≥ 1; synthesis: every level).
    ring: Ring<T>,
    /// The level's scratch ([`Ctx::scratch`]); its first buffer takes the row combined
    /// along axis 0.
    scratch: Vec<Aligned<T>>,
    /// The next row combined along axis 0 together with the current one, for position
    /// `pending` ([`Step::combine_pair`]).
    next_slab: Aligned<T>,
    pending: Option<usize>,
    /// That row comes split into its even and odd samples.
    pending_split: bool,
    /// The pattern of the level's last pair of rows ([`Step::combine_pair`]).
    memo: PairMemo<T>,
    /// A whole output row, compact (analysis rows that feed the next level).
    out: Vec<T>,
}

struct Part<'p, 'a, T> {
    plan: &'p Plan<'a>,
    ctxs: &'p [Ctx<'p>],
    local: &'p [Ctx<'p>],
    src: &'p [T],
    dst: SharedMut<T>,
    dst_len: usize,
    strides: &'p [usize],
    spans: &'p [Span],
    levels: Vec<LevelState<T>>,
    /// This part's [`Plan::need`].
    need: &'p [Vec<usize>],
    /// Per level, the rows of `need` ([`Plan::ghost_len`] samples each).
    ghosts: Vec<Vec<T>>,
}

/// Every level's state for the part computing `spans`.
fn level_states<T: Sample>(plan: &Plan, ctxs: &[Ctx], spans: &[Span]) -> Vec<LevelState<T>> {
    (0..plan.ops.len())
        .map(|l| {
            // images: analysis rings hold the previous level's whole rows
            let row = if plan.lines && plan.way == Way::Analysis && l > 0 {
                ctxs[l - 1].cs()[0]
            } else {
                ctxs[l].cs()[0]
            };
            let (c, d) = plan.caps[l];
            let split = match plan.way {
                Way::Analysis => usize::MAX,
                Way::Synthesis => plan.regions[l + 1][0],
            };
            let needs_out = plan.way == Way::Analysis && l + 1 < plan.ops.len() && !plan.lines;
            LevelState {
                cursor: spans[l].start,
                made: None,
                ring: Ring::new(row, c, d, split),
                scratch: ctxs[l].scratch(),
                next_slab: Aligned::heap(ctxs[l].cs()[0]),
                pending: None,
                pending_split: false,
                memo: PairMemo::default(),
                out: vec![T::default(); if needs_out { row } else { 0 }],
            }
        })
        .collect()
}

impl<'p, 'a, T: Sample> Part<'p, 'a, T> {
    fn run(&mut self) {
        let levels = self.plan.ops.len();
        match self.plan.way {
            Way::Analysis => {
                // one buffer for the ghosts' whole rows (level 0's, the longest, first)
                let mut whole = Vec::new();
                for l in 0..levels {
                    for i in 0..self.need[l].len() {
                        self.ghost_row(l, i, &mut whole);
                    }
                }
                for l in (0..levels).rev() {
                    while self.levels[l].cursor < self.spans[l].own.end {
                        self.analysis_row(l);
                    }
                }
            }
            Way::Synthesis => {
                for l in (1..levels).rev() {
                    for i in 0..self.need[l].len() {
                        self.ghost_row(l, i, &mut Vec::new());
                    }
                }
                while self.levels[0].cursor < self.spans[0].own.end {
                    self.synthesis_row(0);
                }
            }
        }
    }

    /// The output array from the start of row `r` along axis 0.
    fn dst_row(&self, r: usize) -> &'p mut [T] {
        let at = r * self.strides[0];
        assert!(at <= self.dst_len);
        // SAFETY: parts own disjoint rows of every level (`Span::own`) and write only
        // those; the parts of one row that different levels write are disjoint (the
        // details of level `l` lie outside the box of level `l + 1`). No part reads `dst`.
        unsafe { std::slice::from_raw_parts_mut(self.dst.0.add(at), self.dst_len - at) }
    }

    /// The next row of level `l` in its order.
    fn next_row(&self, l: usize) -> Step<'a> {
        self.step_at(l, self.levels[l].cursor)
    }

    /// The row at position `pos` of level `l`'s order.
    fn step_at(&self, l: usize, pos: usize) -> Step<'a> {
        let r = self.plan.order[l][pos];
        Step {
            k: self.plan.ops[l][0].plan.kernels,
            pos,
            r,
            taps: self.plan.ops[l][0].op.row_slices(r),
        }
    }

    /// Row `need[l][i]` of level `l` into the ghosts: as [`Part::analysis_row`] makes it
    /// for the next level's ring, its inputs read from the array (level 0) or from the
    /// ghosts of level `l − 1`.
    ///
    /// `whole` (analysis): room for the whole row before the ghost keeps its prefix.
    fn ghost_row(&mut self, l: usize, i: usize, whole: &mut Vec<T>) {
        let plan = self.plan;
        let need = self.need;
        let r = need[l][i];
        let step = Step {
            k: plan.ops[l][0].plan.kernels,
            pos: usize::MAX,
            r,
            taps: plan.ops[l][0].op.row_slices(r),
        };
        let (src, s0) = (self.src, self.strides[0]);
        let row_len = self.ctxs[l].cs()[0];
        if plan.way == Way::Synthesis {
            // as `synthesis_row`: the coarse inputs from the ghosts of level l + 1 (or the
            // array, below the coarsest level), the rest of the rows from the array
            let levels = plan.ops.len();
            let nc = plan.regions[l + 1][0];
            let w1 = if l + 1 < levels {
                self.ctxs[l + 1].cs()[0]
            } else {
                0
            };
            let (here, above) = self.ghosts.split_at_mut(l + 1);
            let st = &mut self.levels[l];
            if w1 > 0 {
                step.combine(&mut st.scratch[0], 0..w1, |c| {
                    let c = c as usize;
                    if c < nc {
                        &ghost(&need[l + 1], &above[0], c, w1)[..w1]
                    } else {
                        &src[c * s0..c * s0 + w1]
                    }
                });
            }
            step.combine(&mut st.scratch[0], w1..row_len, |c| {
                let c = c as usize;
                &src[c * s0..c * s0 + row_len]
            });
            let (slab, rest) = st.scratch.split_first_mut().expect("slab");
            let out = &mut here[l][i * row_len..(i + 1) * row_len];
            self.local[l].finish_row(&slab[..row_len], out, self.ctxs[l].cs(), rest);
            return;
        }
        let below_len = if l > 0 { plan.ghost_len(l - 1) } else { 0 };
        let keep = plan.ghost_len(l);
        let (below, here) = self.ghosts.split_at_mut(l);
        let st = &mut self.levels[l];
        step.combine(&mut st.scratch[0], 0..row_len, |c| {
            let c = c as usize;
            if l == 0 {
                &src[c * s0..c * s0 + row_len]
            } else {
                &ghost(&need[l - 1], &below[l - 1], c, below_len)[..row_len]
            }
        });
        // the whole row as the next level's ring takes it, of which the ghost keeps the
        // part that level reads
        let (slab, rest) = st.scratch.split_first_mut().expect("slab");
        whole.resize(row_len, T::default());
        self.local[l].finish_row(
            &slab[..row_len],
            &mut whole[..row_len],
            self.ctxs[l].cs(),
            rest,
        );
        here[0][i * keep..(i + 1) * keep].copy_from_slice(&whole[..keep]);
    }

    /// Compute the next row of level `l` in its order (analysis).
    fn analysis_row(&mut self, l: usize) {
        let plan = self.plan;
        let levels = plan.ops.len();
        let step = self.next_row(l);
        self.levels[l].cursor += 1;
        // a row reaching across the lane reads ghosts (level ≥ 1)
        let wraps = |st: &Step| l > 0 && plan.wrap[l].get(st.r) == Some(&true);
        let wrapping = wraps(&step);
        if l > 0 && !wrapping {
            for &c in step.taps.0 {
                let c = c as usize;
                while !matches!(self.levels[l - 1].made, Some(m) if m >= c) {
                    assert!(
                        self.levels[l - 1].cursor < plan.order[l - 1].len(),
                        "cascade: level {} never makes row {c}",
                        l - 1
                    );
                    self.analysis_row(l - 1);
                }
            }
        }
        let (src, strides) = (self.src, self.strides);
        let row_len = self.ctxs[l].cs()[0];
        let next = (step.pos + 1 < self.spans[l].end).then(|| self.step_at(l, step.pos + 1));
        // rows combined in pairs come split into their even and odd samples where the
        // level's lanes take them so (`Ctx::finish_split_row`), saving the lanes' split
        let split_ok = self.ctxs[l].takes_split_rows();
        let mut split = false;
        {
            let st = &mut self.levels[l];
            let s0 = strides[0];
            if st.pending == Some(step.pos) {
                // made with the row before (`combine_pair`)
                std::mem::swap(&mut st.scratch[0], &mut st.next_slab);
                st.pending = None;
                split = st.pending_split;
            } else {
                let ring = &st.ring;
                let ghosts = (l > 0).then(|| (&self.need[l - 1], &self.ghosts[l - 1]));
                let below = if l > 0 { plan.ghost_len(l - 1) } else { 0 };
                let tap = |c: u32| -> &[T] {
                    let c = c as usize;
                    match ghosts {
                        None => &src[c * s0..c * s0 + row_len],
                        Some((rows, data)) if wrapping => &ghost(rows, data, c, below)[..row_len],
                        Some(_) => &ring.get(c)[..row_len],
                    }
                };
                // the next row too when its inputs are at hand (level 0 reads the array;
                // a ring holds what the level below has made), neither reaching across
                let with = next.filter(|n| {
                    !wrapping
                        && !wraps(n)
                        && (l == 0 || n.taps.0.iter().all(|&c| ring.has(c as usize)))
                });
                let paired = with.is_some_and(|n| {
                    let (a, b) = (&mut st.scratch[0], &mut st.next_slab);
                    let (a, b) = (&mut a[..row_len], &mut b[..row_len]);
                    step.combine_pair((&mut st.memo, split_ok), &n, [a, b], 0..row_len, tap)
                });
                if paired {
                    st.pending = Some(step.pos + 1);
                    (split, st.pending_split) = (split_ok, split_ok);
                } else {
                    step.combine(&mut st.scratch[0], 0..row_len, tap);
                }
            }
        }
        let (pos, r) = (step.pos, step.r);
        let owned = self.spans[l].own.contains(&pos);
        let feeds = l + 1 < levels && r < plan.regions[l + 1][0];
        let out_row = owned.then(|| self.dst_row(r));
        let (ctx, local) = (&self.ctxs[l], &self.local[l]);
        let (here, up) = self.levels[l..].split_at_mut(1);
        let st = &mut here[0];
        let (slab, rest) = st.scratch.split_first_mut().expect("slab");
        let slab = &slab[..row_len];
        if !feeds {
            match out_row {
                Some(out) if split => ctx.finish_split_row(slab, out, rest),
                Some(out) => ctx.finish_row(slab, out, strides, rest),
                None => {}
            }
            return;
        }
        let cs = ctx.cs();
        st.made = Some(r);
        let next = &plan.regions[l + 1];
        let slot = up[0].ring.put(r);
        let whole: &[T] = if plan.lines {
            // the whole row into the next level's ring (which reads its prefix)
            if split {
                local.finish_split_row(slab, slot, rest);
            } else {
                local.finish_row(slab, slot, cs, rest);
            }
            slot
        } else {
            debug_assert!(!split, "split rows are rows of images");
            // the coarse box to the next level's ring
            local.finish_row(slab, &mut st.out, cs, rest);
            copy_box_outside(
                strided(&st.out, &cs[1..]),
                strided_mut(slot, &self.ctxs[l + 1].cs()[1..]),
                (&next[1..], whole(next.len() - 1)),
                plan.e,
                None,
            );
            &st.out
        };
        // the rest (details) to the array
        if let Some(out) = out_row {
            copy_box_outside(
                strided(whole, &cs[1..]),
                strided_mut(out, &strides[1..]),
                (&plan.regions[l][1..], &next[1..]),
                plan.e,
                ctx.stream.then_some(ctx.k),
            );
        }
    }

    /// Make input row `c` of level `l` available (synthesis).
    fn synthesis_input(&mut self, l: usize, c: usize) {
        let plan = self.plan;
        let levels = plan.ops.len();
        let nc = plan.regions[l + 1][0];
        let direct = if plan.lines {
            c >= nc || l + 1 == levels
        } else {
            l == 0 && c >= nc
        };
        if direct || self.levels[l].ring.has(c) {
            return;
        }
        if c < nc && l + 1 < levels {
            while self.levels[l + 1].cursor <= c {
                self.synthesis_row(l + 1);
            }
            return;
        }
        // a row of the array (details, or the coarsest block)
        let from = &self.src[c * self.strides[0]..];
        let cs = &self.ctxs[l].cs()[1..];
        let slot = self.levels[l].ring.put(c);
        copy_box_outside(
            strided(from, &self.strides[1..]),
            strided_mut(slot, cs),
            (&plan.regions[l][1..], whole(plan.regions[l].len() - 1)),
            plan.e,
            None,
        );
    }

    /// Compute the next row of level `l` (synthesis): into the array (level 0) or into
    /// the ring of level `l − 1`, completed with that row's details from the array.
    fn synthesis_row(&mut self, l: usize) {
        let plan = self.plan;
        let step = self.next_row(l);
        self.levels[l].cursor += 1;
        // made with the row before (`combine_pair`)
        let made = self.levels[l].pending == Some(step.pos);
        // a row reaching across the lane reads its coarse inputs from the ghosts
        let wraps = |st: &Step| plan.wrap[l].get(st.r) == Some(&true);
        let wrapping = wraps(&step);
        if !made && !wrapping {
            for &c in step.taps.0 {
                self.synthesis_input(l, c as usize);
            }
        }
        let (src, strides) = (self.src, self.strides);
        let row_len = self.ctxs[l].cs()[0];
        let nc = plan.regions[l + 1][0];
        let s0 = strides[0];
        let next =
            (!made && step.pos + 1 < self.spans[l].end).then(|| self.step_at(l, step.pos + 1));
        // rows of the array in place (images); the coarse rows' first `w1` samples are
        // the coarser level's output (when there is one)
        let w1 = if plan.lines && l + 1 < plan.ops.len() {
            self.ctxs[l + 1].cs()[0]
        } else {
            0
        };
        {
            let st = &mut self.levels[l];
            if made {
                std::mem::swap(&mut st.scratch[0], &mut st.next_slab);
                st.pending = None;
            } else {
                let ring = &st.ring;
                let ghosts = self.need.get(l + 1).zip(self.ghosts.get(l + 1));
                let coarse = |c: u32| -> &[T] {
                    let c = c as usize;
                    match ghosts {
                        _ if c >= nc => &src[c * s0..c * s0 + w1],
                        Some((rows, data)) if wrapping => &ghost(rows, data, c, w1)[..w1],
                        _ => &ring.get(c)[..w1],
                    }
                };
                let array = |c: u32| -> &[T] {
                    let c = c as usize;
                    &src[c * s0..c * s0 + row_len]
                };
                let held = |c: u32| -> &[T] {
                    let c = c as usize;
                    if l == 0 && c >= nc {
                        &src[c * s0..c * s0 + row_len]
                    } else {
                        ring.get(c)
                    }
                };
                // the next row too when its inputs are at hand
                let at_hand = |c: usize| {
                    if plan.lines {
                        w1 == 0 || c >= nc || ring.has(c)
                    } else {
                        (l == 0 && c >= nc) || ring.has(c)
                    }
                };
                let with = next.filter(|n| {
                    !wrapping && !wraps(n) && n.taps.0.iter().all(|&c| at_hand(c as usize))
                });
                let (a, b) = (&mut st.scratch[0], &mut st.next_slab);
                let memo = &mut st.memo;
                let paired = with.is_some_and(|n| {
                    if plan.lines {
                        let slabs = [&mut a[..], &mut b[..]];
                        (w1 == 0 || step.combine_pair((memo, false), &n, slabs, 0..w1, coarse))
                            && step.combine_pair((memo, false), &n, [a, b], w1..row_len, array)
                    } else {
                        step.combine_pair((memo, false), &n, [a, b], 0..row_len, held)
                    }
                });
                if paired {
                    st.pending = Some(step.pos + 1);
                } else if plan.lines {
                    if w1 > 0 {
                        step.combine(a, 0..w1, coarse);
                    }
                    step.combine(a, w1..row_len, array);
                } else {
                    step.combine(a, 0..row_len, held);
                }
            }
        }
        let r = step.r;
        let (ctx, local) = (&self.ctxs[l], &self.local[l]);
        if l == 0 {
            debug_assert!(self.spans[0].own.contains(&r));
            let out = self.dst_row(r);
            let st = &mut self.levels[0];
            let (slab, rest) = st.scratch.split_first_mut().expect("slab");
            ctx.finish_row(&slab[..row_len], out, strides, rest);
            return;
        }
        // into the finer level's ring: this level's box, then the rest of that row
        let fcs = self.ctxs[l - 1].cs();
        let (below, here) = self.levels.split_at_mut(l);
        let st = &mut here[0];
        let (slab, rest) = st.scratch.split_first_mut().expect("slab");
        let slab = &slab[..row_len];
        let slot = below[l - 1].ring.put(r);
        if plan.lines {
            // the finer level reads the rest of the row from the array
            local.finish_row(slab, slot, ctx.cs(), rest);
            return;
        }
        local.finish_row(slab, slot, fcs, rest);
        copy_box_outside(
            strided(&src[r * s0..], &strides[1..]),
            strided_mut(slot, &fcs[1..]),
            (&plan.regions[l - 1][1..], &plan.regions[l][1..]),
            plan.e,
            None,
        );
    }
}

/// Ghost row `c` (one of `rows`, increasing; `data` holds them, `len` samples each).
fn ghost<'g, T>(rows: &[usize], data: &'g [T], c: usize, len: usize) -> &'g [T] {
    let i = rows
        .binary_search(&c)
        .unwrap_or_else(|_| panic!("cascade: row {c} is not a ghost"));
    &data[i * len..(i + 1) * len]
}

/// One row of a level's operator along axis 0: its position in the level's order, its
/// index and its taps.
struct Step<'o> {
    /// The kernel table of the level's operator plan.
    k: Kernels,
    pos: usize,
    r: usize,
    taps: (&'o [u32], &'o [f64]),
}

impl Step<'_> {
    /// The row over samples `range` of the input rows (`tap(c)`: row `c` from its
    /// start) into `slab`.
    fn combine<'t, T: Sample + 't>(
        &self,
        slab: &mut [T],
        range: std::ops::Range<usize>,
        tap: impl Fn(u32) -> &'t [T],
    ) {
        let (cols, ws) = self.taps;
        combine_taps(self.k, &mut slab[range.clone()], cols, ws, |c| {
            &tap(c)[range.clone()]
        });
    }
}

impl Step<'_> {
    /// This row into `slab` and `other` into `slab2` over samples `range`, the inputs the
    /// two rows share read once ([`combine_pair_taps`]; `split`: each written as its
    /// even samples, then its odd ones); `false` (nothing written) when they do not pair.
    fn combine_pair<'t, T: Sample + 't>(
        &self,
        (memo, split): (&mut PairMemo<T>, bool),
        other: &Step,
        [slab, slab2]: [&mut [T]; 2],
        range: std::ops::Range<usize>,
        tap: impl Fn(u32) -> &'t [T],
    ) -> bool {
        let (a, b) = (&mut slab[range.clone()], &mut slab2[range.clone()]);
        let out = if split {
            PairOut::Split(a, b)
        } else {
            PairOut::Apart(a, b)
        };
        combine_pair_taps(self.k, memo, [self.taps, other.taps], out, |c| {
            &tap(c)[range.clone()]
        })
    }
}

/// No hole: for [`copy_box_outside`] over a whole box of `m` axes.
fn whole(m: usize) -> &'static [usize] {
    const NONE: [usize; MAX_AXES] = [0; MAX_AXES];
    &NONE[..m]
}
