//! Two rows of an operator combined in one pass over the inputs they share.
//!
//! A job is described by types rather than loose arguments, as zfp's `zfp_field`
//! describes an array: [`PairRows`] (each row's weights and mask over the shared inputs,
//! and the pair kernel that serves them, looked up once), [`PairOut`] (where one step's
//! two outputs go) and [`PairGrid`] (many steps: lanes, or whole rows of a plane, with a
//! [`PairOutput`] layout). One entry per job: [`combine_pair`] (one step),
//! [`combine_pair_grid`] (many) and [`combine_pair_taps`] (two sparse rows).

use super::*;

/// The two rows of a pair over the same `u` inputs: each one's weight per input (`w1`,
/// `w2`, `u` each) and the mask of the inputs it reads (bit `k`: input `k`; non-empty,
/// within the inputs), and `entry`, the pair kernel's table entry ([`pair_entry`] of the
/// rows where the build has the pair kernels, `None` for one output at a time).
///
/// Each output sums its taps in increasing `k`, the first assigning, so the bits are
/// those of one [`combine`] per output over its own taps; each input is loaded once for
/// both outputs (e.g. a coarse and a detail row, or an even and an odd fine row, which
/// read the same stretch of their lane: the loads, not the multiplies, bound the single
/// combines).
#[derive(Clone, Copy, Debug)]
pub struct PairRows<'a, T> {
    pub w1: &'a [T],
    pub m1: u32,
    pub w2: &'a [T],
    pub m2: u32,
    pub entry: Option<u8>,
}

impl<'a, T: Sample> PairRows<'a, T> {
    /// The pair `(w1, m1)`, `(w2, m2)`, its entry looked up for the build of `k` (callers
    /// that apply one pair many times look it up once: [`super::polyphase::Pair`] holds
    /// its entries, [`PairMemo`] remembers the last).
    pub fn new(k: Kernels, (w1, m1): (&'a [T], u32), (w2, m2): (&'a [T], u32)) -> Self {
        let entry = if k.avx2() {
            pair_entry(w1, m1, w2, m2)
        } else {
            None
        };
        PairRows {
            w1,
            m1,
            w2,
            m2,
            entry,
        }
    }

    /// The weights and masks over `u` inputs ([`check_pair`]).
    fn check(&self, u: usize) {
        check_pair(u, self.w1, self.m1, self.w2, self.m2)
    }
}

/// How a pair's two outputs are written, step by step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairOutput {
    /// Each at its own place, samples in order.
    Apart,
    /// Each at its own place, its even samples, then its odd ones, as [`deinterleave`]
    /// places them (for a next axis that reads them so: the same bits, without a pass of
    /// its own).
    Split,
    /// Interleaved at the first place, `(a0 b0 a1 b1 …)`, twice as long (the even and
    /// the odd fine samples of synthesis, without a pass through two buffers and
    /// [`interleave`]).
    Merged,
}

/// Where one step of a pair writes: the two outputs in the layout of [`PairOutput`] (the
/// inputs hold at least as many samples as each output).
#[derive(Debug)]
pub enum PairOut<'o, T> {
    /// [`PairOutput::Apart`]: the first output, the second (as long).
    Apart(&'o mut [T], &'o mut [T]),
    /// [`PairOutput::Split`]: the first output, the second (as long).
    Split(&'o mut [T], &'o mut [T]),
    /// [`PairOutput::Merged`]: both (an even length); written only where the pair has a
    /// vector build.
    Merged(&'o mut [T]),
}

/// One step of `pair` over the inputs `src` into `out`:
/// `o1[i] = Σ_{k ∈ m1} w1[k]·src[k][i]` and `o2[i] = Σ_{k ∈ m2} w2[k]·src[k][i]`, in
/// the layout of `out`. Every `src[k]` holds at least as many samples as each output.
/// Whether it wrote: always, but for [`PairOut::Merged`] without a vector build for the
/// pair or the type. The build is `k`'s; the bits every build's.
pub fn combine_pair<T: Sample>(
    k: Kernels,
    pair: &PairRows<T>,
    src: &[&[T]],
    out: PairOut<'_, T>,
) -> bool {
    let u = src.len();
    pair.check(u);
    let split = matches!(out, PairOut::Split(..));
    match out {
        PairOut::Apart(o1, o2) | PairOut::Split(o1, o2) => {
            assert!(o1.len() == o2.len() && src.iter().all(|s| s.len() >= o1.len()));
            #[cfg(target_arch = "x86_64")]
            if let (true, Some(entry)) = (k.avx2(), pair.entry) {
                let p = input_ptrs(src);
                let o = [o1.as_mut_ptr(), o2.as_mut_ptr()];
                let output = if split {
                    PairOutput::Split
                } else {
                    PairOutput::Apart
                };
                // SAFETY: AVX2 (and AVX-512 at that level) present; lengths and masks
                // checked above; one step.
                if unsafe {
                    pair_avx2_at(
                        entry,
                        pair,
                        &PairSteps::one(o, o1.len(), &p[..u], output),
                        k.level(),
                    )
                } {
                    return true;
                }
            }
            pair_by_parts(k, o1, o2, src, pair);
            if split {
                for o in [o1, o2] {
                    let whole = o.to_vec();
                    deinterleave(k, &whole, 1, o);
                }
            }
            true
        }
        PairOut::Merged(out) => {
            assert!(out.len().is_multiple_of(2));
            let len = out.len() / 2;
            assert!(src.iter().all(|s| s.len() >= len));
            #[cfg(target_arch = "x86_64")]
            if let (true, Some(entry)) = (k.avx2(), pair.entry) {
                let p = input_ptrs(src);
                let o = [out.as_mut_ptr(), out.as_mut_ptr()];
                // SAFETY: AVX2 is present, AVX-512F at the table's level; `out` holds
                // 2·len samples, every input len; one step, the merged output written
                // through the first pointer only.
                return unsafe {
                    pair_avx2_at(
                        entry,
                        pair,
                        &PairSteps::one(o, len, &p[..u], PairOutput::Merged),
                        k.level(),
                    )
                };
            }
            let _ = out;
            false
        }
    }
}

/// Where a pair kernel reads and writes: `count` steps, step `t` reading input `k` at
/// `src[k] + t·in_step` and writing output `j` at `o[j] + t·out_step[j]`, `len` samples
/// each (twice that through `o[0]` when [`PairOutput::Merged`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairSteps<'a, T> {
    pub o: [*mut T; 2],
    pub len: usize,
    pub src: &'a [*const T],
    pub count: usize,
    pub in_step: usize,
    pub out_step: [usize; 2],
    pub output: PairOutput,
}

impl<'a, T> PairSteps<'a, T> {
    /// One step.
    pub(crate) fn one(o: [*mut T; 2], len: usize, src: &'a [*const T], output: PairOutput) -> Self {
        PairSteps {
            o,
            len,
            src,
            count: 1,
            in_step: 0,
            out_step: [0, 0],
            output,
        }
    }
}

/// [`combine_pair`] over two sparse rows (`(columns, weights)`, columns increasing) and
/// the inputs `tap(c)` of their columns: the first row to `out`'s first output, the
/// second to its second, each input they share read once. `false` (nothing written) when
/// the rows share no column, read more than [`PAIR_INPUTS`] inputs together or have no
/// vector build of the pair kernels at this CPU level (then two [`combine_taps`] do the
/// same).
///
/// `memo` remembers the last pair's pattern (the regular row pairs repeat one).
pub fn combine_pair_taps<'t, T: Sample + 't>(
    k: Kernels,
    memo: &mut PairMemo<T>,
    rows: [(&[u32], &[f64]); 2],
    out: PairOut<'_, T>,
    tap: impl Fn(u32) -> &'t [T],
) -> bool {
    let [(c1, w1), (c2, w2)] = rows;
    let Some((cols, n, m1, m2)) = pair_columns(c1, c2) else {
        return false;
    };
    // each row's weights over the columns it reads (in order: its mask's bits)
    let (mut a, mut b) = ([T::default(); PAIR_INPUTS], [T::default(); PAIR_INPUTS]);
    for (out, m, w) in [(&mut a, m1, w1), (&mut b, m2, w2)] {
        let mut i = 0;
        for (k, o) in out.iter_mut().enumerate().take(n) {
            if m >> k & 1 == 1 {
                *o = T::from_f64(w[i]);
                i += 1;
            }
        }
    }
    let mut src: [&[T]; PAIR_INPUTS] = [&[]; PAIR_INPUTS];
    for k in 0..n {
        src[k] = tap(cols[k]);
    }
    let entry = if k.avx2() {
        memo.entry(&a[..n], m1, &b[..n], m2)
    } else {
        None
    };
    // without a vector build the pair would be two combines anyway (and a split
    // written through a copy)
    if entry.is_none() {
        return false;
    }
    let pair = PairRows {
        w1: &a[..n],
        m1,
        w2: &b[..n],
        m2,
        entry,
    };
    combine_pair(k, &pair, &src[..n], out)
}

/// Most inputs two rows combined together by [`combine_pair_taps`] may read.
pub const PAIR_INPUTS: usize = PAIR_KERNEL_MOST;

/// Whether [`combine_pair_taps`] combines two rows reading the columns `c1` and `c2`
/// (increasing) together: they share a column and read at most [`PAIR_INPUTS`] together.
pub fn rows_pair(c1: &[u32], c2: &[u32]) -> bool {
    pair_columns(c1, c2).is_some()
}

/// The columns that two rows (their increasing columns `c1`, `c2`) read together, how
/// many, and each row's mask over them; `None` when the rows share no column or read
/// more than [`PAIR_INPUTS`] together.
pub(crate) fn pair_columns(
    c1: &[u32],
    c2: &[u32],
) -> Option<([u32; PAIR_INPUTS], usize, u32, u32)> {
    let mut cols = [0u32; PAIR_INPUTS];
    let (mut m1, mut m2) = (0u32, 0u32);
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < c1.len() || j < c2.len() {
        if n == PAIR_INPUTS {
            return None;
        }
        let c = match (c1.get(i), c2.get(j)) {
            (Some(&x), Some(&y)) => x.min(y),
            (Some(&x), None) => x,
            (None, Some(&y)) => y,
            (None, None) => unreachable!("one list goes on"),
        };
        cols[n] = c;
        if c1.get(i) == Some(&c) {
            m1 |= 1 << n;
            i += 1;
        }
        if c2.get(j) == Some(&c) {
            m2 |= 1 << n;
            j += 1;
        }
        n += 1;
    }
    // (empty rows share nothing)
    (m1 & m2 != 0).then_some((cols, n, m1, m2))
}

/// The weights and masks of a pair over `u` inputs: at most 32 inputs, a weight per input
/// and output, each mask non-empty and within the inputs.
pub(crate) fn check_pair<T>(u: usize, w1: &[T], m1: u32, w2: &[T], m2: u32) {
    assert!(u <= 32 && w1.len() == u && w2.len() == u);
    let all = if u == 32 { u32::MAX } else { (1u32 << u) - 1 };
    assert!(m1 != 0 && m2 != 0 && m1 & !all == 0 && m2 & !all == 0);
}

/// The start of every input (at most 32), null past them.
pub(crate) fn input_ptrs<T>(src: &[&[T]]) -> [*const T; 32] {
    std::array::from_fn(|k| src.get(k).map_or(std::ptr::null(), |s| s.as_ptr()))
}

/// [`combine_pair`] as one [`combine`] per output (the patterns without an AVX2 build,
/// and the reference the tests compare with).
pub(crate) fn pair_by_parts<T: Sample>(
    k: Kernels,
    o1: &mut [T],
    o2: &mut [T],
    src: &[&[T]],
    pair: &PairRows<T>,
) {
    let PairRows { w1, m1, w2, m2, .. } = *pair;
    for (o, w, m) in [(o1, w1, m1), (o2, w2, m2)] {
        let mut s: [&[T]; 32] = [&[]; 32];
        let mut wk = [T::default(); 32];
        let mut n = 0;
        for k in (0..src.len()).filter(|&k| m >> k & 1 == 1) {
            (s[n], wk[n]) = (src[k], w[k]);
            n += 1;
        }
        combine(k, o, &s[..n], &wk[..n]);
    }
}

/// The pairs and the unit weights of one output of a pair over the inputs `w` (its taps
/// those of `mask`, in increasing `k`): `(p, n, r)` with `p` / `n` the terms (single taps
/// and pairs' first taps) of weight +1 / −1, which the kernels add or subtract instead of
/// multiplying (the same bits), and `r` the pairs of [`pair_taps`]: field `k` of it
/// ([`PAIR_FIELD`] bits) is `j + 1` for a pair `(k, j)` ([`pair_code`]).
pub(crate) fn pattern_of<T: Sample>(w: &[T], mask: u32) -> (u32, u32, u128) {
    let (mut p, mut n, mut r) = (0u32, 0u32, 0u128);
    let mut left = mask & ((1u64 << w.len().min(32)) - 1) as u32;
    while left != 0 {
        let k = left.trailing_zeros() as usize;
        left &= left - 1;
        let wk = w[k];
        // the next tap of the same weight not yet paired
        let mut later = left;
        while later != 0 {
            let j = later.trailing_zeros() as usize;
            later &= later - 1;
            if w[j] == wk {
                r |= ((j + 1) as u128) << (PAIR_FIELD * k);
                left &= !(1 << j);
                break;
            }
        }
        if wk == T::from_f64(1.0) {
            p |= 1 << k;
        } else if wk == T::from_f64(-1.0) {
            n |= 1 << k;
        }
    }
    (p, n, r)
}

/// Bits per input in a pattern's pairs ([`pattern_of`]): `j + 1 ≤ 24` for the
/// [`PAIR_KERNEL_MOST`] inputs.
pub(crate) const PAIR_FIELD: usize = 5;

/// Most inputs of a pair with a vector build (the table in `patterns.rs`).
pub const PAIR_KERNEL_MOST: usize = 24;

/// The pairs `(k, j)` (`k < j`) of one output as [`pattern_of`] encodes them, for the
/// pattern table: field `k` holds `j + 1`.
pub(crate) const fn pair_code(pairs: &[(usize, usize)]) -> u128 {
    let mut r = 0u128;
    let mut i = 0;
    while i < pairs.len() {
        let (k, j) = pairs[i];
        r |= ((j + 1) as u128) << (PAIR_FIELD * k);
        i += 1;
    }
    r
}

/// The patterns `(P1, N1, P2, N2, R1, R2)` of the table entries that serve the pair
/// `(w1, m1)`, `(w2, m2)`, best first: the entry with its unit taps and pairs; then,
/// when no taps pair, the plain entry (every tap multiplied: the same bits).
#[allow(clippy::type_complexity)]
pub(crate) fn pair_wants<T: Sample>(
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) -> [Option<(u32, u32, u32, u32, u128, u128)>; 2] {
    let ((p1, n1, r1), (p2, n2, r2)) = (pattern_of(w1, m1), pattern_of(w2, m2));
    let exact = (p1, n1, p2, n2, r1, r2);
    let plain = (0, 0, 0, 0, 0, 0);
    let also = ((r1, r2) == (0, 0) && exact != plain).then_some(plain);
    [Some(exact), also]
}

/// [`seconds`] of a pattern's pairs, as a constant of the kernel built for it.
pub(crate) struct Seconds<const R: u128>;
impl<const R: u128> Seconds<R> {
    pub(crate) const MASK: u32 = seconds(R);
}

/// The second taps of the pairs `r` (as [`pattern_of`] gives them).
pub(crate) const fn seconds(r: u128) -> u32 {
    let mut m = 0u32;
    let mut k = 0;
    while k < PAIR_KERNEL_MOST {
        let j = (r >> (PAIR_FIELD * k)) & 31;
        if j > 0 {
            m |= 1 << (j - 1);
        }
        k += 1;
    }
    m
}

/// The entry of the pattern table (`pair_patterns`) that serves the pair `(w1, m1)`,
/// `(w2, m2)` over `w1.len()` inputs (the first of `pair_wants` that has one), or `None`
/// when none does: what the pair dispatch looks up on every call, for callers that use
/// one pair many times to look up once ([`PairMemo`], [`super::polyphase::Pair`]).
pub fn pair_entry<T: Sample>(w1: &[T], m1: u32, w2: &[T], m2: u32) -> Option<u8> {
    let u = w1.len();
    if u > PAIR_KERNEL_MOST || w2.len() != u {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    {
        let wants = pair_wants(w1, m1, w2, m2);
        macro_rules! find {
            ($(($U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal, $R1:expr, $R2:expr)),*) => {
                for want in wants.into_iter().flatten() {
                    let mut idx = 0u8;
                    $(
                        if (u, m1, m2) == ($U, $M1, $M2) && want == ($P1, $N1, $P2, $N2, $R1, $R2) {
                            return Some(idx);
                        }
                        idx += 1;
                    )*
                    let _ = idx;
                }
            };
        }
        pair_patterns!(find);
    }
    let _ = (m1, m2);
    None
}

/// A pair's table entry remembered for the next call with the same weights and masks
/// (one entry: the row pairs of an operator's regular rows repeat one pattern), so that
/// [`combine_pair_taps`] looks up [`pair_entry`] once per pattern rather than once
/// per call.
#[derive(Clone, Debug)]
pub struct PairMemo<T> {
    key: Option<MemoKey<T>>,
    entry: Option<u8>,
}

/// A pair as [`PairMemo`] knows it: the inputs' count, the masks and the weights.
pub(crate) type MemoKey<T> = (usize, u32, u32, [T; PAIR_INPUTS], [T; PAIR_INPUTS]);

impl<T: Sample> Default for PairMemo<T> {
    fn default() -> Self {
        PairMemo {
            key: None,
            entry: None,
        }
    }
}

impl<T: Sample> PairMemo<T> {
    /// [`pair_entry`] of the pair, from the memo when it holds this pair.
    pub(crate) fn entry(&mut self, w1: &[T], m1: u32, w2: &[T], m2: u32) -> Option<u8> {
        let u = w1.len();
        if u > PAIR_INPUTS {
            return pair_entry(w1, m1, w2, m2);
        }
        let (mut a, mut b) = ([T::default(); PAIR_INPUTS], [T::default(); PAIR_INPUTS]);
        a[..u].copy_from_slice(w1);
        b[..u].copy_from_slice(&w2[..u]);
        let key = (u, m1, m2, a, b);
        if self.key.as_ref() != Some(&key) {
            self.entry = pair_entry(w1, m1, w2, m2);
            self.key = Some(key);
        }
        self.entry
    }
}

/// Whether [`combine_pair`] has a vector build for the pair `(w1, m1)`, `(w2, m2)` (its
/// inputs' count, masks, unit weights and pairs one of the built patterns): the regular
/// rows of every scheme have one (tested), other pairs go one output at a time.
#[cfg(any(test, feature = "testing"))]
pub fn combine_pair_has_build<T: Sample>(w1: &[T], m1: u32, w2: &[T], m2: u32) -> bool {
    pair_entry(w1, m1, w2, m2).is_some()
}

/// What the positions of a [`PairGrid`] count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridUnit {
    /// Samples: the steps are lanes (e.g. every row of a volume's plane along its last
    /// axis, the weights kept in registers).
    Samples,
    /// Rows of `len` samples: the elements of a lane are whole rows (e.g. the lanes of a
    /// volume's plane along another axis).
    Rows,
}

/// The steps of a pair job: step `t` reads input `k` at `src[off[k] + in_step·t ..]`
/// and writes output `j` at `dst[out[j] + out_step[j]·t ..]`, `len` samples each
/// (positions in `unit`s), in the layout `output` ([`PairOutput::Merged`]: both outputs
/// interleaved at `out[0]`, `2·len` samples). No two outputs of any steps may overlap.
#[derive(Clone, Copy, Debug)]
pub struct PairGrid<'a> {
    pub off: &'a [usize],
    pub in_step: usize,
    pub out: [usize; 2],
    pub out_step: [usize; 2],
    pub len: usize,
    pub count: usize,
    pub unit: GridUnit,
    pub output: PairOutput,
}

/// [`combine_pair`] for every step of `grid`, in one dispatch: the same bits as
/// [`combine_pair`] step by step (`pair.entry` as [`PairRows`] says).
pub fn combine_pair_grid<T: Sample>(
    k: Kernels,
    pair: &PairRows<T>,
    src: &[T],
    dst: &mut [T],
    grid: &PairGrid,
) {
    let u = grid.off.len();
    pair.check(u);
    let (len, count) = (grid.len, grid.count);
    if count == 0 || len == 0 {
        return;
    }
    let unit = match grid.unit {
        GridUnit::Samples => 1,
        GridUnit::Rows => len,
    };
    let merge = grid.output == PairOutput::Merged;
    let width = if merge { 2 * len } else { len };
    let last = count - 1;
    let mut off = [0usize; 32];
    for (o, &c) in off.iter_mut().zip(grid.off) {
        *o = c * unit;
    }
    let g = PairGrid {
        off: &off[..u],
        in_step: grid.in_step * unit,
        out: grid.out.map(|o| o * unit),
        out_step: grid.out_step.map(|s| s * unit),
        unit: GridUnit::Samples,
        ..*grid
    };
    assert!(g
        .off
        .iter()
        .all(|&o| o + g.in_step * last + len <= src.len()));
    let outputs = if merge { 1 } else { 2 };
    for j in 0..outputs {
        assert!(g.out[j] + g.out_step[j] * last + width <= dst.len());
        assert!(
            count == 1 || g.out_step[j] >= width,
            "a pair output overlaps itself"
        );
    }
    assert!(
        merge || outputs_apart(&g, width),
        "the two outputs of a pair overlap"
    );
    // SAFETY: every input and output stretch is inside its slice, and no two outputs of
    // any steps overlap (asserted above).
    unsafe { pair_steps(k, pair, src, dst, &g) }
}

/// Whether no step's first output (`width` samples) meets any step's second, the
/// positions of `g` in samples.
fn outputs_apart(g: &PairGrid, width: usize) -> bool {
    let last = g.count as i128 - 1;
    let (a, b) = (g.out[0] as i128, g.out[1] as i128);
    let (s0, s1, w) = (g.out_step[0] as i128, g.out_step[1] as i128, width as i128);
    if s0 == s1 && s0 > 0 {
        // |b − a + s·n| ≥ w for every n = t' − t in −last ..= last: the nearest n to
        // (a − b)/s decides (|d + s·n| falls, then rises)
        let d = b - a;
        let f = (-d).div_euclid(s0);
        [f, f + 1]
            .iter()
            .all(|&n| (d + s0 * n.clamp(-last, last)).abs() >= w)
    } else {
        let (end0, end1) = (a + s0 * last + w, b + s1 * last + w);
        end0 <= b || end1 <= a
    }
}

/// The steps of [`combine_pair_grid`], `g`'s positions in samples.
///
/// # Safety
/// Every input and output stretch of every step inside its slice, and no two outputs of
/// any steps overlapping; weights and masks as [`check_pair`] checks them.
unsafe fn pair_steps<T: Sample>(
    k: Kernels,
    pair: &PairRows<T>,
    src: &[T],
    dst: &mut [T],
    g: &PairGrid,
) {
    let PairGrid {
        off,
        in_step,
        out,
        out_step,
        len,
        count,
        output,
        ..
    } = *g;
    let u = off.len();
    let p = input_ptrs_at(src, off);
    let merge = output == PairOutput::Merged;
    #[cfg(target_arch = "x86_64")]
    if k.avx2() {
        let d = dst.as_mut_ptr();
        // SAFETY: AVX2 is present (AVX-512F too at the table's level); every
        // input and output stretch lies inside its slice and the outputs of all steps are
        // disjoint (the caller's contract), and `src`, `dst` are distinct slices
        // (borrowed shared and exclusive).
        let done = pair.entry.is_some_and(|entry| unsafe {
            // (merged: both through the first pointer)
            let o = [d.add(out[0]), d.add(if merge { out[0] } else { out[1] })];
            let at = PairSteps {
                o,
                len,
                src: &p[..u],
                count,
                in_step,
                out_step,
                output,
            };
            pair_avx2_at(entry, pair, &at, k.level())
        });
        if done {
            return;
        }
    }
    let _ = p;
    let (mut a, mut b) = (vec![T::default(); len], vec![T::default(); len]);
    for t in 0..count {
        let mut s: [&[T]; 32] = [&[]; 32];
        for (k, &o) in off.iter().enumerate() {
            s[k] = &src[o + in_step * t..][..len];
        }
        pair_by_parts(k, &mut a, &mut b, &s[..u], pair);
        let at = [out[0] + out_step[0] * t, out[1] + out_step[1] * t];
        if merge {
            let o = &mut dst[at[0]..][..2 * len];
            for i in 0..len {
                (o[2 * i], o[2 * i + 1]) = (a[i], b[i]);
            }
        } else if output == PairOutput::Split {
            deinterleave(k, &a, 1, &mut dst[at[0]..][..len]);
            deinterleave(k, &b, 1, &mut dst[at[1]..][..len]);
        } else {
            dst[at[0]..][..len].copy_from_slice(&a);
            dst[at[1]..][..len].copy_from_slice(&b);
        }
    }
}

/// The inputs at `off[k]` of `src` (at most 32), null past them.
pub(crate) fn input_ptrs_at<T>(src: &[T], off: &[usize]) -> [*const T; 32] {
    assert!(off.len() <= 32);
    std::array::from_fn(|k| off.get(k).map_or(std::ptr::null(), |&o| src[o..].as_ptr()))
}
