//! Chaikin (quadratic B-spline) multiresolution with the width-4 local least-squares
//! filters of §9.5.1 / §9.6 and the interpolating boundary blocks of §9.6.1–9.6.2.
//!
//! Regular rows (0-based, `C_j` centred between `F_{2j-1}` and `F_{2j}`):
//! ```text
//! C_j = −¼F_{2j−2} + ¾F_{2j−1} + ¾F_{2j} − ¼F_{2j+1}          a = (−¼, ¾, ¾, −¼)
//! D_j =  ¼F_{2j}   − ¾F_{2j+1} + ¾F_{2j+2} − ¼F_{2j+3}        b = (¼, −¾, ¾, −¼)
//! F_{2i} = ¾C_i + ¼C_{i+1},  F_{2i+1} = ¼C_i + ¾C_{i+1}        p = (¼, ¾, ¾, ¼)
//! Q column j: F_{2j..2j+3} += (−¼, −¾, ¾, ¼)·D_j               q = (−¼, −¾, ¾, ¼)
//! ```

use super::regular::{LevelTriplets, RegularFilters, Taps};
use super::sparse::Triplets;

pub const A: [f64; 4] = [-0.25, 0.75, 0.75, -0.25];
pub const B: [f64; 4] = [0.25, -0.75, 0.75, -0.25];
pub const P: [f64; 4] = [0.25, 0.75, 0.75, 0.25];
pub const Q: [f64; 4] = [-0.25, -0.75, 0.75, 0.25];

/// The regular filters placed as in the comment above.
pub const REGULAR: RegularFilters = RegularFilters {
    a: Taps { w: &A, first: -2 },
    b: Taps { w: &B, first: 0 },
    p: Taps { w: &P, first: -2 },
    q: Taps { w: &Q, first: 0 },
};

/// Shortest lane the interpolating blocks apply to (§9.6.2: As, Ae, Bs, Be must not overlap).
pub const MIN_INTERPOLATING: usize = 8;

/// Interpolating (open, multiple-knot) ends, §9.6.1, for even `m ≥ 8`:
/// `n = m/2 + 1` coarse, `s = m/2 − 1` details; `C_0 = F_0`, `C_{n−1} = F_{m−1}`.
///
/// The rows are REDUCE-RESOLUTION, FIND-DETAILS and RECONSTRUCTION of §9.6.2 written
/// 0-based. Start/end blocks:
/// ```text
/// As: C_0 = F_0;   C_1 = −½F_0 + F_1 + ¾F_2 − ¼F_3
/// Ae: C_{n−2} = −¼F_{m−4} + ¾F_{m−3} + F_{m−2} − ½F_{m−1};   C_{n−1} = F_{m−1}
/// Bs: D_0 = −½F_0 + F_1 − ¾F_2 + ¼F_3;   D_1 = −¼F_2 + ¾F_3 − ¾F_4 + ¼F_5
/// Be: D_{s−1} = ¼F_{m−4} − ¾F_{m−3} + F_{m−2} − ½F_{m−1}
/// Ps: F_0 = C_0;  F_1 = ½C_0 + ½C_1          Pe: mirrored
/// Qs: E_0 = 0, E_1 = ½D_0, E_2 = −¾D_0 + ¼D_1, E_3 = −¼D_0 + ¾D_1,
///     E_4 = −¾D_1 − ¼D_2, E_5 = −¼D_1 − ¾D_2
/// Qe: E_{m−2} = ½D_{s−1}, E_{m−1} = 0
/// ```
pub fn interpolating(m: usize) -> LevelTriplets {
    assert!(m.is_multiple_of(2) && m >= MIN_INTERPOLATING);
    let n = m / 2 + 1;
    let s = m / 2 - 1;
    let mut an = Triplets::new(m, m);
    // REDUCE-RESOLUTION
    an.add(0, 0, 1.0);
    an.add_run(1, 0, &[-0.5, 1.0, 0.75, -0.25]);
    for j in 2..n - 2 {
        an.add_run(j, 2 * j - 2, &A);
    }
    an.add_run(n - 2, m - 4, &[-0.25, 0.75, 1.0, -0.5]);
    an.add(n - 1, m - 1, 1.0);
    // FIND-DETAILS (rows n..m)
    an.add_run(n, 0, &[-0.5, 1.0, -0.75, 0.25]);
    an.add_run(n + 1, 2, &[-0.25, 0.75, -0.75, 0.25]);
    for j in 2..s - 1 {
        an.add_run(n + j, 2 * j, &B);
    }
    an.add_run(n + s - 1, m - 4, &[0.25, -0.75, 1.0, -0.5]);

    // RECONSTRUCTION: F = P C + E, E = Q D (details at columns n..)
    let mut sy = Triplets::new(m, m);
    let d = |j: usize| n + j;
    // P
    sy.add(0, 0, 1.0);
    sy.add(1, 0, 0.5);
    sy.add(1, 1, 0.5);
    for i in 1..n - 2 {
        sy.add(2 * i, i, 0.75);
        sy.add(2 * i, i + 1, 0.25);
        sy.add(2 * i + 1, i, 0.25);
        sy.add(2 * i + 1, i + 1, 0.75);
    }
    sy.add(m - 2, n - 2, 0.5);
    sy.add(m - 2, n - 1, 0.5);
    sy.add(m - 1, n - 1, 1.0);
    // Qs
    sy.add(1, d(0), 0.5);
    sy.add(2, d(0), -0.75);
    sy.add(2, d(1), 0.25);
    sy.add(3, d(0), -0.25);
    sy.add(3, d(1), 0.75);
    sy.add(4, d(1), -0.75);
    sy.add(5, d(1), -0.25);
    if s > 2 {
        sy.add(4, d(2), -0.25);
        sy.add(5, d(2), -0.75);
    }
    // Qr: E_{2i+2} = ¾D_i − ¼D_{i+1}, E_{2i+3} = ¼D_i − ¾D_{i+1}, i = 2 .. s−2
    for i in 2..s.saturating_sub(1) {
        sy.add(2 * i + 2, d(i), 0.75);
        sy.add(2 * i + 2, d(i + 1), -0.25);
        sy.add(2 * i + 3, d(i), 0.25);
        sy.add(2 * i + 3, d(i + 1), -0.75);
    }
    // Qe
    sy.add(m - 2, d(s - 1), 0.5);
    LevelTriplets {
        n,
        analysis: an,
        synthesis: sy,
    }
}
