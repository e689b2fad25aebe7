//! Drainage of a synthesized terrain (with `--base-scale` above the base's own scale).
//!
//! Details copied patch by patch leave closed hollows where a valley of one patch meets a
//! bump of another; D8 flow stops there and the valleys do not join into networks. The
//! depressions are breached, not filled: a priority flood (Barnes, Lehman & Mulla 2014)
//! carves the lowest path out of each depression at most `depth` deep (Soille 2004), so
//! that only the cells on that path change and no lake flattens the relief; deeper
//! basins are kept. Each channel is then widened into a valley: its neighbours are
//! lowered towards its floor by [`WIDEN`] (a one-cell trench would be as rough as a
//! cliff). A lowered cell keeps a lower neighbour, so no new depression is made. Same
//! bytes for a seed: ties are broken by cell index.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::Grid;

/// The carving depth in units of the example's RMS neighbour difference: a depression
/// deeper than that below its spill level is a basin and is kept (on the bench's example,
/// 41 m; 2.2 left the D8 share at 0.74, 3 gives 0.80 with the roughness within 1.25).
pub const BREACH_STEPS: f64 = 3.0;

/// The channel's first and second ring of neighbours keep these fractions of their
/// height above the channel (or first ring) next to them.
pub const WIDEN: [f64; 2] = [0.5, 0.75];

/// RMS central difference `(f[i+1] − f[i−1])/2` of the channel means along both axes.
pub(super) fn rms_step(g: &Grid) -> f64 {
    super::level_gain::mean_gradient2(g, false).sqrt()
}

/// A heap key: `z` as an order-preserving integer (rounded to f32) above the cell index,
/// lowest first under `Reverse`.
fn key(z: f64, i: usize) -> Reverse<u64> {
    let b = (z as f32).to_bits();
    let o = if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    };
    Reverse(((o as u64) << 32) | i as u64)
}

/// Breach the depressions of `g` (single channel) to at most `depth` below their spill
/// level ([`breach`]), then widen the channels ([`widen`], no cell lowered by more than
/// `depth`); returns the number of cells changed.
pub(super) fn drain(g: &mut Grid, depth: f64) -> usize {
    let mut lowered = breach(g, depth);
    let n = lowered.iter().filter(|&&l| l).count();
    if n == 0 {
        return 0;
    }
    n + widen(g, &mut lowered, &WIDEN, depth)
}

/// Breach the depressions of `g` (single channel) down to `depth` below their spill
/// level: a priority flood from the border (Barnes, Lehman & Mulla 2014) visits the
/// cells lowest first, each cell `j` reached from a visited neighbour `i` (its parent,
/// towards the outlet) at the spill level `s_j = max(z_j, s_i)`. When `z_j ≤ z_i` (`j`
/// lies in a depression) and `s_j − z_j ≤ depth`, the chain of parents from `i` is
/// lowered to `z_j − ε, z_j − 2ε, …` until a parent already lies lower (carving,
/// Soille 2004): `j` then drains along its parents to the outlet, and only the cells on
/// that lowest path change. A cell more than `depth` below its spill level is kept as the
/// bottom of a real basin: it starts a new chain (`s_j = z_j`, no parent), so the basin's
/// own cells drain to it. The flood's order is that of the heights rounded to f32, then
/// of the cell index (any order leaves every cell a lower neighbour on its chain).
/// Returns which cells were lowered (none for a grid under 3 × 3, several channels or
/// no positive depth).
pub(super) fn breach(g: &mut Grid, depth: f64) -> Vec<bool> {
    let mut lowered = vec![false; g.data().len()];
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if g.c() != 1 || g.h() < 3 || g.w() < 3 || !(depth > 0.0) || g.data().len() > u32::MAX as usize
    {
        return lowered;
    }
    let (h, w) = (g.h(), g.w());
    let (lo, hi) = g.range();
    let eps = lo.abs().max(hi.abs()).max(hi - lo).max(1e-300) * 1e-6;
    let z = g.data_mut();
    let mut done = vec![false; h * w];
    let mut parent = vec![u32::MAX; h * w];
    let mut spill = vec![0.0f32; h * w];
    let mut heap = BinaryHeap::with_capacity(4 * (h + w));
    for i in 0..h * w {
        let (y, x) = (i / w, i % w);
        if y == 0 || x == 0 || y + 1 == h || x + 1 == w {
            done[i] = true;
            spill[i] = z[i] as f32;
            heap.push(key(z[i], i));
        }
    }
    while let Some(Reverse(k)) = heap.pop() {
        let i = (k & 0xFFFF_FFFF) as usize;
        for j in neighbours(i, h, w) {
            if done[j] {
                continue;
            }
            done[j] = true;
            spill[j] = (z[j] as f32).max(spill[i]);
            if z[j] <= z[i] && spill[j] as f64 - z[j] > depth {
                // a real basin's bottom: kept, and its cells drain to it
                spill[j] = z[j] as f32;
            } else {
                parent[j] = i as u32;
                if z[j] <= z[i] {
                    let mut prev = z[j];
                    let mut k = i;
                    while z[k] >= prev {
                        z[k] = prev - eps;
                        prev = z[k];
                        lowered[k] = true;
                        if parent[k] == u32::MAX {
                            break;
                        }
                        k = parent[k] as usize;
                    }
                }
            }
            heap.push(key(z[j], j));
        }
    }
    lowered
}

/// Widen the channels `taken` (the cells [`breach`] lowered) into valleys: ring `r`
/// (the cells not yet taken with a taken 8-neighbour) moves to
/// `max(m + a_r (z − m), z − cap)`, `m` the lowest taken neighbour, when `z > m`; all of
/// a ring from the heights before it. `cap` (the breaching depth in [`drain`]) bounds
/// how far a cell is lowered, as the carving is bounded: a steep wall beside a channel
/// is not cut down by half its height (on the tests' diamond-square example the
/// unbounded widening took the block means below 40 dB at every depth tried).
/// The cell keeps `m` as a lower neighbour, so no depression is made. Returns the number
/// of cells moved; `taken` gains them.
pub(super) fn widen(g: &mut Grid, taken: &mut [bool], gains: &[f64], cap: f64) -> usize {
    let (h, w) = (g.h(), g.w());
    let z = g.data_mut();
    let mut moved = 0;
    let mut next: Vec<(usize, f64)> = Vec::new();
    for &a in gains {
        next.clear();
        for i in 0..h * w {
            if taken[i] {
                continue;
            }
            let m = neighbours(i, h, w)
                .filter(|&j| taken[j])
                .fold(f64::INFINITY, |m, j| m.min(z[j]));
            if m < z[i] {
                next.push((i, (m + a * (z[i] - m)).max(z[i] - cap)));
            }
        }
        for &(i, v) in &next {
            z[i] = v;
            taken[i] = true;
        }
        moved += next.len();
    }
    moved
}

/// The indices of the (up to 8) neighbours of cell `i` of an `h × w` grid, in [`N8`]'s
/// order.
fn neighbours(i: usize, h: usize, w: usize) -> impl Iterator<Item = usize> {
    let (y, x) = ((i / w) as i64, (i % w) as i64);
    N8.iter().filter_map(move |&(dy, dx)| {
        let (yy, xx) = (y + dy, x + dx);
        (yy >= 0 && xx >= 0 && yy < h as i64 && xx < w as i64)
            .then(|| yy as usize * w + xx as usize)
    })
}

const N8: [(i64, i64); 8] = [
    (-1, -1),
    (-1, 0),
    (-1, 1),
    (0, -1),
    (0, 1),
    (1, -1),
    (1, 0),
    (1, 1),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// The number of cells off the border with no lower 8-neighbour.
    fn pits(g: &Grid) -> usize {
        let (h, w) = (g.h(), g.w());
        let mut n = 0;
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let z = g.at(y, x, 0);
                let lower = N8.iter().any(|&(dy, dx)| {
                    g.at((y as i64 + dy) as usize, (x as i64 + dx) as usize, 0) < z
                });
                n += usize::from(!lower);
            }
        }
        n
    }

    #[test]
    fn a_shallow_pit_is_breached_along_one_path_and_a_deep_one_kept() {
        // a ramp rising to the right, a 2-deep pit and a 14-deep one
        let mut g = Grid::new(9, 11, 1, (0..99).map(|i| 10.0 + (i % 11) as f64).collect()).unwrap();
        *g.at_mut(4, 3, 0) = 10.0; // 2 below its lowest neighbour (12)
        *g.at_mut(4, 8, 0) = 3.0; // 14 below (17)
        let before = g.clone();
        let mut lowered = breach(&mut g, 5.0);
        assert_eq!(pits(&before), 2);
        assert_eq!(pits(&g), 1);
        assert_eq!(g.at(4, 8, 0), 3.0);
        assert_eq!(g.at(4, 3, 0), 10.0);
        // the channel runs from the pit to the left border: 3 cells, none raised
        let n = lowered.iter().filter(|&&l| l).count();
        assert_eq!(n, 3, "{lowered:?}");
        assert!(g.data().iter().zip(before.data()).all(|(a, b)| a <= b));
        // widening moves the channel's neighbours towards it and makes no pit
        let moved = widen(&mut g, &mut lowered, &WIDEN, f64::INFINITY);
        assert!(moved > 0);
        assert_eq!(pits(&g), 1);
        assert!(g.data().iter().zip(before.data()).all(|(a, b)| a <= b));
    }
}
