//! Shallow depressions filled so that valleys drain (with `--base-scale` above the base's
//! own scale).
//!
//! Details copied patch by patch leave small closed hollows where a valley of one patch
//! meets a bump of another; water (D8 flow routing) then stops there and the valleys do
//! not connect. A priority flood (Barnes, Lehman & Mulla 2014) from the border visits the
//! cells in order of their spill level `z`; a neighbour `j` reached from `i` with
//! `z_j ≤ z_i` lies in a depression, and is raised to `z_i + ε` when `z_i − z_j ≤ d`
//! (it then drains to `i`), or left as it is when deeper (a real basin is kept). `d` is
//! [`FILL_STEPS`] times the example's RMS neighbour difference, the depth of the hollows
//! that the fine details make; `ε` is 10⁻⁶ of the heights' magnitude, above f32 rounding.
//! Same bytes for a seed: ties are broken by cell index.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::Grid;

/// The fill depth in units of the example's RMS neighbour difference (on the bench's
/// example, 2 brings the share of cells draining more than 64 cells near the example's).
pub const FILL_STEPS: f64 = 2.0;

#[derive(PartialEq)]
struct Cell(f64, usize);

impl Eq for Cell {}

impl Ord for Cell {
    /// Lowest height first, then lowest index (a min-heap on `BinaryHeap`).
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl PartialOrd for Cell {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// RMS central difference `(f[i+1] − f[i−1])/2` of the channel means along both axes.
pub(super) fn rms_step(g: &Grid) -> f64 {
    super::level_gain::mean_gradient2(g, false).sqrt()
}

/// Fill the depressions of `g` (single channel; others are left alone) whose step below
/// the spill level is at most `depth`; returns the number of cells raised.
pub(super) fn fill_shallow(g: &mut Grid, depth: f64) -> usize {
    // `!(depth > 0.0)` also refuses a NaN depth
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if g.c() != 1 || !(depth > 0.0) || g.h() < 3 || g.w() < 3 {
        return 0;
    }
    let (h, w) = (g.h(), g.w());
    let (lo, hi) = g.range();
    let eps = lo.abs().max(hi.abs()).max(hi - lo).max(1e-300) * 1e-6;
    let z = g.data_mut();
    let mut done = vec![false; h * w];
    let mut heap = BinaryHeap::with_capacity(2 * (h + w));
    for i in 0..h * w {
        let (y, x) = (i / w, i % w);
        if y == 0 || x == 0 || y + 1 == h || x + 1 == w {
            done[i] = true;
            heap.push(Cell(z[i], i));
        }
    }
    let mut raised = 0;
    while let Some(Cell(zi, i)) = heap.pop() {
        let (y, x) = ((i / w) as i64, (i % w) as i64);
        for (dy, dx) in [
            (-1, -1),
            (-1, 0),
            (-1, 1),
            (0, -1),
            (0, 1),
            (1, -1),
            (1, 0),
            (1, 1),
        ] {
            let (yy, xx) = (y + dy, x + dx);
            if yy < 0 || xx < 0 || yy >= h as i64 || xx >= w as i64 {
                continue;
            }
            let j = yy as usize * w + xx as usize;
            if done[j] {
                continue;
            }
            done[j] = true;
            if z[j] <= zi && zi - z[j] <= depth {
                z[j] = zi + eps;
                raised += 1;
            }
            heap.push(Cell(z[j], j));
        }
    }
    raised
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shallow_pit_is_filled_and_a_deep_one_kept() {
        let mut g = Grid::new(5, 7, 1, (0..35).map(|i| 10.0 + (i % 7) as f64).collect()).unwrap();
        *g.at_mut(2, 2, 0) = 10.0; // 1 below its lowest rim (11)
        *g.at_mut(2, 5, 0) = 0.0; // 14 below (14)
        let n = fill_shallow(&mut g, 3.0);
        assert_eq!(n, 1);
        assert!(g.at(2, 2, 0) > 11.0 && g.at(2, 2, 0) < 11.1);
        assert_eq!(g.at(2, 5, 0), 0.0);
    }
}
