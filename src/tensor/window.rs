//! Synthesis of a window: the samples of one box of a non-standard pyramid's
//! reconstruction, computed from only the coefficients that box depends on.
//!
//! One synthesis level along an axis of length `n` is the operator `S` (`n × n`, the
//! scheme's `[P | Q]` with its boundary rows): fine sample `i` is
//! `x[i] = Σ_c S[i, c] · y[c]` over the level's input lane `y = [C | D]`. The samples
//! `O` of the box on that axis so need the columns `I = ⋃_{i ∈ O} cols(S[i, ·])`; the
//! coarse part of `I` (`c < m`, `m` the coarse length) is what the next coarser level
//! must give, the rest are detail coefficients. Going from the window down to the coarse
//! block gives every level's box `O_l` and columns `I_l`; going back up, each level
//! gathers its input over `I_l` (coarse values from the level below it, details from
//! the coefficients), and applies, axis after axis in increasing order as every engine
//! does, the rows `O_l` of `S` restricted to the columns `I_l` ([`Csr::apply`], the
//! same sums in the same order as the kernels): the window's samples are bit-identical
//! to the same box of a whole synthesis, for every scheme and boundary mode.

use super::pyramid::{Order, Pyramid};
use super::workspace::Planner;
use crate::scheme::sparse::{Csr, Triplets};
use crate::scheme::Sample;
use std::ops::Range;

/// One synthesis level of a window: its output box, the input columns of each axis
/// (ascending), the coarse block's extents, and the restricted operator of each axis it
/// transforms (in increasing axis order).
struct Level {
    out: Vec<Range<usize>>,
    cols: Vec<Vec<usize>>,
    coarse: Vec<usize>,
    ops: Vec<(usize, Csr)>,
}

/// The levels of a window's synthesis, finest first, and the box of the coarse block
/// the coarsest level reads.
pub struct WindowPlan {
    levels: Vec<Level>,
    /// The box of the coarse block (its own coordinates) that the window needs.
    pub coarse_box: Vec<Range<usize>>,
}

impl WindowPlan {
    /// The plan of the window `window` (a box of `pyr.shape`, one non-empty range per
    /// axis) of the non-standard pyramid `pyr`; `None` for a standard pyramid or a
    /// window that is not such a box.
    pub fn new(pyr: &Pyramid, window: &[Range<usize>]) -> Option<WindowPlan> {
        let nd = pyr.shape.len();
        if pyr.spec.order != Order::NonStandard
            || window.len() != nd
            || window
                .iter()
                .zip(&pyr.shape)
                .any(|(r, &e)| r.start >= r.end || r.end > e)
        {
            return None;
        }
        let planner = Planner::shared();
        let spec = &pyr.spec;
        let mut need: Vec<Range<usize>> = window.to_vec();
        let mut levels = Vec::new();
        for l in 0..pyr.depth() {
            let next = pyr.region_before(l + 1);
            let mut cols: Vec<Vec<usize>> = need.iter().map(|r| r.clone().collect()).collect();
            let mut ops = Vec::new();
            let mut active: Vec<usize> = (0..spec.axes.len())
                .filter(|&i| l < pyr.axis_levels(i))
                .collect();
            active.sort_by_key(|&i| spec.axes[i]);
            for i in active {
                let a = spec.axes[i];
                let lo = planner.level_ops(spec.scheme, spec.boundary, pyr.lengths[i][l]);
                let s = &lo.two_scale.synthesis;
                let mut used: Vec<usize> = need[a]
                    .clone()
                    .flat_map(|r| s.row_slices(r).0.iter().map(|&c| c as usize))
                    .collect();
                used.sort_unstable();
                used.dedup();
                let mut t = Triplets::new(need[a].len(), used.len());
                for (ro, r) in need[a].clone().enumerate() {
                    let (cs, ws) = s.row_slices(r);
                    for (&c, &w) in cs.iter().zip(ws) {
                        let at = used.binary_search(&(c as usize)).expect("a used column");
                        t.add(ro, at, w);
                    }
                }
                ops.push((a, t.into_csr()));
                cols[a] = used;
            }
            let coarse_need: Vec<Range<usize>> = cols
                .iter()
                .zip(&next)
                .map(|(c, &m)| {
                    let inside: Vec<usize> = c.iter().copied().filter(|&x| x < m).collect();
                    match (inside.first(), inside.last()) {
                        (Some(&a), Some(&b)) => a..b + 1,
                        _ => 0..0,
                    }
                })
                .collect();
            levels.push(Level {
                out: need,
                cols,
                coarse: next,
                ops,
            });
            need = coarse_need;
        }
        Some(WindowPlan {
            levels,
            coarse_box: need,
        })
    }

    /// The box that synthesis level `l` (0: the finest) reads of the box `band` of its
    /// input lane (the plane's coordinates, e.g. a band's ranges): on each axis the span
    /// of the columns its operator rows read that fall in `band`'s range, relative to
    /// its start (`0..0` when none does).
    pub fn reads(&self, l: usize, band: &[Range<usize>]) -> Vec<Range<usize>> {
        let Some(lv) = self.levels.get(l) else {
            return band.iter().map(|_| 0..0).collect();
        };
        reads_of(&lv.cols, band)
    }

    /// The window's samples (raster order over its box) from the coefficients of the
    /// pyramid laid out at the origin of `plane` (a row-major array of extents `shape`,
    /// each at least the pyramid's): only the coefficients the window depends on are read.
    pub fn synthesize<T: Sample>(&self, plane: &[T], shape: &[usize]) -> Vec<T> {
        let st = super::array::strides(shape);
        self.synthesize_by(|p| plane[p.iter().zip(&st).map(|(x, s)| x * s).sum::<usize>()])
    }

    /// [`WindowPlan::synthesize`] with the coefficient at each position of the
    /// pyramid's plane given by `coef` (called only at the positions the window depends
    /// on, so that the coefficients may be held over boxes of their bands alone).
    pub fn synthesize_by<T: Sample>(&self, mut coef: impl FnMut(&[usize]) -> T) -> Vec<T> {
        // the coarse block's box
        let mut cur: Vec<T> = Vec::new();
        let mut cur_box = self.coarse_box.clone();
        if cur_box.iter().all(|r| !r.is_empty()) {
            for_each_index(&box_lists(&cur_box), |p| cur.push(coef(p)));
        }
        for lv in self.levels.iter().rev() {
            let dims: Vec<usize> = lv.cols.iter().map(|c| c.len()).collect();
            let mut input = gather(&lv.cols, &lv.coarse, (&cur, &cur_box), &mut coef);
            let mut shape_now = dims;
            for (a, op) in &lv.ops {
                input = apply_axis(&input, &shape_now, *a, op);
                shape_now[*a] = op.rows();
            }
            cur = input;
            cur_box = lv.out.clone();
        }
        cur
    }
}

/// The span, relative to `band`'s start on each axis, of the columns `cols` (one
/// ascending list per axis, the lane's coordinates) that fall in `band` (`0..0` on an
/// axis where none does): the box of a band that a window's level reads.
pub(crate) fn reads_of(cols: &[Vec<usize>], band: &[Range<usize>]) -> Vec<Range<usize>> {
    cols.iter()
        .zip(band)
        .map(|(c, r)| {
            let lo = c.partition_point(|&x| x < r.start);
            let hi = c.partition_point(|&x| x < r.end);
            if lo < hi {
                c[lo] - r.start..c[hi - 1] + 1 - r.start
            } else {
                0..0
            }
        })
        .collect()
}

/// A window level's input over the product of the columns `cols` (raster order): at a
/// position inside the coarse block (`p[a] < coarse[a]` on every axis) the value the
/// level below gave (`cur`, raster order over the box `cur_box`), elsewhere the
/// coefficient `coef(p)`. The one gather of every window synthesis (this one and the
/// integer lifting's).
pub(crate) fn gather<T: Copy>(
    cols: &[Vec<usize>],
    coarse: &[usize],
    (cur, cur_box): (&[T], &[Range<usize>]),
    coef: &mut impl FnMut(&[usize]) -> T,
) -> Vec<T> {
    let mut input: Vec<T> = Vec::with_capacity(cols.iter().map(|c| c.len()).product());
    let cst = super::array::strides(&box_dims(cur_box));
    for_each_index(cols, |p| {
        let inside = p.iter().zip(coarse).all(|(&x, &m)| x < m);
        input.push(if inside {
            let o: usize = p
                .iter()
                .zip(cur_box)
                .zip(&cst)
                .map(|((&x, r), s)| (x - r.start) * s)
                .sum();
            cur[o]
        } else {
            coef(p)
        });
    });
    input
}

/// The extents of a box.
pub(crate) fn box_dims(b: &[Range<usize>]) -> Vec<usize> {
    b.iter().map(|r| r.len()).collect()
}

/// The indices of a box, one list per axis.
pub(crate) fn box_lists(b: &[Range<usize>]) -> Vec<Vec<usize>> {
    b.iter().map(|r| r.clone().collect()).collect()
}

/// Call `f(p)` for every point of the product of the index lists `lists` (raster order,
/// the last axis fastest).
pub(crate) fn for_each_index(lists: &[Vec<usize>], mut f: impl FnMut(&[usize])) {
    if lists.iter().any(|l| l.is_empty()) {
        return;
    }
    let nd = lists.len();
    let mut k = vec![0usize; nd];
    let mut p: Vec<usize> = lists.iter().map(|l| l[0]).collect();
    loop {
        f(&p);
        let mut a = nd;
        loop {
            if a == 0 {
                return;
            }
            a -= 1;
            k[a] += 1;
            if k[a] < lists[a].len() {
                p[a] = lists[a][k[a]];
                break;
            }
            k[a] = 0;
            p[a] = lists[a][0];
        }
    }
}

/// `op` (`rows × shape[axis]`) applied along `axis` of the compact array `x` of extents
/// `shape`: the result has `op.rows()` on that axis.
fn apply_axis<T: Sample>(x: &[T], shape: &[usize], axis: usize, op: &Csr) -> Vec<T> {
    let outer: usize = shape[..axis].iter().product();
    let inner: usize = shape[axis + 1..].iter().product();
    let (n, m) = (shape[axis], op.rows());
    let mut out = vec![T::default(); outer * m * inner];
    if inner == 0 || n == 0 || m == 0 {
        return out;
    }
    for o in 0..outer {
        op.apply(
            &x[o * n * inner..(o + 1) * n * inner],
            inner,
            &mut out[o * m * inner..(o + 1) * m * inner],
            inner,
            inner,
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheme::{Boundary, Scheme};
    use crate::tensor::{analyze, synthesize, Array, PyramidSpec};

    /// A window of a synthesis is bit-identical to the same box of the whole synthesis,
    /// for every scheme and boundary, 1-D to 3-D, odd extents, levels 0 to 3, windows
    /// in the middle and at the edges.
    #[test]
    fn window_is_the_box_of_the_whole_synthesis() {
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) % 1000) as f32 / 7.0 - 60.0
        };
        for shape in [vec![37usize], vec![23, 19], vec![9, 13, 11]] {
            for scheme in Scheme::ALL {
                for boundary in [
                    Boundary::Symmetric,
                    Boundary::Periodic,
                    Boundary::Interpolating,
                ] {
                    for levels in 0..=3 {
                        let spec = PyramidSpec {
                            scheme,
                            boundary,
                            levels,
                            order: Order::NonStandard,
                            axes: (0..shape.len()).collect(),
                        };
                        let n: usize = shape.iter().product();
                        let data: Vec<f32> = (0..n).map(|_| rnd()).collect();
                        let mut a = Array::from_shape_vec(&shape, data).unwrap();
                        let Ok(pyr) = analyze(&mut a, &spec) else {
                            continue;
                        };
                        let coeffs = a.data().to_vec();
                        let mut whole = a.clone();
                        synthesize(&mut whole, &pyr).unwrap();
                        let windows: Vec<Vec<Range<usize>>> = vec![
                            shape.iter().map(|&e| 0..e).collect(),
                            shape.iter().map(|_| 0..1).collect(),
                            shape.iter().map(|&e| e - 1..e).collect(),
                            shape.iter().map(|&e| e / 3..e / 2 + 1).collect(),
                            shape.iter().map(|&e| e / 2..e).collect(),
                        ];
                        for w in windows {
                            let plan = WindowPlan::new(&pyr, &w).unwrap();
                            let got = plan.synthesize(&coeffs, &shape);
                            let mut want = Vec::new();
                            crate::tensor::for_each_run(&shape, &w, |at, len, _| {
                                want.extend_from_slice(&whole.data()[at..at + len])
                            });
                            assert_eq!(
                                got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                                want.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                                "{shape:?} {scheme:?} {boundary:?} {levels} {w:?}"
                            );
                        }
                    }
                }
            }
        }
    }
}
