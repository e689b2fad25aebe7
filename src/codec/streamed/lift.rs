//! The integer 5/3 pyramid of `--lossless` files ([`crate::codec::lossless::forward`])
//! streamed along axis 0: the integer twin of [`crate::tensor::stream`], in memory
//! bounded by a few rows per level.
//!
//! Level `l` lifts the box `region_l` along axis 0, then along the other active axes in
//! increasing order (the whole-array order). Along axis 0 (rows `x_0 … x_{m−1}`,
//! whole-sample mirror at the ends, `s = ⌊m/2⌋`, `n = ⌈m/2⌉`):
//!
//! ```text
//! d_j = x_{2j+1} − ⌊(x_{2j} + x_{2j+2})/2⌋            (x_{m} read as x_{m−2})
//! c_j = x_{2j} + ⌊(d_{j−1} + d_j + 2)/4⌋               (d_{−1} = d_0, d_s = d_{s−1})
//! ```
//!
//! output row `j` is `c_j`, row `n + j` is `d_j`: a detail row is computed as soon as
//! `x_{2j+2}` arrives, a coarse one right after, and a row is let go once the last row
//! reading it is computed (three input rows and two detail rows a level). Each output
//! row is then lifted along the other axes lane by lane, so every value is the
//! whole-array transform's, and its bands go to the sink (low rows: the coarse box on
//! to the next level). The synthesis undoes the same steps in reverse, pulling rows.

use crate::tensor::{Pyramid, Subband};
use crate::{Error, Result};
use std::collections::HashMap;
use std::ops::Range;

/// `⌊(a + b)/2⌋` (wrapped to 64 bits, as [`crate::scheme::linear::lift_forward`]).
#[inline(always)]
fn half(a: i64, b: i64) -> i64 {
    ((a as i128 + b as i128) >> 1) as i64
}

/// `⌊(a + b + 2)/4⌋` (wrapped to 64 bits).
#[inline(always)]
fn quarter(a: i64, b: i64) -> i64 {
    ((a as i128 + b as i128 + 2) >> 2) as i64
}

/// A band's place in a level's rows.
struct Part {
    band: usize,
    ranges: Vec<Range<usize>>,
    shape: Vec<usize>,
}

/// One level of the stream.
struct Level {
    /// The row box before the level and of its coarse block after it.
    row: Vec<usize>,
    coarse_row: Vec<usize>,
    /// Rows before (`m`) and after (`n`) the level.
    m: usize,
    nc: usize,
    axis0: bool,
    /// The other active axes, as axes of the row, increasing.
    others: Vec<usize>,
    low: Vec<Part>,
    high: Vec<Part>,
}

/// A planned integer stream over the pyramid of a lossless file.
pub(super) struct LiftPlan {
    shape: Vec<usize>,
    levels: Vec<Level>,
    band_shapes: Vec<Vec<usize>>,
}

fn volume(s: &[usize]) -> usize {
    s.iter().product()
}

/// Call `f(at_in_box, at_in_sub, run)` for the contiguous runs of the sub-box `ranges`
/// of the row-major box `shape`.
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

fn prefix(sub: &[usize]) -> Vec<Range<usize>> {
    sub.iter().map(|&s| 0..s).collect()
}

/// Lift every lane along axis `a` of the row-major box `shape` held in `row`, forward
/// or inverse.
fn lift_axis(row: &mut [i64], shape: &[usize], a: usize, forward: bool, scratch: &mut Vec<i64>) {
    let n = shape[a];
    if n < 2 {
        return;
    }
    let inner: usize = shape[a + 1..].iter().product();
    let outer: usize = shape[..a].iter().product();
    scratch.resize(2 * n, 0);
    let (lane, tmp) = scratch.split_at_mut(n);
    let lift = |v: &mut [i64], t: &mut [i64]| {
        if forward {
            crate::scheme::linear::lift_forward(v, t)
        } else {
            crate::scheme::linear::lift_inverse(v, t)
        }
    };
    for o in 0..outer {
        let base = o * n * inner;
        if inner == 1 {
            lift(&mut row[base..base + n], tmp);
            continue;
        }
        for i in 0..inner {
            for (k, v) in lane.iter_mut().enumerate() {
                *v = row[base + k * inner + i];
            }
            lift(lane, tmp);
            for (k, v) in lane.iter().enumerate() {
                row[base + k * inner + i] = *v;
            }
        }
    }
}

impl LiftPlan {
    /// The stream of the integer pyramid `pyr` (axes `0..nd`, non-standard order) whose
    /// bands are `bands` ([`Pyramid::subbands`]).
    pub(super) fn new(pyr: &Pyramid, bands: &[Subband]) -> Result<LiftPlan> {
        let nd = pyr.shape.len();
        if nd < 2 || pyr.spec.axes != (0..nd).collect::<Vec<_>>() || pyr.depth() == 0 {
            return Err(Error::parameter(
                "levels",
                pyr.depth(),
                "a lossless pyramid of 2 axes or more and at least one level",
            ));
        }
        let levels = (0..pyr.depth())
            .map(|l| {
                let (before, after) = (pyr.region_before(l), pyr.region_before(l + 1));
                let axis0 = l < pyr.axis_levels(0);
                let others = (1..nd).filter(|&i| l < pyr.axis_levels(i)).map(|i| i - 1);
                let (mut low, mut high) = (Vec::new(), Vec::new());
                for (b, s) in bands.iter().enumerate().filter(|(_, s)| s.level == l + 1) {
                    let part = Part {
                        band: b,
                        ranges: s.ranges[1..].to_vec(),
                        shape: s.ranges[1..].iter().map(|r| r.len()).collect(),
                    };
                    if axis0 && s.high[0] {
                        high.push(part);
                    } else {
                        low.push(part);
                    }
                }
                Level {
                    row: before[1..].to_vec(),
                    coarse_row: after[1..].to_vec(),
                    m: before[0],
                    nc: after[0],
                    axis0,
                    others: others.collect(),
                    low,
                    high,
                }
            })
            .collect();
        Ok(LiftPlan {
            shape: pyr.shape.clone(),
            levels,
            band_shapes: bands
                .iter()
                .map(|b| b.ranges[1..].iter().map(|r| r.len()).collect())
                .collect(),
        })
    }

    /// Samples of one row of the array.
    pub(super) fn row_len(&self) -> usize {
        volume(&self.shape[1..])
    }

    /// A streamed analysis handing `(band, row, values)` to `sink`.
    pub(super) fn analysis<F: FnMut(usize, usize, &[i64])>(&self, sink: F) -> Analysis<'_, F> {
        Analysis {
            plan: self,
            sink,
            next: 0,
            state: self.levels.iter().map(|_| AState::default()).collect(),
            scratch: Vec::new(),
        }
    }

    /// A streamed synthesis pulling band rows from `source(band, row, values)`; the
    /// array's rows come out of [`Synthesis::pull`] in order.
    pub(super) fn synthesis<S: FnMut(usize, usize, &mut [i64])>(
        &self,
        source: S,
    ) -> Synthesis<'_, S> {
        Synthesis {
            plan: self,
            source,
            next: 0,
            state: self.levels.iter().map(|_| SState::default()).collect(),
            scratch: Vec::new(),
        }
    }
}

/// One level's rows in an analysis: inputs and details (axis 0 only) still read.
#[derive(Default)]
struct AState {
    x: HashMap<usize, Vec<i64>>,
    d: HashMap<usize, Vec<i64>>,
    next_d: usize,
    next_c: usize,
}

/// A streamed analysis ([`LiftPlan::analysis`]).
pub(super) struct Analysis<'p, F> {
    plan: &'p LiftPlan,
    sink: F,
    next: usize,
    state: Vec<AState>,
    scratch: Vec<i64>,
}

impl<F: FnMut(usize, usize, &[i64])> Analysis<'_, F> {
    /// The next row of the array.
    pub(super) fn push(&mut self, row: Vec<i64>) -> Result<()> {
        if row.len() != self.plan.row_len() || self.next >= self.plan.shape[0] {
            return Err(Error::parameter(
                "row",
                self.next,
                "rows of the array's length, no more than its extent",
            ));
        }
        self.next += 1;
        self.arrive(0, self.next - 1, row);
        Ok(())
    }

    /// Check that every row came; hand back the sink.
    pub(super) fn finish(self) -> Result<F> {
        if self.next != self.plan.shape[0] {
            return Err(Error::parameter(
                "rows pushed",
                self.next,
                "every row of the array",
            ));
        }
        Ok(self.sink)
    }

    /// Input row `k` of level `l` arrives: compute every output row it completes.
    fn arrive(&mut self, l: usize, k: usize, row: Vec<i64>) {
        let lv = &self.plan.levels[l];
        if !lv.axis0 {
            self.out(l, k, row);
            return;
        }
        let (m, n) = (lv.m, lv.m.div_ceil(2));
        let s = m / 2;
        self.state[l].x.insert(k, row);
        loop {
            let st = &mut self.state[l];
            let j = st.next_d;
            let right = if 2 * j + 2 < m { 2 * j + 2 } else { 2 * j };
            if j < s
                && [2 * j, 2 * j + 1, right]
                    .iter()
                    .all(|i| st.x.contains_key(i))
            {
                let odd = st.x.remove(&(2 * j + 1)).expect("held");
                let (a, b) = (&st.x[&(2 * j)], &st.x[&right]);
                let d: Vec<i64> = odd
                    .iter()
                    .zip(a.iter().zip(b))
                    .map(|(&o, (&a, &b))| o.wrapping_sub(half(a, b)))
                    .collect();
                st.d.insert(j, d.clone());
                st.next_d += 1;
                self.out(l, n + j, d);
                continue;
            }
            let j = st.next_c;
            let (dl, dr) = (j.saturating_sub(1), j.min(s - 1));
            if j < n && dr < st.next_d && st.x.contains_key(&(2 * j)) {
                let x = st.x.remove(&(2 * j)).expect("held");
                let (a, b) = (&st.d[&dl], &st.d[&dr]);
                let c: Vec<i64> = x
                    .iter()
                    .zip(a.iter().zip(b))
                    .map(|(&x, (&a, &b))| x.wrapping_add(quarter(a, b)))
                    .collect();
                if j >= 1 {
                    st.d.remove(&(j - 1));
                }
                if j + 1 == n {
                    st.d.clear();
                }
                st.next_c += 1;
                self.out(l, j, c);
                continue;
            }
            break;
        }
    }

    /// Output row `r` of level `l` lifted along axis 0: the other axes, then its bands
    /// out and its coarse box on.
    fn out(&mut self, l: usize, r: usize, mut row: Vec<i64>) {
        let plan = self.plan;
        let lv = &plan.levels[l];
        for &a in &lv.others {
            lift_axis(&mut row, &lv.row, a, true, &mut self.scratch);
        }
        let (parts, at) = if r < lv.nc {
            (&lv.low, r)
        } else {
            (&lv.high, r - lv.nc)
        };
        let mut band = Vec::new();
        for p in parts {
            band.clear();
            band.resize(volume(&p.shape), 0);
            runs(&lv.row, &p.ranges, |a, b, k| {
                band[b..b + k].copy_from_slice(&row[a..a + k])
            });
            (self.sink)(p.band, at, &band);
        }
        if r < lv.nc {
            let mut coarse = vec![0i64; volume(&lv.coarse_row)];
            runs(&lv.row, &prefix(&lv.coarse_row), |a, b, k| {
                coarse[b..b + k].copy_from_slice(&row[a..a + k])
            });
            if l + 1 < plan.levels.len() {
                self.arrive(l + 1, r, coarse);
            } else {
                (self.sink)(0, r, &coarse);
            }
        }
    }
}

/// One level's rows in a synthesis: its inputs (after the other axes' inverse) and its
/// even outputs still read.
#[derive(Default)]
struct SState {
    /// detail rows `d_j` by `j`
    d: HashMap<usize, Vec<i64>>,
    /// even output rows `x_{2j}` by `j`
    x: HashMap<usize, Vec<i64>>,
}

/// A streamed synthesis ([`LiftPlan::synthesis`]).
pub(super) struct Synthesis<'p, S> {
    plan: &'p LiftPlan,
    source: S,
    next: usize,
    state: Vec<SState>,
    scratch: Vec<i64>,
}

impl<S: FnMut(usize, usize, &mut [i64])> Synthesis<'_, S> {
    /// The next row of the array.
    pub(super) fn pull(&mut self) -> Result<Vec<i64>> {
        if self.next >= self.plan.shape[0] {
            return Err(Error::parameter(
                "row",
                self.next,
                "no more rows than the array's extent",
            ));
        }
        self.next += 1;
        Ok(self.produce(0, self.next - 1))
    }

    /// Output row `r` of level `l` (pulled in increasing `r`).
    fn produce(&mut self, l: usize, r: usize) -> Vec<i64> {
        let lv = &self.plan.levels[l];
        if !lv.axis0 {
            return self.input(l, r);
        }
        let m = lv.m;
        let s = m / 2;
        let out = if r.is_multiple_of(2) {
            self.even(l, r / 2).clone()
        } else {
            let j = r / 2;
            let right = if 2 * j + 2 < m { j + 1 } else { j };
            self.even(l, j);
            self.even(l, right);
            self.detail(l, j);
            let st = &self.state[l];
            let (a, b, d) = (&st.x[&j], &st.x[&right], &st.d[&j]);
            d.iter()
                .zip(a.iter().zip(b))
                .map(|(&d, (&a, &b))| d.wrapping_add(half(a, b)))
                .collect()
        };
        // rows no output row from `r + 1` on reads
        let st = &mut self.state[l];
        st.x.retain(|&j, _| 2 * j + 1 > r);
        st.d.retain(|&j, _| 2 * j + 2 > r || j + 1 == s);
        out
    }

    /// Even output row `x_{2j}` of level `l`, held.
    fn even(&mut self, l: usize, j: usize) -> &Vec<i64> {
        if !self.state[l].x.contains_key(&j) {
            let s = self.plan.levels[l].m / 2;
            let (dl, dr) = (j.saturating_sub(1), j.min(s - 1));
            self.detail(l, dl);
            self.detail(l, dr);
            let c = self.input(l, j);
            let st = &mut self.state[l];
            let (a, b) = (&st.d[&dl], &st.d[&dr]);
            let x = c
                .iter()
                .zip(a.iter().zip(b))
                .map(|(&c, (&a, &b))| c.wrapping_sub(quarter(a, b)))
                .collect();
            st.x.insert(j, x);
        }
        &self.state[l].x[&j]
    }

    /// Detail row `d_j` of level `l`, held.
    fn detail(&mut self, l: usize, j: usize) {
        if !self.state[l].d.contains_key(&j) {
            let nc = self.plan.levels[l].nc;
            let d = self.input(l, nc + j);
            self.state[l].d.insert(j, d);
        }
    }

    /// Input row `c` of level `l` (its coarse box from level `l + 1`, its bands from
    /// the source) with the other axes' lifting undone.
    fn input(&mut self, l: usize, c: usize) -> Vec<i64> {
        let plan = self.plan;
        let lv = &plan.levels[l];
        let mut row = vec![0i64; volume(&lv.row)];
        let mut band = Vec::new();
        let (parts, at) = if c < lv.nc {
            let coarse = if l + 1 < plan.levels.len() {
                self.produce(l + 1, c)
            } else {
                band.resize(volume(&plan.band_shapes[0]), 0);
                (self.source)(0, c, &mut band);
                std::mem::take(&mut band)
            };
            runs(&lv.row, &prefix(&lv.coarse_row), |a, b, k| {
                row[a..a + k].copy_from_slice(&coarse[b..b + k])
            });
            (&lv.low, c)
        } else {
            (&lv.high, c - lv.nc)
        };
        for p in parts {
            band.clear();
            band.resize(volume(&p.shape), 0);
            (self.source)(p.band, at, &mut band);
            runs(&lv.row, &p.ranges, |a, b, k| {
                row[a..a + k].copy_from_slice(&band[b..b + k])
            });
        }
        for &a in lv.others.iter().rev() {
            lift_axis(&mut row, &lv.row, a, false, &mut self.scratch);
        }
        row
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::lossless;
    use crate::scheme::Scheme;

    /// The streamed analysis gives every band row of the whole-array integer transform,
    /// and the streamed synthesis gives the rows back, on odd shapes and deep pyramids.
    #[test]
    fn the_stream_is_the_whole_integer_transform() {
        for dims in [
            vec![2usize, 2],
            vec![9, 5],
            vec![37, 20],
            vec![13, 1],
            vec![3, 40],
            vec![11, 6, 7],
            vec![4, 9, 3],
        ] {
            for levels in [1usize, 3, 6] {
                let n: usize = dims.iter().product();
                let mut s = 11u64;
                let v: Vec<i64> = (0..n)
                    .map(|i| {
                        crate::entropy::testing::lcg(&mut s);
                        (i as i64 * 37) % 500 + (s >> 54) as i64 - 512
                    })
                    .collect();
                let pyr = lossless::plan(&dims, levels, Scheme::Linear);
                let bands = pyr.subbands();
                let mut whole = v.clone();
                assert!(lossless::forward(&mut whole[..], &pyr));
                let sp = LiftPlan::new(&pyr, &bands).unwrap();
                let rl = sp.row_len();
                let mut got: Vec<Vec<Option<Vec<i64>>>> = bands
                    .iter()
                    .map(|b| vec![None; b.ranges[0].len()])
                    .collect();
                let mut a = sp.analysis(|j, r, d: &[i64]| {
                    assert!(got[j][r].is_none(), "{j} {r} twice");
                    got[j][r] = Some(d.to_vec());
                });
                for r in 0..dims[0] {
                    a.push(v[r * rl..(r + 1) * rl].to_vec()).unwrap();
                }
                let _sink = a.finish().unwrap();
                let mut rows = Vec::new();
                for (j, b) in bands.iter().enumerate() {
                    let want = crate::codec::layout::gather(&whole, &pyr.shape, &b.ranges);
                    let flat: Vec<i64> = got[j]
                        .iter()
                        .flat_map(|r| r.clone().expect("every row"))
                        .collect();
                    assert_eq!(flat, want, "{dims:?} {levels} band {j}");
                    rows.push(flat);
                }
                let mut syn = sp.synthesis(|j, r, out: &mut [i64]| {
                    let w = out.len();
                    out.copy_from_slice(&rows[j][r * w..(r + 1) * w]);
                });
                let back: Vec<i64> = (0..dims[0]).flat_map(|_| syn.pull().unwrap()).collect();
                assert_eq!(back, v, "{dims:?} {levels}");
            }
        }
    }
}
