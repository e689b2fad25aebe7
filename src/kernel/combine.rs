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
    // rows with pairs, and rows too long for one fused pass of `taps` (summed in one
    // pass over all their taps: the terms of a row without pairs are its taps in order,
    // the plain sum, so the same bits as a first pass of 8 taps and one pass per tap after)
    if pair_taps(w, partner) || (k.avx2() && n > MAX_FUSED && n <= 32) {
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
        let p: [*const T; 32] =
            std::array::from_fn(|k| src.get(k).map_or(std::ptr::null(), |s| s.as_ptr()));
        let (n, wide) = (src.len(), k.avx512());
        let (o, wp) = (out.as_mut_ptr(), w.as_ptr().cast_mut());
        macro_rules! arm {
            ($as:ident, $wide_from:expr, $narrow:ident, $wide:ident) => {
                // (`Some` for the type named only: `Sample::f32_ptr`, `f64_ptr`)
                if let (Some(o), Some(wp)) = (T::$as(o), T::$as(wp)) {
                    let p = p
                        .map(|q| T::$as(q.cast_mut()).map_or(std::ptr::null(), |q| q.cast_const()));
                    let w = std::slice::from_raw_parts(wp.cast_const(), n);
                    if wide && len >= $wide_from {
                        $wide(o, len, &p[..n], w, partner);
                    } else {
                        $narrow(o, len, &p[..n], w, partner);
                    }
                    return;
                }
            };
        }
        // SAFETY (both arms): AVX2 with FMA is present, AVX-512F when `wide`; every
        // source holds `len` samples (checked by `combine`), `w` holds `n` weights.
        unsafe {
            arm!(f32_ptr, 16, terms_avx2_f32, terms_avx512_f32);
            arm!(f64_ptr, 8, terms_avx2_f64, terms_avx512_f64);
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
    if let (true, Some(ps), Some(pd)) = (
        k.avx2(),
        T::f32_ptr(src.as_ptr().cast_mut()),
        T::f32_ptr(dst.as_mut_ptr()),
    ) {
        // SAFETY: AVX2 is present; the samples are f32; every column of `op` is below
        // `op.cols()`, so each source row is inside `src`, and each output row inside
        // `dst` (asserted).
        return unsafe { combine_rows_avx2_f32(k, op, ps.cast_const(), len, rows, pd) };
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
    const MOST: usize = 32;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of many taps without pairs (the boundary rows of the wide schemes: 12 to 20
    /// distinct weights) sum in one pass at every CPU level, with the bits of the plain
    /// loop `((w₀x₀ + w₁x₁) + w₂x₂) + …`; so do [`combine_rows`]' rows.
    #[test]
    fn long_rows_without_pairs_give_the_bits_of_the_plain_loop() {
        fn check<T: Sample>() {
            let x: Vec<T> = (0..200)
                .map(|i| T::from_f64(((i * 7919 % 211) as f64 - 105.0) / 13.0))
                .collect();
            for taps in [9usize, 12, 13, 20, 32, 33] {
                // distinct weights (no pairs)
                let w: Vec<T> = (0..taps)
                    .map(|k| T::from_f64(0.0625 * k as f64 - 0.71))
                    .collect();
                for len in [1usize, 7, 8, 15, 16, 17, 31, 33, 64, 100] {
                    let src: Vec<&[T]> = (0..taps).map(|k| &x[3 * k..3 * k + len]).collect();
                    let want: Vec<u64> = (0..len)
                        .map(|i| {
                            let mut acc = w[0] * src[0][i];
                            for k in 1..taps {
                                acc += w[k] * src[k][i];
                            }
                            acc.to_f64().to_bits()
                        })
                        .collect();
                    for level in CpuLevel::available() {
                        let k = Kernels::new(level);
                        let mut out = vec![T::from_f64(9.0); len];
                        combine(k, &mut out, &src, &w);
                        let got: Vec<u64> = out.iter().map(|v| v.to_f64().to_bits()).collect();
                        assert_eq!(got, want, "{level:?} taps {taps} len {len}");
                    }
                }
            }
        }
        check::<f32>();
        check::<f64>();
    }

    /// [`combine_rows`] at every CPU level gives the bits of [`Csr::apply`] (the reference
    /// loops) on the operators of short lanes whose boundary rows are long: every row of
    /// the wide schemes' interpolating levels, rows of lengths around the vector widths.
    #[test]
    fn combine_rows_gives_the_bits_of_the_reference_on_long_boundary_rows() {
        use crate::scheme::{Boundary, Scheme, TwoScale};
        for scheme in [Scheme::ChaikinWide, Scheme::CubicWide, Scheme::LinearWide] {
            for boundary in Boundary::ALL {
                for m in [22usize, 33, 35, 64] {
                    let t = TwoScale::new(scheme, boundary, m);
                    for op in [&t.analysis, &t.synthesis] {
                        for len in [1usize, 9, 16, 40] {
                            let x: Vec<f32> = (0..m * len)
                                .map(|i| ((i * 37 % 101) as f32 - 50.0) / 7.0)
                                .collect();
                            let mut want = vec![0f32; m * len];
                            op.apply(&x, len, &mut want, len, len);
                            for level in CpuLevel::available() {
                                let mut got = vec![1f32; m * len];
                                combine_rows(Kernels::new(level), op, &x, len, 0..m, &mut got);
                                let bits =
                                    |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                                assert_eq!(
                                    bits(&got),
                                    bits(&want),
                                    "{scheme} {boundary} m {m} len {len} {level:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}
