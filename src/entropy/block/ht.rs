//! One code-block coded HT-style: quads by static prefix codes ([`Vlc`]) chosen by
//! context, all-zero stretches by an adaptive run coder ([`MelWriter`]), magnitudes by
//! static prefix codes and raw bits, signs raw. Nothing is arithmetic-decoded and no
//! model adapts except the run coder's state.
//!
//! Quads, neighbours and classes are those of [`super::quad`] (the same scratch of
//! magnitudes, positions outside the block 0). The codes' [`Kind`] sets `L` (levels) and
//! whether the parent P (capped magnitude of the one coefficient a quad shares one level
//! coarser) is a context. For the quad at `(y, x)`, with the class `q` of
//! `s = NW + N₀ + N₁ + NE + W₀ + W₁ + ΣZ` (12 classes), its context is `q` (no parent)
//! or `3q + min(P, 2)`:
//!
//! - **quad symbol** `Σ t_b·L^b`, `t_b = min(|v_b|, L − 1)` for the quad's four
//!   positions in raster order (`L = 2`: the significance pattern, 16 symbols; `L = 3`:
//!   81; `L = 4`: 256). In context 0 the run coder first says whether the quad is all
//!   zero; a non-zero quad's symbol then uses the code after a run ([`Kind::run`]).
//!   Otherwise the symbol uses the code of its context.
//! - **each non-zero position** in raster order: when `t_b = L − 1`, its magnitude `m`
//!   as `v = m − (L − 1)` by the rule of [`super::quad`]: class `c` of
//!   `u = 2(W + N + Z) + NW + NE` (`+ 2P` with the parent),
//!   `k = max(c − KOFF, 0)`, `h = ⌊v / 2^k⌋` as the symbol `min(h, 15)` in the code of
//!   class `c`, `h ≥ 15` followed by `h − 14 = 2^e + r` as `e` in 6 raw bits and `r` in
//!   `e` raw bits; then the `k` low bits of `v`; then the sign bit (1 = negative).
//!
//! A block's bytes are the main bit stream (quad and magnitude codewords and raw bits, in
//! coding order) followed by the run coder's bytes in reverse order: the decoder reads
//! the first from the start and the second from the end, so one length per block
//! suffices.

use super::quad::{each_quad, quad_offsets, Extent, Rows, Scratch, CAP, KOFF, MCLS};
use super::vlc::{lengths, BitReader, BitWriter, MelReader, MelWriter, Vlc};
use std::sync::OnceLock;

/// Quad classes (of `s`).
pub const QCLS: usize = super::quad::QCLS;
/// Symbols of the magnitude codes.
pub const MSYM: usize = 16;

/// The shape of a coder's codes: levels per quad position and whether the parent is a
/// context.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kind {
    /// `L` in 2..=4: a quad symbol is `Σ t_b·L^b` with `t_b = min(|v_b|, L − 1)`
    pub levels: u8,
    /// the quad context is `q·3 + min(P, 2)` and magnitude classes count `2P`
    pub parent: bool,
}

impl Kind {
    /// Quad symbols.
    pub fn symbols(self) -> usize {
        (self.levels as usize).pow(4)
    }

    /// Quad codes: one per context, then the one after a run ([`Kind::run`]).
    pub fn quad_codes(self) -> usize {
        self.run() + 1
    }

    /// The code index of a non-zero quad after the run coder.
    pub fn run(self) -> usize {
        if self.parent {
            QCLS * 3
        } else {
            QCLS
        }
    }
}

/// The prefix codes of the coder.
#[derive(Clone, Debug)]
pub struct Tables {
    pub kind: Kind,
    /// per quad context, then the run code
    quad: Vec<Vlc>,
    /// per magnitude class `c`
    mag: Vec<Vlc>,
    /// `t_b` of every quad symbol
    digits: Vec<[u8; 4]>,
}

impl Tables {
    /// The codes of the given lengths: `quad` has [`Kind::quad_codes`] rows of
    /// [`Kind::symbols`] lengths, `mag` [`MCLS`] rows of [`MSYM`].
    pub fn from_lengths(kind: Kind, quad: &[&[u8]], mag: &[&[u8]]) -> Self {
        let l = kind.levels.clamp(2, 4) as usize;
        let kind = Kind {
            levels: l as u8,
            ..kind
        };
        Tables {
            kind,
            quad: quad.iter().map(|r| Vlc::new(r)).collect(),
            mag: mag.iter().map(|r| Vlc::new(r)).collect(),
            digits: (0..kind.symbols())
                .map(|s| {
                    [
                        (s % l) as u8,
                        (s / l % l) as u8,
                        (s / (l * l) % l) as u8,
                        (s / (l * l * l) % l) as u8,
                    ]
                })
                .collect(),
        }
    }

    /// The default codes: the trained lengths of [`super::ht_table`].
    pub fn standard() -> &'static Tables {
        static T: OnceLock<Tables> = OnceLock::new();
        T.get_or_init(|| {
            use super::ht_table as t;
            let q: Vec<&[u8]> = t::QUAD.iter().map(|r| &r[..]).collect();
            let m: Vec<&[u8]> = t::MAGNITUDE.iter().map(|r| &r[..]).collect();
            let kind = Kind {
                levels: t::LEVELS,
                parent: t::PARENT,
            };
            Tables::from_lengths(kind, &q, &m)
        })
    }
}

/// Symbol counts per code, for training [`Tables`].
#[derive(Clone, Debug)]
pub struct Counts {
    pub kind: Kind,
    pub quad: Vec<Vec<u64>>,
    pub magnitude: Vec<Vec<u64>>,
}

impl Counts {
    pub fn new(kind: Kind) -> Self {
        Counts {
            kind,
            quad: vec![vec![0; kind.symbols()]; kind.quad_codes()],
            magnitude: vec![vec![0; MSYM]; MCLS],
        }
    }

    /// The Huffman code lengths of the counts ([`lengths`]).
    pub fn lengths(&self) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        (
            self.quad.iter().map(|f| lengths(f)).collect(),
            self.magnitude.iter().map(|f| lengths(f)).collect(),
        )
    }

    /// The codes of the counts.
    pub fn tables(&self) -> Tables {
        let (q, m) = self.lengths();
        let q: Vec<&[u8]> = q.iter().map(|r| &r[..]).collect();
        let m: Vec<&[u8]> = m.iter().map(|r| &r[..]).collect();
        Tables::from_lengths(self.kind, &q, &m)
    }
}

/// The quad code context of the quad at scratch index `i` with parent magnitude `pm`.
#[inline(always)]
fn quad_ctx(s: &Scratch, i: usize, pm: u32, parent: bool) -> usize {
    if parent {
        s.quad_class(i) * 3 + pm.min(2) as usize
    } else {
        s.quad_class(i)
    }
}

/// The two streams a block is coded into: the main bits and the run coder's.
#[derive(Default)]
pub struct Writers {
    pub bits: BitWriter,
    pub mel: MelWriter,
}

/// Code the block of `band` laid out by `rows` into `out` (main stream and runs).
pub fn encode(
    band: &[i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    t: &Tables,
    mut counts: Option<&mut Counts>,
    out: &mut Writers,
) {
    let (w, mel) = (&mut out.bits, &mut out.mel);
    s.clear();
    let off = quad_offsets(s.rx());
    let top = t.kind.levels as u32 - 1;
    let (run, parent) = (t.kind.run(), t.kind.parent);
    each_quad(ext, rows, |k, y, x, valid, at| {
        let mut d = [0u8; 4];
        let mut sym = 0;
        for b in 0..4 {
            if valid >> b & 1 == 1 {
                d[b] = band[at[b]].unsigned_abs().min(top) as u8;
            }
        }
        for b in (0..4).rev() {
            sym = sym * (top as usize + 1) + d[b] as usize;
        }
        let i = s.at(k, y, x);
        let pm = if parent { rows.parent(k, y, x) } else { 0 };
        let q = quad_ctx(s, i, pm, parent);
        let code = if q == 0 {
            mel.event(sym == 0);
            if sym == 0 {
                return;
            }
            run
        } else {
            q
        };
        t.quad[code].put(w, sym);
        if let Some(n) = counts.as_deref_mut() {
            n.quad[code][sym] += 1;
        }
        for b in 0..4 {
            if d[b] == 0 {
                continue;
            }
            let v = band[at[b]];
            let a = v.unsigned_abs();
            if d[b] as u32 == top {
                let c = s.mag_ctx(i + off[b], pm);
                let m = (a - top) as u64;
                if let Some(n) = counts.as_deref_mut() {
                    let k = c.saturating_sub(KOFF) as u32;
                    n.magnitude[c][(m >> k).min(15) as usize] += 1;
                }
                put_magnitude(w, &t.mag[c], c, m);
            }
            w.put((v < 0) as u64, 1);
            s.set(i + off[b], a.min(CAP));
        }
    });
}

#[inline(always)]
fn put_magnitude(w: &mut BitWriter, vlc: &Vlc, c: usize, v: u64) {
    let k = c.saturating_sub(KOFF) as u32;
    let h = v >> k;
    if h < 15 {
        vlc.put(w, h as usize);
    } else {
        vlc.put(w, 15);
        let x = h - 14;
        let nb = x.ilog2();
        w.put(nb as u64, 6);
        w.put(x & ((1 << nb) - 1), nb);
    }
    w.put(v & ((1 << k) - 1), k);
}

/// Decode a block written by [`encode`] into `band`, which holds zeros at the block's
/// positions (the others are not touched). A damaged stream decodes to some values,
/// never a panic.
pub fn decode(
    band: &mut [i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    t: &Tables,
    data: &[u8],
) {
    s.clear();
    let off = quad_offsets(s.rx());
    let top = t.kind.levels - 1;
    let (run, parent) = (t.kind.run(), t.kind.parent);
    let mut r = BitReader::new(data);
    let mut mel = MelReader::new(data);
    each_quad(ext, rows, |k, y, x, valid, at| {
        let i = s.at(k, y, x);
        let pm = if parent { rows.parent(k, y, x) } else { 0 };
        let q = quad_ctx(s, i, pm, parent);
        let sym = if q == 0 {
            if mel.event() {
                return;
            }
            t.quad[run].get(&mut r)
        } else {
            t.quad[q].get(&mut r)
        };
        let d = t.digits.get(sym).copied().unwrap_or_default();
        for b in 0..4 {
            if d[b] == 0 || valid >> b & 1 == 0 {
                continue;
            }
            let a = if d[b] == top {
                let c = s.mag_ctx(i + off[b], pm);
                get_magnitude(&mut r, &t.mag[c], c) + top as u64
            } else {
                d[b] as u64
            };
            let neg = r.get(1) == 1;
            let a32 = a as u32;
            band[at[b]] = if neg {
                (a32 as i32).wrapping_neg()
            } else {
                a32 as i32
            };
            s.set(i + off[b], a.min(CAP as u64) as u32);
        }
    });
}

#[inline(always)]
fn get_magnitude(r: &mut BitReader, vlc: &Vlc, c: usize) -> u64 {
    let k = c.saturating_sub(KOFF) as u32;
    let mut h = vlc.get(r) as u64;
    if h == 15 {
        let nb = (r.get(6) as u32).min(32);
        h = ((1u64 << nb) | r.get(nb)) + 14;
    }
    (h << k) | r.get(k)
}
