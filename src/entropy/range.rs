//! Binary range coder (the LZMA "rc" construction: 32-bit range, carry propagated
//! through a cached byte) with adaptive bit models: [`Bit`] (format 1, one estimate
//! whose adaptation rate slows down as it sees more symbols) and [`Mix`] (format 2,
//! the mean of a fast and a slow estimate). Normative description: formats/MRA.md §6.

/// Probability scale: a model's `p` is P(bit = 0) · 2^16.
const PROB_BITS: u32 = 16;
const PROB_ONE: u32 = 1 << PROB_BITS;
const PROB_MIN: u32 = 32;
const PROB_MAX: u32 = PROB_ONE - 32;
const TOP: u32 = 1 << 24;
/// Adaptation shift reached after enough symbols.
const RATE_MAX: u8 = 7;

/// An adaptive binary model: the probability of a 0 it predicts and its update.
pub trait Model {
    /// `P(bit = 0) · 2^16`, within `[32, 2^16 − 32]`.
    fn p0(&self) -> u32;
    /// Learn from a coded bit.
    fn update(&mut self, bit: bool);
    /// Estimated cost in bits of coding `bit` now: `−log₂ P(bit)`.
    #[inline(always)]
    fn cost(&self, bit: bool) -> f32 {
        let p = self.p0();
        let p = if bit { PROB_ONE - p } else { p };
        cost_table()[(p >> COST_SHIFT) as usize]
    }
}

const COST_SHIFT: u32 = 4;

/// `−log₂(p / 2^16)` at the centre of every `2^COST_SHIFT` wide step of `p`.
fn cost_table() -> &'static [f32; (PROB_ONE >> COST_SHIFT) as usize + 1] {
    static TABLE: std::sync::OnceLock<[f32; (PROB_ONE >> COST_SHIFT) as usize + 1]> =
        std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [0f32; (PROB_ONE >> COST_SHIFT) as usize + 1];
        for (i, c) in t.iter_mut().enumerate() {
            let p = ((i as f64 + 0.5) * (1 << COST_SHIFT) as f64).min(PROB_ONE as f64);
            *c = -(p / PROB_ONE as f64).log2() as f32;
        }
        t
    })
}

/// Format 2 model: two estimates of `P(0)`, one adapting with shift `min(1 + n, 4)`,
/// one with `min(1 + n, 6)` (`n` = symbols seen), predicting their mean.
#[derive(Clone, Copy, Debug)]
pub struct Mix {
    fast: u16,
    slow: u16,
    n: u8,
}

impl Default for Mix {
    fn default() -> Self {
        Mix {
            fast: (PROB_ONE / 2) as u16,
            slow: (PROB_ONE / 2) as u16,
            n: 0,
        }
    }
}

impl Model for Mix {
    #[inline(always)]
    fn p0(&self) -> u32 {
        // both estimates stay within [PROB_MIN, PROB_MAX] (`update` clamps them), so
        // their mean does
        (self.fast as u32 + self.slow as u32) / 2
    }

    #[inline(always)]
    fn update(&mut self, bit: bool) {
        let n = self.n as u32;
        if self.n < 8 {
            self.n += 1;
        }
        let step = |p: u16, shift: u32| {
            let p = p as u32;
            let p = if bit {
                p - (p >> shift)
            } else {
                p + ((PROB_ONE - p) >> shift)
            };
            p.clamp(PROB_MIN, PROB_MAX) as u16
        };
        self.fast = step(self.fast, (1 + n).min(4));
        self.slow = step(self.slow, (1 + n).min(6));
    }
}

/// One adaptive binary model: P(0) and a symbol count that sets the adaptation rate
/// `shift = min(2 + n/2, 7)`: fast at first, then stable.
#[derive(Clone, Copy, Debug)]
pub struct Bit {
    p: u16,
    n: u8,
}

impl Default for Bit {
    fn default() -> Self {
        Bit {
            p: (PROB_ONE / 2) as u16,
            n: 0,
        }
    }
}

impl Model for Bit {
    #[inline(always)]
    fn p0(&self) -> u32 {
        self.p as u32
    }

    #[inline(always)]
    fn update(&mut self, bit: bool) {
        let shift = (2 + self.n / 2).min(RATE_MAX) as u32;
        if self.n < 2 * RATE_MAX {
            self.n += 1;
        }
        let p = self.p as u32;
        let p = if bit {
            p - (p >> shift)
        } else {
            p + ((PROB_ONE - p) >> shift)
        };
        self.p = p.clamp(PROB_MIN, PROB_MAX) as u16;
    }
}

/// Range encoder writing into a byte vector.
pub struct Encoder {
    low: u64,
    range: u32,
    cache: u8,
    cache_size: u64,
    out: Vec<u8>,
}

impl Default for Encoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Encoder {
    pub fn new() -> Self {
        Encoder {
            low: 0,
            range: u32::MAX,
            cache: 0,
            cache_size: 1,
            out: Vec::new(),
        }
    }

    #[inline(always)]
    fn shift_low(&mut self) {
        if (self.low as u32) < 0xFF00_0000 || (self.low >> 32) != 0 {
            let carry = (self.low >> 32) as u8;
            let mut temp = self.cache;
            loop {
                self.out.push(temp.wrapping_add(carry));
                temp = 0xFF;
                self.cache_size -= 1;
                if self.cache_size == 0 {
                    break;
                }
            }
            self.cache = ((self.low >> 24) & 0xFF) as u8;
        }
        self.cache_size += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    /// Code `bit` with the adaptive model `m`, then update `m`.
    #[inline(always)]
    pub fn bit<M: Model>(&mut self, m: &mut M, bit: bool) {
        let bound = (self.range >> PROB_BITS) * m.p0();
        if bit {
            self.low += bound as u64;
            self.range -= bound;
        } else {
            self.range = bound;
        }
        m.update(bit);
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    /// Code `bit` with probability ½ (no model).
    #[inline(always)]
    pub fn raw(&mut self, bit: bool) {
        self.range >>= 1;
        if bit {
            self.low += self.range as u64;
        }
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    /// Flush as briefly as the stream allows (format 2): the final value is the one in
    /// `[low, low + range)` with the most trailing zero bytes, the always-zero first
    /// byte is left out, and so are the trailing zero bytes (a decoder reads zeros past
    /// the end). Decode with [`Decoder::new_short`].
    pub fn finish_short(mut self) -> Vec<u8> {
        let end = self.low + self.range as u64 - 1;
        for k in [32u32, 24, 16, 8, 0] {
            let mask = (1u64 << k) - 1;
            let v = (self.low + mask) & !mask;
            if v <= end {
                self.low = v;
                break;
            }
        }
        let mut out = self.finish();
        debug_assert_eq!(out.first(), Some(&0));
        while out.last() == Some(&0) {
            out.pop();
        }
        if !out.is_empty() {
            out.remove(0);
        }
        out
    }

    /// Flush and return the coded bytes.
    pub fn finish(mut self) -> Vec<u8> {
        for _ in 0..5 {
            self.shift_low();
        }
        self.out
    }
}

/// Range decoder over a byte slice; reading past the end yields zero bytes (never panics).
pub struct Decoder<'a> {
    code: u32,
    range: u32,
    data: &'a [u8],
    pos: usize,
}

impl<'a> Decoder<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        let mut d = Decoder {
            code: 0,
            range: u32::MAX,
            data,
            pos: 0,
        };
        for _ in 0..5 {
            d.code = (d.code << 8) | d.next() as u32;
        }
        d
    }

    #[inline(always)]
    fn next(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }

    /// A decoder of a stream written by [`Encoder::finish_short`].
    pub fn new_short(data: &'a [u8]) -> Self {
        let mut d = Decoder {
            code: 0,
            range: u32::MAX,
            data,
            pos: 0,
        };
        for _ in 0..4 {
            d.code = (d.code << 8) | d.next() as u32;
        }
        d
    }

    /// Bytes consumed beyond the end of the input (a sign of a damaged stream).
    pub fn overrun(&self) -> usize {
        self.pos.saturating_sub(self.data.len())
    }

    #[inline(always)]
    pub fn bit<M: Model>(&mut self, m: &mut M) -> bool {
        let bound = (self.range >> PROB_BITS) * m.p0();
        let bit = if self.code < bound {
            self.range = bound;
            false
        } else {
            self.code = self.code.wrapping_sub(bound);
            self.range -= bound;
            true
        };
        m.update(bit);
        while self.range < TOP {
            self.range <<= 8;
            self.code = (self.code << 8) | self.next() as u32;
        }
        bit
    }

    #[inline(always)]
    pub fn raw(&mut self) -> bool {
        self.range >>= 1;
        let bit = if self.code >= self.range {
            self.code = self.code.wrapping_sub(self.range);
            true
        } else {
            false
        };
        while self.range < TOP {
            self.range <<= 8;
            self.code = (self.code << 8) | self.next() as u32;
        }
        bit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_round_trip_with_skewed_and_raw_bits() {
        let mut models = [Bit::default(); 4];
        let mut seq = Vec::new();
        let mut x = 12345u32;
        for i in 0..20000 {
            x = x.wrapping_mul(1664525).wrapping_add(1013904223);
            let skew = (x >> 8) % 100 < if i % 4 == 0 { 3 } else { 60 };
            seq.push((i % 4, skew, (x >> 20) & 1 == 1));
        }
        let mut e = Encoder::new();
        for &(m, b, r) in &seq {
            e.bit(&mut models[m], b);
            e.raw(r);
        }
        let bytes = e.finish();
        let mut models = [Bit::default(); 4];
        let mut d = Decoder::new(&bytes);
        for &(m, b, r) in &seq {
            assert_eq!(d.bit(&mut models[m]), b);
            assert_eq!(d.raw(), r);
        }
        // skewed bits cost less than one bit each
        assert!(bytes.len() < 20000 * 2 / 8);
    }

    /// Short flushes decode like full ones, for streams of every length from empty to
    /// a few hundred bits, with [`Mix`] models, and are never longer.
    #[test]
    fn short_streams_round_trip_with_mixed_models() {
        let mut x = 99u32;
        for len in (0..300).step_by(7) {
            let seq: Vec<(usize, bool)> = (0..len)
                .map(|i| {
                    x = x.wrapping_mul(1664525).wrapping_add(1013904223);
                    (i % 3, (x >> 8) % 100 < if i % 3 == 0 { 5 } else { 50 })
                })
                .collect();
            let code = |short: bool| {
                let mut m = [Mix::default(); 3];
                let mut e = Encoder::new();
                for &(k, b) in &seq {
                    e.bit(&mut m[k], b);
                }
                if short {
                    e.finish_short()
                } else {
                    e.finish()
                }
            };
            let (short, full) = (code(true), code(false));
            assert!(
                short.len() < full.len(),
                "{len}: {} vs {}",
                short.len(),
                full.len()
            );
            let mut m = [Mix::default(); 3];
            let mut d = Decoder::new_short(&short);
            for &(k, b) in &seq {
                assert_eq!(d.bit(&mut m[k]), b, "{len}");
            }
            assert!(d.overrun() <= 4);
        }
    }
}
