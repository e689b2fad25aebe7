//! Cubic B-spline multiresolution with the width-7 local filters of §9.5.1.
//!
//! Regular rows (periodic/symmetric placement, `C_j` at fine `2j`, `D_j` at `2j+1`):
//! ```text
//! a = (⅛, −½, ⅜, 1, ⅜, −½, ⅛)   C_j = Σ a_t F_{2j−3+t}
//! b = (−⅛, ½, −¾, ½, −⅛)         D_j = Σ b_t F_{2j−1+t}
//! p = (⅛, ½, ¾, ½, ⅛)            column j of P at rows 2j−2 … 2j+2
//! q = (⅛, ½, ⅜, −1, ⅜, ½, ⅛)     column j of Q at rows 2j−2 … 2j+4
//! ```
//! The notes print a different q, which does not give `[A;B][P|Q] = I`; this q is the
//! regular column of `[A;B]⁻¹` (checked by the tests).
//!
//! ## Interpolating ends (derivation)
//! `P` is the open cubic subdivision of §7.4 on `n` coarse points, `m = 2n − 3` fine:
//! `F_0 = C_0, F_1 = ½(C_0+C_1), F_2 = ¾C_1 + ¼C_2, F_3 = 3⁄16 C_1 + 11⁄16 C_2 + ⅛C_3,
//! F_4 = ½(C_2+C_3)`, regular vertex/edge rules `F_{2j−1} = ⅛C_{j−1} + ¾C_j + ⅛C_{j+1}`,
//! `F_{2j} = ½(C_j + C_{j+1})` inside, and the mirror image at the end. Vertex points sit
//! at odd fine indices, details at the even ones `2, 4, …, m−3` (`s = n − 3`).
//! The boundary blocks are derived, in exact rational arithmetic, by
//! `tools/derive_cubic_boundary.py`:
//! 1. `A`: row 0 is `C_0 = F_0` (interpolation); rows 1 and 2 are the local least-squares
//!    rows of §9.5.1 over the window `F_0 … F_6` (`(P_WᵀP_W)⁻¹P_Wᵀ`), so `A P = I`;
//!    rows from 3 on are regular (`a` over `F_{2j−4} … F_{2j+2}`).
//! 2. `Q`: columns 0 and 1 are the shortest vectors (column 1: closest to the regular
//!    `q`) in the null space of `A` that the regular rows of `B` annihilate, normalised to
//!    −1 at their detail's own position; further columns are regular.
//! 3. `B`: rows 0 and 1 are the shortest rows with `B P = 0` and `B Q = I`.
//!
//! The end blocks are the mirror images. `[A;B][P|Q] = I` exactly (rationally) and is
//! checked in f64 by the tests.

use super::regular::{LevelTriplets, RegularFilters, Taps};
use super::sparse::Triplets;

pub const A: [f64; 7] = [0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125];
pub const B: [f64; 5] = [-0.125, 0.5, -0.75, 0.5, -0.125];
pub const P: [f64; 5] = [0.125, 0.5, 0.75, 0.5, 0.125];
pub const Q: [f64; 7] = [0.125, 0.5, 0.375, -1.0, 0.375, 0.5, 0.125];

pub const REGULAR: RegularFilters = RegularFilters {
    a: Taps { w: &A, first: -3 },
    b: Taps { w: &B, first: -1 },
    p: Taps { w: &P, first: -2 },
    q: Taps { w: &Q, first: -2 },
};

/// Shortest (odd) lane the interpolating blocks apply to without overlapping.
pub const MIN_INTERPOLATING: usize = 13;

/// Open cubic subdivision rows `F_0 … F_4` (coarse column, weight).
const PS: [&[(usize, f64)]; 5] = [
    &[(0, 1.0)],
    &[(0, 0.5), (1, 0.5)],
    &[(1, 0.75), (2, 0.25)],
    &[(1, 3.0 / 16.0), (2, 11.0 / 16.0), (3, 0.125)],
    &[(2, 0.5), (3, 0.5)],
];

/// `A` rows 1 and 2 over `F_0 … F_6`.
const AS: [[f64; 7]; 2] = [
    [
        -5899.0 / 18499.0,
        11798.0 / 18499.0,
        17970.0 / 18499.0,
        -360.0 / 1423.0,
        -3480.0 / 18499.0,
        3720.0 / 18499.0,
        -930.0 / 18499.0,
    ],
    [
        3321.0 / 18499.0,
        -6642.0 / 18499.0,
        -1474.0 / 18499.0,
        1816.0 / 1423.0,
        8068.0 / 18499.0,
        -11176.0 / 18499.0,
        2794.0 / 18499.0,
    ],
];

/// `B` rows 0 and 1 over `F_0 … F_6`.
const BS: [[f64; 7]; 2] = [
    [
        -3594.0 / 18499.0,
        7188.0 / 18499.0,
        -14795750768465.0 / 50825692678748.0,
        125370078837.0 / 977417166899.0,
        -775076904773.0 / 25412846339374.0,
        -15931443067.0 / 12706423169687.0,
        15931443067.0 / 50825692678748.0,
    ],
    [
        0.0,
        0.0,
        -614543773.0 / 5494966504.0,
        614543773.0 / 1373741626.0,
        -1843631319.0 / 2747483252.0,
        614543773.0 / 1373741626.0,
        -614543773.0 / 5494966504.0,
    ],
];

/// `Q` columns 0 and 1 over rows `F_0 … F_7`.
const QS: [[f64; 8]; 2] = [
    [
        0.0,
        1050.0 / 599.0,
        -1.0,
        3139.0 / 9584.0,
        1107.0 / 2396.0,
        1107.0 / 9584.0,
        0.0,
        0.0,
    ],
    [
        0.0,
        -135104940.0 / 614543773.0,
        -1425370.0 / 614543773.0,
        1047080643.0 / 2458175092.0,
        -1.0,
        2205266519.0 / 4916350184.0,
        686870813.0 / 1229087546.0,
        686870813.0 / 4916350184.0,
    ],
];

/// Interpolating ends for odd `m ≥ 13`: `n = (m+3)/2` coarse, `s = (m−3)/2` details.
pub fn interpolating(m: usize) -> LevelTriplets {
    assert!(m % 2 == 1 && m >= MIN_INTERPOLATING);
    let n = (m + 3) / 2;
    let s = (m - 3) / 2;
    let mut an = Triplets::new(m, m);
    let mut sy = Triplets::new(m, m);
    // A
    an.add(0, 0, 1.0);
    an.add(n - 1, m - 1, 1.0);
    for (r, row) in AS.iter().enumerate() {
        for (k, &w) in row.iter().enumerate() {
            an.add(1 + r, k, w);
            an.add(n - 2 - r, m - 1 - k, w);
        }
    }
    for j in 3..n - 3 {
        an.add_run(j, 2 * j - 4, &A);
    }
    // B
    for (r, row) in BS.iter().enumerate() {
        for (k, &w) in row.iter().enumerate() {
            an.add(n + r, k, w);
            an.add(n + s - 1 - r, m - 1 - k, w);
        }
    }
    for i in 2..s - 2 {
        an.add_run(n + i, 2 * i, &B);
    }
    // P
    for (i, row) in PS.iter().enumerate() {
        for &(c, w) in row.iter() {
            sy.add(i, c, w);
            sy.add(m - 1 - i, n - 1 - c, w);
        }
    }
    for i in 5..m - 5 {
        let j = i / 2;
        if i % 2 == 1 {
            // vertex point of C_{(i+1)/2}
            let v = i.div_ceil(2);
            sy.add(i, v - 1, 0.125);
            sy.add(i, v, 0.75);
            sy.add(i, v + 1, 0.125);
        } else {
            sy.add(i, j, 0.5);
            sy.add(i, j + 1, 0.5);
        }
    }
    // Q
    for (c, col) in QS.iter().enumerate() {
        for (k, &w) in col.iter().enumerate() {
            sy.add(k, n + c, w);
            sy.add(m - 1 - k, n + s - 1 - c, w);
        }
    }
    for i in 2..s - 2 {
        for (t, &w) in Q.iter().enumerate() {
            sy.add(2 * i - 1 + t, n + i, w);
        }
    }
    LevelTriplets {
        n,
        analysis: an,
        synthesis: sy,
    }
}
