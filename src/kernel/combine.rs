//! Rows combined tap by tap: `out = Σ_k w_k · src_k` over whole runs of samples.

use super::*;

/// Most taps fused into one pass; longer rows accumulate in further passes.
pub(crate) const MAX_FUSED: usize = 8;

/// `out[i] = Σ_k w[k] · src[k][i]` for every `i < out.len()`, `k` in column order, summed
/// as [`sum_terms`] says (the rounding of [`Csr`]'s row kernel, so both
/// paths give the same bits): rows without equal weights by `taps` / `taps_avx2`
/// (the first tap assigns, the others accumulate), rows with pairs by the terms' loop.
///
/// Every `src[k]` must hold at least `out.len()` samples. The build is `k`'s.
#[inline]
pub fn combine<T: Sample>(k: Kernels, out: &mut [T], src: &[&[T]], w: &[T]) {
    assert_eq!(src.len(), w.len());
    assert!(src.iter().all(|s| s.len() >= out.len()));
    let n = w.len();
    let mut stack = [0usize; 32];
    let mut heap = Vec::new();
    let partner = if n <= 32 {
        &mut stack[..n]
    } else {
        heap.resize(n, 0);
        &mut heap[..]
    };
    if pair_taps(w, partner) {
        return combine_terms(k, out, src, w, partner);
    }
    #[cfg(target_arch = "x86_64")]
    if k.avx2() {
        // SAFETY: AVX2 is present (and AVX-512 when the table has it: a table holds no
        // build the CPU lacks).
        return unsafe { combine_avx2(out, src, w, k.avx512()) };
    }
    combine_generic(out, src, w)
}

/// [`combine`] of a row whose taps pair (`partner` from [`pair_taps`]).
pub(crate) fn combine_terms<T: Sample>(
    k: Kernels,
    out: &mut [T],
    src: &[&[T]],
    w: &[T],
    partner: &[usize],
) {
    let len = out.len();
    #[cfg(target_arch = "x86_64")]
    if k.avx2() && src.len() <= 32 {
        use std::any::TypeId;
        let p: [*const T; 32] =
            std::array::from_fn(|k| src.get(k).map_or(std::ptr::null(), |s| s.as_ptr()));
        let wide = k.avx512();
        macro_rules! arm {
            ($t:ty, $wide_from:expr, $narrow:ident, $wide:ident) => {
                if TypeId::of::<T>() == TypeId::of::<$t>() {
                    let n = src.len();
                    let o = out.as_mut_ptr() as *mut $t;
                    let (p, w) = (
                        std::slice::from_raw_parts(p.as_ptr() as *const *const $t, n),
                        std::slice::from_raw_parts(w.as_ptr() as *const $t, n),
                    );
                    if wide && len >= $wide_from {
                        $wide(o, len, p, w, partner);
                    } else {
                        $narrow(o, len, p, w, partner);
                    }
                    return;
                }
            };
        }
        // SAFETY (both arms): AVX2 with FMA is present, AVX-512F when `wide`; every
        // source holds `len` samples (checked by `combine`); T is the type named.
        unsafe {
            arm!(f32, 16, terms_avx2_f32, terms_avx512_f32);
            arm!(f64, 8, terms_avx2_f64, terms_avx512_f64);
        }
    }
    let _ = k;
    for (i, o) in out.iter_mut().enumerate() {
        *o = sum_terms(w, partner, |k| src[k][i]);
    }
}

/// `dst[i·len ..][..len] = Σ_k w_rk · src[c_rk·len ..][..len]` for the rows `r` of `op`
/// in `rows` (`i = r − rows.start`): [`combine`] for every row of an operator whose
/// elements are rows of `len` samples, in one call (short rows, e.g. the lanes of a
/// volume's plane, spend as long in a call's set-up as in its loop). The same sums in
/// the same order as [`combine`]: the same bits.
pub fn combine_rows<T: Sample>(
    k: Kernels,
    op: &Csr,
    src: &[T],
    len: usize,
    rows: std::ops::Range<usize>,
    dst: &mut [T],
) {
    assert!(rows.end <= op.rows() && op.cols() * len <= src.len());
    assert!(rows.len() * len <= dst.len());
    #[cfg(target_arch = "x86_64")]
    if std::any::TypeId::of::<T>() == std::any::TypeId::of::<f32>() && k.avx2() {
        let (ps, pd) = (src.as_ptr() as *const f32, dst.as_mut_ptr() as *mut f32);
        // SAFETY: AVX2 is present; T is f32; every column of `op` is below `op.cols()`,
        // so each source row is inside `src`, and each output row inside `dst` (asserted).
        return unsafe { combine_rows_avx2_f32(k, op, ps, len, rows, pd) };
    }
    for (i, r) in rows.enumerate() {
        let (cols, ws) = op.row_slices(r);
        let at = |c: u32| c as usize * len;
        combine_taps(k, &mut dst[i * len..i * len + len], cols, ws, |c| {
            &src[at(c)..at(c) + len]
        });
    }
}

/// `out = Σ_t w_t · tap(c_t)`: [`combine`] over the inputs `tap(c)` of a sparse row's
/// columns `cols` and weights `ws` (each input at least `out.len()` samples).
pub fn combine_taps<'t, T: Sample + 't>(
    k: Kernels,
    out: &mut [T],
    cols: &[u32],
    ws: &[f64],
    tap: impl Fn(u32) -> &'t [T],
) {
    const MOST: usize = 16;
    let mut taps: [&[T]; MOST] = [&[]; MOST];
    let mut w = [T::default(); MOST];
    if cols.len() <= MOST {
        for (t, (&c, &wc)) in cols.iter().zip(ws).enumerate() {
            taps[t] = tap(c);
            w[t] = T::from_f64(wc);
        }
        combine(k, out, &taps[..cols.len()], &w[..cols.len()]);
    } else {
        let t: Vec<&[T]> = cols.iter().map(|&c| tap(c)).collect();
        let wv: Vec<T> = ws.iter().map(|&x| T::from_f64(x)).collect();
        combine(k, out, &t, &wv);
    }
}
