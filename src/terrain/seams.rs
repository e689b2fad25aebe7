//! The seam ratio of a synthesized terrain or volume: second differences across the
//! finest patch borders against those elsewhere (1 when the borders do not show).

use rayon::prelude::*;

use super::Grid;

/// Mean |second difference| of channel-mean heights across the lines `period·j − 1 + δ`
/// (`δ ∈ {−1, 0, 1}`: the finest patch borders, which lie near fine index `2t − 1`)
/// divided by the same over every other line; rows and columns together.
pub fn seam_ratio(g: &Grid, period: usize) -> f64 {
    let (h, w) = (g.h(), g.w());
    if h < 3 || w < 3 {
        return f64::NAN;
    }
    // the heights themselves when there is one channel (no copy of the grid)
    let means: Vec<f64>;
    let height: &[f64] = if g.c() == 1 {
        g.data()
    } else {
        means = (0..h * w).map(|i| g.mean_at(i / w, i % w)).collect();
        &means
    };
    let tally = SeamTally::new(period);
    let border: Vec<bool> = (0..h.max(w)).map(|i| tally.is_border(i)).collect();
    // per-row sums in parallel, added in row order (the same figure for any thread count)
    let rows: Vec<[(f64, usize); 2]> = (1..h - 1)
        .into_par_iter()
        .map(|y| {
            let mut t = [(0.0, 0usize); 2];
            let r = &height[y * w..(y + 1) * w];
            let (up, down) = (
                &height[(y - 1) * w..y * w],
                &height[(y + 1) * w..(y + 2) * w],
            );
            for x in 1..w - 1 {
                let sx = (r[x + 1] - 2.0 * r[x] + r[x - 1]).abs();
                let sy = (down[x] - 2.0 * r[x] + up[x]).abs();
                let bx = &mut t[border[x] as usize];
                bx.0 += sx;
                bx.1 += 1;
                let by = &mut t[border[y] as usize];
                by.0 += sy;
                by.1 += 1;
            }
            t
        })
        .collect();
    let mut seams = tally;
    for t in rows {
        seams.off.0 += t[0].0;
        seams.off.1 += t[0].1;
        seams.on.0 += t[1].0;
        seams.on.1 += t[1].1;
    }
    seams.ratio()
}

/// Second differences split by whether their line is a patch border (`period·j − 1 ± 1`),
/// for the seam ratios of images and volumes.
pub(crate) struct SeamTally {
    period: usize,
    on: (f64, usize),
    off: (f64, usize),
}

impl SeamTally {
    pub(crate) fn new(period: usize) -> SeamTally {
        SeamTally {
            period: period.max(1),
            on: (0.0, 0),
            off: (0.0, 0),
        }
    }

    /// Whether line `i` is a patch border `period·j − 1 ± 1` (j ≥ 1).
    pub(crate) fn is_border(&self, i: usize) -> bool {
        (1..=1 + i / self.period).any(|j| {
            let b = (self.period * j) as i64 - 1;
            (i as i64 - b).abs() <= 1
        })
    }

    /// Count `s`, the second difference across line `i` of its axis.
    pub(crate) fn add(&mut self, i: usize, s: f64) {
        let border = self.is_border(i);
        let t = if border { &mut self.on } else { &mut self.off };
        t.0 += s;
        t.1 += 1;
    }

    /// Mean on the borders ÷ mean elsewhere (NaN when either is undefined).
    pub(crate) fn ratio(&self) -> f64 {
        if self.on.1 == 0 || self.off.1 == 0 || self.off.0 == 0.0 {
            return f64::NAN;
        }
        (self.on.0 / self.on.1 as f64) / (self.off.0 / self.off.1 as f64)
    }
}
