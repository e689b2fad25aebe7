//! The table of tap patterns that have a vector build of the pair kernels.

/// The tap patterns `(inputs, m1, m2)` with vector builds (AVX2 and AVX-512): the regular rows of the three
/// schemes, analysis (coarse, detail) and synthesis (even, odd fine rows), as
/// [`super::polyphase`] pairs them.
#[cfg(target_arch = "x86_64")]
macro_rules! pair_patterns {
    ($m:ident) => {
        $m!(
            // (U, M1, M2, P1, N1, P2, N2, R1, R2): inputs, the masks of the two outputs,
            // the terms of weight +1 and −1 of each (added or subtracted, not
            // multiplied), and the pairs of each (see `pattern_of`)
            (2, 0b11, 0b11, 0, 0, 0, 0, 0, 0),
            (4, 0b1111, 0b1111, 0, 0, 0, 0, 0, 0),
            (6, 0b001111, 0b111100, 0, 0, 0, 0, 0, 0),
            (7, 0b0111011, 0b1111111, 0, 0, 0, 0, 0, 0),
            (7, 0b1111111, 0b1111100, 0, 0, 0, 0, 0, 0),
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0, 0, 0),
            (7, 0b1111111, 0b0011111, 0, 0, 0, 0, 0, 0),
            // the regular rows of the schemes, their symmetric taps paired: Haar's
            // analysis and synthesis
            (2, 0b11, 0b11, 0, 0, 0, 0, 0x2, 0),
            (2, 0b11, 0b11, 0b1, 0, 0b1, 0b10, 0x2, 0),
            // Chaikin's analysis and synthesis
            (4, 0b1111, 0b1111, 0, 0, 0, 0, 0x34, 0),
            (6, 0b001111, 0b111100, 0, 0, 0, 0, 0, 0x5600),
            (4, 0b1111, 0b1111, 0, 0, 0, 0, 0x3, 0x3),
            // cubic's analysis (`a`'s centre of weight 1) and synthesis (`q`'s of −1)
            (7, 0b1111111, 0b0011111, 0b0001000, 0, 0, 0, 0x567, 0x45),
            (7, 0b1111111, 0b1111100, 0b0001000, 0, 0, 0, 0x567, 0x6700),
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0b0100000, 0x67003, 0x70030),
            (7, 0b0111011, 0b1111111, 0, 0b0010000, 0, 0, 0x6002, 0x67003)
        )
    };
}
