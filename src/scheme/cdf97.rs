//! CDF 9/7 (Cohen–Daubechies–Feauveau; JPEG 2000's irreversible pair, PyWavelets `bior4.4`):
//! the reference wavelet users compare with. Its synthesis is **not** a B-spline subdivision.
//!
//! ```text
//! a: 9 taps (sum 1)     C_j = Σ a_t F_{2j−4+t}
//! p: 7 taps (sum 2)     column j of P at rows 2j−3 … 2j+3
//! b = flip(p)           D_j = Σ b_t F_{2j−2+t}
//! q = flip(a)           column j of Q at rows 2j−3 … 2j+5
//! ```
//! Closed form: with `y = sin²(ω/2)` and the Daubechies polynomial
//! `P₄(y) = 1 + 4y + 10y² + 20y³` of real root `y_r ≈ −0.3423`,
//! `p(ω) = 2 cos⁴(ω/2) (1 − y/y_r)` and `a(ω) = cos⁴(ω/2) P₄(y) / (1 − y/y_r)`
//! (so `a p̄ + a_π p̄_π = 2`). The taps below are that product expanded in 30-digit arithmetic
//! (`tools/derive_open_ends.py`, `cdf97_taps`) and rounded; PyWavelets' `bior4.4` agrees to its
//! printed 12 digits (`tests/reference/pywt_filters.json`).
//!
//! Frequency facts: `A` has 4 zeros at π, `P` has 4; supports `a` 9, `b` 7, `p` 7, `q` 9;
//! `‖a‖·‖p‖ = 1.011` (nearly orthogonal).
//!
//! Interpolating ends: 9/7 has no subdivision with open ends, so the interpolating mode uses the
//! symmetric extension (whole-sample mirrors), and `C_0` is not `F_0`.

use super::regular::{RegularFilters, Taps};

pub const A: [f64; 9] = [
    0.02674875741081009,
    -0.016864118442874953,
    -0.07822326652899027,
    0.26686411844287494,
    0.6029490182363604,
    0.26686411844287494,
    -0.07822326652899027,
    -0.016864118442874953,
    0.02674875741081009,
];
pub const B: [f64; 7] = [
    0.09127176311425009,
    -0.05754352622850018,
    -0.5912717631142501,
    1.1150870524570005,
    -0.5912717631142501,
    -0.05754352622850018,
    0.09127176311425009,
];
pub const P: [f64; 7] = [
    -0.09127176311425009,
    -0.05754352622850018,
    0.5912717631142501,
    1.1150870524570005,
    0.5912717631142501,
    -0.05754352622850018,
    -0.09127176311425009,
];
pub const Q: [f64; 9] = [
    0.02674875741081009,
    0.016864118442874953,
    -0.07822326652899027,
    -0.26686411844287494,
    0.6029490182363604,
    -0.26686411844287494,
    -0.07822326652899027,
    0.016864118442874953,
    0.02674875741081009,
];

/// The regular filters placed as in the comment above.
pub const REGULAR: RegularFilters = RegularFilters {
    a: Taps { w: &A, first: -4 },
    b: Taps { w: &B, first: -2 },
    p: Taps { w: &P, first: -3 },
    q: Taps { w: &Q, first: -3 },
};
