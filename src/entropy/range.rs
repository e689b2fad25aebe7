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
/// A model's first estimate: `P(0) = ½`.
const HALF: u16 = (PROB_ONE / 2) as u16;

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
            fast: HALF,
            slow: HALF,
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
        self.fast = adapt(self.fast, bit, (1 + n).min(4));
        self.slow = adapt(self.slow, bit, (1 + n).min(6));
    }
}

/// The estimate `p` of `P(0) · 2^16` moved towards the coded `bit` by `2^−shift` of the
/// distance: `p − p·2^−shift` after a 1, `p + (2^16 − p)·2^−shift` after a 0, kept within
/// `[32, 2^16 − 32]`.
#[inline(always)]
fn adapt(p: u16, bit: bool, shift: u32) -> u16 {
    let p = p as u32;
    let p = if bit {
        p - (p >> shift)
    } else {
        p + ((PROB_ONE - p) >> shift)
    };
    p.clamp(PROB_MIN, PROB_MAX) as u16
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
        Bit { p: HALF, n: 0 }
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
        self.p = adapt(self.p, bit, shift);
    }
}

/// A range encoder's interval `[low, low + range)` and the bytes it has settled, the
/// carry propagated through a cached byte (LZMA's `shift_low`): a byte leaves once no
/// carry can change it; the cached byte and the `0xFF` bytes after it wait (`pending`).
pub(crate) struct Writer {
    pub(crate) low: u64,
    pub(crate) range: u32,
    cache: u8,
    pending: u64,
    out: Vec<u8>,
}

impl Default for Writer {
    fn default() -> Self {
        Writer {
            low: 0,
            range: u32::MAX,
            cache: 0,
            pending: 1,
            out: Vec::new(),
        }
    }
}

impl Writer {
    #[inline(always)]
    fn shift(&mut self) {
        if (self.low as u32) < 0xFF00_0000 || (self.low >> 32) != 0 {
            let carry = (self.low >> 32) as u8;
            let mut byte = self.cache;
            loop {
                self.out.push(byte.wrapping_add(carry));
                byte = 0xFF;
                self.pending -= 1;
                if self.pending == 0 {
                    break;
                }
            }
            self.cache = ((self.low >> 24) & 0xFF) as u8;
        }
        self.pending += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    /// Renormalise: while `range < 2^24`, `range ·= 2^8` and a byte of `low` moves out.
    #[inline(always)]
    pub(crate) fn renormalise(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.shift();
        }
    }

    /// Flush and return the coded bytes.
    pub(crate) fn finish(mut self) -> Vec<u8> {
        for _ in 0..5 {
            self.shift();
        }
        self.out
    }

    /// Flush with the fewest bytes: the value in `[low, low + range)` with the most
    /// trailing zero bytes; the always-zero first byte and the trailing zero bytes are
    /// left out (the decoder reads zeros past the end).
    pub(crate) fn finish_short(mut self) -> Vec<u8> {
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
}

/// A range decoder's offset `code` into its interval of width `range`, and its input:
/// the bytes, then zeros past the end.
pub(crate) struct Reader<'a> {
    pub(crate) code: u32,
    pub(crate) range: u32,
    data: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// The reader of `data` whose code starts with its first `n` bytes (big-endian).
    pub(crate) fn new(data: &'a [u8], n: usize) -> Self {
        let mut r = Reader {
            code: 0,
            range: u32::MAX,
            data,
            pos: 0,
        };
        for _ in 0..n {
            r.code = (r.code << 8) | r.next() as u32;
        }
        r
    }

    #[inline(always)]
    fn next(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }

    /// Renormalise: while `range < 2^24`, `range ·= 2^8` and the next byte enters `code`.
    #[inline(always)]
    pub(crate) fn renormalise(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.code = (self.code << 8) | self.next() as u32;
        }
    }

    /// Bytes consumed beyond the end of the input (a sign of a damaged stream).
    pub(crate) fn overrun(&self) -> usize {
        self.pos.saturating_sub(self.data.len())
    }
}

/// Range encoder writing into a byte vector.
#[derive(Default)]
pub struct Encoder(Writer);

impl Encoder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Code `bit` with the adaptive model `m`, then update `m`.
    #[inline(always)]
    pub fn bit<M: Model>(&mut self, m: &mut M, bit: bool) {
        let w = &mut self.0;
        let bound = (w.range >> PROB_BITS) * m.p0();
        if bit {
            w.low += bound as u64;
            w.range -= bound;
        } else {
            w.range = bound;
        }
        m.update(bit);
        w.renormalise();
    }

    /// Code `bit` with probability ½ (no model).
    #[inline(always)]
    pub fn raw(&mut self, bit: bool) {
        let w = &mut self.0;
        w.range >>= 1;
        if bit {
            w.low += w.range as u64;
        }
        w.renormalise();
    }

    /// Flush as briefly as the stream allows (format 2): the final value is the one in
    /// `[low, low + range)` with the most trailing zero bytes, the always-zero first
    /// byte is left out, and so are the trailing zero bytes (a decoder reads zeros past
    /// the end). Decode with [`Decoder::new_short`].
    pub fn finish_short(self) -> Vec<u8> {
        self.0.finish_short()
    }

    /// Flush and return the coded bytes.
    pub fn finish(self) -> Vec<u8> {
        self.0.finish()
    }
}

/// Range decoder over a byte slice; reading past the end yields zero bytes (never panics).
pub struct Decoder<'a>(Reader<'a>);

impl<'a> Decoder<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Decoder(Reader::new(data, 5))
    }

    /// A decoder of a stream written by [`Encoder::finish_short`].
    pub fn new_short(data: &'a [u8]) -> Self {
        Decoder(Reader::new(data, 4))
    }

    /// Bytes consumed beyond the end of the input (a sign of a damaged stream).
    pub fn overrun(&self) -> usize {
        self.0.overrun()
    }

    #[inline(always)]
    pub fn bit<M: Model>(&mut self, m: &mut M) -> bool {
        let r = &mut self.0;
        let bound = (r.range >> PROB_BITS) * m.p0();
        let bit = if r.code < bound {
            r.range = bound;
            false
        } else {
            r.code = r.code.wrapping_sub(bound);
            r.range -= bound;
            true
        };
        m.update(bit);
        r.renormalise();
        bit
    }

    #[inline(always)]
    pub fn raw(&mut self) -> bool {
        let r = &mut self.0;
        r.range >>= 1;
        let bit = if r.code >= r.range {
            r.code = r.code.wrapping_sub(r.range);
            true
        } else {
            false
        };
        r.renormalise();
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
