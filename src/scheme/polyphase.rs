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

use super::kernel::{combine, deinterleave, interleave};
use super::sample::Sample;
use super::sparse::Csr;

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
}

impl Polyphase {
    /// Find the runs of `op`: tries (row_step, col_step) = (1, 2) and (2, 1) and keeps the
    /// split that covers more rows.
    pub fn new(op: &Csr) -> Polyphase {
        let a = Self::split(op, 1, 2);
        let b = Self::split(op, 2, 1);
        if b.boundary_rows.len() < a.boundary_rows.len() {
            b
        } else {
            a
        }
    }

    fn split(op: &Csr, row_step: usize, col_step: usize) -> Polyphase {
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
        Polyphase {
            rows,
            col_step,
            runs,
            boundary_rows: (0..rows).filter(|&r| !covered[r]).collect(),
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
        let m = self.rows;
        assert!(x.len() >= m * e && y.len() >= m * e && scratch.len() >= m * e);
        let (x, y) = (&x[..m * e], &mut y[..m * e]);
        let ne = m.div_ceil(2);
        if self.col_step == 2 && !self.runs.is_empty() {
            deinterleave(x, e, scratch);
        }
        // Row-strided runs (synthesis, `col_step` 1 so `scratch` is free): the even and
        // the odd rows are computed over the stretch where both phases are regular, into
        // the two halves of `scratch`, then interleaved.
        let mut paired = [usize::MAX; 2];
        let even = self
            .runs
            .iter()
            .position(|r| r.row_step == 2 && r.row0 % 2 == 0);
        let odd = self
            .runs
            .iter()
            .position(|r| r.row_step == 2 && r.row0 % 2 == 1);
        if let (Some(ei), Some(oi), 1) = (even, odd, self.col_step) {
            let (ev, od) = (&self.runs[ei], &self.runs[oi]);
            let (a, b) = (ev.row0 / 2, od.row0 / 2);
            let (p0, p1) = (a.max(b), (a + ev.count).min(b + od.count));
            if p1 > p0 && ev.cols.len() <= 16 && od.cols.len() <= 16 {
                paired = [ei, oi];
                let n = (p1 - p0) * e;
                let (t0, t1) = scratch[..2 * n].split_at_mut(n);
                run_part(1, ne, ev, p0 - a, p1 - p0, x, &[], e, t0);
                run_part(1, ne, od, p0 - b, p1 - p0, x, &[], e, t1);
                interleave(t0, t1, e, &mut y[2 * p0 * e..2 * p1 * e]);
                // rows of either run outside the common stretch
                for (run, base) in [(ev, a), (od, b)] {
                    let inside = (p0 - base)..(p1 - base);
                    for i in (0..inside.start).chain(inside.end..run.count) {
                        op_row(op, run.row0 + 2 * i, x, y, e);
                    }
                }
            }
        }
        for (ri, run) in self.runs.iter().enumerate() {
            if paired.contains(&ri) {
                continue;
            }
            if run.row_step == 1 && run.cols.len() <= 16 {
                let len = run.count * e;
                run_part(
                    self.col_step,
                    ne,
                    run,
                    0,
                    run.count,
                    x,
                    scratch,
                    e,
                    &mut y[run.row0 * e..run.row0 * e + len],
                );
            } else {
                op_rows_run(op, run, x, y, e);
            }
        }
        for &r in &self.boundary_rows {
            op_row(op, r, x, y, e);
        }
    }
}

/// One row of `op` on element-wide samples: `y_r = Σ w x_c` (first tap assigns).
#[inline]
fn op_row<T: Sample>(op: &Csr, r: usize, x: &[T], y: &mut [T], e: usize) {
    let (cols, ws) = op.row_slices(r);
    if e == 1 {
        let mut acc = T::default();
        for (k, (&c, &w)) in cols.iter().zip(ws).enumerate() {
            let v = T::from_f64(w) * x[c as usize];
            acc = if k == 0 { v } else { acc + v };
        }
        y[r] = acc;
        return;
    }
    let out = &mut y[r * e..r * e + e];
    if cols.is_empty() {
        out.fill(T::default());
    }
    for (k, (&c, &w)) in cols.iter().zip(ws).enumerate() {
        let w = T::from_f64(w);
        let xs = &x[c as usize * e..c as usize * e + e];
        if k == 0 {
            for (o, &v) in out.iter_mut().zip(xs) {
                *o = w * v;
            }
        } else {
            for (o, &v) in out.iter_mut().zip(xs) {
                *o += w * v;
            }
        }
    }
}

fn op_rows_run<T: Sample>(op: &Csr, run: &Run, x: &[T], y: &mut [T], e: usize) {
    for i in 0..run.count {
        op_row(op, run.row0 + run.row_step * i, x, y, e);
    }
}

/// Rows `i0 .. i0 + count` of `run` into `out` (contiguous): every tap is one slice of
/// the lane (`col_step` 1) or of its even/odd halves in `halves` (`col_step` 2, even
/// half `ne` elements long).
#[allow(clippy::too_many_arguments)]
#[inline]
fn run_part<T: Sample>(
    col_step: usize,
    ne: usize,
    run: &Run,
    i0: usize,
    count: usize,
    x: &[T],
    halves: &[T],
    e: usize,
    out: &mut [T],
) {
    let mut src: [&[T]; 16] = [&[]; 16];
    let mut w = [T::default(); 16];
    let taps = run.cols.len();
    let len = count * e;
    for (k, (&c, &wk)) in run.cols.iter().zip(&run.weights).enumerate() {
        src[k] = if col_step == 2 {
            let start = (c % 2) * ne * e + (c / 2 + i0) * e;
            &halves[start..start + len]
        } else {
            let start = (c + i0) * e;
            &x[start..start + len]
        };
        w[k] = T::from_f64(wk);
    }
    combine(&mut out[..len], &src[..taps], &w[..taps]);
}
