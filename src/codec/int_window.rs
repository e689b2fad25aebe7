//! Synthesis of a window of a lossless file: the samples of one box of the integer
//! pyramid's inverse ([`super::lossless::inverse`]), computed from only the
//! coefficients that box depends on, bit-identical to the same box of the whole inverse.
//!
//! One inverse level along an axis of length `n` (coarse length `m = ⌈n/2⌉`) takes the
//! lane `[C | D]` to the fine samples by the integer lifting of the scheme (the 5/3 of
//! [`crate::scheme::linear::lift_inverse`] or the S-transform). A fine sample `x[i]`
//! of the 5/3 reads `C[⌊i/2⌋ ..= ⌊i/2⌋+1]` and `D[⌊i/2⌋−1 ..= ⌊i/2⌋+1]` (clamped as
//! the lifting clamps at the lane's ends); of the S-transform the pair `C[⌊i/2⌋]`,
//! `D[⌊i/2⌋]`. The box's samples `[o0, o1)` on that axis are so computed by the same
//! lifting on the segment `[a, b)` of the lane, `a = (o0 − 2)` rounded down to even
//! (0 for the S-transform's pairs: `o0` rounded down to even) and `b = min(n, o1 + 2)`
//! (`o1` rounded up to even for the S-transform): the segment's coarse values
//! `C[a/2 .. a/2 + ⌈(b−a)/2⌉)` and details `D[a/2 .. a/2 + ⌊(b−a)/2⌋)`, lifted as a lane
//! of its own. Its ends differ from the whole lane's only within 2 samples of a cut
//! inside the lane (where the lifting's end rules stand in for the missing
//! neighbours), outside `[o0, o1)`; at the lane's true ends the segment's rules are the
//! lane's. Going from the window down to the coarse block gives every level's box and
//! columns; going back up, each level gathers its input (coarse values from the level
//! below, details from the bands) and lifts each axis in decreasing order, as
//! [`super::lossless::inverse`] does.

use crate::scheme::Scheme;
use crate::tensor::{box_lists, for_each_index, gather, Pyramid};
use std::ops::Range;

/// The segment of a lane of length `n` that gives the samples `o` exactly (module doc),
/// and its coarse and detail ranges (indices into `C` and `D`).
fn segment(
    scheme: Scheme,
    n: usize,
    o: &Range<usize>,
) -> (Range<usize>, Range<usize>, Range<usize>) {
    let (a, b) = if scheme == Scheme::Linear {
        (o.start.saturating_sub(2) & !1, (o.end + 2).min(n))
    } else {
        (o.start & !1, o.end.next_multiple_of(2).min(n))
    };
    let (c0, len) = (a / 2, b - a);
    (a..b, c0..c0 + len.div_ceil(2), c0..c0 + len / 2)
}

/// The ranges one axis of a window's inverse level lifts: the segment, its coarse and
/// its detail part.
type Lift = (Range<usize>, Range<usize>, Range<usize>);

/// One inverse level of a window: its output box, and on each axis it lifts (in
/// decreasing axis order) the segment, coarse and detail ranges; the coarse block's
/// extents (the level's `m` per axis).
struct Level {
    out: Vec<Range<usize>>,
    /// Per axis: `Some((segment, coarse, detail))` when the axis is lifted at this level.
    lifts: Vec<Option<Lift>>,
    coarse: Vec<usize>,
}

/// The levels of a lossless window's inverse, finest first, and the box of the coarse
/// block the coarsest level reads.
pub(super) struct IntWindow {
    scheme: Scheme,
    levels: Vec<Level>,
    /// The box of the coarse block (its own coordinates) the window needs.
    pub(super) coarse_box: Vec<Range<usize>>,
}

impl IntWindow {
    /// The plan of the box `window` (one non-empty range per axis, within `pyr.shape`)
    /// of the integer pyramid `pyr` ([`super::lossless::plan`]); `None` for a window
    /// that is not such a box.
    pub(super) fn new(pyr: &Pyramid, window: &[Range<usize>]) -> Option<IntWindow> {
        let nd = pyr.shape.len();
        if window.len() != nd
            || window
                .iter()
                .zip(&pyr.shape)
                .any(|(r, &e)| r.start >= r.end || r.end > e)
        {
            return None;
        }
        let mut region = pyr.shape.clone();
        let mut need = window.to_vec();
        let mut levels = Vec::new();
        for l in 0..pyr.depth() {
            let mut next = region.clone();
            let mut lifts = vec![None; nd];
            for (i, &a) in pyr.spec.axes.iter().enumerate() {
                if l < pyr.axis_levels(i) {
                    next[a] = pyr.lengths[i][l + 1];
                    lifts[a] = Some(segment(pyr.spec.scheme, region[a], &need[a]));
                }
            }
            let coarse_need = (0..nd)
                .map(|a| match &lifts[a] {
                    Some((_, c, _)) => c.clone(),
                    None => need[a].clone(),
                })
                .collect();
            levels.push(Level {
                out: need,
                lifts,
                coarse: next.clone(),
            });
            need = coarse_need;
            region = next;
        }
        Some(IntWindow {
            scheme: pyr.spec.scheme,
            levels,
            coarse_box: need,
        })
    }

    /// The columns level `l` (0: the finest) reads on each axis, ascending, in the
    /// lane's coordinates.
    fn cols(&self, l: usize) -> Vec<Vec<usize>> {
        let lv = &self.levels[l];
        lv.lifts
            .iter()
            .zip(&lv.out)
            .zip(&lv.coarse)
            .map(|((lift, o), &m)| match lift {
                Some((_, c, d)) => c.clone().chain(d.start + m..d.end + m).collect(),
                None => o.clone().collect(),
            })
            .collect()
    }

    /// The box that level `l` (0: the finest) reads of the box `band` of its input lane
    /// (as [`crate::tensor::WindowPlan::reads`]): on each axis the span of its columns
    /// inside `band`'s range, relative to its start (`0..0` when none is).
    pub(super) fn reads(&self, l: usize, band: &[Range<usize>]) -> Vec<Range<usize>> {
        if l >= self.levels.len() {
            return band.iter().map(|_| 0..0).collect();
        }
        crate::tensor::reads_of(&self.cols(l), band)
    }

    /// The window's samples (raster order over its box): `coef(p)` gives the
    /// coefficient at the plane position `p` (a detail coefficient of a level, or of
    /// the coarse block inside [`IntWindow::coarse_box`]); only those the window
    /// depends on are asked for.
    pub(super) fn synthesize(&self, coef: &dyn Fn(&[usize]) -> i64) -> Vec<i64> {
        let mut cur: Vec<i64> = Vec::new();
        let mut cur_box = self.coarse_box.clone();
        for_each_index(&box_lists(&cur_box), |p| cur.push(coef(p)));
        let mut scratch = Vec::new();
        for (l, lv) in self.levels.iter().enumerate().rev() {
            let cols = self.cols(l);
            let mut dims: Vec<usize> = cols.iter().map(|c| c.len()).collect();
            let mut x = gather(&cols, &lv.coarse, (&cur, &cur_box), &mut |p| coef(p));
            for a in (0..dims.len()).rev() {
                let Some((seg, c, _)) = &lv.lifts[a] else {
                    continue;
                };
                let nc = c.len();
                let keep = lv.out[a].start - seg.start..lv.out[a].end - seg.start;
                x = lift_axis(
                    &x,
                    &dims,
                    a,
                    |lane, out| {
                        // the segment's lane: coarse then details, as gathered
                        scratch.resize(lane.len(), 0);
                        let mut v = lane.to_vec();
                        inverse_lane(self.scheme, &mut v, nc, &mut scratch);
                        out.copy_from_slice(&v[keep.clone()]);
                    },
                    keep.len(),
                );
                dims[a] = keep.len();
            }
            cur = x;
            cur_box = lv.out.clone();
        }
        cur
    }
}

/// One inverse level of `scheme` on a lane of `nc` coarse values then its details.
fn inverse_lane(scheme: Scheme, lane: &mut [i64], nc: usize, scratch: &mut [i64]) {
    debug_assert_eq!(nc, lane.len().div_ceil(2));
    if scheme == Scheme::Linear {
        crate::scheme::linear::lift_inverse(lane, scratch);
    } else {
        super::lossless::s_inverse(lane);
    }
}

/// `f(lane, out)` along `axis` of the compact array `x` of extents `shape`, each lane
/// giving `m` values: the result has `m` on that axis.
fn lift_axis(
    x: &[i64],
    shape: &[usize],
    axis: usize,
    mut f: impl FnMut(&[i64], &mut [i64]),
    m: usize,
) -> Vec<i64> {
    let outer: usize = shape[..axis].iter().product();
    let inner: usize = shape[axis + 1..].iter().product();
    let n = shape[axis];
    let mut out = vec![0i64; outer * m * inner];
    let (mut lane, mut res) = (vec![0i64; n], vec![0i64; m]);
    for o in 0..outer {
        for i in 0..inner {
            for (k, v) in lane.iter_mut().enumerate() {
                *v = x[(o * n + k) * inner + i];
            }
            f(&lane, &mut res);
            for (k, &v) in res.iter().enumerate() {
                out[(o * m + k) * inner + i] = v;
            }
        }
    }
    out
}
