//! Plain bit streams, static prefix codes and an adaptive run coder: the pieces of the
//! HT-style coder ([`super::ht`]), none of which does arithmetic decoding.
//!
//! - Bits are packed least significant first into bytes; reading past the end gives 0.
//! - A prefix code ([`Vlc`]) is the canonical Huffman code of a table of code lengths
//!   (at most [`MAX_LEN`] bits); codeword bits go out first bit first, so a decoder peeks
//!   [`MAX_LEN`] bits and finds `(symbol, length)` in one table lookup.
//! - The run coder ([`MelWriter`], [`MelReader`]) codes a sequence of binary events
//!   "zero / not zero" with a state `s` in 0..=12 and run exponent `e = E[s]`
//!   (E = 0,0,0,1,1,1,2,2,2,3,3,4,5): a run of `2^e` zeros is the bit 1 (then
//!   `s += 1`); `r < 2^e` zeros then a non-zero is the bit 0 and `r` in `e` bits (then
//!   `s −= 1`); an unfinished run at the end is the bit 1. This is the MEL coder of
//!   HTJ2K (ISO 15444-15) in its exponents, not in its bit stuffing.

/// Longest codeword of a [`Vlc`].
pub const MAX_LEN: u32 = 11;

/// A bit stream being written, least significant bit first.
#[derive(Default)]
pub struct BitWriter {
    pub out: Vec<u8>,
    buf: u64,
    n: u32,
}

impl BitWriter {
    /// Append the `nb` (at most 32) low bits of `v` (bits above `nb` must be 0).
    #[inline(always)]
    pub fn put(&mut self, v: u64, nb: u32) {
        debug_assert!(nb <= 32 && (nb == 32 || v >> nb == 0));
        self.buf |= v << self.n;
        self.n += nb;
        if self.n >= 32 {
            self.out.extend_from_slice(&(self.buf as u32).to_le_bytes());
            self.buf >>= 32;
            self.n -= 32;
        }
    }

    /// Flush the last partial byte (zero padded); the writer starts again empty, its
    /// bytes left in `out`.
    pub fn flush(&mut self) {
        let bytes = self.n.div_ceil(8) as usize;
        self.out.extend_from_slice(&self.buf.to_le_bytes()[..bytes]);
        self.buf = 0;
        self.n = 0;
    }

    /// Empty the writer (keeping its capacity).
    pub fn clear(&mut self) {
        self.out.clear();
        self.buf = 0;
        self.n = 0;
    }
}

/// A bit stream being read, least significant bit first; past its end it reads zeros.
pub struct BitReader<'a> {
    data: &'a [u8],
    pos: usize,
    buf: u64,
    n: u32,
}

impl<'a> BitReader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        BitReader {
            data,
            pos: 0,
            buf: 0,
            n: 0,
        }
    }

    /// Fill the buffer to at least 56 bits.
    #[inline(always)]
    fn refill(&mut self) {
        if let Some(w) = self.data.get(self.pos..self.pos + 8) {
            let v = u64::from_le_bytes(w.try_into().expect("8 bytes"));
            self.buf |= v << self.n;
            let take = (63 - self.n) / 8;
            self.pos += take as usize;
            self.n += take * 8;
        } else {
            while self.n <= 56 {
                let b = self.data.get(self.pos).copied().unwrap_or(0);
                self.pos = self.pos.saturating_add(1);
                self.buf |= (b as u64) << self.n;
                self.n += 8;
            }
        }
    }

    /// The next `nb` (at most 32) bits, not consumed.
    #[inline(always)]
    pub fn peek(&mut self, nb: u32) -> u64 {
        if self.n < nb {
            self.refill();
        }
        self.buf & ((1u64 << nb) - 1)
    }

    /// Consume `nb` bits (at most those peeked).
    #[inline(always)]
    pub fn skip(&mut self, nb: u32) {
        self.buf >>= nb;
        self.n -= nb;
    }

    /// The next `nb` (at most 32) bits.
    #[inline(always)]
    pub fn get(&mut self, nb: u32) -> u64 {
        let v = self.peek(nb);
        self.skip(nb);
        v
    }
}

/// A static prefix code: the canonical Huffman code of its code lengths.
#[derive(Clone, Debug)]
pub struct Vlc {
    /// per symbol: codeword (first bit lowest) and length
    enc: Vec<(u16, u8)>,
    /// per [`MAX_LEN`]-bit window: `symbol << 4 | length`
    lut: Vec<u16>,
}

impl Vlc {
    /// The code of lengths `len` (each 1 to [`MAX_LEN`], satisfying Kraft's
    /// inequality; a complete code when they come from [`lengths`]).
    pub fn new(len: &[u8]) -> Self {
        let mut order: Vec<usize> = (0..len.len()).collect();
        order.sort_by_key(|&s| (len[s], s));
        let mut enc = vec![(0u16, 0u8); len.len()];
        let mut lut = vec![0u16; 1 << MAX_LEN];
        let mut code = 0u32;
        let mut prev = 0u8;
        for &s in &order {
            let l = len[s].clamp(1, MAX_LEN as u8);
            code <<= l - prev;
            prev = l;
            if code >= 1 << l {
                break; // lengths over Kraft's bound: the remaining symbols get no codeword
            }
            let rev = (code.reverse_bits() >> (32 - l as u32)) as u16;
            enc[s] = (rev, l);
            for fill in 0..1u32 << (MAX_LEN - l as u32) {
                lut[(rev as u32 | fill << l) as usize] = (s as u16) << 4 | l as u16;
            }
            code += 1;
        }
        Vlc { enc, lut }
    }

    /// Write symbol `s`.
    #[inline(always)]
    pub fn put(&self, w: &mut BitWriter, s: usize) {
        let (c, l) = self.enc[s];
        w.put(c as u64, l as u32);
    }

    /// Read a symbol.
    #[inline(always)]
    pub fn get(&self, r: &mut BitReader) -> usize {
        let e = self.lut[r.peek(MAX_LEN) as usize];
        r.skip((e & 15) as u32);
        (e >> 4) as usize
    }

    /// The length of symbol `s`'s codeword.
    pub fn len(&self, s: usize) -> u8 {
        self.enc[s].1
    }
}

/// Huffman code lengths, at most [`MAX_LEN`], for the symbol counts `f` (each counted
/// one more, so every symbol gets a codeword); when the code is too deep the counts are
/// halved (rounding up) until it fits.
pub fn lengths(f: &[u64]) -> Vec<u8> {
    let mut w: Vec<u64> = f.iter().map(|&c| c + 1).collect();
    loop {
        let l = huffman(&w);
        if l.iter().all(|&x| x as u32 <= MAX_LEN) {
            return l;
        }
        for v in w.iter_mut() {
            *v = v.div_ceil(2);
        }
    }
}

/// Huffman code lengths of weights `w` (at least two symbols get length ≥ 1).
fn huffman(w: &[u64]) -> Vec<u8> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let n = w.len();
    if n == 1 {
        return vec![1];
    }
    // nodes 0..n are leaves; parents appended
    let mut parent = vec![usize::MAX; n];
    let mut heap: BinaryHeap<Reverse<(u64, usize)>> = w
        .iter()
        .enumerate()
        .map(|(i, &x)| Reverse((x, i)))
        .collect();
    while heap.len() > 1 {
        let Reverse((a, i)) = heap.pop().expect("two nodes");
        let Reverse((b, j)) = heap.pop().expect("two nodes");
        let p = parent.len();
        parent.push(usize::MAX);
        parent[i] = p;
        parent[j] = p;
        heap.push(Reverse((a + b, p)));
    }
    (0..n)
        .map(|mut i| {
            let mut d = 0u8;
            while parent[i] != usize::MAX {
                i = parent[i];
                d = d.saturating_add(1);
            }
            d
        })
        .collect()
}

/// Run exponents of the run coder's states.
const MEL_E: [u8; 13] = [0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 4, 5];

/// The run coder's writer (module docs).
#[derive(Default)]
pub struct MelWriter {
    pub w: BitWriter,
    s: usize,
    run: u32,
}

impl MelWriter {
    /// Code one event.
    #[inline(always)]
    pub fn event(&mut self, zero: bool) {
        let e = MEL_E[self.s] as u32;
        if zero {
            self.run += 1;
            if self.run == 1 << e {
                self.w.put(1, 1);
                self.run = 0;
                self.s = (self.s + 1).min(12);
            }
        } else {
            self.w.put((self.run as u64) << 1, e + 1);
            self.run = 0;
            self.s = self.s.saturating_sub(1);
        }
    }

    /// End the events (an unfinished run as a full one) and flush the bits.
    pub fn finish(&mut self) {
        if self.run > 0 {
            self.w.put(1, 1);
        }
        self.w.flush();
    }

    /// Start again empty.
    pub fn clear(&mut self) {
        self.w.clear();
        self.s = 0;
        self.run = 0;
    }
}

/// The run coder's reader (module docs), reading its bytes from the end of `data`
/// backwards.
pub struct MelReader<'a> {
    data: &'a [u8],
    /// bytes read from the end
    pos: usize,
    buf: u32,
    n: u32,
    s: usize,
    /// zeros still to come
    run: u32,
    /// a non-zero follows them
    one: bool,
}

impl<'a> MelReader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        MelReader {
            data,
            pos: 0,
            buf: 0,
            n: 0,
            s: 0,
            run: 0,
            one: false,
        }
    }

    #[inline(always)]
    fn bits(&mut self, nb: u32) -> u32 {
        while self.n < nb {
            let b = if self.pos < self.data.len() {
                self.data[self.data.len() - 1 - self.pos]
            } else {
                0
            };
            self.pos = self.pos.saturating_add(1);
            self.buf |= (b as u32) << self.n;
            self.n += 8;
        }
        let v = self.buf & ((1u32 << nb) - 1);
        self.buf >>= nb;
        self.n -= nb;
        v
    }

    /// The next event: true for a zero.
    #[inline(always)]
    pub fn event(&mut self) -> bool {
        if self.run == 0 && !self.one {
            let e = MEL_E[self.s] as u32;
            if self.bits(1) == 1 {
                self.run = 1 << e;
                self.s = (self.s + 1).min(12);
            } else {
                self.run = self.bits(e);
                self.one = true;
                self.s = self.s.saturating_sub(1);
            }
        }
        if self.run > 0 {
            self.run -= 1;
            true
        } else {
            self.one = false;
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_vlc_and_runs_round_trip() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            seed >> 33
        };
        let counts: Vec<u64> = (0..81)
            .map(|i| if i % 7 == 0 { 0 } else { 1000 >> (i % 9) })
            .collect();
        let vlc = Vlc::new(&lengths(&counts));
        let kraft: f64 = (0..81).map(|s| 0.5f64.powi(vlc.len(s) as i32)).sum();
        assert!(
            (kraft - 1.0).abs() < 1e-9,
            "complete code, Kraft sum {kraft}"
        );
        let mut w = BitWriter::default();
        let mut mel = MelWriter::default();
        let mut log = Vec::new();
        for i in 0..5000 {
            let s = (next() % 81) as usize;
            let raw = next() & 0xffff_ffff;
            let nb = (next() % 33) as u32;
            let raw = if nb == 32 { raw } else { raw & ((1 << nb) - 1) };
            let zero = next() % 10 < 8 - (i / 1000) as u64;
            vlc.put(&mut w, s);
            w.put(raw, nb);
            mel.event(zero);
            log.push((s, raw, nb, zero));
        }
        w.flush();
        mel.finish();
        let mut r = BitReader::new(&w.out);
        let back: Vec<u8> = mel.w.out.iter().rev().copied().collect();
        let mut mr = MelReader::new(&back);
        for &(s, raw, nb, zero) in &log {
            assert_eq!(vlc.get(&mut r), s);
            assert_eq!(r.get(nb), raw);
            assert_eq!(mr.event(), zero);
        }
    }
}
