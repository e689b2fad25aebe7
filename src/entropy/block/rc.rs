//! A multi-symbol range coder over 16-symbol alphabets with adaptive 15-bit CDFs (the
//! AV1 / Daala construction), and a raw bit stream beside it.
//!
//! Coding symbol `s` with cumulative frequencies `c` (`c[-1] = 0`, `c[15] = 2^15`):
//! `r = ⌊range / 2^15⌋`, `low += r·c[s−1]`, `range = r·(c[s] − c[s−1])` (the last symbol
//! takes what is left, `range − r·c[14]`), renormalised a byte at a time when
//! `range < 2^24`; the carry goes through a cached byte as in LZMA's coder. The decoder
//! finds `s` by comparing its offset against `r·c[s]`, no division.
//!
//! After each symbol the CDF moves towards the one that gives `s` all the mass but one
//! unit per other symbol: `c[i] += (t[i] − c[i]) >> rate`, `t[i] = i + 1` below `s`,
//! `2^15 − (15 − i)` from `s` on; `rate = min(⌊log₂(n + 2)⌋, limit)` after `n` symbols
//! (a running mean at first, as a count-based estimate learns, then a fixed window of
//! about `2^limit` symbols). Every
//! symbol keeps a frequency of at least 1 (a convex mix of two CDFs with that property,
//! and flooring both ends of a frequency loses less than 1).

use crate::entropy::range::{Reader, Writer};

/// Symbols of every alphabet.
pub const SYMBOLS: usize = 16;
const PROB_BITS: u32 = 15;
const ONE: i32 = 1 << PROB_BITS;

/// An adaptive CDF of 16 symbols: `c[i]` = cumulative frequency up to and including
/// symbol `i` (`c[15] = 2^15`), the symbols seen (up to 255) and the adaptation limit.
#[derive(Clone, Copy, Debug)]
pub struct Cdf {
    c: [u16; SYMBOLS],
    count: u8,
    limit: u8,
}

/// The default adaptation limit: a window of about 32 symbols.
pub const LIMIT: u8 = 5;

impl Default for Cdf {
    fn default() -> Self {
        Self::uniform(LIMIT)
    }
}

impl Cdf {
    /// Every symbol equally likely, adapting up to `limit` (1 to 14).
    pub fn uniform(limit: u8) -> Self {
        let mut c = [0u16; SYMBOLS];
        for (i, v) in c.iter_mut().enumerate() {
            *v = ((i as i32 + 1) * ONE / SYMBOLS as i32) as u16;
        }
        Cdf {
            c,
            count: 0,
            limit: limit.clamp(1, 14),
        }
    }

    /// A CDF from cumulative frequencies `c` (`c[15] = 2^15`, increasing), counted as
    /// `seen` symbols, adapting up to `limit`.
    pub fn from_cumulative(c: [u16; SYMBOLS], seen: u8, limit: u8) -> Self {
        Cdf {
            c,
            count: seen,
            limit: limit.clamp(1, 14),
        }
    }

    /// The cumulative frequencies.
    pub fn cumulative(&self) -> [u16; SYMBOLS] {
        self.c
    }

    /// A CDF starting from the frequencies `f` (each at least 1, any total): the
    /// cumulative sums scaled to 2^15, every symbol kept at least 1.
    pub fn from_freqs(f: &[u32; SYMBOLS]) -> Self {
        let total: u64 = f.iter().map(|&v| v.max(1) as u64).sum();
        let spare = (ONE as u64) - SYMBOLS as u64;
        let mut c = [0u16; SYMBOLS];
        let mut acc = 0u64;
        for (i, v) in c.iter_mut().enumerate() {
            acc += f[i].max(1) as u64;
            *v = (acc * spare / total) as u16 + i as u16 + 1;
        }
        c[SYMBOLS - 1] = ONE as u16;
        Cdf {
            c,
            count: 0,
            limit: LIMIT,
        }
    }

    #[inline(always)]
    fn update(&mut self, s: usize) {
        let rate = (self.count as u32 + 2).ilog2().min(self.limit as u32);
        self.count = self.count.saturating_add(1);
        // in 16-bit lanes: the targets and every c[i] (i < 15) lie in 0..2^15, so
        // `t − c` and the result fit an i16 and the shift floors as in i32
        for i in 0..SYMBOLS - 1 {
            let t = if i < s {
                i as i16 + 1
            } else {
                (ONE - (SYMBOLS - 1 - i) as i32) as i16
            };
            let c = self.c[i] as i16;
            self.c[i] = c.wrapping_add(t.wrapping_sub(c) >> rate) as u16;
        }
    }

    /// Symbol `s`'s part of an interval of width `range`: its start `r·c[s−1]` and width
    /// `r·(c[s] − c[s−1])`, `r = ⌊range / 2^15⌋` (the last symbol takes what is left).
    #[inline(always)]
    fn interval(&self, range: u32, s: usize) -> (u32, u32) {
        let r = range >> PROB_BITS;
        let lo = if s == 0 { 0 } else { r * self.c[s - 1] as u32 };
        let width = if s < SYMBOLS - 1 {
            r * self.c[s] as u32 - lo
        } else {
            range - lo
        };
        (lo, width)
    }

    /// `−log₂ P(s)` in bits.
    pub fn cost(&self, s: usize) -> f64 {
        let lo = if s == 0 { 0.0 } else { self.c[s - 1] as f64 };
        -((self.c[s] as f64 - lo) / ONE as f64).log2()
    }

    /// [`Cdf::cost`] to about 0.01 bit ([`bits_of`]), for the encoder's choices.
    #[inline(always)]
    pub fn cost_fast(&self, s: usize) -> f32 {
        let lo = if s == 0 { 0 } else { self.c[s - 1] as u32 };
        bits_of(self.c[s] as u32 - lo)
    }
}

/// `−log₂(f / 2^15)` for a frequency `1 ≤ f ≤ 2^15`, to about 0.01 bit: with
/// `f = 2^e·m`, `m ∈ [1, 2)`, `log₂ f = e + log₂ m` and
/// `log₂ m ≈ t(1.3466 − 0.3466t)`, `t = m − 1`.
#[inline(always)]
pub fn bits_of(f: u32) -> f32 {
    let b = (f.max(1) as f32).to_bits();
    let e = ((b >> 23) as i32 - 127) as f32;
    let t = f32::from_bits((b & 0x007f_ffff) | 0x3f80_0000) - 1.0;
    PROB_BITS as f32 - (e + t * (1.3466 - 0.3466 * t))
}

/// An adaptive binary model for the same coder: `p = P(0)·2^15`, starting at ½; after
/// each bit `p += (t − p) >> rate` with `t = 2^15 − 32` after a 0 and `32` after a 1,
/// `rate = min(⌊log₂(n + 2)⌋, limit)` after `n` bits (as [`Cdf`]), so `p` stays in
/// `[32, 2^15 − 32]`. Coding a bit splits the interval at `s = ⌊range / 2^15⌋·p`: a 0
/// keeps `[0, s)`, a 1 takes `[s, range)`.
#[derive(Clone, Copy, Debug)]
pub struct Bit {
    p: u16,
    count: u8,
}

impl Default for Bit {
    fn default() -> Self {
        Bit {
            p: (ONE / 2) as u16,
            count: 0,
        }
    }
}

impl Bit {
    #[inline(always)]
    fn update(&mut self, bit: bool, limit: u8) {
        let rate = (self.count as u32 + 2).ilog2().min(limit as u32);
        self.count = self.count.saturating_add(1);
        let t = if bit { 32 } else { ONE - 32 };
        let p = self.p as i32;
        self.p = (p + ((t - p) >> rate)) as u16;
    }

    /// `−log₂ P(bit)` in bits.
    pub fn cost(&self, bit: bool) -> f64 {
        let p0 = self.p as f64 / ONE as f64;
        -(if bit { 1.0 - p0 } else { p0 }).log2()
    }

    /// [`Bit::cost`] to about 0.01 bit ([`bits_of`]).
    #[inline(always)]
    pub fn cost_fast(&self, bit: bool) -> f32 {
        let p = self.p as u32;
        bits_of(if bit { ONE as u32 - p } else { p })
    }
}

/// `N` CDFs: `seen[k]` at context `k·step`, every other context uniform
/// (`c[i] = 2^11·(i + 1)`, the CDF of a context without counts).
pub const fn spread<const N: usize>(seen: &[[u16; 16]], step: usize) -> [[u16; 16]; N] {
    let mut uniform = [0u16; 16];
    let mut i = 0;
    while i < 16 {
        uniform[i] = 2048 * (i as u16 + 1);
        i += 1;
    }
    let mut t = [uniform; N];
    let mut k = 0;
    while k < seen.len() {
        t[k * step] = seen[k];
        k += 1;
    }
    t
}

/// Range decoder of what [`Encoder`] wrote (its code starts with 4 bytes); reading past
/// the end yields zero bytes.
pub struct Decoder<'a>(Reader<'a>);

impl<'a> Decoder<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Decoder(Reader::new(data, 4))
    }

    /// Decode one symbol with `cdf`, then adapt it.
    #[inline(always)]
    pub fn symbol(&mut self, cdf: &mut Cdf) -> usize {
        let d = &mut self.0;
        let r = d.range >> PROB_BITS;
        let mut s = 0;
        while s < SYMBOLS - 1 && d.code >= r * cdf.c[s] as u32 {
            s += 1;
        }
        let lo;
        (lo, d.range) = cdf.interval(d.range, s);
        // a damaged stream may leave the offset past the last interval's end
        d.code = d.code.wrapping_sub(lo);
        cdf.update(s);
        d.renormalise();
        s
    }

    /// Decode one bit with `m`, then adapt it (up to `limit`).
    #[inline(always)]
    pub fn bit(&mut self, m: &mut Bit, limit: u8) -> bool {
        let d = &mut self.0;
        let split = (d.range >> PROB_BITS) * m.p as u32;
        let bit = d.code >= split;
        if bit {
            d.code -= split;
            d.range -= split;
        } else {
            d.range = split;
        }
        m.update(bit, limit);
        d.renormalise();
        bit
    }
}

/// Range encoder of [`Cdf`] symbols.
pub struct Encoder(Writer);

impl Default for Encoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Encoder {
    pub fn new() -> Self {
        Encoder(Writer::default())
    }

    /// Code symbol `s` (< 16) with `cdf`, then adapt it.
    #[inline(always)]
    pub fn symbol(&mut self, cdf: &mut Cdf, s: usize) {
        let w = &mut self.0;
        let lo;
        (lo, w.range) = cdf.interval(w.range, s);
        w.low += lo as u64;
        cdf.update(s);
        w.renormalise();
    }

    /// Code `bit` with `m`, then adapt it (up to `limit`).
    #[inline(always)]
    pub fn bit(&mut self, m: &mut Bit, bit: bool, limit: u8) {
        let w = &mut self.0;
        let split = (w.range >> PROB_BITS) * m.p as u32;
        if bit {
            w.low += split as u64;
            w.range -= split;
        } else {
            w.range = split;
        }
        m.update(bit, limit);
        w.renormalise();
    }

    /// Flush with the fewest bytes: the value in `[low, low + range)` with the most
    /// trailing zero bytes; the always-zero first byte and the trailing zero bytes are
    /// left out (the decoder reads zeros past the end).
    pub fn finish(self) -> Vec<u8> {
        self.0.finish_short()
    }
}

/// Raw bits packed least significant first into bytes.
#[derive(Default)]
pub struct BitWriter {
    acc: u64,
    n: u32,
    out: Vec<u8>,
}

impl BitWriter {
    /// Append the low `n` bits of `v` (`n` ≤ 32).
    #[inline(always)]
    pub fn put(&mut self, v: u64, n: u32) {
        debug_assert!(n <= 32);
        self.acc |= (v & ((1u64 << n) - 1)) << self.n;
        self.n += n;
        if self.n >= 32 {
            self.out.extend_from_slice(&(self.acc as u32).to_le_bytes());
            self.acc >>= 32;
            self.n -= 32;
        }
    }

    pub fn finish(mut self) -> Vec<u8> {
        while self.n > 0 {
            self.out.push(self.acc as u8);
            self.acc >>= 8;
            self.n = self.n.saturating_sub(8);
        }
        self.out
    }
}

/// Reader of [`BitWriter`]'s bits; zeros past the end.
pub struct BitReader<'a> {
    acc: u64,
    n: u32,
    data: &'a [u8],
    pos: usize,
}

impl<'a> BitReader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        BitReader {
            acc: 0,
            n: 0,
            data,
            pos: 0,
        }
    }

    #[inline(always)]
    fn refill(&mut self) {
        if let Some(b) = self.data.get(self.pos..self.pos + 4) {
            let w = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            self.acc |= (w as u64) << self.n;
            self.pos += 4;
        } else {
            let mut w = 0u32;
            for k in 0..4 {
                w |= (self.data.get(self.pos + k).copied().unwrap_or(0) as u32) << (8 * k);
            }
            self.acc |= (w as u64) << self.n;
            self.pos += 4;
        }
        self.n += 32;
    }

    /// The next `n` bits (`n` ≤ 32).
    #[inline(always)]
    pub fn get(&mut self, n: u32) -> u64 {
        if self.n < n {
            self.refill();
        }
        let v = self.acc & ((1u64 << n) - 1);
        self.acc >>= n;
        self.n -= n;
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contexts [`spread`] fills are the uniform CDF, and the listed ones land every
    /// `step`-th.
    #[test]
    fn spread_puts_the_seen_contexts_every_step_among_uniform_ones() {
        let seen = [[7u16; 16], [9u16; 16]];
        let t: [[u16; 16]; 5] = spread(&seen, 2);
        let uniform = Cdf::uniform(LIMIT).cumulative();
        assert_eq!(t, [seen[0], uniform, seen[1], uniform, uniform]);
    }

    /// Every model's cumulative counts below the last stay in `0..2^15` and ascend, from
    /// every start (the trained priors included) and after any symbols:
    /// what the 16-bit update and the decoder's search rely on.
    #[test]
    fn cumulative_counts_ascend_below_2_15_under_updates() {
        use super::super::prior::{MAGNITUDE, PATTERN, WEIGHT};
        let mut starts: Vec<Cdf> = vec![Cdf::uniform(LIMIT), Cdf::uniform(14)];
        starts.extend(
            PATTERN
                .iter()
                .chain(&MAGNITUDE)
                .map(|c| Cdf::from_cumulative(*c, WEIGHT, 7)),
        );
        let mut f = [0u32; SYMBOLS];
        f[3] = 1000;
        starts.push(Cdf::from_freqs(&f));
        let mut x = 5u64;
        for mut m in starts {
            for step in 0..400 {
                let c = m.cumulative();
                assert!(c[..SYMBOLS - 1].iter().all(|&v| v < ONE as u16), "{c:?}");
                assert!(c.windows(2).all(|w| w[0] <= w[1]), "{c:?}");
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                // runs of one symbol, then any
                let s = if step % 100 < 50 {
                    15 * (step / 100 % 2)
                } else {
                    (x >> 60) as usize
                };
                let before = m;
                m.update(s);
                // the 32-bit update's result
                let rate = (before.count as u32 + 2).ilog2().min(before.limit as u32);
                for i in 0..SYMBOLS - 1 {
                    let t = if i < s {
                        i as i32 + 1
                    } else {
                        ONE - (SYMBOLS - 1 - i) as i32
                    };
                    let c = before.c[i] as i32;
                    assert_eq!(m.c[i] as i32, c + ((t - c) >> rate));
                }
            }
        }
    }

    /// The fast costs stay within 0.01 bit of the exact ones over every frequency.
    #[test]
    fn fast_costs_are_within_a_hundredth_of_a_bit() {
        for f in 1..=ONE as u32 {
            let exact = -(f as f64 / ONE as f64).log2();
            assert!((bits_of(f) as f64 - exact).abs() < 0.01, "f = {f}");
        }
    }
}
