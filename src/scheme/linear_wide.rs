//! Linear B-spline subdivision with a **window-9 local least-squares** analysis made exact at
//! Nyquist, which is CDF's 9/3 pair (PyWavelets `bior2.4`).
//!
//! The least-squares fit of the linear B-spline to the nine fine points `F_{2j−4} … F_{2j+4}`
//! (§9.5.1) moved to the nearest row that still gives `A P = I` and has four zeros at π is
//! ```text
//! a = (3, −6, −16, 38, 90, 38, −16, −6, 3) / 128     C_j = Σ a_t F_{2j−4+t}
//! b = (−½, 1, −½)                                    D_j = F_{2j+1} − ½(F_{2j} + F_{2j+2})
//! p = (½, 1, ½)                                      (linear subdivision, as `scheme::linear`)
//! q = flip(a)                                        column j of Q at rows 2j−3 … 2j+5
//! ```
//! — the dual of order 4 of Cohen–Daubechies–Feauveau for the linear B-spline: both
//! constructions give the same row. Dyadic, so exact in any float type.
//!
//! Frequency facts: `A` has 4 zeros at π, `P` has 2; supports `a` 9, `b` 3, `p` 3, `q` 9;
//! `‖a‖·‖p‖ = 1.030` (5/3: 1.038).
//!
//! Why this analysis: of the analyses tried for the linear `P` (5/3; windows 9 and 13 with 0, 2
//! or 4 zeros at π; bior2.6, bior2.8), every window-9 and window-13 row keeps details within
//! 0.01 dB of this one and 0.03–0.09 dB better than 5/3; this one is the shortest, dyadic and a
//! classical filter. The 5/3 pair stays as `linear` for its reversible integer lifting.
//!
//! Interpolating ends: `C_0 = F_0` with start blocks derived by `tools/derive_open_ends.py`.

use super::open_ends::{self, OpenEnds};
use super::regular::{RegularFilters, Taps};

pub const A: [f64; 9] = [
    3.0 / 128.0,
    -6.0 / 128.0,
    -16.0 / 128.0,
    38.0 / 128.0,
    90.0 / 128.0,
    38.0 / 128.0,
    -16.0 / 128.0,
    -6.0 / 128.0,
    3.0 / 128.0,
];
pub const B: [f64; 3] = [-1.0 / 2.0, 1.0, -1.0 / 2.0];
pub const P: [f64; 3] = [1.0 / 2.0, 1.0, 1.0 / 2.0];
pub const Q: [f64; 9] = [
    3.0 / 128.0,
    6.0 / 128.0,
    -16.0 / 128.0,
    -38.0 / 128.0,
    90.0 / 128.0,
    -38.0 / 128.0,
    -16.0 / 128.0,
    6.0 / 128.0,
    3.0 / 128.0,
];

/// The regular filters placed as in the comment above.
pub const REGULAR: RegularFilters = RegularFilters {
    a: Taps { w: &A, first: -4 },
    b: Taps { w: &B, first: 0 },
    p: Taps { w: &P, first: -1 },
    q: Taps { w: &Q, first: -3 },
};

/// Interpolating ends: the open linear B-spline `P` with derived start blocks.
pub const OPEN: OpenEnds = OpenEnds {
    spline: &open_ends::LINEAR,
    a: &A,
    b: &B,
    q: &Q,
    a_start: A_START,
    b_start: B_START,
    q_start: Q_START,
    min_len: MIN_INTERPOLATING,
};

// Start blocks derived by `tools/derive_open_ends.py` (printed by `python3 tools/derive_open_ends.py
// rust`); the end blocks are their mirror images.
pub const MIN_INTERPOLATING: usize = 17;
pub const A_START: &[(usize, usize, &[f64])] = &[(
    1,
    0,
    &[
        -0.1421362489486964,
        0.2842724978973928,
        0.7106812447434819,
        0.2943650126156434,
        -0.12195121951219512,
        -0.050462573591253154,
        0.021026072329688814,
        0.008410428931875526,
        -0.004205214465937763,
    ],
)];
pub const B_START: &[&[f64]] = &[
    &[
        -0.5910513172066766,
        1.1821026344133536,
        -0.5769463609949697,
        -0.028209912423412385,
        0.013888445156964444,
        0.0004330221094830365,
        0.00029106064868154624,
        -0.0010151434068464626,
        0.0005075717034234736,
    ],
    &[
        1.0914764550532194e-05,
        -2.182952910151204e-05,
        -0.4999864194464253,
        0.9999946684219527,
        -0.4999938348811531,
        -6.998659647218438e-06,
        -4.704227271714486e-06,
        1.6407114190827527e-05,
        -8.203557095626445e-06,
    ],
    &[
        6.748428941936774e-06,
        -1.3496857884026696e-05,
        1.0059140501381125e-05,
        -6.6214231185160904e-06,
        -0.49999320025921234,
        0.9999930219415428,
        -0.5000046903799522,
        1.635881836128997e-05,
        -8.179409180368535e-06,
    ],
    &[
        -1.287788085015131e-05,
        2.5755761700301272e-05,
        -8.75097716101711e-06,
        -8.253807378403305e-06,
        5.796019123985413e-06,
        -3.3382308702726544e-06,
        -0.5000022438291737,
        1.0000078258892182,
        -0.5000039129446093,
    ],
];
pub const Q_START: &[&[f64]] = &[
    &[
        0.0,
        0.725708060891511,
        -0.2404851815136631,
        -0.10040210189391367,
        0.039644043245406414,
        0.019835411906626122,
        3.94409964482113e-06,
        -1.6313959655581476e-05,
        7.003465731667192e-06,
        2.991082654742681e-06,
        -1.0213004223657638e-06,
        -5.106502111432252e-07,
    ],
    &[
        0.0,
        -0.1267108846670666,
        -0.3011504207190026,
        0.7015507418965289,
        -0.29575980044694056,
        -0.12443748418991249,
        0.046870945109582125,
        0.023442140527700175,
        -1.94240456829466e-06,
        -7.921591156351316e-07,
        3.580863371865708e-07,
        1.790431685811073e-07,
    ],
    &[
        0.0,
        0.024916314648335665,
        0.05056492531061254,
        -0.1231586225382448,
        -0.2968961517830146,
        0.7031200291052033,
        -0.2968777363201643,
        -0.1249983539372544,
        0.04687433301351643,
        0.02343724496885353,
        1.569241907214291e-07,
        7.846209538856721e-08,
    ],
    &[
        0.0,
        -0.0034668182232046197,
        -0.008650374354549344,
        0.01912071767207586,
        0.04692458659754326,
        -0.12498834662025642,
        -0.29686858518349807,
        0.7031211410983255,
        -0.2968734363686834,
        -0.12499940212478514,
        0.04687463211911324,
        0.023437316059556634,
    ],
];
