//! Haar: averages and half-differences (§9.2, §9.4).
//!
//! ```text
//! C_j = ½(F_{2j} + F_{2j+1}),   D_j = ½(F_{2j} − F_{2j+1})
//! F_{2j} = C_j + D_j,           F_{2j+1} = C_j − D_j
//! ```
//! Every boundary mode is the same for Haar: its filters never leave the lane.

use super::regular::LevelTriplets;
use super::sparse::Triplets;

/// Even `m ≥ 2`: `n = s = m/2`.
pub fn level(m: usize) -> LevelTriplets {
    assert!(m.is_multiple_of(2) && m >= 2);
    let n = m / 2;
    let mut an = Triplets::new(m, m);
    let mut sy = Triplets::new(m, m);
    for j in 0..n {
        an.add_run(j, 2 * j, &[0.5, 0.5]);
        an.add_run(n + j, 2 * j, &[0.5, -0.5]);
        sy.add(2 * j, j, 1.0);
        sy.add(2 * j, n + j, 1.0);
        sy.add(2 * j + 1, j, 1.0);
        sy.add(2 * j + 1, n + j, -1.0);
    }
    LevelTriplets {
        n,
        analysis: an,
        synthesis: sy,
    }
}
