//! One code-block coded by quads with static frequency tables and two interleaved rANS
//! states: the HT-style coder's symbols ([`super::ht`], `L = 3`) without prefix-code
//! rounding and without a run mode.
//!
//! Quads, neighbours and classes are those of [`super::quad`]. For the quad at `(y, x)`
//! with the class `q` of `s = NW + N₀ + N₁ + NE + W₀ + W₁ + ΣZ` (12 classes) and the
//! parent P (capped magnitude of the coefficient the quad shares one level coarser), its
//! context is `q` ([`Kind::parent`] off) or `3q + min(P, 2)`:
//!
//! - **quad symbol** `Σ t_b·3^b`, `t_b = min(|v_b|, 2)` (81 symbols), coded in its
//!   context, the all-zero quad included;
//! - **each position with `t_b = 2`**: `m − 2` as in [`super::ht`] (class `c` of
//!   `u = 2(W + N + Z) + NW + NE` (`+ 2P` with the parent), `k = max(c − KOFF, 0)`,
//!   `h = ⌊(m − 2) / 2^k⌋` as the symbol `min(h, 15)` of class `c`, `h ≥ 15` followed by
//!   `h − 14 = 2^e + r` as `e` in 6 raw bits and `r` in `e` raw bits, then the `k` low
//!   bits raw); each non-zero position's sign raw (1 = negative).
//!
//! Every symbol `s` of a table with frequencies `f` (summing to `2^SCALE`, every
//! symbol at least 1) and cumulative starts `c` is coded by rANS: the `i`-th symbol of
//! the block by state `x` of lane `i mod 2`, `x' = ⌊x / f_s⌋·2^SCALE + (x mod f_s) + c_s`
//! (encoder, symbols in reverse), `s = sym(x mod 2^SCALE)`,
//! `x = f_s·⌊x / 2^SCALE⌋ + (x mod 2^SCALE) − c_s` (decoder), states kept in
//! `[2^16, 2^32)` by 16-bit words. A block's bytes are `varint(rANS bytes)`, the rANS
//! bytes (the two final states, lane 0 first, then the words in the decoder's order, all
//! little-endian 16-bit), then the raw bit stream.

use super::quad::{each_quad, quad_offsets, Extent, Rows, Scratch, CAP, KOFF, MCLS, QCLS};
use super::vlc::{BitReader, BitWriter};
use crate::format::put_varint;

/// Frequency precision: every table sums to `2^SCALE`.
pub const SCALE: u32 = 12;
const MASK: u32 = (1 << SCALE) - 1;
/// The low end of a normalised state.
const LOW: u32 = 1 << 16;
/// Quad symbols (`3^4`).
pub const QSYM: usize = 81;
/// Magnitude symbols.
pub const MSYM: usize = 16;

/// Whether the parent is a quad context (and counts in the magnitude class).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kind {
    pub parent: bool,
}

impl Kind {
    /// Quad contexts.
    pub fn quad_codes(self) -> usize {
        if self.parent {
            QCLS * 3
        } else {
            QCLS
        }
    }
}

/// One static table: per symbol its start and frequency (packed `start | freq << 16`)
/// and per slot `x mod 2^SCALE` its symbol (4 KiB a table, so that the decoder's tables
/// stay in cache).
#[derive(Clone, Debug)]
pub struct Table {
    enc: Vec<u32>,
    dec: Vec<u8>,
}

impl Table {
    /// The table of counts `n` (any values): frequencies proportional to `n`, every
    /// symbol at least 1, summing to `2^SCALE`.
    pub fn from_counts(n: &[u64]) -> Self {
        let f = normalise(n);
        let mut enc = Vec::with_capacity(f.len());
        let mut dec = vec![0u8; 1 << SCALE];
        let mut start = 0u32;
        for (s, &fs) in f.iter().enumerate() {
            enc.push(start | fs << 16);
            dec[start as usize..(start + fs) as usize].fill(s as u8);
            start += fs;
        }
        Table { enc, dec }
    }

    /// The frequency of symbol `s`.
    pub fn freq(&self, s: usize) -> u32 {
        self.enc[s] >> 16
    }
}

/// Frequencies summing to `2^SCALE` from counts `n` (at most `2^SCALE` symbols): each
/// `1 + ⌊n_s·(2^SCALE − len) / Σn⌋`, the remainder added to the most frequent.
fn normalise(n: &[u64]) -> Vec<u32> {
    let total: u64 = n.iter().sum();
    let room = (1u64 << SCALE) - n.len() as u64;
    let mut f: Vec<u32> = n
        .iter()
        .map(|&c| {
            1 + if total == 0 {
                0
            } else {
                (c as u128 * room as u128 / total as u128) as u32
            }
        })
        .collect();
    let sum: u32 = f.iter().sum();
    let top = (0..f.len())
        .max_by_key(|&i| (n[i], std::cmp::Reverse(i)))
        .unwrap_or(0);
    f[top] += (1 << SCALE) - sum;
    f
}

/// The coder's tables: per quad context and per magnitude class.
#[derive(Clone, Debug)]
pub struct Tables {
    pub kind: Kind,
    quad: Vec<Table>,
    mag: Vec<Table>,
}

impl Tables {
    /// The tables of the counts `n`.
    pub fn from_counts(n: &Counts) -> Self {
        Tables {
            kind: n.kind,
            quad: n.quad.iter().map(|c| Table::from_counts(c)).collect(),
            mag: n.magnitude.iter().map(|c| Table::from_counts(c)).collect(),
        }
    }

    /// `−log₂` of the probability the tables give symbol `s` of code `code` (quad codes
    /// first, then the magnitude classes).
    pub fn cost(&self, code: usize, s: usize) -> f64 {
        let t = if code < self.quad.len() {
            &self.quad[code]
        } else {
            &self.mag[code - self.quad.len()]
        };
        SCALE as f64 - (t.freq(s) as f64).log2()
    }
}

/// Symbol counts per code, for training [`Tables`]; with `trace`, every coded symbol in
/// order as `code << 8 | symbol` (quad codes first, then magnitude classes, then the
/// raw sign bits in the 9 contexts `3·sg(W) + sg(N)` they would have, sg = 0, 1, 2 for
/// zero, positive, negative), each block opened by `u32::MAX`; `raw_bits` and `rans_bytes` total the two streams.
#[derive(Clone, Debug)]
pub struct Counts {
    pub kind: Kind,
    pub quad: Vec<Vec<u64>>,
    pub magnitude: Vec<Vec<u64>>,
    pub trace: Option<Vec<u32>>,
    pub raw_bits: u64,
    pub rans_bytes: u64,
}

impl Counts {
    pub fn new(kind: Kind) -> Self {
        Counts {
            kind,
            quad: vec![vec![0; QSYM]; kind.quad_codes()],
            magnitude: vec![vec![0; MSYM]; MCLS],
            trace: None,
            raw_bits: 0,
            rans_bytes: 0,
        }
    }
}

/// What a block is coded into (kept across blocks, no allocation per block once grown):
/// the symbols in coding order, the rANS words, the raw bits.
#[derive(Default)]
pub struct Writers {
    syms: Vec<u32>,
    words: Vec<u16>,
    pub bits: BitWriter,
}

#[inline(always)]
fn quad_ctx(s: &Scratch, i: usize, pm: u32, parent: bool) -> usize {
    if parent {
        s.quad_class(i) * 3 + pm.min(2) as usize
    } else {
        s.quad_class(i)
    }
}

/// Code the block of `band` laid out by `rows`, appending its bytes to `out`.
#[allow(clippy::too_many_arguments)]
pub fn encode(
    band: &[i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    t: &Tables,
    mut counts: Option<&mut Counts>,
    w: &mut Writers,
    out: &mut Vec<u8>,
) {
    s.clear();
    w.syms.clear();
    w.words.clear();
    w.bits.clear();
    let off = quad_offsets(s.rx());
    let parent = t.kind.parent;
    let nq = t.quad.len();
    if let Some(tr) = counts.as_deref_mut().and_then(|n| n.trace.as_mut()) {
        tr.push(u32::MAX);
    }
    let (syms, bits) = (&mut w.syms, &mut w.bits);
    each_quad(ext, rows, |k, y, x, valid, at| {
        let mut d = [0u32; 4];
        for b in 0..4 {
            if valid >> b & 1 == 1 {
                d[b] = band[at[b]].unsigned_abs().min(2);
            }
        }
        let sym = (d[0] + 3 * d[1] + 9 * d[2] + 27 * d[3]) as usize;
        let i = s.at(k, y, x);
        let pm = if parent { rows.parent(k, y, x) } else { 0 };
        let q = quad_ctx(s, i, pm, parent);
        syms.push(t.quad[q].enc[sym]);
        if let Some(n) = counts.as_deref_mut() {
            n.quad[q][sym] += 1;
            if let Some(tr) = n.trace.as_mut() {
                tr.push((q as u32) << 8 | sym as u32);
            }
        }
        if sym == 0 {
            return;
        }
        for b in 0..4 {
            if d[b] == 0 {
                continue;
            }
            let v = band[at[b]];
            let a = v.unsigned_abs();
            if d[b] == 2 {
                let c = s.mag_ctx(i + off[b], pm);
                let m = (a - 2) as u64;
                let kk = c.saturating_sub(KOFF) as u32;
                let h = m >> kk;
                let hs = h.min(15) as usize;
                syms.push(t.mag[c].enc[hs]);
                if let Some(n) = counts.as_deref_mut() {
                    n.magnitude[c][hs] += 1;
                    if let Some(tr) = n.trace.as_mut() {
                        tr.push(((nq + c) as u32) << 8 | hs as u32);
                    }
                }
                if h >= 15 {
                    let e = h - 14;
                    let nb = e.ilog2();
                    bits.put(nb as u64, 6);
                    bits.put(e & ((1 << nb) - 1), nb);
                }
                bits.put(m & ((1 << kk) - 1), kk);
            }
            bits.put((v < 0) as u64, 1);
            if let Some(tr) = counts.as_deref_mut().and_then(|n| n.trace.as_mut()) {
                // the sign's would-be context: the signs of W and N inside the block
                let (py, px) = (y + b / 2, x + b % 2);
                let sg = |u: i32| (u > 0) as u32 + 2 * (u < 0) as u32;
                let w = if px > 0 { sg(band[at[b] - 1]) } else { 0 };
                let nn = if b >= 2 {
                    sg(band[at[b - 2]])
                } else if py > 0 {
                    sg(band[rows.row(k, py - 1) + px])
                } else {
                    0
                };
                tr.push(((nq + MCLS) as u32 + 3 * w + nn) << 8 | (v < 0) as u32);
            }
            s.set(i + off[b], a.min(CAP));
        }
    });
    // rANS: the symbols in reverse, symbol i by lane i mod 2
    let mut x = [LOW; 2];
    for (i, &e) in w.syms.iter().enumerate().rev() {
        let (start, f) = (e & 0xffff, e >> 16);
        let l = &mut x[i & 1];
        if *l >= f << (32 - SCALE) {
            w.words.push(*l as u16);
            *l >>= 16;
        }
        *l = ((*l / f) << SCALE) + *l % f + start;
    }
    let rans_len = 8 + 2 * w.words.len();
    put_varint(out, rans_len as u64);
    out.extend_from_slice(&x[0].to_le_bytes());
    out.extend_from_slice(&x[1].to_le_bytes());
    for &wd in w.words.iter().rev() {
        out.extend_from_slice(&wd.to_le_bytes());
    }
    w.bits.flush();
    out.extend_from_slice(&w.bits.out);
    if let Some(n) = counts {
        n.raw_bits += 8 * w.bits.out.len() as u64;
        n.rans_bytes += rans_len as u64;
    }
}

/// The rANS words being read: past the end, zeros.
struct Words<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Words<'_> {
    #[inline(always)]
    fn next(&mut self) -> u32 {
        let v = match self.data.get(self.pos..self.pos + 2) {
            Some(b) => u16::from_le_bytes([b[0], b[1]]) as u32,
            None => 0,
        };
        self.pos += 2;
        v
    }
}

/// Decode one symbol of table `t` by state `x`.
#[inline(always)]
fn get(t: &Table, x: &mut u32, r: &mut Words) -> usize {
    let slot = *x & MASK;
    let s = t.dec[slot as usize] as usize;
    let e = t.enc[s];
    *x = (e >> 16)
        .wrapping_mul(*x >> SCALE)
        .wrapping_add(slot)
        .wrapping_sub(e & 0xffff);
    if *x < LOW {
        *x = *x << 16 | r.next();
    }
    s
}

/// Decode a block written by [`encode`] (its bytes `data`, from its length on) into
/// `band`, which holds zeros at the block's positions. Damaged bytes decode to some
/// values, never a panic; a length past the data is an error.
pub fn decode(
    band: &mut [i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    t: &Tables,
    data: &[u8],
) -> crate::Result<()> {
    let mut cur = crate::format::Cursor::new(data, "code-block");
    let n = cur.varint()?;
    let left = (data.len() - cur.pos) as u64;
    if n > left {
        return Err(crate::Error::format(
            format!("a rANS stream declaring {n} bytes, {left} left"),
            "streams within the code-block",
        ));
    }
    let body = cur.take(n as usize)?;
    let raw = &data[cur.pos..];
    let st = |k: usize| {
        body.get(4 * k..4 * k + 4)
            .map_or(LOW, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let mut x = [st(0), st(1)];
    let mut r = Words { data: body, pos: 8 };
    let mut bits = BitReader::new(raw);
    s.clear();
    let off = quad_offsets(s.rx());
    let parent = t.kind.parent;
    let mut lane = 0usize;
    each_quad(ext, rows, |k, y, xx, valid, at| {
        let i = s.at(k, y, xx);
        let pm = if parent { rows.parent(k, y, xx) } else { 0 };
        let q = quad_ctx(s, i, pm, parent);
        let mut sym = get(&t.quad[q], &mut x[lane], &mut r) as u32;
        lane ^= 1;
        if sym == 0 {
            return;
        }
        for b in 0..4 {
            let d = sym % 3;
            sym /= 3;
            if d == 0 || valid >> b & 1 == 0 {
                continue;
            }
            let a = if d == 2 {
                let c = s.mag_ctx(i + off[b], pm);
                let kk = c.saturating_sub(KOFF) as u32;
                let mut h = get(&t.mag[c], &mut x[lane], &mut r) as u64;
                lane ^= 1;
                if h == 15 {
                    let nb = (bits.get(6) as u32).min(32);
                    h = ((1u64 << nb) | bits.get(nb)) + 14;
                }
                ((h << kk) | bits.get(kk)).wrapping_add(2)
            } else {
                1
            };
            let neg = bits.get(1) == 1;
            let a32 = a as u32;
            band[at[b]] = if neg {
                (a32 as i32).wrapping_neg()
            } else {
                a32 as i32
            };
            s.set(i + off[b], a32.min(CAP));
        }
    });
    Ok(())
}
