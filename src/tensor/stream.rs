//! A non-standard (Mallat) pyramid streamed along axis 0: one transform over an array of
//! any length along its first axis, in memory bounded by a few rows per level.
//!
//! A *row* is a slab of the array at one index of axis 0 (a line of an image with its
//! channels, a plane of a volume): `shape[1..]` samples, row-major. Level `l` of the
//! pyramid reads rows of the box `region_l` (the coarse block of level `l − 1`) and makes
//! rows of the same box, each one:
//!
//! - **analysis**: output row `r` is `Σ_c A_rc · (input row c)` (the level's axis-0
//!   operator, the same sums in the same order as [`super::pyramid::analyze`]), then the
//!   level along the row's other active axes in increasing order. Its coarse box (when
//!   `r < n_{l+1}`, the box of level `l + 1`) is input row `r` of level `l + 1`; the rest
//!   (details) goes to the sink as band rows ([`BandRow`]).
//! - **synthesis**: input row `c` of level `l` is output row `c` of level `l + 1` (its
//!   coarse box; at the coarsest level, a row of the coarsest block) completed with the
//!   detail band rows of level `l` at `c`, or (when `c ≥ n_{l+1}`) detail band rows
//!   only; output row `r` is `Σ_c S_rc · (input row c)` then the other axes.
//!
//! So every sample gets the sums of the whole-array transform in the same order: the
//! same bits, for every scheme, boundary, size and level count.
//!
//! A level keeps an input row from its arrival until the last output row that reads it
//! is computed, and computes an output row as soon as all its inputs are there: with
//! local filters that is a few rows per level (the filter's support, doubled), whatever
//! the array's length. Periodic ends keep their bound too: an output row that reaches
//! across the lane waits (with its few inputs from the start of the lane) until the end
//! of the lane arrives, so its rows come out last.
//!
//! **Row order (analysis)**: the sink sees a band row as soon as it is computed, that is
//! when the last input row it reads has arrived; rows made by the same arrival come in
//! increasing row index of their level. With interpolating and symmetric ends every band's
//! rows come in increasing row order (a test holds it); with periodic ends the rows that
//! reach across the lane (the first one or two of each band per level) come at the end.
//! The coarsest block's rows (band 0) come as they are made too.
//!
//! **Row order (synthesis)**: output rows of level 0 are made in increasing order; each
//! pulls, depth first, what it reads: for every input row `c` of its taps in increasing
//! `c` not yet held, (coarse rows) output row `c` of level `l + 1` recursively, then the
//! low-half detail bands of level `l` at row `c` in [`Pyramid::subbands`] order; (detail
//! rows) the high-half bands at row `c − n_{l+1}`. [`StreamPlan::pull_order`] lists the
//! resulting `(band, row)` sequence exactly, without computing anything.

use super::aligned::Aligned;
use super::fused::{AxisOp, Ctx};
use super::pyramid::{Order, Pyramid, PyramidSpec, Subband};
use super::transform::transform_axis_with;
use super::workspace::{LevelOps, Planner};
use crate::kernel::{combine_taps, Kernels};
use crate::scheme::Sample;
use crate::{Error, Result};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

/// One row of one band, as the analysis hands it to its sink (and the synthesis asks
/// its source to fill).
#[derive(Debug)]
pub struct BandRow<'a, T> {
    /// Index into [`Pyramid::subbands`] (0 = the coarsest block).
    pub band: usize,
    /// The band's level (0 for the coarsest block, 1 = finest details).
    pub level: usize,
    /// Per transformed axis: high-pass along it.
    pub high: &'a [bool],
    /// Row index within the band along axis 0.
    pub row: usize,
    /// The band's extent along axes `1..` (the row's shape, row-major).
    pub shape: &'a [usize],
    /// The samples (`shape`'s product).
    pub data: &'a [T],
}

/// A band's place in the rows of one level: its index, its box inside the row box.
#[derive(Clone, Debug)]
struct Part {
    band: usize,
    ranges: Vec<Range<usize>>,
    shape: Vec<usize>,
}

/// One level of the stream.
struct Level {
    /// Row box before the level (`region_l[1..]`).
    row: Vec<usize>,
    /// Row box of the coarse block after it (`region_{l+1}[1..]`).
    coarse_row: Vec<usize>,
    /// Rows along axis 0 before and after the level.
    n: usize,
    nc: usize,
    /// The level's operators along axis 0, when axis 0 is active at this level.
    axis0: Option<Arc<LevelOps>>,
    /// The other active axes (increasing) as axes of the row, with their operators.
    others: Vec<(usize, Arc<LevelOps>)>,
    /// The detail bands of rows `< nc` (low along axis 0) and of rows `≥ nc`.
    low: Vec<Part>,
    high: Vec<Part>,
    /// Whether the coarse box and the low parts, and the high parts, cover the row box
    /// (disjoint boxes whose samples add up to the box's): then a synthesis input row
    /// is written whole by its parts and need not be zeroed first.
    covered: [bool; 2],
    /// Per input row of the synthesis: the output rows that read it.
    syn_uses: Vec<u32>,
    /// When the level's active axes are the leading `k ≥ 2` axes and the rest of the
    /// row is whole: the box over those axes and the samples per element, for the fused
    /// engine's row kernels ([`Ctx::finish_row`]).
    fused: Option<(Vec<usize>, usize)>,
}

/// A planned stream: the pyramid, its bands and its levels' operators.
pub struct StreamPlan {
    pyr: Pyramid,
    bands: Vec<Subband>,
    levels: Vec<Level>,
    kernels: Kernels,
    /// Samples of one row of the array.
    row_len: usize,
}

impl StreamPlan {
    /// Plan the stream of a non-standard pyramid `spec` over an array of `shape`, with
    /// the operators of [`Planner::shared`]. Axis 0 must be one of the transformed axes.
    pub fn new(shape: &[usize], spec: &PyramidSpec) -> Result<Self> {
        Self::new_in(Planner::shared(), shape, spec)
    }

    /// [`StreamPlan::new`] with the operators of `planner`.
    pub fn new_in(planner: &Planner, shape: &[usize], spec: &PyramidSpec) -> Result<Self> {
        if spec.order != Order::NonStandard {
            return Err(Error::parameter(
                "order",
                spec.order,
                "non-standard (a stream runs Mallat pyramids)",
            ));
        }
        if shape.is_empty() || !spec.axes.contains(&0) {
            return Err(Error::parameter(
                "axes",
                format!("{:?}", spec.axes),
                "axes including axis 0 (the axis the rows stream along)",
            ));
        }
        let pyr = Pyramid::plan(shape, spec)?;
        let bands = pyr.subbands();
        let depth = pyr.depth();
        let region = |l: usize| pyr.region_before(l);
        let i0 = spec.axes.iter().position(|&a| a == 0).unwrap_or(0);
        let ops =
            |i: usize, l: usize| planner.level_ops(spec.scheme, spec.boundary, pyr.lengths[i][l]);
        let levels = (0..depth)
            .map(|l| {
                let (before, after) = (region(l), region(l + 1));
                let axis0 = (l < pyr.axis_levels(i0)).then(|| ops(i0, l));
                let mut others: Vec<(usize, Arc<LevelOps>)> = (0..spec.axes.len())
                    .filter(|&i| i != i0 && l < pyr.axis_levels(i))
                    .map(|i| (spec.axes[i] - 1, ops(i, l)))
                    .collect();
                others.sort_by_key(|o| o.0);
                let (mut low, mut high) = (Vec::new(), Vec::new());
                for (b, s) in bands.iter().enumerate().filter(|(_, s)| s.level == l + 1) {
                    let part = Part {
                        band: b,
                        ranges: s.ranges[1..].to_vec(),
                        shape: s.ranges[1..].iter().map(|r| r.len()).collect(),
                    };
                    if axis0.is_some() && s.high[i0] {
                        high.push(part);
                    } else {
                        low.push(part);
                    }
                }
                let mut lv = Level {
                    row: before[1..].to_vec(),
                    coarse_row: after[1..].to_vec(),
                    n: before[0],
                    nc: after[0],
                    axis0,
                    others,
                    covered: [
                        volume(&after[1..]) + low.iter().map(|p| volume(&p.shape)).sum::<usize>()
                            == volume(&before[1..]),
                        high.iter().map(|p| volume(&p.shape)).sum::<usize>()
                            == volume(&before[1..]),
                    ],
                    low,
                    high,
                    syn_uses: Vec::new(),
                    fused: None,
                };
                // active axes exactly 0..k, the rest of the row whole (as
                // `pyramid::fused_axes` asks)
                let k = 1 + lv.others.len();
                let leading = lv.axis0.is_some()
                    && lv.others.iter().enumerate().all(|(j, o)| o.0 == j)
                    && (k..shape.len()).all(|d| before[d] == shape[d]);
                if k >= 2 && leading {
                    lv.fused = Some((before[..k].to_vec(), shape[k..].iter().product()));
                }
                let mut uses = vec![0u32; lv.n];
                for r in 0..lv.n {
                    match taps(&lv, r, false) {
                        [] => uses[r] += 1,
                        t => t.iter().for_each(|&c| uses[c as usize] += 1),
                    }
                }
                lv.syn_uses = uses;
                lv
            })
            .collect();
        Ok(StreamPlan {
            row_len: shape[1..].iter().product(),
            kernels: planner.kernels(),
            pyr,
            bands,
            levels,
        })
    }

    /// The pyramid the stream computes (what [`super::pyramid::analyze`] returns).
    pub fn pyramid(&self) -> &Pyramid {
        &self.pyr
    }

    /// The bands ([`Pyramid::subbands`]) the band rows index.
    pub fn bands(&self) -> &[Subband] {
        &self.bands
    }

    /// Samples of one row of the array (`shape[1..]`'s product).
    pub fn row_len(&self) -> usize {
        self.row_len
    }

    /// Rows of the array (its length along axis 0).
    pub fn rows(&self) -> usize {
        self.pyr.shape[0]
    }

    /// A streamed analysis handing band rows to `sink`: push the array's rows in order
    /// ([`Analysis::push`]), then [`Analysis::finish`].
    pub fn analysis<T: Sample, F: FnMut(BandRow<T>)>(&self, sink: F) -> Analysis<'_, T, F> {
        Analysis {
            plan: self,
            sink,
            next: 0,
            state: self
                .levels
                .iter()
                .map(|lv| AnalysisLevel::new(lv))
                .collect(),
            pool: Vec::new(),
            scratch: self.levels.iter().map(|_| None).collect(),
        }
    }

    /// Analyse the array whose row `r` `source` writes into its slice, every band row to
    /// `sink` (the rows pulled in order, one row buffer).
    pub fn analyze<T: Sample>(
        &self,
        mut source: impl FnMut(usize, &mut [T]),
        sink: impl FnMut(BandRow<T>),
    ) -> Result<()> {
        let mut a = self.analysis(sink);
        let mut row = vec![T::default(); self.row_len];
        for r in 0..self.rows() {
            source(r, &mut row);
            a.push(&row)?;
        }
        a.finish().map(|_| ())
    }

    /// A streamed synthesis pulling band rows from `source(band, row, samples)` (the
    /// order of the module's documentation, [`StreamPlan::pull_order`]), which writes
    /// every sample of `samples` (the buffer is not cleared before): the array's rows
    /// come out of [`Synthesis::pull`] in order.
    pub fn synthesis<T: Sample, S: FnMut(usize, usize, &mut [T])>(
        &self,
        source: S,
    ) -> Synthesis<'_, T, S> {
        Synthesis {
            plan: self,
            source,
            next: 0,
            held: self.levels.iter().map(|_| HashMap::new()).collect(),
            pool: Vec::new(),
            scratch: self.levels.iter().map(|_| None).collect(),
            dry: false,
        }
    }

    /// Synthesize the array, band rows from `source`, row `r` of the array to
    /// `sink(r, samples)` in order.
    pub fn synthesize<T: Sample>(
        &self,
        source: impl FnMut(usize, usize, &mut [T]),
        mut sink: impl FnMut(usize, &[T]),
    ) -> Result<()> {
        let mut s = self.synthesis(source);
        let mut row = vec![T::default(); self.row_len];
        for r in 0..self.rows() {
            s.pull(&mut row)?;
            sink(r, &row);
        }
        Ok(())
    }

    /// The `(band, row)` pairs a synthesis pulls from its source, in order (computed
    /// without arithmetic).
    pub fn pull_order(&self) -> Vec<(usize, usize)> {
        self.pulls_by_row().0
    }

    /// [`StreamPlan::pull_order`] with, for each row `r` of the array, how many of the
    /// pairs are pulled up to the end of [`Synthesis::pull`] of row `r`.
    pub fn pulls_by_row(&self) -> (Vec<(usize, usize)>, Vec<usize>) {
        let mut order = Vec::new();
        let mut ends = Vec::with_capacity(self.rows());
        let count = std::cell::Cell::new(0usize);
        let mut s = Synthesis::<f32, _> {
            plan: self,
            source: |b: usize, r: usize, _: &mut [f32]| {
                order.push((b, r));
                count.set(count.get() + 1);
            },
            next: 0,
            held: self.levels.iter().map(|_| HashMap::new()).collect(),
            pool: Vec::new(),
            scratch: self.levels.iter().map(|_| None).collect(),
            dry: true,
        };
        for _ in 0..self.rows() {
            s.pull(&mut []).expect("pull_order: a dry pull");
            ends.push(count.get());
        }
        drop(s);
        (order, ends)
    }
}

/// Samples of a box.
fn volume(shape: &[usize]) -> usize {
    shape.iter().product()
}

/// Call `f(at_in_box, at_in_sub, run)` for every contiguous run of the sub-box
/// `ranges` of a row-major box `shape` (`run` samples along the last axis).
fn runs(shape: &[usize], ranges: &[Range<usize>], mut f: impl FnMut(usize, usize, usize)) {
    let nd = shape.len();
    if nd == 0 {
        f(0, 0, 1);
        return;
    }
    let run = ranges[nd - 1].len();
    let lines: usize = ranges[..nd - 1].iter().map(|r| r.len()).product();
    if run == 0 || lines == 0 {
        return;
    }
    let mut idx = vec![0usize; nd - 1];
    for line in 0..lines {
        let mut at = 0;
        for d in 0..nd - 1 {
            at = at * shape[d] + ranges[d].start + idx[d];
        }
        at = at * shape[nd - 1] + ranges[nd - 1].start;
        f(at, line * run, run);
        for d in (0..nd - 1).rev() {
            idx[d] += 1;
            if idx[d] < ranges[d].len() {
                break;
            }
            idx[d] = 0;
        }
    }
}

/// The sub-box `ranges` of `src` (box `shape`) into `dst`, compact.
fn copy_out<T: Copy>(src: &[T], shape: &[usize], ranges: &[Range<usize>], dst: &mut [T]) {
    runs(shape, ranges, |a, b, n| {
        dst[b..b + n].copy_from_slice(&src[a..a + n])
    });
}

/// `src` (compact) into the sub-box `ranges` of `dst` (box `shape`).
fn copy_in<T: Copy>(src: &[T], dst: &mut [T], shape: &[usize], ranges: &[Range<usize>]) {
    runs(shape, ranges, |a, b, n| {
        dst[a..a + n].copy_from_slice(&src[b..b + n])
    });
}

/// The box `[0, sub)` as ranges.
fn prefix(sub: &[usize]) -> Vec<Range<usize>> {
    sub.iter().map(|&s| 0..s).collect()
}

/// A row buffer of `n` samples from `pool`.
fn take<T: Sample>(pool: &mut Vec<Vec<T>>, n: usize) -> Vec<T> {
    let mut v = pool.pop().unwrap_or_default();
    v.clear();
    v.resize(n, T::default());
    v
}

/// A row buffer of `n` samples from `pool` whose samples the caller overwrites: only
/// what it grows by is zeroed (a megabyte plane zeroed before every row was a pass
/// over memory of its own).
fn take_dirty<T: Sample>(pool: &mut Vec<Vec<T>>, n: usize) -> Vec<T> {
    let mut v = pool.pop().unwrap_or_default();
    v.truncate(n);
    v.resize(n, T::default());
    v
}

/// The level's operators over its leading axes as the fused engine takes them.
fn axis_ops(lv: &Level, analysis: bool) -> Vec<AxisOp<'_>> {
    fn one(o: &LevelOps, analysis: bool) -> AxisOp<'_> {
        if analysis {
            AxisOp {
                op: &o.two_scale.analysis,
                plan: &o.analysis,
                order: &o.analysis_order,
                parts: &o.analysis_parts,
            }
        } else {
            AxisOp {
                op: &o.two_scale.synthesis,
                plan: &o.synthesis,
                order: &o.synthesis_order,
                parts: &o.synthesis_parts,
            }
        }
    }
    lv.axis0
        .iter()
        .map(|o| one(o, analysis))
        .chain(lv.others.iter().map(|(_, o)| one(o, analysis)))
        .collect()
}

/// The level's other active axes over `row` (box `lv.row`), analysis or synthesis:
/// through the fused engine's row kernels where the level is fused (`spare`: a buffer
/// of the row's length, `scratch`: the level's [`Ctx::scratch`], made on first use),
/// else axis by axis.
fn other_axes<T: Sample>(
    k: Kernels,
    lv: &Level,
    row: &mut Vec<T>,
    spare: &mut Vec<T>,
    scratch: &mut Option<Vec<Aligned<T>>>,
    analysis: bool,
) {
    if let Some((region, e)) = &lv.fused {
        let ops = axis_ops(lv, analysis);
        let ctx = Ctx::new(region, *e, &ops, false);
        let sc = scratch.get_or_insert_with(|| ctx.scratch());
        spare.resize(row.len(), T::default());
        ctx.finish_row(row, spare, ctx.cs(), &mut sc[1..]);
        std::mem::swap(row, spare);
        return;
    }
    for (a, ops) in &lv.others {
        let op = if analysis {
            &ops.two_scale.analysis
        } else {
            &ops.two_scale.synthesis
        };
        transform_axis_with(k, row, &lv.row, &lv.row, *a, op);
    }
}

/// Rows of at least this many samples are combined along axis 0 in pieces of
/// [`PIECE`] samples on the pool (a volume's planes: a 1024² plane is a few
/// milliseconds of sums that the other threads would otherwise wait through).
const PAR_ROW: usize = 1 << 17;
/// Samples of one piece of a row combined on the pool.
const PIECE: usize = 1 << 15;

/// Output row `r` of a level along axis 0: `Σ_c W_rc · input(c)` over the box `len`
/// samples long, or the input row itself when axis 0 is not active (or a lane of one).
/// A row of [`PAR_ROW`] samples or more is cut into pieces summed on the pool: every
/// sample sums the same taps in the same order, the same bits on any thread count.
fn axis0_row<'t, T: Sample + 't>(
    k: Kernels,
    op: Option<&crate::scheme::sparse::Csr>,
    r: usize,
    out: &mut [T],
    input: impl Fn(u32) -> &'t [T] + Sync,
) {
    use rayon::prelude::*;
    let par = out.len() >= PAR_ROW && rayon::current_num_threads() > 1;
    match op {
        Some(op) if op.rows() > 1 => {
            let (cols, ws) = op.row_slices(r);
            if par {
                out.par_chunks_mut(PIECE).enumerate().for_each(|(i, o)| {
                    let (at, n) = (i * PIECE, o.len());
                    combine_taps(k, o, cols, ws, |c| &input(c)[at..at + n]);
                });
            } else {
                combine_taps(k, out, cols, ws, input);
            }
        }
        _ if par => {
            let src = input(r as u32);
            out.par_chunks_mut(PIECE)
                .zip(src.par_chunks(PIECE))
                .for_each(|(o, s)| o.copy_from_slice(s));
        }
        _ => out.copy_from_slice(input(r as u32)),
    }
}

/// The input rows of level `lv` that output row `r` reads (analysis or synthesis).
fn taps(lv: &Level, r: usize, analysis: bool) -> &[u32] {
    match &lv.axis0 {
        Some(o) if o.two_scale.analysis.rows() > 1 => {
            let op = if analysis {
                &o.two_scale.analysis
            } else {
                &o.two_scale.synthesis
            };
            op.row_slices(r).0
        }
        _ => &[],
    }
}

/// One level's state in an analysis: its held input rows and what each output row
/// still waits for.
struct AnalysisLevel<T> {
    /// Input row → (samples, output rows still to read it).
    held: HashMap<usize, (Vec<T>, u32)>,
    /// Per output row: inputs not yet arrived (`u32::MAX` once computed).
    missing: Vec<u32>,
    /// Per input row: the output rows reading it.
    readers: Vec<Vec<u32>>,
}

impl<T> AnalysisLevel<T> {
    fn new(lv: &Level) -> Self {
        let mut readers = vec![Vec::new(); lv.n];
        let mut missing = vec![0u32; lv.n];
        for (r, m) in missing.iter_mut().enumerate() {
            let t = taps(lv, r, true);
            if t.is_empty() {
                readers[r].push(r as u32);
                *m = 1;
            } else {
                for &c in t {
                    readers[c as usize].push(r as u32);
                }
                *m = t.len() as u32;
            }
        }
        AnalysisLevel {
            held: HashMap::new(),
            missing,
            readers,
        }
    }
}

/// A streamed analysis ([`StreamPlan::analysis`]).
pub struct Analysis<'p, T, F> {
    plan: &'p StreamPlan,
    sink: F,
    /// Rows pushed so far.
    next: usize,
    state: Vec<AnalysisLevel<T>>,
    pool: Vec<Vec<T>>,
    /// Per level, the fused row kernels' scratch.
    scratch: Vec<Option<Vec<Aligned<T>>>>,
}

impl<T: Sample, F: FnMut(BandRow<T>)> Analysis<'_, T, F> {
    /// The next row of the array (`row_len` samples).
    pub fn push(&mut self, row: &[T]) -> Result<()> {
        let plan = self.plan;
        if row.len() != plan.row_len {
            return Err(Error::parameter(
                "row length",
                row.len(),
                "the samples of one row of the array",
            ));
        }
        if self.next >= plan.rows() {
            return Err(Error::parameter(
                "row",
                self.next,
                "no more rows than the array's length along axis 0",
            ));
        }
        let r = self.next;
        self.next += 1;
        let mut v = take(&mut self.pool, row.len());
        v.copy_from_slice(row);
        if plan.levels.is_empty() {
            self.emit(0, r, &v, &plan.pyr.shape[1..]);
            self.pool.push(v);
            return Ok(());
        }
        self.arrive(0, r, v);
        Ok(())
    }

    /// Rows held now over all levels (input rows waiting for an output row that reads
    /// them): what bounds the stream's memory.
    pub fn held_rows(&self) -> usize {
        self.state.iter().map(|s| s.held.len()).sum()
    }

    /// Check that every row came and every band row went out; hand back the sink.
    pub fn finish(self) -> Result<F> {
        if self.next != self.plan.rows() {
            return Err(Error::parameter(
                "rows pushed",
                self.next,
                "every row of the array",
            ));
        }
        debug_assert!(self.state.iter().all(|s| s.held.is_empty()));
        Ok(self.sink)
    }

    /// Row `r` of band `band` to the sink.
    fn emit(&mut self, band: usize, row: usize, data: &[T], shape: &[usize]) {
        let b = &self.plan.bands[band];
        (self.sink)(BandRow {
            band,
            level: b.level,
            high: &b.high,
            row,
            shape,
            data,
        });
    }

    /// Input row `c` of level `l` arrives: compute the output rows it completes.
    fn arrive(&mut self, l: usize, c: usize, data: Vec<T>) {
        let st = &mut self.state[l];
        let readers = std::mem::take(&mut st.readers[c]);
        if readers.is_empty() {
            self.pool.push(data);
            return;
        }
        st.held.insert(c, (data, readers.len() as u32));
        let mut ready: Vec<u32> = Vec::new();
        for &r in &readers {
            let m = &mut st.missing[r as usize];
            *m -= 1;
            if *m == 0 {
                ready.push(r);
            }
        }
        ready.sort_unstable();
        for r in ready {
            self.compute(l, r as usize);
        }
    }

    /// Output row `r` of level `l`: along axis 0, then the other axes; coarse box on,
    /// details out.
    fn compute(&mut self, l: usize, r: usize) {
        let plan = self.plan;
        let lv = &plan.levels[l];
        let len = volume(&lv.row);
        let mut out = take(&mut self.pool, len);
        let st = &mut self.state[l];
        st.missing[r] = u32::MAX;
        {
            let held = &st.held;
            let op = lv.axis0.as_ref().map(|o| &o.two_scale.analysis);
            axis0_row(
                plan.kernels,
                op,
                r,
                &mut out,
                |c| &held[&(c as usize)].0[..],
            );
        }
        // inputs no longer read
        let t = taps(lv, r, true);
        let ids: Vec<usize> = if t.is_empty() {
            vec![r]
        } else {
            t.iter().map(|&c| c as usize).collect()
        };
        for c in ids {
            let e = st.held.get_mut(&c).expect("stream: a held row");
            e.1 -= 1;
            if e.1 == 0 {
                let (v, _) = st.held.remove(&c).expect("stream: a held row");
                self.pool.push(v);
            }
        }
        let mut spare = take(&mut self.pool, 0);
        other_axes(
            plan.kernels,
            lv,
            &mut out,
            &mut spare,
            &mut self.scratch[l],
            true,
        );
        self.pool.push(spare);
        let (parts, row) = if r < lv.nc {
            (&lv.low, r)
        } else {
            (&lv.high, r - lv.nc)
        };
        let mut band = Vec::new();
        for p in parts {
            band.clear();
            band.resize(volume(&p.shape), T::default());
            copy_out(&out, &lv.row, &p.ranges, &mut band);
            self.emit(p.band, row, &band, &p.shape);
        }
        if r < lv.nc {
            let mut coarse = take(&mut self.pool, volume(&lv.coarse_row));
            copy_out(&out, &lv.row, &prefix(&lv.coarse_row), &mut coarse);
            self.pool.push(out);
            if l + 1 < plan.levels.len() {
                self.arrive(l + 1, r, coarse);
            } else {
                self.emit(0, r, &coarse, &lv.coarse_row);
                self.pool.push(coarse);
            }
        } else {
            self.pool.push(out);
        }
    }
}

/// A streamed synthesis ([`StreamPlan::synthesis`]).
pub struct Synthesis<'p, T, S> {
    plan: &'p StreamPlan,
    source: S,
    /// Rows of the array made so far.
    next: usize,
    /// Per level: input row → (samples, output rows still to read it).
    held: Vec<HashMap<usize, (Vec<T>, u32)>>,
    pool: Vec<Vec<T>>,
    /// Per level, the fused row kernels' scratch.
    scratch: Vec<Option<Vec<Aligned<T>>>>,
    /// Only record what is pulled ([`StreamPlan::pull_order`]).
    dry: bool,
}

impl<T: Sample, S: FnMut(usize, usize, &mut [T])> Synthesis<'_, T, S> {
    /// The next row of the array into `out` (`row_len` samples).
    pub fn pull(&mut self, out: &mut [T]) -> Result<()> {
        let plan = self.plan;
        if !self.dry && out.len() != plan.row_len {
            return Err(Error::parameter(
                "row length",
                out.len(),
                "the samples of one row of the array",
            ));
        }
        if self.next >= plan.rows() {
            return Err(Error::parameter(
                "row",
                self.next,
                "no more rows than the array's length along axis 0",
            ));
        }
        let r = self.next;
        self.next += 1;
        if plan.levels.is_empty() {
            (self.source)(0, r, out);
            return Ok(());
        }
        let row = self.produce(0, r);
        if !self.dry {
            out.copy_from_slice(&row);
        }
        self.pool.push(row);
        Ok(())
    }

    /// Rows held now over all levels (input rows waiting for an output row that reads
    /// them): what bounds the stream's memory.
    pub fn held_rows(&self) -> usize {
        self.held.iter().map(|h| h.len()).sum()
    }

    /// Output row `r` of level `l` (box `row` of the level).
    fn produce(&mut self, l: usize, r: usize) -> Vec<T> {
        let plan = self.plan;
        let lv = &plan.levels[l];
        let t = taps(lv, r, false);
        let ids: Vec<usize> = if t.is_empty() {
            vec![r]
        } else {
            t.iter().map(|&c| c as usize).collect()
        };
        for &c in &ids {
            self.input(l, c);
        }
        // (written whole by the sums along axis 0: not zeroed first)
        let mut out = take_dirty(&mut self.pool, if self.dry { 0 } else { volume(&lv.row) });
        if !self.dry {
            let held = &self.held[l];
            let op = lv.axis0.as_ref().map(|o| &o.two_scale.synthesis);
            axis0_row(
                plan.kernels,
                op,
                r,
                &mut out,
                |c| &held[&(c as usize)].0[..],
            );
        }
        for c in ids {
            let e = self.held[l].get_mut(&c).expect("stream: a held row");
            e.1 -= 1;
            if e.1 == 0 {
                let (v, _) = self.held[l].remove(&c).expect("stream: a held row");
                self.pool.push(v);
            }
        }
        if !self.dry {
            // (written whole by the other axes, or not read)
            let mut spare = self.pool.pop().unwrap_or_default();
            other_axes(
                plan.kernels,
                lv,
                &mut out,
                &mut spare,
                &mut self.scratch[l],
                false,
            );
            self.pool.push(spare);
        }
        out
    }

    /// Input row `c` of level `l` held (made from the coarser level and the source).
    fn input(&mut self, l: usize, c: usize) {
        if self.held[l].contains_key(&c) {
            return;
        }
        let plan = self.plan;
        let lv = &plan.levels[l];
        let dry = self.dry;
        let n = if dry { 0 } else { volume(&lv.row) };
        let mut row = if lv.covered[usize::from(c >= lv.nc)] {
            take_dirty(&mut self.pool, n)
        } else {
            take(&mut self.pool, n)
        };
        // a pooled buffer: a band row of the finest level is a megabyte or more, which a
        // fresh one would map and fault in afresh at every row
        // (kept as long as it is: each band row is written whole by the source)
        let mut band = self.pool.pop().unwrap_or_default();
        let (parts, at) = if c < lv.nc {
            if l + 1 < plan.levels.len() {
                let coarse = self.produce(l + 1, c);
                if !dry {
                    copy_in(&coarse, &mut row, &lv.row, &prefix(&lv.coarse_row));
                }
                self.pool.push(coarse);
            } else {
                let m = if dry { 0 } else { volume(&lv.coarse_row) };
                band.truncate(m);
                band.resize(m, T::default());
                (self.source)(0, c, &mut band);
                if !dry {
                    copy_in(&band, &mut row, &lv.row, &prefix(&lv.coarse_row));
                }
            }
            (&lv.low, c)
        } else {
            (&lv.high, c - lv.nc)
        };
        for p in parts {
            // (the source writes every sample: not zeroed first)
            band.truncate(if dry { 0 } else { volume(&p.shape) });
            band.resize(if dry { 0 } else { volume(&p.shape) }, T::default());
            (self.source)(p.band, at, &mut band);
            if !dry {
                copy_in(&band, &mut row, &lv.row, &p.ranges);
            }
        }
        self.pool.push(band);
        let uses = lv.syn_uses[c];
        self.held[l].insert(c, (row, uses));
    }
}
