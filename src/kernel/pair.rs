//! Two rows of an operator combined in one pass over the inputs they share.

use super::*;

/// Two [`combine`]s over one set of inputs: `o1[i] = Σ_{k ∈ m1} w1[k]·src[k][i]` and
/// `o2[i] = Σ_{k ∈ m2} w2[k]·src[k][i]`, where bit `k` of a mask says that input `k` is
/// one of that output's taps. Each output sums its taps in increasing `k`, the first
/// assigning, so the bits are those of one [`combine`] per output over its own taps;
/// each input is loaded once for both outputs (e.g. a coarse and a detail row, or an even
/// and an odd fine row, which read the same stretch of their lane: the loads, not the
/// multiplies, bound the single combines).
///
/// Every `src[k]` must hold at least `o1.len()` samples; `o2` as long as `o1`; both masks
/// non-empty and within `src`. The build is `k`'s.
#[cfg(any(test, feature = "testing"))]
#[allow(clippy::too_many_arguments)]
pub fn combine_pair<T: Sample>(
    k: Kernels,
    o1: &mut [T],
    o2: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) {
    let entry = if k.avx2() {
        pair_entry(w1, m1, w2, m2)
    } else {
        None
    };
    combine_pair_at(k, entry, o1, o2, src, w1, m1, w2, m2, false)
}

/// [`combine_pair`] with the pair's [`pair_entry`] looked up before (`entry` must be it,
/// or `None` for one output at a time); `split`: each output split into its even
/// samples, then its odd ones, as [`deinterleave`] places them (the same bits).
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_at<T: Sample>(
    k: Kernels,
    entry: Option<u8>,
    o1: &mut [T],
    o2: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
    split: bool,
) {
    let u = src.len();
    check_pair(u, w1, m1, w2, m2);
    assert!(o1.len() == o2.len() && src.iter().all(|s| s.len() >= o1.len()));
    #[cfg(target_arch = "x86_64")]
    if let (true, Some(entry)) = (k.avx2(), entry) {
        let p = input_ptrs(src);
        let o = [o1.as_mut_ptr(), o2.as_mut_ptr()];
        // SAFETY: AVX2 (and AVX-512 at that level) present; lengths and masks checked
        // above; one step.
        if unsafe {
            pair_avx2_at(
                entry,
                PairRows { w1, m1, w2, m2 },
                &PairSteps::one(o, o1.len(), &p[..u], PairOutput::apart_or_split(split)),
                k.level(),
            )
        } {
            return;
        }
    }
    let _ = entry;
    pair_by_parts(k, o1, o2, src, w1, m1, w2, m2);
    if split {
        for o in [o1, o2] {
            let whole = o.to_vec();
            deinterleave(k, &whole, 1, o);
        }
    }
}

/// The two rows of a pair over the same inputs: each one's weight per input and the mask
/// of the inputs it reads (bit `k`: input `k`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairRows<'a, T> {
    pub w1: &'a [T],
    pub m1: u32,
    pub w2: &'a [T],
    pub m2: u32,
}

/// How a pair's two outputs are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PairOutput {
    /// Each at its own pointer, samples in order.
    Apart,
    /// Each at its own pointer, its even samples, then its odd ones ([`deinterleave`]).
    Split,
    /// Interleaved at the first pointer, `(a0 b0 a1 b1 …)`, twice as long.
    Merged,
}

impl PairOutput {
    pub(crate) fn apart_or_split(split: bool) -> PairOutput {
        if split {
            PairOutput::Split
        } else {
            PairOutput::Apart
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
/// the inputs `tap(c)` of their columns: `o1` the first row, `o2` the second, each input
/// they share read once. `false` (nothing written) when the rows share no column, read
/// more than [`PAIR_INPUTS`] inputs together or have no vector build of the pair kernels
/// at this CPU level (then two [`combine_taps`] do the same).
///
/// `memo` remembers the last pair's pattern (the regular row pairs repeat one); `split`
/// writes each output as its even samples, then its odd ones ([`combine_pair_at`]).
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_taps<'t, T: Sample + 't>(
    k: Kernels,
    memo: &mut PairMemo<T>,
    split: bool,
    o1: &mut [T],
    o2: &mut [T],
    row1: (&[u32], &[f64]),
    row2: (&[u32], &[f64]),
    tap: impl Fn(u32) -> &'t [T],
) -> bool {
    let ((c1, w1), (c2, w2)) = (row1, row2);
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
    combine_pair_at(k, entry, o1, o2, &src[..n], &a[..n], m1, &b[..n], m2, split);
    true
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
#[allow(clippy::too_many_arguments)]
pub(crate) fn pair_by_parts<T: Sample>(
    k: Kernels,
    o1: &mut [T],
    o2: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) {
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

/// [`combine_pair`] with its two outputs interleaved into `out`: `out[2i]` the first,
/// `out[2i + 1]` the second (the even and the odd fine samples of synthesis, without a
/// pass through two buffers and [`interleave`]). The same bits; `false` (nothing written)
/// where there is no AVX2 build for the pattern or the type.
#[cfg(any(test, feature = "testing"))]
pub fn combine_pair_merged<T: Sample>(
    k: Kernels,
    out: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) -> bool {
    combine_pair_merged_at(k, pair_entry(w1, m1, w2, m2), out, src, w1, m1, w2, m2)
}

/// [`combine_pair_merged`] with the pair's [`pair_entry`] looked up before (`entry` must
/// be it).
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_merged_at<T: Sample>(
    k: Kernels,
    entry: Option<u8>,
    out: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) -> bool {
    let u = src.len();
    check_pair(u, w1, m1, w2, m2);
    assert!(out.len().is_multiple_of(2));
    let len = out.len() / 2;
    assert!(src.iter().all(|s| s.len() >= len));
    #[cfg(target_arch = "x86_64")]
    if let (true, Some(entry)) = (k.avx2(), entry) {
        let p = input_ptrs(src);
        let o = [out.as_mut_ptr(), out.as_mut_ptr()];
        // SAFETY: AVX2 is present, AVX-512F at the table's level; `out` holds 2·len
        // samples, every input len; one step, the merged output written through the
        // first pointer only.
        return unsafe {
            pair_avx2_at(
                entry,
                PairRows { w1, m1, w2, m2 },
                &PairSteps::one(o, len, &p[..u], PairOutput::Merged),
                k.level(),
            )
        };
    }
    let _ = entry;
    false
}

/// [`combine_pair`] for `count` pairs of rows of `len` samples (the elements of a lane are
/// whole rows, e.g. the lanes of a volume's plane): pair `t` reads the rows
/// `cols[k] + in_step·t` of `src` and writes the rows `rows[j] + out_step[j]·t` of `dst`
/// (`j` = 0 for the first output, 1 for the second). The same bits as [`combine_pair`] pair
/// by pair; one dispatch for all of them.
// the engine calls the `_at` forms with the entry its plan holds: this form and the
// other lookups of their own (`lookup`, `combine_pair_rows_split`, `combine_pair_lanes`)
// serve the tests (feature `testing`)
#[cfg(feature = "testing")]
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_rows<T: Sample>(
    k: Kernels,
    src: &[T],
    len: usize,
    cols: &[usize],
    in_step: usize,
    w1: (&[T], u32),
    w2: (&[T], u32),
    dst: &mut [T],
    rows: [usize; 2],
    out_step: [usize; 2],
    count: usize,
) {
    let entry = lookup(k, w1, w2);
    pair_rows(
        k, entry, src, len, cols, in_step, w1, w2, dst, rows, out_step, count, false,
    )
}

/// [`combine_pair_rows`] with every output row split into its even samples, then its
/// odd ones (as [`deinterleave`] makes them, for a next axis that reads them so): the
/// same bits, placed as `deinterleave` places them, without a pass of its own.
#[cfg(feature = "testing")]
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_rows_split<T: Sample>(
    k: Kernels,
    src: &[T],
    len: usize,
    cols: &[usize],
    in_step: usize,
    w1: (&[T], u32),
    w2: (&[T], u32),
    dst: &mut [T],
    rows: [usize; 2],
    out_step: [usize; 2],
    count: usize,
) {
    let entry = lookup(k, w1, w2);
    pair_rows(
        k, entry, src, len, cols, in_step, w1, w2, dst, rows, out_step, count, true,
    )
}

/// [`pair_entry`] of a pair where the build has the pair kernels (`None` elsewhere).
#[cfg(feature = "testing")]
fn lookup<T: Sample>(k: Kernels, (w1, m1): (&[T], u32), (w2, m2): (&[T], u32)) -> Option<u8> {
    if k.avx2() {
        pair_entry(w1, m1, w2, m2)
    } else {
        None
    }
}

/// [`combine_pair_rows`] (`split`: [`combine_pair_rows_split`]) with the pair's
/// [`pair_entry`] looked up before (`entry` must be it, or `None` for one output at a
/// time): for callers that apply one pair many times ([`super::polyphase::Pair`] holds
/// its entries).
#[allow(clippy::too_many_arguments)]
pub(crate) fn pair_rows<T: Sample>(
    k: Kernels,
    entry: Option<u8>,
    src: &[T],
    len: usize,
    cols: &[usize],
    in_step: usize,
    (w1, m1): (&[T], u32),
    (w2, m2): (&[T], u32),
    dst: &mut [T],
    rows: [usize; 2],
    out_step: [usize; 2],
    count: usize,
    split: bool,
) {
    let u = cols.len();
    check_pair(u, w1, m1, w2, m2);
    if count == 0 || len == 0 {
        return;
    }
    let last = count - 1;
    assert!(cols
        .iter()
        .all(|&c| (c + in_step * last + 1) * len <= src.len()));
    for j in 0..2 {
        assert!((rows[j] + out_step[j] * last + 1) * len <= dst.len());
    }
    // the two outputs' rows never meet (a pair's rows are different rows of an operator)
    let row = |j: usize, t: usize| rows[j] + out_step[j] * t;
    let apart = rows[0].abs_diff(rows[1]);
    let disjoint = if out_step[0] == out_step[1] && out_step[0] > 0 {
        !apart.is_multiple_of(out_step[0]) || apart >= out_step[0] * count
    } else {
        row(0, last).max(rows[0]) < rows[1].min(row(1, last))
            || row(1, last).max(rows[1]) < rows[0].min(row(0, last))
    };
    assert!(disjoint, "combine_pair_rows: the two outputs share a row");
    let mut off = [0usize; 32];
    for (o, &c) in off.iter_mut().zip(cols) {
        *o = c * len;
    }
    let out = [rows[0] * len, rows[1] * len];
    let steps = [out_step[0] * len, out_step[1] * len];
    let (w1, w2) = ((w1, m1), (w2, m2));
    // SAFETY: every input and output row is inside its slice and the output rows are
    // distinct (asserted above).
    unsafe {
        pair_steps(
            k,
            entry,
            src,
            &off[..u],
            in_step * len,
            w1,
            w2,
            dst,
            out,
            steps,
            len,
            count,
            PairOutput::apart_or_split(split),
        )
    }
}

/// [`combine_pair`] on `count` lanes at once, `len` samples of each output per lane: lane
/// `t` reads input `k` at `src[off[k] + in_step·t ..][..len]` and writes its first output
/// at `dst[out[0] + out_step·t ..][..len]`, its second at `dst[out[1] + out_step·t ..]`
/// — or, when `merge`, both interleaved at `dst[out[0] + out_step·t ..][..2·len]` (the
/// even and the odd fine samples). Each lane's two outputs must lie within its `out_step`
/// samples and apart. One dispatch for all the lanes (e.g. every row of a volume's plane
/// along its last axis, the weights kept in registers); the same bits as
/// [`combine_pair`] lane by lane.
#[cfg(feature = "testing")]
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_lanes<T: Sample>(
    k: Kernels,
    src: &[T],
    off: &[usize],
    in_step: usize,
    w1: (&[T], u32),
    w2: (&[T], u32),
    dst: &mut [T],
    out: [usize; 2],
    out_step: usize,
    len: usize,
    count: usize,
    merge: bool,
) {
    let entry = lookup(k, w1, w2);
    combine_pair_lanes_at(
        k, entry, src, off, in_step, w1, w2, dst, out, out_step, len, count, merge,
    )
}

/// [`combine_pair_lanes`] with the pair's [`pair_entry`] looked up before (`entry` must
/// be it, or `None` for one output at a time).
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_lanes_at<T: Sample>(
    k: Kernels,
    entry: Option<u8>,
    src: &[T],
    off: &[usize],
    in_step: usize,
    (w1, m1): (&[T], u32),
    (w2, m2): (&[T], u32),
    dst: &mut [T],
    out: [usize; 2],
    out_step: usize,
    len: usize,
    count: usize,
    merge: bool,
) {
    let u = off.len();
    check_pair(u, w1, m1, w2, m2);
    if count == 0 || len == 0 {
        return;
    }
    let last = count - 1;
    assert!(off.iter().all(|&o| o + in_step * last + len <= src.len()));
    // each lane's outputs inside its own stretch of `out_step` samples, apart
    let (lo, hi) = (out[0].min(out[1]), out[0].max(out[1]));
    let reach = if merge { out[0] + 2 * len } else { hi + len };
    assert!(
        merge || hi >= lo + len,
        "combine_pair_lanes: the two outputs overlap"
    );
    assert!(reach - if merge { out[0] } else { lo } <= out_step);
    assert!(reach + out_step * last <= dst.len());
    let steps = [out_step, out_step];
    let (w1, w2) = ((w1, m1), (w2, m2));
    // SAFETY: every input and output stretch is inside its slice, and each lane's outputs
    // lie apart within its own `out_step` samples (asserted above).
    unsafe {
        pair_steps(
            k,
            entry,
            src,
            off,
            in_step,
            w1,
            w2,
            dst,
            out,
            steps,
            len,
            count,
            if merge {
                PairOutput::Merged
            } else {
                PairOutput::Apart
            },
        )
    }
}

/// The steps of [`combine_pair_rows`] and [`combine_pair_lanes`]: step `t` reads input
/// `k` at `src[off[k] + in_step·t ..][..len]` and writes output `j` at
/// `dst[out[j] + out_step[j]·t ..][..len]` (`merge`: both interleaved at `out[0]`, twice
/// as long).
///
/// # Safety
/// Every input and output stretch of every step inside its slice, and no two outputs of
/// any steps overlapping; weights and masks as [`check_pair`] checks them.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn pair_steps<T: Sample>(
    k: Kernels,
    entry: Option<u8>,
    src: &[T],
    off: &[usize],
    in_step: usize,
    (w1, m1): (&[T], u32),
    (w2, m2): (&[T], u32),
    dst: &mut [T],
    out: [usize; 2],
    out_step: [usize; 2],
    len: usize,
    count: usize,
    output: PairOutput,
) {
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
        let done = entry.is_some_and(|entry| unsafe {
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
            pair_avx2_at(entry, PairRows { w1, m1, w2, m2 }, &at, k.level())
        });
        if done {
            return;
        }
    }
    let _ = (p, entry);
    let (mut a, mut b) = (vec![T::default(); len], vec![T::default(); len]);
    for t in 0..count {
        let mut s: [&[T]; 32] = [&[]; 32];
        for (k, &o) in off.iter().enumerate() {
            s[k] = &src[o + in_step * t..][..len];
        }
        pair_by_parts(k, &mut a, &mut b, &s[..u], w1, m1, w2, m2);
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
