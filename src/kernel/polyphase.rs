//! A two-scale operator seen the way the notes write it: **regular rows**, one filter slid
//! along the lane, plus the **boundary rows** at the start and the end (§9.6: the blocks
//! As, Ae, Bs, Be, …). The split is read off the assembled [`Csr`], so it holds for every
//! scheme, boundary and length without a second description of the filters.
//!
//! A run of regular rows is `r = row0 + row_step·i` (`i < count`) with entries
//! `(cols[k] + col_step·i, weights[k])`:
//! - analysis `[A; B]`: `row_step = 1`, `col_step = 2` (a coarse or detail row per pair of
//!   fine elements), e.g. Chaikin's `C_i = −¼F_{2i−1} + ¾F_{2i} + ¾F_{2i+1} − ¼F_{2i+2}`;
//! - synthesis `[P | Q]`: `row_step = 2`, `col_step = 1` (even and odd fine rows are two
//!   runs), e.g. `F_{2i} = ¾C_i + ¼C_{i+1} + …` with the details at packed columns `n + i`.
//!
//! Applied to a contiguous lane, a run becomes a few whole-run vector operations: with
//! `col_step = 2` the lane is first split into its even and odd elements, so tap `k` reads
//! the contiguous slice starting at element `cols[k] / 2` of one half.

use crate::kernel::{
    self, combine, combine_pair, deinterleave, edge_rows, interleave, EdgeGroup, Kernels, PairOut,
    PairRows,
};
use crate::scheme::sparse::Csr;
use crate::scheme::{Build, Sample};

/// Shortest run worth a vector pass; shorter stretches stay boundary rows.
const MIN_RUN: usize = 4;

/// Regular rows `row0 + row_step·i`, `i < count`.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    pub row0: usize,
    pub row_step: usize,
    pub count: usize,
    pub col_step: usize,
    /// Columns of row `row0`, increasing.
    pub cols: Vec<usize>,
    pub weights: Vec<f64>,
}

/// An operator split into regular runs and boundary rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Polyphase {
    pub rows: usize,
    pub col_step: usize,
    pub runs: Vec<Run>,
    /// Rows in no run, increasing.
    pub boundary_rows: Vec<usize>,
    /// Two runs computed together, reading their inputs once (see [`Pair`]).
    pub pair: Option<Pair>,
    /// The stretches of rows outside the pair (all rows when there is none), increasing.
    pub unpaired: Vec<std::ops::Range<usize>>,
    /// The rows [`Polyphase::apply_lane`] computes one by one (no run, or a paired run's
    /// rows outside the pair), increasing.
    pub edge_rows: Vec<usize>,
    /// The same rows in groups of up to 8 for lanes of single samples
    /// ([`kernel::edge_rows`]), and the rows no group takes.
    pub edges: Vec<EdgeGroup>,
    pub edge_rest: Vec<usize>,
    /// Analysis (`col_step` 2) whose rows outside the pair and the short runs read only
    /// samples within this many of the lane's ends: lanes of single samples may then come
    /// already split into their even and odd samples ([`Polyphase::apply_lane_split`]).
    pub split_reach: Option<usize>,
    /// The kernel table every application of this plan runs (chosen when it is made).
    pub kernels: Kernels,
}

/// Two regular runs whose rows read the same stretch of the lane: a coarse and a detail
/// run (analysis), or the even and the odd fine rows (synthesis). Row `first[j] + t` of
/// `runs[j]`, `t < count`, reads the inputs `cols[k] + col_step·t` for the `k` in mask
/// `masks[j]`, with weights `weights[j][k]`; each row sums its own taps in column order
/// (the bits of one row at a time), but each input is loaded once for both rows
/// ([`kernel::combine_pair`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Pair {
    pub runs: [usize; 2],
    pub first: [usize; 2],
    pub count: usize,
    /// Union of the two rows' columns at `t = 0`, increasing.
    pub cols: Vec<usize>,
    pub weights: [Vec<f64>; 2],
    pub masks: [u32; 2],
    /// [`kernel::pair_entry`] of the pair for `f32` and for `f64` samples (looked up once
    /// here rather than per lane).
    pub entries: [Option<u8>; 2],
}

/// Most inputs a [`Pair`] reads (as many as a pair kernel takes).
pub const PAIR_MOST: usize = kernel::PAIR_KERNEL_MOST;

/// Most taps of a run computed over the whole run at once ([`run_part`]); longer rows go
/// one by one.
const RUN_MOST: usize = 32;

impl Pair {
    /// The two rows' weights as samples (inputs past `cols.len()` weigh 0).
    pub fn sample_weights<T: Sample>(&self) -> [[T; PAIR_MOST]; 2] {
        let mut w = [[T::default(); PAIR_MOST]; 2];
        for (wj, pj) in w.iter_mut().zip(&self.weights) {
            for (x, &v) in wj.iter_mut().zip(pj) {
                *x = T::from_f64(v);
            }
        }
        w
    }

    /// [`kernel::pair_entry`] of the pair for samples of type `T`.
    pub fn entry<T: Sample>(&self) -> Option<u8> {
        match T::BUILD {
            Build::F32 => self.entries[0],
            Build::F64 => self.entries[1],
            Build::Plain => None, // (the kernels are built for f32 and f64)
        }
    }

    /// The pair's [`PairRows`] over its weights `w0`, `w1` as samples, its entry where
    /// the build of `k` has the pair kernels.
    pub fn rows<'a, T: Sample>(&self, k: Kernels, w0: &'a [T], w1: &'a [T]) -> PairRows<'a, T> {
        let [m0, m1] = self.masks;
        PairRows {
            w1: w0,
            m1: m0,
            w2: w1,
            m2: m1,
            entry: if k.avx2() { self.entry::<T>() } else { None },
        }
    }

    /// Row `first[0] + t` of `r0` with row `first[1] + t` of `r1`, `t < count`.
    fn new(runs: [usize; 2], rs: [&Run; 2], first: [usize; 2], count: usize) -> Option<Pair> {
        let col_step = rs[0].col_step;
        let mut cols: Vec<usize> = (0..2)
            .flat_map(|j| rs[j].cols.iter().map(move |&c| c + col_step * first[j]))
            .collect();
        cols.sort_unstable();
        cols.dedup();
        if count == 0 || cols.len() > PAIR_MOST {
            return None;
        }
        let mut weights = [vec![0.0; cols.len()], vec![0.0; cols.len()]];
        let mut masks = [0u32; 2];
        for j in 0..2 {
            for (&c, &w) in rs[j].cols.iter().zip(&rs[j].weights) {
                let k = cols.binary_search(&(c + col_step * first[j])).ok()?;
                weights[j][k] = w;
                masks[j] |= 1 << k;
            }
        }
        // rows that share no input gain nothing from going together
        if masks[0] & masks[1] == 0 {
            return None;
        }
        let mut pair = Pair {
            runs,
            first,
            count,
            cols,
            weights,
            masks,
            entries: [None; 2],
        };
        let u = pair.cols.len();
        let [a, b] = pair.sample_weights::<f32>();
        let [c, d] = pair.sample_weights::<f64>();
        pair.entries = [
            kernel::pair_entry(&a[..u], masks[0], &b[..u], masks[1]),
            kernel::pair_entry(&c[..u], masks[0], &d[..u], masks[1]),
        ];
        Some(pair)
    }

    /// The pairing of an analysis split: its two element-strided runs, a coarse row with
    /// the detail row that reads the fewest other inputs.
    fn analysis(runs: &[Run]) -> Option<Pair> {
        let [r0, r1] = runs else { return None };
        if r0.row_step != 1 || r1.row_step != 1 || r0.col_step != 2 {
            return None;
        }
        // row i of r0 with row i + d of r1, whose columns are those of r1's first row
        // moved on by 2·d relative to row i of r0 (with `− 2·d` here a pair with d ≠ 0 —
        // the interpolating Chaikin analysis, d = −1 — goes unfound: the offset chosen
        // makes the two rows share no column)
        let union = |d: isize| {
            let mut c: Vec<isize> = r0.cols.iter().map(|&c| c as isize).collect();
            c.extend(r1.cols.iter().map(|&c| c as isize + 2 * d));
            c.sort_unstable();
            c.dedup();
            c.len()
        };
        let d = (-4isize..=4).min_by_key(|&d| (union(d), d.abs()))?;
        let s0 = (-d).max(0) as usize;
        let s1 = (s0 as isize + d) as usize;
        let count = r0.count.saturating_sub(s0).min(r1.count.saturating_sub(s1));
        Pair::new([0, 1], [r0, r1], [s0, s1], count)
    }

    /// The pairing of a synthesis split: the even and the odd fine rows over the
    /// stretch where both are regular.
    fn synthesis(runs: &[Run]) -> Option<Pair> {
        let ei = runs
            .iter()
            .position(|r| r.row_step == 2 && r.row0 % 2 == 0)?;
        let oi = runs
            .iter()
            .position(|r| r.row_step == 2 && r.row0 % 2 == 1)?;
        let (ev, od) = (&runs[ei], &runs[oi]);
        if ev.col_step != 1 {
            return None;
        }
        let (a, b) = (ev.row0 / 2, od.row0 / 2);
        let (p0, p1) = (a.max(b), (a + ev.count).min(b + od.count));
        if p1 <= p0 {
            return None;
        }
        Pair::new([ei, oi], [ev, od], [p0 - a, p0 - b], p1 - p0)
    }
}

impl Polyphase {
    /// Find the runs of `op`: tries (row_step, col_step) = (1, 2) and (2, 1) and keeps the
    /// split that covers more rows. Applied with the kernels of `kernels`.
    pub fn new(op: &Csr, kernels: Kernels) -> Polyphase {
        // the rest (pair, edge groups) only for the split kept: the other one's rows are
        // nearly all boundary rows, whose edge groups took most of the build
        let a = Self::find_runs(op, 1, 2);
        let b = Self::find_runs(op, 2, 1);
        let uncovered =
            |(_, covered): &(Vec<Run>, Vec<bool>)| covered.iter().filter(|&&c| !c).count();
        if uncovered(&b) < uncovered(&a) {
            Self::split(op, 2, 1, b, kernels)
        } else {
            Self::split(op, 1, 2, a, kernels)
        }
    }

    /// The regular runs of `op` for rows `row_step` apart sliding `col_step` columns, and
    /// which rows they cover.
    fn find_runs(op: &Csr, row_step: usize, col_step: usize) -> (Vec<Run>, Vec<bool>) {
        let rows = op.rows();
        // the pattern of row r relative to its slide position
        let key = |r: usize| -> Vec<(isize, f64)> {
            let shift = (col_step * (r / row_step)) as isize;
            op.row(r).map(|(c, w)| (c as isize - shift, w)).collect()
        };
        let mut covered = vec![false; rows];
        let mut runs = Vec::new();
        for phase in 0..row_step.min(rows) {
            let mut r = phase;
            while r < rows {
                let k = key(r);
                let mut count = 1;
                while r + count * row_step < rows && key(r + count * row_step) == k {
                    count += 1;
                }
                if count >= MIN_RUN && !k.is_empty() {
                    for i in 0..count {
                        covered[r + i * row_step] = true;
                    }
                    let (cols, weights) = op.row(r).unzip();
                    runs.push(Run {
                        row0: r,
                        row_step,
                        count,
                        col_step,
                        cols,
                        weights,
                    });
                }
                r += count * row_step;
            }
        }
        (runs, covered)
    }

    /// The operator split along `runs` (which cover the rows `covered`).
    fn split(
        op: &Csr,
        row_step: usize,
        col_step: usize,
        (runs, covered): (Vec<Run>, Vec<bool>),
        kernels: Kernels,
    ) -> Polyphase {
        let rows = op.rows();
        let pair = if row_step == 1 {
            Pair::analysis(&runs)
        } else {
            Pair::synthesis(&runs)
        };
        let mut in_pair = vec![false; rows];
        if let Some(p) = &pair {
            for j in 0..2 {
                let run = &runs[p.runs[j]];
                for t in 0..p.count {
                    in_pair[run.row0 + run.row_step * (p.first[j] + t)] = true;
                }
            }
        }
        let mut unpaired: Vec<std::ops::Range<usize>> = Vec::new();
        for r in (0..rows).filter(|&r| !in_pair[r]) {
            match unpaired.last_mut() {
                Some(last) if last.end == r => last.end += 1,
                _ => unpaired.push(r..r + 1),
            }
        }
        let boundary_rows: Vec<usize> = (0..rows).filter(|&r| !covered[r]).collect();
        // the rows computed one by one: no run, or a paired run's rows outside the pair
        let mut edge_rows = boundary_rows.clone();
        if let Some(p) = &pair {
            for j in 0..2 {
                let run = &runs[p.runs[j]];
                let (s, n) = (p.first[j], p.count);
                edge_rows.extend(
                    (0..s)
                        .chain(s + n..run.count)
                        .map(|i| run.row0 + run.row_step * i),
                );
            }
        }
        edge_rows.sort_unstable();
        let (edges, edge_rest) = edge_groups(op, &edge_rows);
        // the farthest any row read one by one reaches from the nearer end of the lane
        // (every other run a short one of `run_part`, which reads the halves)
        let paired_runs = pair.as_ref().map_or([usize::MAX; 2], |p| p.runs);
        let short = |(i, r): (usize, &Run)| {
            paired_runs.contains(&i) || (r.row_step == 1 && r.cols.len() <= RUN_MOST)
        };
        let reach = edge_rows
            .iter()
            .flat_map(|&r| op.row_slices(r).0)
            .map(|&c| (c as usize + 1).min(rows - c as usize))
            .max()
            .unwrap_or(0);
        let split_reach = (col_step == 2 && runs.iter().enumerate().all(short)).then_some(reach);
        Polyphase {
            rows,
            col_step,
            runs,
            boundary_rows,
            pair,
            unpaired,
            edge_rows,
            edges,
            edge_rest,
            split_reach,
            kernels,
        }
    }

    /// Scratch samples [`Polyphase::apply_lane`] needs for a lane of `e`-wide elements.
    pub fn scratch_len(&self, e: usize) -> usize {
        self.rows * e
    }

    /// `y = op · x` on one contiguous lane of `rows` elements of `e` samples each
    /// (`x`, `y` distinct). Same bits as [`Csr::apply`]: every row sums its taps in
    /// column order.
    pub fn apply_lane<T: Sample>(
        &self,
        op: &Csr,
        x: &[T],
        y: &mut [T],
        e: usize,
        scratch: &mut [T],
    ) {
        let (m, k) = (self.rows, self.kernels);
        assert!(x.len() >= m * e && y.len() >= m * e && scratch.len() >= m * e);
        let (x, y) = (&x[..m * e], &mut y[..m * e]);
        let ne = m.div_ceil(2);
        if self.col_step == 2 && !self.runs.is_empty() {
            deinterleave(k, x, e, scratch);
        }
        let mut paired = [usize::MAX; 2];
        if let Some(pair) = &self.pair {
            // its runs' rows outside the pair are edge rows, below
            paired = pair.runs;
            let r0 = &self.runs[pair.runs[0]];
            let (f, n) = (pair.first, pair.count);
            if self.col_step == 1 {
                // Synthesis (`scratch` is free): the even and the odd rows into its two
                // halves, then interleaved.
                let p0 = r0.row0 / 2 + f[0];
                let out = &mut y[2 * p0 * e..2 * (p0 + n) * e];
                // samples (not wider elements) straight into place where there is a build
                if e > 1 || !pair_merged(k, pair, x, out) {
                    let (t0, t1) = scratch[..2 * n * e].split_at_mut(n * e);
                    let lane = LaneIn {
                        x,
                        halves: &[],
                        e,
                        col_step: 1,
                        ne,
                    };
                    pair_part(k, pair, &lane, t0, t1);
                    interleave(k, t0, t1, e, out);
                }
            } else {
                // Analysis: the coarse and the detail rows straight into `y`.
                self.analysis_pair(pair, x, scratch, y, e);
            }
        }
        self.other_rows(op, x, scratch, y, e, paired);
    }

    /// [`Polyphase::apply_lane`] for analysis on a lane of single samples that comes
    /// already split into its even samples, then its odd ones (`halves`, as
    /// [`deinterleave`] makes them): the same bits without the split's pass. `x_ends`
    /// (`rows` samples) takes the samples near the ends, for the rows read one by one.
    /// Only where [`Polyphase::split_reach`] is known.
    pub fn apply_lane_split<T: Sample>(
        &self,
        op: &Csr,
        halves: &[T],
        y: &mut [T],
        x_ends: &mut [T],
    ) {
        let m = self.rows;
        let reach = self.split_reach.expect("a lane that may come split");
        assert!(halves.len() >= m && y.len() >= m && x_ends.len() >= m);
        let (halves, y, x) = (&halves[..m], &mut y[..m], &mut x_ends[..m]);
        let ne = m.div_ceil(2);
        for c in (0..reach.min(m)).chain(m.saturating_sub(reach)..m) {
            x[c] = halves[(c % 2) * ne + c / 2];
        }
        let mut paired = [usize::MAX; 2];
        if let Some(pair) = &self.pair {
            paired = pair.runs;
            self.analysis_pair(pair, x, halves, y, 1);
        }
        self.other_rows(op, x, halves, y, 1, paired);
    }

    /// Analysis: the rows of `pair` straight into `y` (`halves` the lane split).
    fn analysis_pair<T: Sample>(&self, pair: &Pair, x: &[T], halves: &[T], y: &mut [T], e: usize) {
        let (r0, r1) = (&self.runs[pair.runs[0]], &self.runs[pair.runs[1]]);
        let (f, n) = (pair.first, pair.count);
        let ne = self.rows.div_ceil(2);
        let (lo, hi) = y.split_at_mut(r1.row0 * e);
        let o0 = &mut lo[(r0.row0 + f[0]) * e..(r0.row0 + f[0] + n) * e];
        let o1 = &mut hi[f[1] * e..(f[1] + n) * e];
        let lane = LaneIn {
            x,
            halves,
            e,
            col_step: 2,
            ne,
        };
        pair_part(self.kernels, pair, &lane, o0, o1);
    }

    /// The runs but the `paired` ones, and the rows near the ends (`halves`: the lane
    /// split, for `col_step` 2).
    fn other_rows<T: Sample>(
        &self,
        op: &Csr,
        x: &[T],
        halves: &[T],
        y: &mut [T],
        e: usize,
        paired: [usize; 2],
    ) {
        let (ne, k) = (self.rows.div_ceil(2), self.kernels);
        let lane = LaneIn {
            x,
            halves,
            e,
            col_step: self.col_step,
            ne,
        };
        for (ri, run) in self.runs.iter().enumerate() {
            if paired.contains(&ri) {
                continue;
            }
            if run.row_step == 1 && run.cols.len() <= RUN_MOST {
                let len = run.count * e;
                run_part(k, run, &lane, &mut y[run.row0 * e..run.row0 * e + len]);
            } else {
                op_rows_run(k, op, run, x, y, e);
            }
        }
        // the rows near the ends: 8 at a time where the build has it
        let rest = if e == 1 && edge_rows(k, &self.edges, x, y) {
            &self.edge_rest
        } else {
            &self.edge_rows
        };
        for &r in rest {
            op_row(k, op, r, x, y, e);
        }
    }
}

/// `rows` (increasing) in groups of up to 8 that follow one another, each row of at most
/// [`EDGE_SPAN`](kernel::EDGE_SPAN) taps, and the rows left over.
fn edge_groups(op: &Csr, rows: &[usize]) -> (Vec<EdgeGroup>, Vec<usize>) {
    let (mut groups, mut rest) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < rows.len() {
        // the longest group from rows[i] that still reads few enough samples
        let mut best = None;
        let mut n = 1;
        while n <= 8 && i + n <= rows.len() && rows[i + n - 1] == rows[i] + n - 1 {
            let slices: Vec<(&[u32], &[f64])> =
                (0..n).map(|q| op.row_slices(rows[i + q])).collect();
            match EdgeGroup::new(rows[i], &slices) {
                Some(g) => best = Some(g),
                None => break,
            }
            n += 1;
        }
        match best {
            Some(g) => {
                i += g.n;
                groups.push(g);
            }
            None => {
                rest.push(rows[i]);
                i += 1;
            }
        }
    }
    (groups, rest)
}

/// One row of `op` on element-wide samples: `y_r = Σ w x_c`, summed as
/// [`kernel::sum_terms`](kernel::sum_terms) says.
#[inline]
fn op_row<T: Sample>(k: Kernels, op: &Csr, r: usize, x: &[T], y: &mut [T], e: usize) {
    let (cols, ws) = op.row_slices(r);
    if e > 1 {
        let out = &mut y[r * e..r * e + e];
        kernel::combine_taps(k, out, cols, ws, |c| &x[c as usize * e..c as usize * e + e]);
        return;
    }
    let n = cols.len();
    let x = |k: usize| x[cols[k] as usize];
    if n > 32 {
        let w: Vec<T> = ws.iter().map(|&v| T::from_f64(v)).collect();
        y[r] = kernel::row_sum(&w, x);
        return;
    }
    let mut w = [T::default(); 32];
    let mut partner = [0usize; 32];
    for k in 0..n {
        w[k] = T::from_f64(ws[k]);
    }
    kernel::pair_taps(&w[..n], &mut partner[..n]);
    y[r] = kernel::sum_terms(&w[..n], &partner[..n], x);
}

fn op_rows_run<T: Sample>(k: Kernels, op: &Csr, run: &Run, x: &[T], y: &mut [T], e: usize) {
    for i in 0..run.count {
        op_row(k, op, run.row0 + run.row_step * i, x, y, e);
    }
}

/// Where a lane's taps are read: the lane `x` of elements of `e` samples (`col_step`
/// 1), or its even/odd halves `halves` (`col_step` 2, even half `ne` elements long).
#[derive(Clone, Copy)]
struct LaneIn<'a, T> {
    x: &'a [T],
    halves: &'a [T],
    e: usize,
    col_step: usize,
    ne: usize,
}

impl<'a, T> LaneIn<'a, T> {
    /// The `len` samples of column `c` onwards (of the lane, or of its half).
    #[inline]
    fn tap(&self, c: usize, len: usize) -> &'a [T] {
        let e = self.e;
        if self.col_step == 2 {
            let start = (c % 2) * self.ne * e + (c / 2) * e;
            &self.halves[start..start + len]
        } else {
            &self.x[c * e..c * e + len]
        }
    }
}

/// The rows of `run` into `out` (contiguous): every tap is one slice of the lane.
#[inline]
fn run_part<T: Sample>(k: Kernels, run: &Run, lane: &LaneIn<T>, out: &mut [T]) {
    let mut src: [&[T]; RUN_MOST] = [&[]; RUN_MOST];
    let mut w = [T::default(); RUN_MOST];
    let taps = run.cols.len();
    let len = run.count * lane.e;
    for (k, (&c, &wk)) in run.cols.iter().zip(&run.weights).enumerate() {
        src[k] = lane.tap(c, len);
        w[k] = T::from_f64(wk);
    }
    combine(k, &mut out[..len], &src[..taps], &w[..taps]);
}

/// The rows of `pair` into `o0` and `o1` (contiguous) with [`kernel::combine_pair`]:
/// every input is one slice of the lane.
#[inline]
fn pair_part<T: Sample>(k: Kernels, pair: &Pair, lane: &LaneIn<T>, o0: &mut [T], o1: &mut [T]) {
    let mut src: [&[T]; PAIR_MOST] = [&[]; PAIR_MOST];
    let [w0, w1] = pair.sample_weights::<T>();
    let len = pair.count * lane.e;
    let u = pair.cols.len();
    for (k, &c) in pair.cols.iter().enumerate() {
        src[k] = lane.tap(c, len);
    }
    let rows = pair.rows(k, &w0[..u], &w1[..u]);
    let out = PairOut::Apart(&mut o0[..len], &mut o1[..len]);
    combine_pair(k, &rows, &src[..u], out);
}

/// The rows of a synthesis `pair` (even and odd fine samples) straight into `out`,
/// interleaved ([`PairOut::Merged`]); `false` (nothing written) where that has no
/// build.
fn pair_merged<T: Sample>(k: Kernels, pair: &Pair, x: &[T], out: &mut [T]) -> bool {
    let mut src: [&[T]; PAIR_MOST] = [&[]; PAIR_MOST];
    let [w0, w1] = pair.sample_weights::<T>();
    let n = pair.count;
    let u = pair.cols.len();
    for (k, &c) in pair.cols.iter().enumerate() {
        src[k] = &x[c..c + n];
    }
    let rows = pair.rows(k, &w0[..u], &w1[..u]);
    combine_pair(k, &rows, &src[..u], PairOut::Merged(&mut out[..2 * n]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::CpuLevel;
    use crate::scheme::{Boundary, Scheme, TwoScale};

    /// Every scheme and boundary pairs its regular rows in both directions, leaving a few
    /// rows near the ends (and, in analysis, where the coarse rows meet the details):
    /// among them the interpolating Chaikin analysis, whose detail row `i` reads the
    /// columns of coarse row `i + 1` (it goes unpaired when the offset's sign is wrong).
    #[test]
    fn every_operator_pairs_its_regular_rows() {
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                for n in [64usize, 256, 257] {
                    // rows near the ends: the boundary blocks, or the rows whose regular
                    // window folds at a mirror, grow with the longest regular filter; lanes
                    // shorter than eight of them are mostly ends
                    let reach = scheme.regular().map_or(0, |f| f.a.w.len().max(f.q.w.len()));
                    if n < 8 * reach {
                        continue;
                    }
                    let t = TwoScale::new(scheme, boundary, n);
                    for (name, op) in [("analysis", &t.analysis), ("synthesis", &t.synthesis)] {
                        let p = Polyphase::new(op, Kernels::detected());
                        let pair = p.pair.as_ref().unwrap_or_else(|| {
                            panic!("{scheme:?} {boundary:?} {n} {name}: no pair")
                        });
                        let unpaired: usize = p.unpaired.iter().map(|r| r.len()).sum();
                        assert!(
                            unpaired <= 20.max(3 * reach),
                            "{scheme:?} {boundary:?} {n} {name}: {unpaired} rows unpaired"
                        );
                        assert_eq!(2 * pair.count + unpaired, n, "{scheme:?} {boundary:?} {n}");
                        assert!(pair.masks[0] & pair.masks[1] != 0);
                    }
                }
            }
        }
    }

    /// The pairs of regular rows the engine combines: along a lane ([`Polyphase::pair`])
    /// and along axis 0 (consecutive rows of the fused levels' order, analysis by first
    /// column, synthesis by index, paired from the start as the cascade pairs them), rows
    /// away from the ends only; `(weights, masks)` over the pair's inputs.
    fn regular_pairs(scheme: Scheme, boundary: Boundary) -> Vec<([Vec<f64>; 2], [u32; 2])> {
        let n = 512;
        let t = TwoScale::new(scheme, boundary, n);
        let mut pairs = Vec::new();
        for (analysis, op) in [(true, &t.analysis), (false, &t.synthesis)] {
            let p = Polyphase::new(op, Kernels::detected());
            let pair = p.pair.as_ref().expect("a lane pair");
            pairs.push((pair.weights.clone(), pair.masks));
            let mut order: Vec<usize> = (0..n).collect();
            if analysis {
                order.sort_by_key(|&r| (op.row_slices(r).0.first().copied(), r));
            }
            let mut i = 0;
            while i + 1 < n {
                let (c1, w1) = op.row_slices(order[i]);
                let (c2, w2) = op.row_slices(order[i + 1]);
                let Some((cols, u, m1, m2)) = kernel::pair_columns(c1, c2) else {
                    i += 1;
                    continue;
                };
                let middle = cols[..u].iter().all(|&c| (64..n as u32 - 64).contains(&c));
                if middle {
                    let spread = |m: u32, ws: &[f64]| {
                        let mut at = ws.iter();
                        (0..u)
                            .map(|k| {
                                if m >> k & 1 == 1 {
                                    at.next().copied()
                                } else {
                                    Some(0.0)
                                }
                            })
                            .collect::<Option<Vec<f64>>>()
                            .expect("a weight per tap")
                    };
                    pairs.push(([spread(m1, w1), spread(m2, w2)], [m1, m2]));
                }
                i += 2;
            }
        }
        pairs.sort_by(|a, b| format!("{a:?}").cmp(&format!("{b:?}")));
        pairs.dedup();
        pairs
    }

    /// Every pair of regular rows of every scheme and boundary has a vector build of the
    /// pair kernels (for `f32` and `f64` samples), and every CPU level gives the bits of
    /// one combine per output in the scalar build (the rule of `sum_terms`): apart, split
    /// into even and odd samples, and interleaved.
    #[test]
    fn every_schemes_regular_pairs_have_a_build() {
        fn check<T: Sample>(w: &[Vec<f64>; 2], m: [u32; 2], name: &str) {
            let u = w[0].len();
            let w1: Vec<T> = w[0].iter().map(|&v| T::from_f64(v)).collect();
            let w2: Vec<T> = w[1].iter().map(|&v| T::from_f64(v)).collect();
            let entry = kernel::pair_entry(&w1, m[0], &w2, m[1]);
            #[cfg(target_arch = "x86_64")]
            assert!(
                entry.is_some(),
                "{name}: no build for {u} inputs, masks {m:?}, {w:?}"
            );
            for len in [1usize, 7, 8, 9, 16, 17, 33, 64, 100] {
                let x: Vec<T> = (0..len + u)
                    .map(|i| T::from_f64(((i * 7919 % 211) as f64 - 105.0) / 13.0))
                    .collect();
                let src: Vec<&[T]> = (0..u).map(|k| &x[k..k + len]).collect();
                let (mut e1, mut e2) = (vec![T::default(); len], vec![T::default(); len]);
                let s = Kernels::scalar();
                let rows = PairRows::new(s, (&w1, m[0]), (&w2, m[1]));
                kernel::pair_by_parts(s, &mut e1, &mut e2, &src, &rows);
                let bits = |v: &[T]| v.iter().map(|x| x.to_f64().to_bits()).collect::<Vec<_>>();
                for level in CpuLevel::available() {
                    let k = Kernels::new(level);
                    let entry = if k.avx2() { entry } else { None };
                    for split in [false, true] {
                        let (mut a, mut b) = (vec![T::default(); len], vec![T::default(); len]);
                        let rows = PairRows {
                            entry,
                            ..PairRows::new(s, (&w1, m[0]), (&w2, m[1]))
                        };
                        let out = if split {
                            PairOut::Split(&mut a, &mut b)
                        } else {
                            PairOut::Apart(&mut a, &mut b)
                        };
                        combine_pair(k, &rows, &src, out);
                        let (mut f1, mut f2) = (e1.clone(), e2.clone());
                        if split {
                            deinterleave(s, &e1, 1, &mut f1);
                            deinterleave(s, &e2, 1, &mut f2);
                        }
                        let what = format!("{name} {level:?} split {split} len {len}");
                        assert_eq!(bits(&a), bits(&f1), "{what}: first output");
                        assert_eq!(bits(&b), bits(&f2), "{what}: second output");
                    }
                }
                let mut merged = vec![T::default(); 2 * len];
                let k = Kernels::detected();
                let rows = PairRows {
                    entry,
                    ..PairRows::new(s, (&w1, m[0]), (&w2, m[1]))
                };
                if combine_pair(k, &rows, &src, PairOut::Merged(&mut merged)) {
                    let want: Vec<T> = (0..2 * len)
                        .map(|i| if i % 2 == 0 { e1[i / 2] } else { e2[i / 2] })
                        .collect();
                    assert_eq!(bits(&merged), bits(&want), "{name} merged len {len}");
                }
            }
        }
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                for (w, m) in regular_pairs(scheme, boundary) {
                    let name = format!("{scheme} {boundary}");
                    check::<f32>(&w, m, &name);
                    check::<f64>(&w, m, &name);
                }
            }
        }
    }
}
