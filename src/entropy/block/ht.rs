//! One code-block coded HT-style: quads by static prefix codes ([`Vlc`]) chosen by
//! context, all-zero stretches by an adaptive run coder ([`MelWriter`]), magnitudes by
//! static prefix codes and raw bits, signs raw. Nothing is arithmetic-decoded and no
//! model adapts except the run coder's state.
//!
//! Quads, neighbours and classes are those of [`super::quad`] (the same scratch of
//! magnitudes, positions outside the block 0), without the parent. For the quad at
//! `(y, x)`, the class `q` of `s = NW + N₀ + N₁ + NE + W₀ + W₁ + ΣZ` (12 classes):
//!
//! - **quad symbol**: with [`Tables::joint`], `Σ t_b·3^b` where `t_b` is 0 (zero),
//!   1 (`|v| = 1`) or 2 (`|v| ≥ 2`) for the quad's four positions in raster order
//!   (81 symbols); otherwise the significance pattern `Σ [v_b ≠ 0]·2^b` (16 symbols).
//!   When `q = 0` the run coder first says whether the quad is all zero; a non-zero
//!   quad's symbol then uses the code of the context after a run ([`RUN`]). Otherwise the
//!   symbol uses the code of class `q`.
//! - **each non-zero position** in raster order: its magnitude `m`, unless the quad
//!   symbol already says `m = 1`, as `v = m − 1` (`m − 2` in the joint alphabet) by the
//!   rule of [`super::quad`]: class `c` of `u = 2(W + N + Z) + NW + NE`,
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
/// The code index of a non-zero quad after the run coder (class 0).
pub const RUN: usize = QCLS;
/// Symbols of the magnitude codes.
pub const MSYM: usize = 16;

/// `t_b` digits of the 81 joint quad symbols.
const DIGITS: [[u8; 4]; 81] = {
    let mut d = [[0u8; 4]; 81];
    let mut s = 0;
    while s < 81 {
        d[s] = [
            (s % 3) as u8,
            (s / 3 % 3) as u8,
            (s / 9 % 3) as u8,
            (s / 27 % 3) as u8,
        ];
        s += 1;
    }
    d
};

/// The prefix codes of the coder.
#[derive(Clone, Debug)]
pub struct Tables {
    /// the ternary quad alphabet (81 symbols) instead of significance patterns (16)
    pub joint: bool,
    /// per class `q`, then [`RUN`]
    quad: Vec<Vlc>,
    /// per magnitude class `c`
    mag: Vec<Vlc>,
}

impl Tables {
    /// The codes of the given lengths: `quad` has [`QCLS`] + 1 rows of 81 (joint) or 16
    /// lengths, `mag` [`MCLS`] rows of [`MSYM`].
    pub fn from_lengths(joint: bool, quad: &[&[u8]], mag: &[&[u8]]) -> Self {
        Tables {
            joint,
            quad: quad.iter().map(|l| Vlc::new(l)).collect(),
            mag: mag.iter().map(|l| Vlc::new(l)).collect(),
        }
    }

    /// The default codes: the trained lengths of [`super::ht_table`].
    pub fn standard() -> &'static Tables {
        static T: OnceLock<Tables> = OnceLock::new();
        T.get_or_init(|| {
            use super::ht_table as t;
            let q: Vec<&[u8]> = t::QUAD.iter().map(|r| &r[..]).collect();
            let m: Vec<&[u8]> = t::MAGNITUDE.iter().map(|r| &r[..]).collect();
            Tables::from_lengths(t::JOINT, &q, &m)
        })
    }
}

/// Symbol counts per code, for training [`Tables`].
#[derive(Clone, Debug)]
pub struct Counts {
    pub joint: bool,
    pub quad: Vec<Vec<u64>>,
    pub magnitude: Vec<Vec<u64>>,
}

impl Counts {
    pub fn new(joint: bool) -> Self {
        Counts {
            joint,
            quad: vec![vec![0; if joint { 81 } else { 16 }]; QCLS + 1],
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
        Tables::from_lengths(self.joint, &q, &m)
    }
}

/// Code the block of `band` laid out by `rows` into `w` (main stream) and `mel`.
#[allow(clippy::too_many_arguments)]
pub fn encode(
    band: &[i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    t: &Tables,
    mut counts: Option<&mut Counts>,
    w: &mut BitWriter,
    mel: &mut MelWriter,
) {
    s.clear();
    let off = quad_offsets(s.rx());
    let base = if t.joint { 2 } else { 1 };
    each_quad(ext, rows, |k, y, x, valid, at| {
        let mut d = [0u8; 4];
        let mut sym = 0;
        for b in 0..4 {
            if valid >> b & 1 == 1 && band[at[b]] != 0 {
                d[b] = if t.joint && band[at[b]].unsigned_abs() > 1 {
                    2
                } else {
                    1
                };
            }
        }
        for b in (0..4).rev() {
            sym = sym * if t.joint { 3 } else { 2 } + d[b] as usize;
        }
        let i = s.at(k, y, x);
        let q = s.quad_class(i);
        let code = if q == 0 {
            mel.event(sym == 0);
            if sym == 0 {
                return;
            }
            RUN
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
            if d[b] == 2 || !t.joint {
                let c = s.mag_ctx(i + off[b], 0);
                let m = (a - base) as u64;
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
    let base = if t.joint { 2 } else { 1 };
    let mut r = BitReader::new(data);
    let mut mel = MelReader::new(data);
    each_quad(ext, rows, |k, y, x, valid, at| {
        let i = s.at(k, y, x);
        let q = s.quad_class(i);
        let sym = if q == 0 {
            if mel.next() {
                return;
            }
            t.quad[RUN].get(&mut r)
        } else {
            t.quad[q].get(&mut r)
        };
        let d = if t.joint {
            DIGITS[sym.min(80)]
        } else {
            [
                (sym & 1) as u8,
                (sym >> 1 & 1) as u8,
                (sym >> 2 & 1) as u8,
                (sym >> 3 & 1) as u8,
            ]
        };
        for b in 0..4 {
            if d[b] == 0 || valid >> b & 1 == 0 {
                continue;
            }
            let a = if d[b] == 2 || !t.joint {
                let c = s.mag_ctx(i + off[b], 0);
                get_magnitude(&mut r, &t.mag[c], c) + base
            } else {
                1
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
