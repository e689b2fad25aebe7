//! Linear B-spline multiresolution with the CDF 5/3 analysis (Le Gall 5/3, JPEG 2000's
//! reversible filter pair, PyWavelets `bior2.2`).
//!
//! Regular rows (`C_j` at fine `2j`, `D_j` at `2j+1`):
//! ```text
//! a = (−⅛, ¼, ¾, ¼, −⅛)       C_j = Σ a_t F_{2j−2+t}
//! b = (−½, 1, −½)             D_j = F_{2j+1} − ½(F_{2j} + F_{2j+2})
//! p = (½, 1, ½)               F_{2j} = C_j + …, F_{2j+1} = ½(C_j + C_{j+1}) + …   (linear subdivision)
//! q = (−⅛, −¼, ¾, −¼, −⅛)     column j of Q at rows 2j−1 … 2j+3
//! ```
//! `b` and `q` are the alternating flips of `p` and `a` (§9.5), so `[A;B][P|Q] = I`.
//!
//! Frequency facts: `A` has 2 zeros at π (a line passes to the coarse level unaliased),
//! `P` has 2 (the linear B-spline); `B` annihilates lines. Supports: `a` 5, `b` 3, `p` 3, `q` 5.
//! The basis is close to orthogonal (`‖a‖·‖p‖ = 1.038`, 1 for an orthogonal pair), which is why it
//! keeps details almost as well as CDF 9/7 (`docs/filters.md`).
//!
//! Interpolating ends: `C_0 = F_0`, the open linear B-spline is regular up to its ends, so only
//! the first detail needs a start block (derived by `tools/derive_open_ends.py`).
//!
//! The same pair as integer lifting, exactly reversible for integer samples, is
//! [`lift_forward`] / [`lift_inverse`]:
//! ```text
//! D_j = F_{2j+1} − ⌊(F_{2j} + F_{2j+2}) / 2⌋
//! C_j = F_{2j} + ⌊(D_{j−1} + D_j + 2) / 4⌋
//! ```
//! with whole-sample mirrored ends (`F_{−1} = F_1`, `D_{−1} = D_0`, …).

use super::open_ends::{self, OpenEnds};
use super::regular::{RegularFilters, Taps};

pub const A: [f64; 5] = [-1.0 / 8.0, 1.0 / 4.0, 3.0 / 4.0, 1.0 / 4.0, -1.0 / 8.0];
pub const B: [f64; 3] = [-1.0 / 2.0, 1.0, -1.0 / 2.0];
pub const P: [f64; 3] = [1.0 / 2.0, 1.0, 1.0 / 2.0];
pub const Q: [f64; 5] = [-1.0 / 8.0, -1.0 / 4.0, 3.0 / 4.0, -1.0 / 4.0, -1.0 / 8.0];

regular_and_open!([-2, 0, -1, -1], LINEAR, "linear");

// Start blocks derived by `tools/derive_open_ends.py` (printed by `python3 tools/derive_open_ends.py
// rust`); the end blocks are their mirror images.
pub const MIN_INTERPOLATING: usize = 5;
pub const A_START: &[(usize, usize, &[f64])] = &[];
pub const B_START: &[&[f64]] = &[&[-0.574468085106383, 1.148936170212766, -0.574468085106383]];
pub const Q_START: &[&[f64]] = &[&[
    0.0,
    0.7615740740740741,
    -0.2175925925925926,
    -0.1087962962962963,
]];

/// Reversible integer 5/3 lifting of a lane (`x.len() ≥ 1`), in place, packed as
/// `[C_0 … C_{n−1}, D_0 … D_{s−1}]` with `n = ⌈m/2⌉` (the layout of the symmetric level):
/// `D_j = x_{2j+1} − ⌊(x_{2j} + x_{2j+2})/2⌋`, `C_j = x_{2j} + ⌊(D_{j−1} + D_j + 2)/4⌋`
/// (whole-sample mirror at the ends). The floors are exact (sums in 128 bits) and the
/// final additions wrap, so every 64-bit lane inverts exactly.
/// `scratch` must hold `x.len()` values.
pub fn lift_forward(x: &mut [i64], scratch: &mut [i64]) {
    let m = x.len();
    if m < 2 {
        return;
    }
    let n = m.div_ceil(2);
    let s = m / 2;
    let f = |i: isize| -> i64 {
        // whole-sample mirror
        let mut i = i;
        let last = m as isize - 1;
        if i < 0 {
            i = -i;
        }
        if i > last {
            i = 2 * last - i;
        }
        x[i as usize]
    };
    let (c, d) = scratch[..m].split_at_mut(n);
    for (j, dj) in d.iter_mut().enumerate().take(s) {
        let j = j as isize;
        *dj = f(2 * j + 1).wrapping_sub(half(f(2 * j), f(2 * j + 2)));
    }
    for (j, cj) in c.iter_mut().enumerate() {
        let dl = if j == 0 { d[0] } else { d[j - 1] };
        let dr = if j < s { d[j] } else { d[s - 1] };
        *cj = x[2 * j].wrapping_add(quarter(dl, dr));
    }
    x.copy_from_slice(&scratch[..m]);
}

/// `⌊(a + b)/2⌋` without overflow (wrapped back to 64 bits).
#[inline(always)]
fn half(a: i64, b: i64) -> i64 {
    (a as i128 + b as i128).div_euclid(2) as i64
}

/// `⌊(a + b + 2)/4⌋` without overflow (wrapped back to 64 bits).
#[inline(always)]
fn quarter(a: i64, b: i64) -> i64 {
    (a as i128 + b as i128 + 2).div_euclid(4) as i64
}

/// Inverse of [`lift_forward`]: the exact integer samples back.
pub fn lift_inverse(x: &mut [i64], scratch: &mut [i64]) {
    let m = x.len();
    if m < 2 {
        return;
    }
    let n = m.div_ceil(2);
    let s = m / 2;
    let (c, d) = x.split_at(n);
    let out = &mut scratch[..m];
    for j in 0..n {
        let dl = if j == 0 { d[0] } else { d[j - 1] };
        let dr = if j < s { d[j] } else { d[s - 1] };
        out[2 * j] = c[j].wrapping_sub(quarter(dl, dr));
    }
    for j in 0..s {
        let right = if 2 * j + 2 < m {
            out[2 * j + 2]
        } else {
            out[2 * j]
        };
        out[2 * j + 1] = d[j].wrapping_add(half(out[2 * j], right));
    }
    x.copy_from_slice(out);
}
