//! Regular (interior) filter rows and the two boundary modes that need nothing but
//! them: `periodic` (indices wrap around) and `symmetric` (the signal is mirrored at
//! its ends, §9.6.1 first paragraph).
//!
//! Positions are counted in half-samples so both mirror kinds are integers: fine
//! sample `k` sits at `2k`; coarse sample `j` of a row whose taps start at fine index
//! `2j + f` and has `L` taps is centred at `4j + 2f + L − 1`.
//!
//! ```text
//! half-sample mirror (even-length filters, Chaikin):  … F1 F0 | F0 F1 F2 …   mirror at −½
//! whole-sample mirror (odd-length filters, cubic):    … F2 F1 | F0 F1 F2 …   mirror at 0
//! ```

use super::sparse::Triplets;

/// One regular filter: taps `w[t]` at offset `2j + first + t`.
#[derive(Clone, Copy, Debug)]
pub struct Taps {
    pub w: &'static [f64],
    pub first: isize,
}

impl Taps {
    /// Centre of row/column `j` in half-samples.
    fn centre(&self, j: isize) -> isize {
        4 * j + 2 * self.first + self.w.len() as isize - 1
    }
    fn is_antisymmetric(&self) -> bool {
        let n = self.w.len();
        (0..n).all(|t| self.w[t] == -self.w[n - 1 - t]) && self.w.iter().any(|&x| x != 0.0)
    }
}

/// The four regular filters of a scheme: rows of A and B (analysis), columns of P and
/// Q (synthesis).
#[derive(Clone, Copy, Debug)]
pub struct RegularFilters {
    pub a: Taps,
    pub b: Taps,
    pub p: Taps,
    pub q: Taps,
}

/// A level ready to be compressed: `n` coarse samples, analysis `[A; B]` and
/// synthesis `[P | Q]` (details at columns/rows `n..m`).
pub struct LevelTriplets {
    pub n: usize,
    pub analysis: Triplets,
    pub synthesis: Triplets,
}

/// Periodic extension: `F_{k+m} = F_k`; needs even `m` (`n = s = m/2`).
pub fn periodic(f: &RegularFilters, m: usize) -> LevelTriplets {
    debug_assert!(m.is_multiple_of(2) && m >= 2);
    let n = m / 2;
    let s = m / 2;
    let (mi, ni, si) = (m as isize, n as isize, s as isize);
    let mut an = Triplets::new(m, m);
    let mut sy = Triplets::new(m, m);
    for j in 0..ni {
        for (t, &w) in f.a.w.iter().enumerate() {
            an.add(
                j as usize,
                (2 * j + f.a.first + t as isize).rem_euclid(mi) as usize,
                w,
            );
        }
    }
    for j in 0..si {
        for (t, &w) in f.b.w.iter().enumerate() {
            an.add(
                n + j as usize,
                (2 * j + f.b.first + t as isize).rem_euclid(mi) as usize,
                w,
            );
        }
    }
    for j in 0..ni {
        for (t, &w) in f.p.w.iter().enumerate() {
            sy.add(
                (2 * j + f.p.first + t as isize).rem_euclid(mi) as usize,
                j as usize,
                w,
            );
        }
    }
    for j in 0..si {
        for (t, &w) in f.q.w.iter().enumerate() {
            sy.add(
                (2 * j + f.q.first + t as isize).rem_euclid(mi) as usize,
                n + j as usize,
                w,
            );
        }
    }
    LevelTriplets {
        n,
        analysis: an,
        synthesis: sy,
    }
}

/// The mirror points (half-samples) of a lane of `m` fine samples.
#[derive(Clone, Copy)]
struct Mirror {
    lo: isize,
    hi: isize,
}

impl Mirror {
    /// Fold a position into `[lo, hi]`, counting reflections.
    fn fold(&self, mut x: isize) -> (isize, u32) {
        let mut flips = 0;
        loop {
            if x < self.lo {
                x = 2 * self.lo - x;
            } else if x > self.hi {
                x = 2 * self.hi - x;
            } else {
                return (x, flips);
            }
            flips += 1;
        }
    }
    /// Number of samples `j ≥ 0` of a filter centred at `c(j)` that lie in the lane,
    /// leaving out antisymmetric ones sitting on a mirror point (they are zero).
    fn count(&self, t: &Taps) -> usize {
        let anti = t.is_antisymmetric();
        let mut j = self.first(t);
        let mut n = 0;
        while t.centre(j) <= self.hi {
            let c = t.centre(j);
            if c >= self.lo && !(anti && (c == self.lo || c == self.hi)) {
                n += 1;
            }
            j += 1;
        }
        n
    }
    /// The filter index of the first sample inside the lane (lane index 0).
    fn first(&self, t: &Taps) -> isize {
        let anti = t.is_antisymmetric();
        (-8..)
            .find(|&k| {
                let c = t.centre(k);
                c >= self.lo && !(anti && c == self.lo)
            })
            .unwrap()
    }
    /// Map an extended coarse/detail index to `(index in lane, sign)`, or `None` for an
    /// antisymmetric sample that the mirror forces to zero.
    fn fold_index(&self, t: &Taps, j: isize) -> Option<(usize, f64)> {
        let anti = t.is_antisymmetric();
        let (x, flips) = self.fold(t.centre(j));
        if anti && (x == self.lo || x == self.hi) {
            return None;
        }
        let off = x - (2 * t.first + t.w.len() as isize - 1);
        debug_assert!(off % 4 == 0, "mirror maps sample centres onto centres");
        let jj = off / 4;
        let first = self.first(t);
        let sign = if anti && flips % 2 == 1 { -1.0 } else { 1.0 };
        Some(((jj - first) as usize, sign))
    }
}

/// Symmetric extension: half-sample mirrors (`whole == false`) at −½ and m−½, or
/// whole-sample mirrors at 0 and m−1. Works for every length `m ≥ 2` when the filters
/// are (anti)symmetric about their centres; the counts `n`, `s` follow from which
/// centres fall inside the lane.
pub fn symmetric(f: &RegularFilters, m: usize, whole: bool) -> LevelTriplets {
    let mi = m as isize;
    let mir = if whole {
        Mirror {
            lo: 0,
            hi: 2 * mi - 2,
        }
    } else {
        Mirror {
            lo: -1,
            hi: 2 * mi - 1,
        }
    };
    let n = mir.count(&f.a);
    let s = mir.count(&f.b);
    assert_eq!(n + s, m, "symmetric extension is critically sampled");
    let fine = |k: isize| -> usize { (mir.fold(2 * k).0 / 2) as usize };
    let mut an = Triplets::new(m, m);
    let mut sy = Triplets::new(m, m);
    // analysis rows: C_j = Σ a_t F_{2j+f+t} with F folded
    for (row0, taps, count) in [(0usize, &f.a, n), (n, &f.b, s)] {
        let first = mir.first(taps);
        for j in 0..count as isize {
            let jj = j + first;
            for (t, &w) in taps.w.iter().enumerate() {
                an.add(row0 + j as usize, fine(2 * jj + taps.first + t as isize), w);
            }
        }
    }
    // synthesis: F_i = Σ_j p_{i,j} C_j over the extended C, folded back with signs
    let reach = 4 + (f.p.w.len().max(f.q.w.len()) as isize);
    for (col0, taps) in [(0usize, &f.p), (n, &f.q)] {
        let cnt = if col0 == 0 { n } else { s } as isize;
        let first = mir.first(taps);
        for j in first - reach..first + cnt + reach {
            let Some((jj, sign)) = mir.fold_index(taps, j) else {
                continue;
            };
            for (t, &w) in taps.w.iter().enumerate() {
                let i = 2 * j + taps.first + t as isize;
                if (0..mi).contains(&i) {
                    sy.add(i as usize, col0 + jj, sign * w);
                }
            }
        }
    }
    LevelTriplets {
        n,
        analysis: an,
        synthesis: sy,
    }
}
