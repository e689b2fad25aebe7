//! Interpolating (open) ends for schemes whose boundary blocks were derived by
//! `tools/derive_open_ends.py`: the open B-spline subdivision `P` of §7.4 / §9.6 (multiple
//! knots, `C_0 = F_0`, `C_{n−1} = F_{m−1}`) with a regular analysis row `a`, and start blocks
//! for `A`, `B` and `Q`; the end blocks are their mirror images.
//!
//! Positions are lane positions counted in half-samples: coarse `C_j` is centred at fine
//! `c0/2 + 2j`, detail `D_k` at `e0/2 + 2k`, and a regular filter of `L` taps centred at `x`
//! covers the fine samples `x − (L−1)/2 … x + (L−1)/2`.
//!
//! ```text
//!  A: C_0 = F_0 | start rows (local least squares, §9.5.1) | regular a … | mirror | C_{n−1} = F_{m−1}
//!  B:             start rows (B P = 0, B Q = I)            | regular b = flip(p) … | mirror
//!  P:  open B-spline end rows                               | regular p …           | mirror
//!  Q:             start columns (in ker A)                  | regular q = flip(a) … | mirror
//! ```
//! `flip(w)_k = ±(−1)^k w_{1−k}` (§9.5: alternate the signs of the reversed filter).

use super::regular::LevelTriplets;
use super::sparse::Triplets;

/// The open B-spline subdivision of one degree: the interpolating lane layout.
#[derive(Debug)]
pub struct OpenSpline {
    /// Regular column of `P` (sums to 2).
    pub p: &'static [f64],
    /// Twice the fine position of `C_0`'s centre.
    pub c0: isize,
    /// Twice the fine position of `D_0`'s centre.
    pub e0: isize,
    /// `m = 2n − extra` fine samples for `n` coarse ones.
    pub extra: usize,
    /// The first rows of `P` as (coarse column, weight); the last rows are their mirror images.
    pub start_rows: &'static [&'static [(usize, f64)]],
}

/// Linear B-spline: `F_{2i} = C_i`, `F_{2i+1} = ½(C_i + C_{i+1})`, `m = 2n − 1`.
pub const LINEAR: OpenSpline = OpenSpline {
    p: &[0.5, 1.0, 0.5],
    c0: 0,
    e0: 2,
    extra: 1,
    start_rows: &[&[(0, 1.0)]],
};

/// Quadratic B-spline (Chaikin) with the end rows of §9.6.1, `m = 2n − 2`.
pub const QUADRATIC: OpenSpline = OpenSpline {
    p: &[0.25, 0.75, 0.75, 0.25],
    c0: -1,
    e0: 3,
    extra: 2,
    start_rows: &[&[(0, 1.0)], &[(0, 0.5), (1, 0.5)]],
};

/// Cubic B-spline with the open end rows of §7.4 (see `scheme::cubic`), `m = 2n − 3`.
pub const CUBIC: OpenSpline = OpenSpline {
    p: &[0.125, 0.5, 0.75, 0.5, 0.125],
    c0: -2,
    e0: 4,
    extra: 3,
    start_rows: &[
        &[(0, 1.0)],
        &[(0, 0.5), (1, 0.5)],
        &[(1, 0.75), (2, 0.25)],
        &[(1, 3.0 / 16.0), (2, 11.0 / 16.0), (3, 0.125)],
        &[(2, 0.5), (3, 0.5)],
    ],
};

/// A scheme's interpolating ends: its spline, regular rows, and derived start blocks.
#[derive(Debug)]
pub struct OpenEnds {
    pub spline: &'static OpenSpline,
    /// Regular analysis rows `a` (coarse) and `b` (details), regular detail column `q`.
    pub a: &'static [f64],
    pub b: &'static [f64],
    pub q: &'static [f64],
    /// `A` rows near the start: (row `j`, first fine column, taps).
    pub a_start: &'static [(usize, usize, &'static [f64])],
    /// `B` rows `0, 1, …` from fine sample 0.
    pub b_start: &'static [&'static [f64]],
    /// `Q` columns `0, 1, …` from fine sample 0.
    pub q_start: &'static [&'static [f64]],
    /// Shortest lane the blocks fit without overlapping (every longer lane of the spline's
    /// parity reconstructs; checked by the derivation and the tests).
    pub min_len: usize,
}

impl OpenEnds {
    /// Coarse length of a lane of `m` fine samples, if `m` has the spline's parity and fits.
    pub fn coarse_len(&self, m: usize) -> Option<usize> {
        let extra = self.spline.extra;
        (m >= self.min_len && (m + extra).is_multiple_of(2)).then_some((m + extra) / 2)
    }

    /// First fine index of a regular filter of `len` taps centred at `centre` half-samples.
    fn first(centre: isize, len: usize) -> isize {
        let lo = centre - (len as isize - 1);
        debug_assert!(lo % 2 == 0, "filter taps fall on samples");
        lo / 2
    }

    /// `[A; B]` and `[P | Q]` for a lane of `m` fine samples (`coarse_len(m)` must be `Some`).
    pub fn level(&self, m: usize) -> LevelTriplets {
        let n = self
            .coarse_len(m)
            .expect("a lane length native for the open ends");
        let s = m - n;
        let sp = self.spline;
        let mut an = Triplets::new(m, m);
        let mut sy = Triplets::new(m, m);
        let add_run = |t: &mut Triplets, r: usize, first: isize, w: &[f64]| {
            for (k, &x) in w.iter().enumerate() {
                let c = first + k as isize;
                assert!((0..m as isize).contains(&c), "regular row inside the lane");
                if x != 0.0 {
                    t.add(r, c as usize, x);
                }
            }
        };
        // A
        an.add(0, 0, 1.0);
        an.add(n - 1, m - 1, 1.0);
        let ka = self.a_start.iter().map(|r| r.0 + 1).max().unwrap_or(1);
        for &(j, f, w) in self.a_start {
            for (k, &x) in w.iter().enumerate() {
                an.add(j, f + k, x);
                an.add(n - 1 - j, m - 1 - f - k, x);
            }
        }
        for j in ka..n - ka {
            let c = sp.c0 + 4 * j as isize;
            add_run(&mut an, j, Self::first(c, self.a.len()), self.a);
        }
        // B
        let kb = self.b_start.len();
        for (k, w) in self.b_start.iter().enumerate() {
            for (i, &x) in w.iter().enumerate() {
                if x != 0.0 {
                    an.add(n + k, i, x);
                    an.add(n + s - 1 - k, m - 1 - i, x);
                }
            }
        }
        for k in kb..s - kb {
            let c = sp.e0 + 4 * k as isize;
            add_run(&mut an, n + k, Self::first(c, self.b.len()), self.b);
        }
        // P: regular columns away from the end rows, then the end rows
        let ends = sp.start_rows.len();
        for j in 0..n {
            let c = sp.c0 + 4 * j as isize;
            let first = Self::first(c, sp.p.len());
            for (k, &x) in sp.p.iter().enumerate() {
                let i = first + k as isize;
                if i >= ends as isize && i < (m - ends) as isize {
                    sy.add(i as usize, j, x);
                }
            }
        }
        for (i, row) in sp.start_rows.iter().enumerate() {
            for &(c, x) in row.iter() {
                sy.add(i, c, x);
                sy.add(m - 1 - i, n - 1 - c, x);
            }
        }
        // Q
        for (k, w) in self.q_start.iter().enumerate() {
            for (i, &x) in w.iter().enumerate() {
                if x != 0.0 {
                    sy.add(i, n + k, x);
                    sy.add(m - 1 - i, n + s - 1 - k, x);
                }
            }
        }
        for k in kb..s - kb {
            let c = sp.e0 + 4 * k as isize;
            let first = Self::first(c, self.q.len());
            for (t, &x) in self.q.iter().enumerate() {
                sy.add((first + t as isize) as usize, n + k, x);
            }
        }
        LevelTriplets {
            n,
            analysis: an,
            synthesis: sy,
        }
    }
}
