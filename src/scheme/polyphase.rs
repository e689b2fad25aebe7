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

use super::kernel::{combine, deinterleave, scatter_every};
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
        let mut src: [&[T]; 16] = [&[]; 16];
        let mut w = [T::default(); 16];
        for run in &self.runs {
            let taps = run.cols.len();
            let len = run.count * e;
            if taps > src.len() {
                // never for the schemes here; stay correct anyway
                op_rows_run(op, run, x, y, e);
                continue;
            }
            for (k, (&c, &wk)) in run.cols.iter().zip(&run.weights).enumerate() {
                let start = if self.col_step == 2 {
                    (c % 2) * ne * e + (c / 2) * e
                } else {
                    c * e
                };
                src[k] = if self.col_step == 2 {
                    &scratch[start..start + len]
                } else {
                    &x[start..start + len]
                };
                w[k] = T::from_f64(wk);
            }
            if run.row_step == 1 {
                combine(
                    &mut y[run.row0 * e..run.row0 * e + len],
                    &src[..taps],
                    &w[..taps],
                );
            } else {
                // a row-strided run: compute it contiguously, then put it in place
                let mut tmp = [T::default(); 256];
                let mut done = 0;
                let chunk = (tmp.len() / e).max(1);
                if e > tmp.len() {
                    op_rows_run(op, run, x, y, e);
                    continue;
                }
                while done < run.count {
                    let c = chunk.min(run.count - done);
                    let part: [&[T]; 16] = std::array::from_fn(|k| {
                        if k < taps {
                            &src[k][done * e..]
                        } else {
                            &[][..]
                        }
                    });
                    combine(&mut tmp[..c * e], &part[..taps], &w[..taps]);
                    scatter_every(
                        &tmp[..c * e],
                        e,
                        y,
                        run.row0 + run.row_step * done,
                        run.row_step,
                    );
                    done += c;
                }
            }
        }
        for &r in &self.boundary_rows {
            op_row(op, r, x, y, e);
        }
    }
}

/// One row of `op` on element-wide samples: `y_r = Σ w x_c`.
#[inline]
fn op_row<T: Sample>(op: &Csr, r: usize, x: &[T], y: &mut [T], e: usize) {
    let out = &mut y[r * e..r * e + e];
    let mut first = true;
    for (c, w) in op.row(r) {
        let w = T::from_f64(w);
        let xs = &x[c * e..c * e + e];
        if first {
            for (o, &v) in out.iter_mut().zip(xs) {
                *o = w * v;
            }
            first = false;
        } else {
            for (o, &v) in out.iter_mut().zip(xs) {
                *o += w * v;
            }
        }
    }
    if first {
        out.fill(T::default());
    }
}

fn op_rows_run<T: Sample>(op: &Csr, run: &Run, x: &[T], y: &mut [T], e: usize) {
    for i in 0..run.count {
        op_row(op, run.row0 + run.row_step * i, x, y, e);
    }
}
