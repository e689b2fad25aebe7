//! The table of tap patterns that have a vector build of the pair kernels.

/// The tap patterns `(inputs, m1, m2, …)` with vector builds (AVX2 and AVX-512): the
/// regular rows of every scheme of `Scheme::ALL`, analysis (coarse, detail) and synthesis
/// (even, odd fine rows), as [`super::polyphase`] pairs them along a lane ("lanes") and as
/// the fused levels and the cascade pair consecutive rows along axis 0 ("rows"). A pair
/// without an entry goes one output at a time (the same bits, about half the speed); the
/// test `every_schemes_regular_pairs_have_a_build` lists the pairs that must have one.
#[cfg(target_arch = "x86_64")]
macro_rules! pair_patterns {
    ($m:ident) => {
        $m!(
            // (U, M1, M2, P1, N1, P2, N2, R1, R2): inputs, the masks of the two outputs,
            // the terms of weight +1 and −1 of each (added or subtracted, not
            // multiplied), and the pairs of each ([`super::pair_code`], see `pattern_of`);
            // first the plain patterns (no pairs), which serve rows of distinct weights
            (2, 0b11, 0b11, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            (4, 0b1111, 0b1111, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            (6, 0b001111, 0b111100, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            (7, 0b0111011, 0b1111111, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            (7, 0b1111111, 0b1111100, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            (7, 0b1111111, 0b0011111, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            // haar: lanes analysis, rows analysis
            (2, 0b11, 0b11, 0, 0, 0, 0, pair_code(&[(0, 1)]), pair_code(&[])),
            // haar: lanes synthesis, rows synthesis
            (2, 0b11, 0b11, 0b1, 0, 0b1, 0b10, pair_code(&[(0, 1)]), pair_code(&[])),
            // chaikin: lanes synthesis, rows synthesis
            (4, 0b1111, 0b1111, 0, 0, 0, 0, pair_code(&[(0, 2)]), pair_code(&[(0, 2)])),
            // chaikin: lanes analysis, rows analysis (periodic)
            (4, 0b1111, 0b1111, 0, 0, 0, 0, pair_code(&[(0, 3), (1, 2)]), pair_code(&[])),
            // chaikin: rows analysis (interpolating, symmetric)
            (6, 0b1111, 0b111100, 0, 0, 0, 0, pair_code(&[]), pair_code(&[(2, 5), (3, 4)])),
            // cubic: lanes synthesis (interpolating), rows synthesis (interpolating)
            (7, 0b111011, 0b1111111, 0, 0b10000, 0, 0, pair_code(&[(0, 1), (3, 5)]), pair_code(&[(0, 2), (3, 6), (4, 5)])),
            // cubic: lanes synthesis (periodic, symmetric), rows synthesis (periodic, symmetric)
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0b100000, pair_code(&[(0, 2), (3, 6), (4, 5)]), pair_code(&[(1, 2), (4, 6)])),
            // cubic: lanes analysis (periodic, symmetric), rows analysis (interpolating)
            (7, 0b1111111, 0b11111, 0b1000, 0, 0, 0, pair_code(&[(0, 6), (1, 5), (2, 4)]), pair_code(&[(0, 4), (1, 3)])),
            // cubic: lanes analysis (interpolating)
            (7, 0b1111111, 0b1111100, 0b1000, 0, 0, 0, pair_code(&[(0, 6), (1, 5), (2, 4)]), pair_code(&[(2, 6), (3, 5)])),
            // cubic: rows analysis (periodic, symmetric)
            (9, 0b11111, 0b111111100, 0, 0, 0b100000, 0, pair_code(&[(0, 4), (1, 3)]), pair_code(&[(2, 8), (3, 7), (4, 6)])),
            // linear: lanes synthesis, rows synthesis
            (5, 0b1101, 0b11111, 0b1, 0, 0, 0, pair_code(&[(2, 3)]), pair_code(&[(0, 1), (2, 4)])),
            // linear: lanes analysis (periodic, symmetric), rows analysis (periodic)
            (5, 0b11111, 0b111, 0, 0, 0b10, 0, pair_code(&[(0, 4), (1, 3)]), pair_code(&[(0, 2)])),
            // linear: lanes analysis (interpolating)
            (5, 0b11111, 0b11100, 0, 0, 0b1000, 0, pair_code(&[(0, 4), (1, 3)]), pair_code(&[(2, 4)])),
            // linear: rows analysis (interpolating, symmetric)
            (7, 0b111, 0b1111100, 0b10, 0, 0, 0, pair_code(&[(0, 2)]), pair_code(&[(2, 6), (3, 5)])),
            // linear-wide: lanes synthesis, rows synthesis
            (7, 0b111101, 0b1111111, 0b1, 0, 0, 0, pair_code(&[(2, 5), (3, 4)]), pair_code(&[(0, 1), (2, 6), (3, 5)])),
            // linear-wide: lanes analysis (periodic, symmetric), rows analysis
            (9, 0b111111111, 0b111, 0, 0, 0b10, 0, pair_code(&[(0, 8), (1, 7), (2, 6), (3, 5)]), pair_code(&[(0, 2)])),
            // linear-wide: lanes analysis (interpolating)
            (9, 0b111111111, 0b111000000, 0, 0, 0b10000000, 0, pair_code(&[(0, 8), (1, 7), (2, 6), (3, 5)]), pair_code(&[(6, 8)])),
            // chaikin-wide: lanes analysis (periodic, symmetric), rows analysis (periodic)
            (12, 0b111111111111, 0b1111, 0, 0, 0, 0, pair_code(&[(0, 11), (1, 10), (2, 9), (3, 8), (4, 7), (5, 6)]), pair_code(&[])),
            // chaikin-wide: lanes analysis (interpolating)
            (12, 0b111111111111, 0b111100000000, 0, 0, 0, 0, pair_code(&[(0, 11), (1, 10), (2, 9), (3, 8), (4, 7), (5, 6)]), pair_code(&[])),
            // chaikin-wide: rows analysis (interpolating, symmetric)
            (14, 0b1111, 0b11111111111100, 0, 0, 0, 0, pair_code(&[]), pair_code(&[(2, 13), (3, 12), (4, 11), (5, 10), (6, 9), (7, 8)])),
            // chaikin-wide: lanes synthesis, rows synthesis
            (8, 0b11111111, 0b11111111, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            // cubic-wide: lanes synthesis (interpolating), rows synthesis (interpolating)
            (13, 0b111111111011, 0b1111111111111, 0, 0, 0, 0, pair_code(&[(0, 1), (3, 11), (4, 10), (5, 9), (6, 8)]), pair_code(&[(0, 2), (3, 12), (4, 11), (5, 10), (6, 9), (7, 8)])),
            // cubic-wide: lanes synthesis (periodic, symmetric), rows synthesis (periodic, symmetric)
            (13, 0b1111111111111, 0b1111111110110, 0, 0, 0, 0, pair_code(&[(0, 2), (3, 12), (4, 11), (5, 10), (6, 9), (7, 8)]), pair_code(&[(1, 2), (4, 12), (5, 11), (6, 10), (7, 9)])),
            // cubic-wide: lanes analysis (periodic, symmetric), rows analysis (periodic, symmetric)
            (19, 0b1111111111111111111, 0b11111, 0, 0, 0, 0, pair_code(&[(0, 18), (1, 17), (2, 16), (3, 15), (4, 14), (5, 13), (6, 12), (7, 11), (8, 10)]), pair_code(&[(0, 4), (1, 3)])),
            // cubic-wide: lanes analysis (interpolating)
            (19, 0b1111111111111111111, 0b1111100000000000000, 0, 0, 0, 0, pair_code(&[(0, 18), (1, 17), (2, 16), (3, 15), (4, 14), (5, 13), (6, 12), (7, 11), (8, 10)]), pair_code(&[(14, 18), (15, 17)])),
            // cubic-wide: rows analysis (interpolating)
            (19, 0b1111111111111111111, 0b1111111111111111111, 0, 0, 0, 0, pair_code(&[]), pair_code(&[])),
            // cubic-wide: rows analysis (interpolating)
            (21, 0b11111, 0b111111111111111111100, 0, 0, 0, 0, pair_code(&[(0, 4), (1, 3)]), pair_code(&[(2, 20), (3, 19), (4, 18), (5, 17), (6, 16), (7, 15), (8, 14), (9, 13), (10, 12)])),
            // cdf97: rows analysis
            (11, 0b1111111, 0b11111111100, 0, 0, 0, 0, pair_code(&[(0, 6), (1, 5), (2, 4)]), pair_code(&[(2, 10), (3, 9), (4, 8), (5, 7)])),
            // cdf97: lanes synthesis, rows synthesis
            (9, 0b11110111, 0b111111111, 0, 0, 0, 0, pair_code(&[(0, 2), (4, 7), (5, 6)]), pair_code(&[(0, 3), (1, 2), (4, 8), (5, 7)])),
            // cdf97: lanes analysis
            (9, 0b111111111, 0b1111111, 0, 0, 0, 0, pair_code(&[(0, 8), (1, 7), (2, 6), (3, 5)]), pair_code(&[(0, 6), (1, 5), (2, 4)]))
        )
    };
}
