//! One code-block coded by quads: the 2×2 significance pattern of each quad as one
//! 16-symbol [`Cdf`] symbol, then every significant coefficient's magnitude as one
//! symbol with its low bits and sign raw.
//!
//! Within a block of `planes × rows × cols` (positions outside the block count as 0, so
//! blocks are independent), quads are visited plane by plane in raster order; for the
//! quad at `(y, x)` (even) with already coded magnitudes (capped at 2^20) NW, N₀, N₁, NE
//! (row `y − 1`, columns `x − 1 … x + 2`), W₀, W₁ (column `x − 1`), the quad of the
//! previous plane Z₀…Z₃ and the parent P (the one coefficient at `(y/2, x/2)` all four
//! share):
//!
//! - **pattern** `b₀ + 2b₁ + 4b₂ + 8b₃` (b = coefficient ≠ 0, raster order in the quad):
//!   context = class of `s = NW + N₀ + N₁ + NE + W₀ + W₁ + ΣZ` (12) × `min(P, 2)`;
//! - **magnitude** `m ≥ 1` of each significant coefficient, in raster order: with
//!   `u = 2(W + N + Z) + NW + NE + 2P` (its own neighbours, those of the quad coded
//!   before it included), class `c = 0` for `u = 0`, else `1 + ⌊log₂ u⌋` (at most
//!   [`MCLS`] − 1), and shift `k = max(c − KOFF, 0)`: symbol `h = ⌊(m − 1) / 2^k⌋` in
//!   context `c` when `h < 15`, else 15 and `h − 14 = 2^e + r` as `e` in 6 raw bits and
//!   `r` in `e` raw bits; then the `k` low bits of `m − 1` and the sign, raw; or, with
//!   sign contexts (coder 2, formats/MRA.md §15.4), the `k` low bits raw and the sign
//!   as an adaptive [`Bit`] in context `3w + n` ([`SIGNS`]: the signs of W and N, 0
//!   for zero or outside the block, 1 positive, 2 negative).

use super::prior;
use super::rc::{Bit, BitReader, BitWriter, Cdf, Decoder, Encoder};
use crate::entropy::walk::{class_in, classes};

pub(super) const QCLS: usize = 12;
pub const PCLS: usize = 3;
/// Pattern contexts.
pub const PATTERNS: usize = QCLS * PCLS;
/// Magnitude classes.
pub const MCLS: usize = 26;
/// Classes of `u` below which magnitudes are coded whole (`k = 0`).
pub const KOFF: usize = 5;
pub(super) const CAP: u32 = 1 << 20;

/// Class of the quad activity `s`: 0, 1, 2, 3, 4, 5–6, 7–9, 10–14, 15–22, 23–35, 36–60, more.
#[inline(always)]
fn qcls(s: u32) -> usize {
    const T: [u8; 61] = classes(&[0, 1, 2, 3, 4, 6, 9, 14, 22, 35]);
    class_in(&T, s as u64, 11)
}

#[inline(always)]
fn mclass(u: u32) -> usize {
    if u == 0 {
        0
    } else {
        (1 + u.ilog2() as usize).min(MCLS - 1)
    }
}

/// Sign contexts: `3·w + n`, `w` and `n` the signs of the W and N neighbours (0 zero
/// or outside the block, 1 positive, 2 negative).
pub const SIGNS: usize = 9;

/// The models of one code-block, fresh at its start.
pub struct Models {
    pattern: [Cdf; QCLS * PCLS],
    mag: [Cdf; MCLS],
    sign: [Bit; SIGNS],
}

impl Models {
    /// Models adapting up to `limit` ([`Cdf::uniform`]), from the trained priors
    /// ([`prior`]) when `trained`, else uniform.
    pub fn new(limit: u8, trained: bool) -> Self {
        if !trained || prior::WEIGHT == 0 {
            return Models {
                pattern: [Cdf::uniform(limit); PATTERNS],
                mag: [Cdf::uniform(limit); MCLS],
                sign: [Bit::default(); SIGNS],
            };
        }
        let from = |c: &[u16; 16]| Cdf::from_cumulative(*c, prior::WEIGHT, limit);
        Models {
            pattern: std::array::from_fn(|i| from(&prior::PATTERN[i])),
            mag: std::array::from_fn(|i| from(&prior::MAGNITUDE[i])),
            sign: [Bit::default(); SIGNS],
        }
    }
}

/// Symbol counts per context, for training the priors.
pub struct Counts {
    pub pattern: [[u32; 16]; PATTERNS],
    pub magnitude: [[u32; 16]; MCLS],
}

impl Default for Counts {
    fn default() -> Self {
        Counts {
            pattern: [[0; 16]; PATTERNS],
            magnitude: [[0; 16]; MCLS],
        }
    }
}

/// Where a block lies: its extents and, for each of its positions, where the band
/// holds it.
#[derive(Clone, Copy, Debug)]
pub struct Extent {
    pub planes: usize,
    pub rows: usize,
    pub cols: usize,
}

/// The magnitudes a block's contexts read, with a zero plane before the first, a zero
/// row above each plane and a zero column on each side; rows and columns rounded up to
/// even (the positions past the block stay 0).
pub struct Scratch {
    mag: Vec<u32>,
    /// signs where the signs have contexts (0 zero, 1 positive, 2 negative)
    sgn: Vec<u8>,
    rx: usize,
    plane: usize,
    /// whether `mag` / `sgn` are known to be all zeros (fresh, not yet handed out):
    /// [`Scratch::clear`] then has nothing to do
    mag_zero: bool,
    sgn_zero: bool,
}

impl Scratch {
    pub fn new(ext: Extent) -> Self {
        let ry = ext.rows.next_multiple_of(2) + 1;
        let rx = ext.cols.next_multiple_of(2) + 2;
        Scratch {
            mag: vec![0; (ext.planes + 1) * ry * rx],
            sgn: vec![0; (ext.planes + 1) * ry * rx],
            rx,
            plane: ry * rx,
            mag_zero: true,
            sgn_zero: true,
        }
    }

    /// Index of block position `(k, y, x)`.
    #[inline(always)]
    pub(super) fn at(&self, k: usize, y: usize, x: usize) -> usize {
        (k + 1) * self.plane + (y + 1) * self.rx + x + 1
    }

    /// Zero every magnitude (nothing to do on a fresh scratch: its allocation is
    /// zeroed already); the caller writes them from here on.
    pub(super) fn clear(&mut self) {
        if !self.mag_zero {
            self.mag.fill(0);
        }
        self.mag_zero = false;
    }

    /// Zero every sign, as [`Scratch::clear`] the magnitudes.
    pub(super) fn clear_signs(&mut self) {
        if !self.sgn_zero {
            self.sgn.fill(0);
        }
        self.sgn_zero = false;
    }

    /// The sign context of the coefficient at index `i` ([`SIGNS`]).
    #[inline(always)]
    fn sign_ctx(&self, i: usize) -> usize {
        3 * self.sgn[i - 1] as usize + self.sgn[i - self.rx] as usize
    }

    /// The row stride.
    pub(super) fn rx(&self) -> usize {
        self.rx
    }

    /// Set the magnitude at index `i`.
    #[inline(always)]
    pub(super) fn set(&mut self, i: usize, m: u32) {
        self.mag[i] = m;
    }

    /// The class of the quad activity `s` of the quad at index `i` (the pattern context
    /// without the parent).
    #[inline(always)]
    pub(super) fn quad_class(&self, i: usize) -> usize {
        self.pattern_ctx(i, 0) / PCLS
    }

    /// The pattern context of the quad at index `i` with parent magnitude `pm`.
    #[inline(always)]
    fn pattern_ctx(&self, i: usize, pm: u32) -> usize {
        let (m, rx, pl) = (&self.mag, self.rx, self.plane);
        let s = m[i - rx - 1]
            + m[i - rx]
            + m[i - rx + 1]
            + m[i - rx + 2]
            + m[i - 1]
            + m[i + rx - 1]
            + m[i - pl]
            + m[i - pl + 1]
            + m[i - pl + rx]
            + m[i - pl + rx + 1];
        qcls(s) * PCLS + pm.min(2) as usize
    }

    /// The magnitude class of the coefficient at index `i`.
    #[inline(always)]
    pub(super) fn mag_ctx(&self, i: usize, pm: u32) -> usize {
        let (m, rx, pl) = (&self.mag, self.rx, self.plane);
        let u = 2 * (m[i - 1] + m[i - rx] + m[i - pl] + pm) + m[i - rx - 1] + m[i - rx + 1];
        mclass(u)
    }
}

/// Offsets of the four positions of a quad from its first, in the scratch.
#[inline(always)]
pub(super) fn quad_offsets(rx: usize) -> [usize; 4] {
    [0, 1, rx, rx + 1]
}

/// The bits of a quad's pattern that lie inside the block.
#[inline(always)]
fn valid_bits(ext: Extent, y: usize, x: usize) -> usize {
    let right = x + 1 < ext.cols;
    let below = y + 1 < ext.rows;
    1 | (right as usize) << 1 | (below as usize) << 2 | ((right && below) as usize) << 3
}

/// Call `f(k, y, x, valid, at)` for every quad of the block in raster order: plane `k`,
/// first row `y` and column `x`, the pattern bits inside the block ([`valid_bits`]) and
/// the offsets in the band of its four positions (the bottom row repeats the top one
/// past the block's last row).
#[inline(always)]
pub(super) fn each_quad(
    ext: Extent,
    rows: &impl Rows,
    mut f: impl FnMut(usize, usize, usize, usize, [usize; 4]),
) {
    for k in 0..ext.planes {
        for y in (0..ext.rows).step_by(2) {
            let r0 = rows.row(k, y);
            let r1 = if y + 1 < ext.rows {
                rows.row(k, y + 1)
            } else {
                r0
            };
            for x in (0..ext.cols).step_by(2) {
                let at = [r0 + x, r0 + x + 1, r1 + x, r1 + x + 1];
                f(k, y, x, valid_bits(ext, y, x), at);
            }
        }
    }
}

/// How a block's positions map to the band: `get(k, y)` = offset in the band of the
/// block's row `y` of plane `k`; the parent's magnitude of quad `(k, y, x)` by `parent`.
pub trait Rows {
    fn row(&self, k: usize, y: usize) -> usize;
    fn parent(&self, k: usize, y: usize, x: usize) -> u32;
}

/// Code the block of `band` (indices) laid out by `rows` into `e` and `w`.
pub fn encode(
    band: &[i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    (limit, trained, signs): (u8, bool, bool),
    mut counts: Option<&mut Counts>,
    (e, w): (&mut Encoder, &mut BitWriter),
) {
    let mut m = Models::new(limit, trained);
    s.clear();
    if signs {
        s.clear_signs();
    }
    let off = quad_offsets(s.rx);
    each_quad(ext, rows, |k, y, x, valid, at| {
        let mut pattern = 0;
        for (b, &a) in at.iter().enumerate() {
            if valid >> b & 1 == 1 && band[a] != 0 {
                pattern |= 1 << b;
            }
        }
        let i = s.at(k, y, x);
        let pm = rows.parent(k, y, x);
        let pc = s.pattern_ctx(i, pm);
        e.symbol(&mut m.pattern[pc], pattern);
        if let Some(n) = counts.as_deref_mut() {
            n.pattern[pc][pattern] += 1;
        }
        for b in 0..4 {
            if pattern >> b & 1 == 1 {
                let v = band[at[b]];
                let c = s.mag_ctx(i + off[b], pm);
                let a = v.unsigned_abs();
                if let Some(n) = counts.as_deref_mut() {
                    let k = c.saturating_sub(KOFF) as u32;
                    n.magnitude[c][(((a - 1) as u64 >> k).min(15)) as usize] += 1;
                }
                let j = i + off[b];
                if signs {
                    put_magnitude(e, w, &mut m.mag[c], c, a, None);
                    e.bit(&mut m.sign[s.sign_ctx(j)], v < 0, limit);
                    s.sgn[j] = 1 + (v < 0) as u8;
                } else {
                    put_magnitude(e, w, &mut m.mag[c], c, a, Some(v < 0));
                }
                s.mag[j] = a.min(CAP);
            }
        }
    });
}

/// Choose the indices of a detail block by rate–distortion and code them as [`encode`]
/// codes them: `x` holds the coefficients divided by the band's step at the positions
/// `rows` gives, `q` receives the indices chosen there. Each coefficient of magnitude
/// `|x|` may take `a₀ = round(|x|)`, `a₀ − 1` (when ≥ 1) or 0; with `J(a) = (|x| − a)² +
/// λ·bits(a)` read from the block's models as they stand:
///
/// - the quad's pattern is the subset `S` of its coefficients with `a₀ ≥ 1` minimising
///   `λ·bits(S) + Σ_{S} min(J(a₀), J(a₀ − 1)) + Σ_{not S} |x|²`, the non-zero costs
///   estimated with the quad's earlier coefficients at `a₀`;
/// - then each coefficient of `S`, in order, takes the one of `a₀`, `a₀ − 1` (≥ 1)
///   with the least `J`, its magnitude context now the coded one.
///
/// `λ = 0` gives `a₀` everywhere (rounding).
// the block's values and indices, its layout, scratch and models, λ, the streams
#[allow(clippy::too_many_arguments)]
pub fn encode_rdo(
    x: &[f32],
    q: &mut [i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    (limit, trained, signs): (u8, bool, bool),
    lambda: f32,
    (e, w): (&mut Encoder, &mut BitWriter),
) {
    let mut m = Models::new(limit, trained);
    s.clear();
    if signs {
        s.clear_signs();
    }
    let off = quad_offsets(s.rx);
    let sign_cost = |m: &Models, s: &Scratch, j: usize, neg: bool| {
        if signs {
            m.sign[s.sign_ctx(j)].cost_fast(neg)
        } else {
            1.0
        }
    };
    each_quad(ext, rows, |k, y, xq, valid, at| {
        let i = s.at(k, y, xq);
        let pm = rows.parent(k, y, xq);
        let mut a0 = [0u32; 4];
        let mut ax = [0f32; 4];
        let mut cand = 0usize;
        for b in 0..4 {
            if valid >> b & 1 == 1 {
                q[at[b]] = 0;
                let t = x[at[b]].abs();
                if t.is_finite() {
                    let r = (t + 0.5).min(2.0e9) as u32;
                    (a0[b], ax[b]) = (r, t);
                    cand |= ((r > 0) as usize) << b;
                }
            }
        }
        let pc = s.pattern_ctx(i, pm);
        let mut pattern = cand;
        if cand != 0 && lambda > 0.0 {
            // the non-zero choices' costs, the quad's earlier coefficients at a₀
            for b in 0..4 {
                if cand >> b & 1 == 1 {
                    s.mag[i + off[b]] = a0[b].min(CAP);
                    if signs {
                        s.sgn[i + off[b]] = 1 + (x[at[b]] < 0.0) as u8;
                    }
                }
            }
            let mut nz = [0f32; 4];
            let mut z = [0f32; 4];
            for b in 0..4 {
                if cand >> b & 1 == 1 {
                    let j = i + off[b];
                    let c = s.mag_ctx(j, pm);
                    let sc = sign_cost(&m, s, j, x[at[b]] < 0.0);
                    nz[b] = best_magnitude(&m.mag[c], c, a0[b], ax[b], lambda).1 + lambda * sc;
                    z[b] = ax[b] * ax[b];
                }
            }
            for (b, &o) in off.iter().enumerate() {
                if cand >> b & 1 == 1 {
                    s.mag[i + o] = 0;
                    if signs {
                        s.sgn[i + o] = 0;
                    }
                }
            }
            let cdf = &m.pattern[pc];
            let mut best = f32::INFINITY;
            let mut sub = cand;
            loop {
                let mut j = lambda * cdf.cost_fast(sub);
                for b in 0..4 {
                    if cand >> b & 1 == 1 {
                        j += if sub >> b & 1 == 1 { nz[b] } else { z[b] };
                    }
                }
                if j < best {
                    (best, pattern) = (j, sub);
                }
                if sub == 0 {
                    break;
                }
                sub = (sub - 1) & cand;
            }
        }
        e.symbol(&mut m.pattern[pc], pattern);
        for b in 0..4 {
            if pattern >> b & 1 == 1 {
                let j = i + off[b];
                let c = s.mag_ctx(j, pm);
                let a = if lambda > 0.0 {
                    best_magnitude(&m.mag[c], c, a0[b], ax[b], lambda).0
                } else {
                    a0[b]
                };
                let neg = x[at[b]] < 0.0;
                q[at[b]] = if neg { -(a as i32) } else { a as i32 };
                if signs {
                    put_magnitude(e, w, &mut m.mag[c], c, a, None);
                    e.bit(&mut m.sign[s.sign_ctx(j)], neg, limit);
                    s.sgn[j] = 1 + neg as u8;
                } else {
                    put_magnitude(e, w, &mut m.mag[c], c, a, Some(neg));
                }
                s.mag[j] = a.min(CAP);
            }
        }
    });
}

/// Of `a₀` and `a₀ − 1` (when ≥ 1), the magnitude with the least
/// `(|x| − a)² + λ·bits(a)` in magnitude class `c`, and that cost (sign not counted).
#[inline(always)]
fn best_magnitude(cdf: &Cdf, c: usize, a0: u32, ax: f32, lambda: f32) -> (u32, f32) {
    let d = ax - a0 as f32;
    let j0 = d * d + lambda * magnitude_bits(cdf, c, a0);
    if a0 < 2 {
        return (a0, j0);
    }
    let d = ax - (a0 - 1) as f32;
    let j1 = d * d + lambda * magnitude_bits(cdf, c, a0 - 1);
    if j1 < j0 {
        (a0 - 1, j1)
    } else {
        (a0, j0)
    }
}

/// The bits of magnitude `a ≥ 1` in class `c` as [`put_magnitude`] codes it, sign
/// left out.
#[inline(always)]
fn magnitude_bits(cdf: &Cdf, c: usize, a: u32) -> f32 {
    let k = c.saturating_sub(KOFF) as u32;
    let h = (a - 1) >> k;
    if h < 15 {
        cdf.cost_fast(h as usize) + k as f32
    } else {
        cdf.cost_fast(15) + (6 + (h - 14).ilog2() + k) as f32
    }
}

#[inline(always)]
fn put_magnitude(
    e: &mut Encoder,
    w: &mut BitWriter,
    cdf: &mut Cdf,
    c: usize,
    a: u32,
    neg: Option<bool>,
) {
    let k = c.saturating_sub(KOFF) as u32;
    let v = (a - 1) as u64;
    let h = v >> k;
    if h < 15 {
        e.symbol(cdf, h as usize);
    } else {
        e.symbol(cdf, 15);
        let x = h - 14;
        let nb = x.ilog2();
        w.put(nb as u64, 6);
        w.put(x, nb);
    }
    match neg {
        Some(neg) => w.put(((v & ((1 << k) - 1)) << 1) | neg as u64, k + 1),
        None => w.put(v & ((1 << k) - 1), k),
    }
}

/// Decode a block written by [`encode`] into `band`, which holds zeros at the block's
/// positions (the others are not touched). A damaged stream decodes to some values, never a panic.
pub fn decode(
    band: &mut [i32],
    ext: Extent,
    rows: &impl Rows,
    s: &mut Scratch,
    (limit, trained, signs): (u8, bool, bool),
    d: &mut Decoder,
    r: &mut BitReader,
) {
    let mut m = Models::new(limit, trained);
    s.clear();
    if signs {
        s.clear_signs();
    }
    let off = quad_offsets(s.rx);
    each_quad(ext, rows, |k, y, x, valid, at| {
        let i = s.at(k, y, x);
        let pm = rows.parent(k, y, x);
        let pattern = d.symbol(&mut m.pattern[s.pattern_ctx(i, pm)]) & valid;
        let mut bits = pattern;
        while bits != 0 {
            let b = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let j = i + off[b];
            let c = s.mag_ctx(j, pm);
            let (a, neg) = if signs {
                let a = get_magnitude(d, r, &mut m.mag[c], c, false).0;
                let neg = d.bit(&mut m.sign[s.sign_ctx(j)], limit);
                s.sgn[j] = 1 + neg as u8;
                (a, neg)
            } else {
                get_magnitude(d, r, &mut m.mag[c], c, true)
            };
            band[at[b]] = if neg {
                (a as u32 as i32).wrapping_neg()
            } else {
                a as u32 as i32
            };
            s.mag[j] = a.min(CAP as u64) as u32;
        }
    });
}

#[inline(always)]
fn get_magnitude(
    d: &mut Decoder,
    r: &mut BitReader,
    cdf: &mut Cdf,
    c: usize,
    sign: bool,
) -> (u64, bool) {
    let k = c.saturating_sub(KOFF) as u32;
    let mut h = d.symbol(cdf) as u64;
    if h == 15 {
        let nb = (r.get(6) as u32).min(32);
        h = ((1u64 << nb) | r.get(nb)) + 14;
    }
    if !sign {
        return (((h << k) | r.get(k)) + 1, false);
    }
    let low = r.get(k + 1);
    (((h << k) | (low >> 1)) + 1, low & 1 == 1)
}
