//! The inner loops every transform ends in, written over whole runs of samples so they
//! vectorise, with AVX2 (with FMA) and AVX-512 builds picked at run time. Every build and
//! every path gives the same bits: each output sums its row's taps as [`pair_taps`] and
//! [`sum_terms`] say.
//!
//! **How a row's sum is taken.** The taps in increasing column order; scanning them so, a
//! tap not yet paired pairs with the next tap of the same weight not yet paired, if any
//! (the symmetric taps of the regular filters: cubic's `a` sums `(x₀ + x₆)`, `(x₁ + x₅)`,
//! `(x₂ + x₄)` and takes `x₃` alone). The terms — single taps, and pairs at their first
//! tap — in column order: the first is `w·x` (a pair's `x` the sum of its two inputs, the
//! earlier first), each next single tap adds the rounded product `w·x`, each next pair is
//! `fma(x_a + x_b, w, acc)`, rounded once. A row without equal weights is the plain
//! sum `((w₀x₀ + w₁x₁) + w₂x₂) + …`. Pairs halve the multiplies of the regular rows and
//! move half of the rest into FMAs: the arithmetic of cubic's pair of rows goes from 12
//! multiplies and 10 adds per pair of outputs to 6 FMAs or multiplies and 5–7 adds.

use super::sample::Sample;
use super::sparse::Simd;

/// [`pair_taps`]' mark of the second tap of a pair.
pub const SECOND: usize = usize::MAX;

/// The pairs of a row whose weights are `w` (in column order): `partner[k]` is `k` for a
/// single tap, `j > k` for the first tap of a pair whose second is `j`, and [`SECOND`] for
/// a pair's second tap. Scanning in order, a tap not yet paired pairs with the next tap
/// of the same weight not yet paired. `true` when some taps pair.
#[inline]
pub fn pair_taps<T: Sample>(w: &[T], partner: &mut [usize]) -> bool {
    let n = w.len();
    assert!(partner.len() >= n);
    for (k, p) in partner.iter_mut().enumerate().take(n) {
        *p = k;
    }
    let mut any = false;
    for k in 0..n {
        if partner[k] != k {
            continue;
        }
        if let Some(j) = (k + 1..n).find(|&j| partner[j] == j && w[j] == w[k]) {
            (partner[k], partner[j]) = (j, SECOND);
            any = true;
        }
    }
    any
}

/// One output of a row, `x(k)` the input of tap `k`: the sum [`pair_taps`] plans (see the
/// module's documentation; the reference every build and path gives the bits of).
#[inline(always)]
pub fn sum_terms<T: Sample>(w: &[T], partner: &[usize], x: impl Fn(usize) -> T) -> T {
    let mut acc = T::default();
    let mut first = true;
    for k in 0..w.len() {
        let p = partner[k];
        if p == SECOND {
            continue;
        }
        let v = if p == k { x(k) } else { x(k) + x(p) };
        acc = if first {
            w[k] * v
        } else if p == k {
            acc + w[k] * v
        } else {
            v.fused_mul_add(w[k], acc)
        };
        first = false;
    }
    acc
}

/// [`sum_terms`] of a row given as weights alone (pairs worked out here).
pub fn row_sum<T: Sample>(w: &[T], x: impl Fn(usize) -> T) -> T {
    let mut partner = vec![0; w.len()];
    pair_taps(w, &mut partner);
    sum_terms(w, &partner, x)
}

/// Most taps fused into one pass; longer rows accumulate in further passes.
const MAX_FUSED: usize = 8;

/// `out[i] = Σ_k w[k] · src[k][i]` for every `i < out.len()`, `k` in column order, summed
/// as [`sum_terms`] says (the rounding of [`super::sparse::Csr`]'s row kernel, so both
/// paths give the same bits): rows without equal weights by `taps` / `taps_avx2`
/// (the first tap assigns, the others accumulate), rows with pairs by the terms' loop.
///
/// Every `src[k]` must hold at least `out.len()` samples.
#[inline]
pub fn combine<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T]) {
    combine_with(Simd::detected(), out, src, w)
}

/// [`combine`] with the build `simd` (at most [`Simd::detected`]; tests compare the
/// builds).
#[inline]
pub fn combine_with<T: Sample>(simd: Simd, out: &mut [T], src: &[&[T]], w: &[T]) {
    assert_eq!(src.len(), w.len());
    assert!(src.iter().all(|s| s.len() >= out.len()));
    assert!(simd <= Simd::detected(), "{simd:?} is not available");
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
        return combine_terms(simd, out, src, w, partner);
    }
    #[cfg(target_arch = "x86_64")]
    if simd >= Simd::Avx2 {
        // SAFETY: AVX2 is present (and AVX-512 when asked for, checked above).
        return unsafe { combine_avx2(out, src, w, simd == Simd::Avx512) };
    }
    combine_generic(out, src, w)
}

/// [`combine`]'s AVX2 build (`wide`: AVX-512F present too, see [`taps_avx2`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn combine_avx2<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T], wide: bool) {
    let n = src.len();
    if n == 0 || n > MAX_FUSED {
        return combine_generic(out, src, w);
    }
    // SAFETY (all arms): AVX2 is present, AVX-512F too when `wide` (this function's
    // contract).
    unsafe {
        match n {
            1 => taps_avx2::<T, 1>(out, src, w, wide),
            2 => taps_avx2::<T, 2>(out, src, w, wide),
            3 => taps_avx2::<T, 3>(out, src, w, wide),
            4 => taps_avx2::<T, 4>(out, src, w, wide),
            5 => taps_avx2::<T, 5>(out, src, w, wide),
            6 => taps_avx2::<T, 6>(out, src, w, wide),
            7 => taps_avx2::<T, 7>(out, src, w, wide),
            _ => taps_avx2::<T, 8>(out, src, w, wide),
        }
    }
}

/// [`combine`] of a row whose taps pair (`partner` from [`pair_taps`]).
fn combine_terms<T: Sample>(simd: Simd, out: &mut [T], src: &[&[T]], w: &[T], partner: &[usize]) {
    let len = out.len();
    #[cfg(target_arch = "x86_64")]
    if simd >= Simd::Avx2 && src.len() <= 32 {
        use std::any::TypeId;
        let p: [*const T; 32] =
            std::array::from_fn(|k| src.get(k).map_or(std::ptr::null(), |s| s.as_ptr()));
        let wide = simd == Simd::Avx512;
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
        // source holds `len` samples (checked by `combine_with`); T is the type named.
        unsafe {
            arm!(f32, 16, terms_avx2_f32, terms_avx512_f32);
            arm!(f64, 8, terms_avx2_f64, terms_avx512_f64);
        }
    }
    let _ = simd;
    for (i, o) in out.iter_mut().enumerate() {
        *o = sum_terms(w, partner, |k| src[k][i]);
    }
}

#[inline(always)]
fn combine_generic<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T]) {
    let n = src.len();
    if n == 0 {
        out.fill(T::default());
        return;
    }
    let first = n.min(MAX_FUSED);
    match first {
        1 => taps::<T, 1>(out, src, w),
        2 => taps::<T, 2>(out, src, w),
        3 => taps::<T, 3>(out, src, w),
        4 => taps::<T, 4>(out, src, w),
        5 => taps::<T, 5>(out, src, w),
        6 => taps::<T, 6>(out, src, w),
        7 => taps::<T, 7>(out, src, w),
        _ => taps::<T, 8>(out, src, w),
    }
    for k in first..n {
        let (s, wk) = (&src[k][..out.len()], w[k]);
        for (o, &x) in out.iter_mut().zip(s) {
            *o += wk * x;
        }
    }
}

/// `N` taps in one pass over `out`.
#[inline(always)]
fn taps<T: Sample, const N: usize>(out: &mut [T], src: &[&[T]], w: &[T]) {
    let len = out.len();
    let s: [&[T]; N] = std::array::from_fn(|k| &src[k][..len]);
    let w: [T; N] = std::array::from_fn(|k| w[k]);
    for i in 0..len {
        let mut acc = w[0] * s[0][i];
        for k in 1..N {
            acc += w[k] * s[k][i];
        }
        out[i] = acc;
    }
}

/// [`taps`] with AVX2 intrinsics for `f32`/`f64`: blocks of four vectors keep four
/// independent sums in flight (each output's sum is a chain of dependent adds in a fixed
/// order, for the bits, so one vector at a time would wait on add latency), then single
/// vectors, then scalars. Separate multiply and add (rows without pairs, so no FMA): the
/// same bits as the scalar loop. Short runs (lanes of a few hundred samples) are common, so the set-up is kept to
/// plain loops. `wide`: 512-bit vectors (AVX-512F, which the caller has checked) on runs
/// of at least one such vector.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn taps_avx2<T: Sample, const N: usize>(out: &mut [T], src: &[&[T]], w: &[T], wide: bool) {
    use std::any::TypeId;
    let len = out.len();
    debug_assert!(src.len() == N && src.iter().all(|s| s.len() >= len));
    if TypeId::of::<T>() == TypeId::of::<f32>() {
        let mut p = [std::ptr::null::<f32>(); N];
        let mut ws = [0f32; N];
        for k in 0..N {
            p[k] = src[k].as_ptr() as *const f32;
            ws[k] = w[k].to_f64() as f32;
        }
        // SAFETY: AVX2 is present, AVX-512F when `wide`; every source holds `len` samples (checked by
        // `combine`); T is f32.
        unsafe {
            if wide && len >= 16 {
                taps_avx512_f32::<N>(out.as_mut_ptr() as *mut f32, len, &p, &ws)
            } else {
                taps_avx2_f32::<N>(out.as_mut_ptr() as *mut f32, len, &p, &ws)
            }
        }
    } else if TypeId::of::<T>() == TypeId::of::<f64>() {
        let mut p = [std::ptr::null::<f64>(); N];
        let mut ws = [0f64; N];
        for k in 0..N {
            p[k] = src[k].as_ptr() as *const f64;
            ws[k] = w[k].to_f64();
        }
        // SAFETY: as above; T is f64.
        unsafe {
            if wide && len >= 8 {
                taps_avx512_f64::<N>(out.as_mut_ptr() as *mut f64, len, &p, &ws)
            } else {
                taps_avx2_f64::<N>(out.as_mut_ptr() as *mut f64, len, &p, &ws)
            }
        }
    } else {
        taps::<T, N>(out, src, w)
    }
}

/// `o[i] = Σ_k ws[k]·p[k][i]`, `i < len` (first tap assigns; rows without pairs): blocks
/// of four vectors, then single vectors, then scalars. One body for `f32` and `f64` (their intrinsics differ).
macro_rules! taps_avx2_body {
    ($name:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $zero:ident, $mul:ident, $add:ident, $load:ident, $store:ident) => {
        /// See [`taps_avx2_body`].
        ///
        /// # Safety
        /// The target feature present; `o` and every `p[k]` valid for `len` samples.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feat)]
        unsafe fn $name<const N: usize>(o: *mut $t, len: usize, p: &[*const $t; N], ws: &[$t; N]) {
            use std::arch::x86_64::*;
            const L: usize = $lanes;
            let mut wv = [$zero(); N];
            for k in 0..N {
                wv[k] = $set1(ws[k]);
            }
            let mut i = 0;
            // SAFETY (all blocks): i + width <= len, so every access is inside the runs.
            unsafe {
                while i + 4 * L <= len {
                    let mut a0 = $mul(wv[0], $load(p[0].add(i)));
                    let mut a1 = $mul(wv[0], $load(p[0].add(i + L)));
                    let mut a2 = $mul(wv[0], $load(p[0].add(i + 2 * L)));
                    let mut a3 = $mul(wv[0], $load(p[0].add(i + 3 * L)));
                    for k in 1..N {
                        a0 = $add(a0, $mul(wv[k], $load(p[k].add(i))));
                        a1 = $add(a1, $mul(wv[k], $load(p[k].add(i + L))));
                        a2 = $add(a2, $mul(wv[k], $load(p[k].add(i + 2 * L))));
                        a3 = $add(a3, $mul(wv[k], $load(p[k].add(i + 3 * L))));
                    }
                    $store(o.add(i), a0);
                    $store(o.add(i + L), a1);
                    $store(o.add(i + 2 * L), a2);
                    $store(o.add(i + 3 * L), a3);
                    i += 4 * L;
                }
                while i + L <= len {
                    let mut a = $mul(wv[0], $load(p[0].add(i)));
                    for k in 1..N {
                        a = $add(a, $mul(wv[k], $load(p[k].add(i))));
                    }
                    $store(o.add(i), a);
                    i += L;
                }
                if i < len && len >= L {
                    // the last vector again, ending at `len` (its first samples recomputed:
                    // the same sums, the same bits; the output is apart from the inputs)
                    let j = len - L;
                    let mut a = $mul(wv[0], $load(p[0].add(j)));
                    for k in 1..N {
                        a = $add(a, $mul(wv[k], $load(p[k].add(j))));
                    }
                    $store(o.add(j), a);
                    i = len;
                }
                while i < len {
                    let mut a = ws[0] * *p[0].add(i);
                    for k in 1..N {
                        a += ws[k] * *p[k].add(i);
                    }
                    *o.add(i) = a;
                    i += 1;
                }
            }
        }
    };
}

/// `o[i] = ` [`sum_terms`] of the row `w` (pairs `partner`) over `p[k][i]`, `i < len`: the
/// rows whose taps pair outside [`combine_pair`]'s patterns (terms looked up per vector).
macro_rules! terms_avx2_body {
    ($name:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $mul:ident, $add:ident, $fma:ident, $load:ident, $store:ident) => {
        /// See [`terms_avx2_body`].
        ///
        /// # Safety
        /// The target feature present; `o` and every `p[k]` valid for `len` samples;
        /// `partner` from [`pair_taps`] of `w`, as long as `p`.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feat)]
        unsafe fn $name(o: *mut $t, len: usize, p: &[*const $t], w: &[$t], partner: &[usize]) {
            use std::arch::x86_64::*;
            const L: usize = $lanes;
            // the terms: (first input, second input or usize::MAX, weight)
            let mut terms = [(0usize, usize::MAX, 0.0 as $t); 32];
            let mut n = 0;
            for k in 0..w.len() {
                let q = partner[k];
                if q != SECOND {
                    terms[n] = (k, if q == k { usize::MAX } else { q }, w[k]);
                    n += 1;
                }
            }
            let terms = &terms[..n];
            // `$n` vectors from `i` (four at once keep four independent sums in flight)
            macro_rules! at {
                ($i:expr, $n:literal) => {{
                    let i = $i;
                    let mut acc = [$set1(0.0); $n];
                    for (t, &(a, b, wk)) in terms.iter().enumerate() {
                        let wv = $set1(wk);
                        for (j, acc) in acc.iter_mut().enumerate() {
                            let x = $load(p[a].add(i + j * L));
                            *acc = if b == usize::MAX {
                                let m = $mul(wv, x);
                                if t == 0 {
                                    m
                                } else {
                                    $add(*acc, m)
                                }
                            } else {
                                let v = $add(x, $load(p[b].add(i + j * L)));
                                if t == 0 {
                                    $mul(wv, v)
                                } else {
                                    $fma(v, wv, *acc)
                                }
                            };
                        }
                    }
                    for (j, &acc) in acc.iter().enumerate() {
                        $store(o.add(i + j * L), acc);
                    }
                }};
            }
            let mut i = 0;
            // SAFETY (all blocks): i + width <= len, so every access is inside the runs.
            unsafe {
                while i + 4 * L <= len {
                    at!(i, 4);
                    i += 4 * L;
                }
                while i + L <= len {
                    at!(i, 1);
                    i += L;
                }
                if i < len && len >= L {
                    // the last vector again, ending at `len` (the same sums, the same bits)
                    at!(len - L, 1);
                    i = len;
                }
                while i < len {
                    *o.add(i) = sum_terms(w, partner, |k| *p[k].add(i));
                    i += 1;
                }
            }
        }
    };
}
terms_avx2_body!(
    terms_avx2_f32,
    "avx2,fma",
    f32,
    8,
    _mm256_set1_ps,
    _mm256_mul_ps,
    _mm256_add_ps,
    _mm256_fmadd_ps,
    _mm256_loadu_ps,
    _mm256_storeu_ps
);
terms_avx2_body!(
    terms_avx2_f64,
    "avx2,fma",
    f64,
    4,
    _mm256_set1_pd,
    _mm256_mul_pd,
    _mm256_add_pd,
    _mm256_fmadd_pd,
    _mm256_loadu_pd,
    _mm256_storeu_pd
);
terms_avx2_body!(
    terms_avx512_f32,
    "avx512f,fma",
    f32,
    16,
    _mm512_set1_ps,
    _mm512_mul_ps,
    _mm512_add_ps,
    _mm512_fmadd_ps,
    _mm512_loadu_ps,
    _mm512_storeu_ps
);
terms_avx2_body!(
    terms_avx512_f64,
    "avx512f,fma",
    f64,
    8,
    _mm512_set1_pd,
    _mm512_mul_pd,
    _mm512_add_pd,
    _mm512_fmadd_pd,
    _mm512_loadu_pd,
    _mm512_storeu_pd
);

/// Split `x` (elements of `e` samples) into its even elements, then its odd elements:
/// `dst = [x_0, x_2, x_4, … | x_1, x_3, …]`.
#[inline]
pub fn deinterleave<T: Sample>(x: &[T], e: usize, dst: &mut [T]) {
    assert_eq!(x.len() % e, 0);
    assert!(dst.len() >= x.len());
    #[cfg(target_arch = "x86_64")]
    if super::sparse::cpu_has_avx2() {
        // SAFETY: AVX2 is present.
        return unsafe { deinterleave_avx2(x, e, dst) };
    }
    deinterleave_generic(x, e, dst)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn deinterleave_avx2<T: Sample>(x: &[T], e: usize, dst: &mut [T]) {
    if e == 1 && std::mem::size_of::<T>() == 4 && x.len() >= 16 {
        use std::arch::x86_64::*;
        let m = x.len();
        let ne = m.div_ceil(2);
        let pairs = m / 16 * 8; // pairs done by vectors
        let (px, pd) = (x.as_ptr() as *const f32, dst.as_mut_ptr() as *mut f32);
        let mut i = 0;
        while i < pairs {
            // SAFETY: 2i + 16 <= m; even outputs i..i+8 < ne, odd ne+i..ne+i+8 <= m;
            // T is a 4-byte float, moved as bits.
            unsafe {
                let v0 = _mm256_loadu_ps(px.add(2 * i));
                let v1 = _mm256_loadu_ps(px.add(2 * i + 8));
                let ev = _mm256_shuffle_ps(v0, v1, 0x88); // x0 x2 x8 x10 | x4 x6 x12 x14
                let od = _mm256_shuffle_ps(v0, v1, 0xDD); // x1 x3 x9 x11 | x5 x7 x13 x15
                let ev = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(ev), 0xD8));
                let od = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(od), 0xD8));
                _mm256_storeu_ps(pd.add(i), ev);
                _mm256_storeu_ps(pd.add(ne + i), od);
            }
            i += 8;
        }
        for (j, &v) in x.iter().enumerate().skip(2 * pairs) {
            let at = if j % 2 == 0 { j / 2 } else { ne + j / 2 };
            dst[at] = v;
        }
        return;
    }
    deinterleave_generic(x, e, dst)
}

#[inline(always)]
fn deinterleave_generic<T: Sample>(x: &[T], e: usize, dst: &mut [T]) {
    let m = x.len() / e;
    let ne = m.div_ceil(2);
    let (even, odd) = dst[..x.len()].split_at_mut(ne * e);
    if e == 1 {
        let pairs = m / 2;
        for ((ev, od), p) in even.iter_mut().zip(odd.iter_mut()).zip(x.chunks_exact(2)) {
            *ev = p[0];
            *od = p[1];
        }
        if m % 2 == 1 {
            even[pairs] = x[m - 1];
        }
    } else {
        for (i, el) in x.chunks_exact(e).enumerate() {
            let half = if i % 2 == 0 { &mut *even } else { &mut *odd };
            half[(i / 2) * e..(i / 2) * e + e].copy_from_slice(el);
        }
    }
}

/// `dst = [a_0, b_0, a_1, b_1, …]` for elements of `e` samples (`a`, `b` of equal length).
#[inline]
pub fn interleave<T: Sample>(a: &[T], b: &[T], e: usize, dst: &mut [T]) {
    assert_eq!(a.len(), b.len());
    assert!(dst.len() >= 2 * a.len());
    #[cfg(target_arch = "x86_64")]
    if super::sparse::cpu_has_avx2() {
        // SAFETY: AVX2 is present.
        return unsafe { interleave_avx2(a, b, e, dst) };
    }
    interleave_generic(a, b, e, dst)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn interleave_avx2<T: Sample>(a: &[T], b: &[T], e: usize, dst: &mut [T]) {
    if e == 1 && std::mem::size_of::<T>() == 4 {
        use std::arch::x86_64::*;
        let n = a.len() / 8 * 8;
        let dst = &mut dst[..2 * a.len()];
        let (pa, pb, pd) = (
            a.as_ptr() as *const f32,
            b.as_ptr() as *const f32,
            dst.as_mut_ptr() as *mut f32,
        );
        let mut i = 0;
        while i < n {
            // SAFETY: i + 8 <= a.len() = b.len(), 2i + 16 <= dst.len(); T is a 4-byte
            // float, moved as bits.
            unsafe {
                let x = _mm256_loadu_ps(pa.add(i));
                let y = _mm256_loadu_ps(pb.add(i));
                let lo = _mm256_unpacklo_ps(x, y); // a0 b0 a1 b1 | a4 b4 a5 b5
                let hi = _mm256_unpackhi_ps(x, y); // a2 b2 a3 b3 | a6 b6 a7 b7
                _mm256_storeu_ps(pd.add(2 * i), _mm256_permute2f128_ps(lo, hi, 0x20));
                _mm256_storeu_ps(pd.add(2 * i + 8), _mm256_permute2f128_ps(lo, hi, 0x31));
            }
            i += 8;
        }
        return interleave_generic(&a[n..], &b[n..], 1, &mut dst[2 * n..]);
    }
    interleave_generic(a, b, e, dst)
}

#[inline(always)]
fn interleave_generic<T: Sample>(a: &[T], b: &[T], e: usize, dst: &mut [T]) {
    let dst = &mut dst[..2 * a.len()];
    if e == 1 {
        for ((d, &x), &y) in dst.chunks_exact_mut(2).zip(a).zip(b) {
            d[0] = x;
            d[1] = y;
        }
    } else {
        for ((d, x), y) in dst
            .chunks_exact_mut(2 * e)
            .zip(a.chunks_exact(e))
            .zip(b.chunks_exact(e))
        {
            d[..e].copy_from_slice(x);
            d[e..].copy_from_slice(y);
        }
    }
}

/// `dst.copy_from_slice(src)` with non-temporal stores where the CPU has AVX2: the
/// destination lines go to memory without being read first (a level's output that does
/// not fit in cache is written once and read back only by the next level). Ends with a
/// store fence ([`stream_fence`]).
#[inline]
pub fn stream_copy<T: Sample>(src: &[T], dst: &mut [T]) {
    stream_copy_unfenced(src, dst);
    stream_fence();
}

/// [`stream_copy`] without its store fence, for many short copies in a row (the rows of
/// an image): the caller fences once after the last ([`stream_fence`]), before anything
/// another thread may read them. A fence per 16 KB row of a 4096² image cost about 5% of
/// the CPU time of a cubic pyramid forward and back (one thread, 38.6–39.5 → 36.7–37.5 ms
/// symmetric, 41.1–41.5 → 38.9–39.1 ms periodic).
#[inline]
pub fn stream_copy_unfenced<T: Sample>(src: &[T], dst: &mut [T]) {
    assert_eq!(src.len(), dst.len());
    #[cfg(target_arch = "x86_64")]
    if super::sparse::cpu_has_avx2() {
        // SAFETY: AVX2 is present.
        return unsafe { stream_copy_avx2(src, dst) };
    }
    dst.copy_from_slice(src)
}

/// Order the non-temporal stores made so far before every later store (`sfence`), so
/// that a thread that learns of this one's work (through rayon's join) also sees them.
#[inline]
pub fn stream_fence() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of x86_64.
    unsafe {
        std::arch::x86_64::_mm_sfence()
    };
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn stream_copy_avx2<T: Sample>(src: &[T], dst: &mut [T]) {
    use std::arch::x86_64::*;
    let size = std::mem::size_of::<T>();
    let n = src.len();
    // scalar stores up to the first 32-byte boundary of dst
    let mis = (dst.as_ptr() as usize) % 32;
    let head = if mis == 0 {
        0
    } else {
        ((32 - mis) / size).min(n)
    };
    if !(dst.as_ptr() as usize).is_multiple_of(size) || !(32 - mis).is_multiple_of(size) {
        return dst.copy_from_slice(src);
    }
    dst[..head].copy_from_slice(&src[..head]);
    let per = 32 / size;
    let body = (n - head) / per * per;
    let (ps, pd) = (
        unsafe { src.as_ptr().add(head) } as *const __m256i,
        unsafe { dst.as_mut_ptr().add(head) } as *mut __m256i,
    );
    for v in 0..body / per {
        // SAFETY: v·32 + 32 bytes lie within src[head..head + body] and dst likewise;
        // dst + head is 32-byte aligned.
        unsafe { _mm256_stream_si256(pd.add(v), _mm256_loadu_si256(ps.add(v))) };
    }
    dst[head + body..].copy_from_slice(&src[head + body..]);
}

/// `dst[c·stride + r] = src[r·cols + c]` for a `rows × cols` block `src`: the lanes of one
/// axis become rows of another. 8 × 8 tiles in registers for 4-byte samples with AVX2.
pub fn transpose<T: Sample>(src: &[T], rows: usize, cols: usize, dst: &mut [T], stride: usize) {
    assert!(src.len() >= rows * cols);
    assert!(cols == 0 || rows == 0 || (stride >= rows && dst.len() >= (cols - 1) * stride + rows));
    #[cfg(target_arch = "x86_64")]
    if std::mem::size_of::<T>() == 4 && super::sparse::cpu_has_avx2() {
        // SAFETY: AVX2 is present; T is a 4-byte float, moved as bits; bounds above.
        return unsafe { transpose_avx2_32(src, rows, cols, dst, stride) };
    }
    transpose_generic(src, rows, cols, dst, stride, 0, 0)
}

/// The tiles of [`transpose`] from row `r0` and column `c0` on (the rest of the block is
/// done), plain loops.
fn transpose_generic<T: Sample>(
    src: &[T],
    rows: usize,
    cols: usize,
    dst: &mut [T],
    stride: usize,
    r0: usize,
    c0: usize,
) {
    const B: usize = 16;
    // columns c0.. of every row, then rows r0.. of columns ..c0
    for (rs, cs) in [((0, rows), (c0, cols)), ((r0, rows), (0, c0))] {
        for rb in (rs.0..rs.1).step_by(B) {
            for cb in (cs.0..cs.1).step_by(B) {
                for r in rb..(rb + B).min(rs.1) {
                    let line = &src[r * cols + cb..r * cols + (cb + B).min(cs.1)];
                    for (i, &v) in line.iter().enumerate() {
                        dst[(cb + i) * stride + r] = v;
                    }
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn transpose_avx2_32<T: Sample>(
    src: &[T],
    rows: usize,
    cols: usize,
    dst: &mut [T],
    stride: usize,
) {
    use std::arch::x86_64::*;
    let (r8, c8) = (rows / 8 * 8, cols / 8 * 8);
    let (r16, c16) = (rows / 16 * 16, cols / 16 * 16);
    let ps = src.as_ptr() as *const f32;
    let pd = dst.as_mut_ptr() as *mut f32;
    // the 8 × 8 tile at row rb, column cb of src
    let tile = |rb: usize, cb: usize| {
        // SAFETY: rows rb..rb+8 < rows, columns cb..cb+8 <= cols of src; dst rows
        // cb..cb+8 at stride, columns rb..rb+8 <= rows <= stride (checked by the caller).
        unsafe {
            let l = |i: usize| _mm256_loadu_ps(ps.add((rb + i) * cols + cb));
            let (a0, a1, a2, a3, a4, a5, a6, a7) = (l(0), l(1), l(2), l(3), l(4), l(5), l(6), l(7));
            let t0 = _mm256_unpacklo_ps(a0, a1);
            let t1 = _mm256_unpackhi_ps(a0, a1);
            let t2 = _mm256_unpacklo_ps(a2, a3);
            let t3 = _mm256_unpackhi_ps(a2, a3);
            let t4 = _mm256_unpacklo_ps(a4, a5);
            let t5 = _mm256_unpackhi_ps(a4, a5);
            let t6 = _mm256_unpacklo_ps(a6, a7);
            let t7 = _mm256_unpackhi_ps(a6, a7);
            let u0 = _mm256_shuffle_ps(t0, t2, 0x44);
            let u1 = _mm256_shuffle_ps(t0, t2, 0xEE);
            let u2 = _mm256_shuffle_ps(t1, t3, 0x44);
            let u3 = _mm256_shuffle_ps(t1, t3, 0xEE);
            let u4 = _mm256_shuffle_ps(t4, t6, 0x44);
            let u5 = _mm256_shuffle_ps(t4, t6, 0xEE);
            let u6 = _mm256_shuffle_ps(t5, t7, 0x44);
            let u7 = _mm256_shuffle_ps(t5, t7, 0xEE);
            let s = |i: usize, v: __m256| _mm256_storeu_ps(pd.add((cb + i) * stride + rb), v);
            s(0, _mm256_permute2f128_ps(u0, u4, 0x20));
            s(1, _mm256_permute2f128_ps(u1, u5, 0x20));
            s(2, _mm256_permute2f128_ps(u2, u6, 0x20));
            s(3, _mm256_permute2f128_ps(u3, u7, 0x20));
            s(4, _mm256_permute2f128_ps(u0, u4, 0x31));
            s(5, _mm256_permute2f128_ps(u1, u5, 0x31));
            s(6, _mm256_permute2f128_ps(u2, u6, 0x31));
            s(7, _mm256_permute2f128_ps(u3, u7, 0x31));
        }
    };
    // 16 × 16 blocks: 64 bytes of every source row and of every destination row, whole
    // cache lines written at once (tile by tile across a row of 8 × 8 tiles, the
    // destination's rows at a power-of-two stride share a few cache sets and their
    // half-written lines were evicted before the next tile completed them)
    for rb in (0..r16).step_by(16) {
        for cb in (0..c16).step_by(16) {
            tile(rb, cb);
            tile(rb + 8, cb);
            tile(rb, cb + 8);
            tile(rb + 8, cb + 8);
        }
    }
    // the 8-wide rest: rows r16..r8 of every column, columns c16..c8 of rows ..r16
    for rb in (r16..r8).step_by(8) {
        for cb in (0..c8).step_by(8) {
            tile(rb, cb);
        }
    }
    for rb in (0..r16).step_by(8) {
        for cb in (c16..c8).step_by(8) {
            tile(rb, cb);
        }
    }
    transpose_generic(src, rows, cols, dst, stride, r8, c8)
}

/// `dst[i·len ..][..len] = Σ_k w_rk · src[c_rk·len ..][..len]` for the rows `r` of `op`
/// in `rows` (`i = r − rows.start`): [`combine`] for every row of an operator whose
/// elements are rows of `len` samples, in one call (short rows, e.g. the lanes of a
/// volume's plane, spend as long in a call's set-up as in its loop). The same sums in
/// the same order as [`combine`]: the same bits.
pub fn combine_rows<T: Sample>(
    op: &super::sparse::Csr,
    src: &[T],
    len: usize,
    rows: std::ops::Range<usize>,
    dst: &mut [T],
) {
    assert!(rows.end <= op.rows() && op.cols() * len <= src.len());
    assert!(rows.len() * len <= dst.len());
    #[cfg(target_arch = "x86_64")]
    if std::any::TypeId::of::<T>() == std::any::TypeId::of::<f32>() && super::sparse::cpu_has_avx2()
    {
        let (ps, pd) = (src.as_ptr() as *const f32, dst.as_mut_ptr() as *mut f32);
        // SAFETY: AVX2 is present; T is f32; every column of `op` is below `op.cols()`,
        // so each source row is inside `src`, and each output row inside `dst` (asserted).
        return unsafe { combine_rows_avx2_f32(op, ps, len, rows, pd) };
    }
    for (i, r) in rows.enumerate() {
        let (cols, ws) = op.row_slices(r);
        let at = |c: u32| c as usize * len;
        combine_taps(&mut dst[i * len..i * len + len], cols, ws, |c| {
            &src[at(c)..at(c) + len]
        });
    }
}

/// `out = Σ_t w_t · tap(c_t)`: [`combine`] over the inputs `tap(c)` of a sparse row's
/// columns `cols` and weights `ws` (each input at least `out.len()` samples).
pub fn combine_taps<'t, T: Sample + 't>(
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
        combine(out, &taps[..cols.len()], &w[..cols.len()]);
    } else {
        let t: Vec<&[T]> = cols.iter().map(|&c| tap(c)).collect();
        let wv: Vec<T> = ws.iter().map(|&x| T::from_f64(x)).collect();
        combine(out, &t, &wv);
    }
}

/// [`combine_rows`] for `f32` with AVX2: the rows' tap loops ([`taps_avx2_f32`]) called
/// from one function, without a call's checks and dispatch per row.
///
/// # Safety
/// AVX2 present; every column of `op` times `len` plus `len` within `src`; the output rows
/// `0..rows.len()` of `len` samples within `dst`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn combine_rows_avx2_f32(
    op: &super::sparse::Csr,
    src: *const f32,
    len: usize,
    rows: std::ops::Range<usize>,
    dst: *mut f32,
) {
    let mut partner = [0usize; 32];
    let mut wf = [0f32; 32];
    let mut pf = [std::ptr::null::<f32>(); 32];
    for (i, r) in rows.enumerate() {
        let (cols, ws) = op.row_slices(r);
        // SAFETY (all): the caller's bounds; columns below op.cols().
        let o = unsafe { dst.add(i * len) };
        let n = cols.len();
        if n <= 32 {
            for k in 0..n {
                wf[k] = ws[k] as f32;
                pf[k] = unsafe { src.add(cols[k] as usize * len) };
            }
            if pair_taps(&wf[..n], &mut partner[..n]) {
                unsafe { terms_avx2_f32(o, len, &pf[..n], &wf[..n], &partner[..n]) };
                continue;
            }
        }
        macro_rules! arm {
            ($n:literal) => {{
                let p: [*const f32; $n] =
                    std::array::from_fn(|k| unsafe { src.add(cols[k] as usize * len) });
                let w: [f32; $n] = std::array::from_fn(|k| ws[k] as f32);
                unsafe { taps_avx2_f32::<$n>(o, len, &p, &w) }
            }};
        }
        match cols.len() {
            0 => unsafe { std::ptr::write_bytes(o, 0, len) },
            1 => arm!(1),
            2 => arm!(2),
            3 => arm!(3),
            4 => arm!(4),
            5 => arm!(5),
            6 => arm!(6),
            7 => arm!(7),
            8 => arm!(8),
            _ => {
                // SAFETY: as above, as slices.
                let out = unsafe { std::slice::from_raw_parts_mut(o, len) };
                let t: Vec<&[f32]> = cols
                    .iter()
                    .map(|&c| unsafe { std::slice::from_raw_parts(src.add(c as usize * len), len) })
                    .collect();
                let wv: Vec<f32> = ws.iter().map(|&x| x as f32).collect();
                combine_with(Simd::detected(), out, &t, &wv);
            }
        }
    }
}

/// Two [`combine`]s over one set of inputs: `o1[i] = Σ_{k ∈ m1} w1[k]·src[k][i]` and
/// `o2[i] = Σ_{k ∈ m2} w2[k]·src[k][i]`, where bit `k` of a mask says that input `k` is
/// one of that output's taps. Each output sums its taps in increasing `k`, the first
/// assigning, so the bits are those of one [`combine`] per output over its own taps;
/// each input is loaded once for both outputs (e.g. a coarse and a detail row, or an even
/// and an odd fine row, which read the same stretch of their lane: the loads, not the
/// multiplies, bound the single combines).
///
/// Every `src[k]` must hold at least `o1.len()` samples; `o2` as long as `o1`; both masks
/// non-empty and within `src`.
pub fn combine_pair<T: Sample>(
    o1: &mut [T],
    o2: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) {
    combine_pair_with(Simd::detected(), o1, o2, src, w1, m1, w2, m2)
}

/// [`combine_pair`] with the build `simd` (at most [`Simd::detected`]; tests compare the
/// builds).
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_with<T: Sample>(
    simd: Simd,
    o1: &mut [T],
    o2: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) {
    let entry = if simd >= Simd::Avx2 {
        pair_entry(w1, m1, w2, m2)
    } else {
        None
    };
    combine_pair_at(simd, entry, o1, o2, src, w1, m1, w2, m2, false)
}

/// [`combine_pair`] with the pair's [`pair_entry`] looked up before (`entry` must be it,
/// or `None` for one output at a time); `split`: each output split into its even
/// samples, then its odd ones, as [`deinterleave`] places them (the same bits).
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_at<T: Sample>(
    simd: Simd,
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
    assert!(simd <= Simd::detected(), "{simd:?} is not available");
    #[cfg(target_arch = "x86_64")]
    if let (true, Some(entry)) = (simd >= Simd::Avx2, entry) {
        let p = input_ptrs(src);
        let o = [o1.as_mut_ptr(), o2.as_mut_ptr()];
        let wide = simd == Simd::Avx512;
        // SAFETY: AVX2 (and AVX-512 when `wide`) present; lengths and masks checked
        // above; one step.
        if unsafe {
            pair_avx2_at(
                entry,
                o,
                o1.len(),
                &p[..u],
                w1,
                m1,
                w2,
                m2,
                1,
                0,
                [0, 0],
                false,
                split,
                wide,
            )
        } {
            return;
        }
    }
    let _ = entry;
    pair_by_parts(o1, o2, src, w1, m1, w2, m2, simd);
    if split {
        for o in [o1, o2] {
            let whole = o.to_vec();
            deinterleave(&whole, 1, o);
        }
    }
}

/// [`combine_pair`] over two sparse rows (`(columns, weights)`, columns increasing) and
/// the inputs `tap(c)` of their columns: `o1` the first row, `o2` the second, each input
/// they share read once. `false` (nothing written) when the rows share no column or read
/// more than [`PAIR_INPUTS`] inputs together (then two [`combine_taps`] do the same).
///
/// `memo` remembers the last pair's pattern (the regular row pairs repeat one); `split`
/// writes each output as its even samples, then its odd ones ([`combine_pair_at`]).
pub fn combine_pair_taps<'t, T: Sample + 't>(
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
    let simd = Simd::detected();
    let entry = if simd >= Simd::Avx2 {
        memo.entry(&a[..n], m1, &b[..n], m2)
    } else {
        None
    };
    combine_pair_at(
        simd,
        entry,
        o1,
        o2,
        &src[..n],
        &a[..n],
        m1,
        &b[..n],
        m2,
        split,
    );
    true
}

/// Most inputs two rows combined together by [`combine_pair_taps`] may read.
pub const PAIR_INPUTS: usize = 8;

/// Whether [`combine_pair_taps`] combines two rows reading the columns `c1` and `c2`
/// (increasing) together: they share a column and read at most [`PAIR_INPUTS`] together.
pub fn rows_pair(c1: &[u32], c2: &[u32]) -> bool {
    pair_columns(c1, c2).is_some()
}

/// The columns that two rows (their increasing columns `c1`, `c2`) read together, how
/// many, and each row's mask over them; `None` when the rows share no column or read
/// more than [`PAIR_INPUTS`] together.
fn pair_columns(c1: &[u32], c2: &[u32]) -> Option<([u32; PAIR_INPUTS], usize, u32, u32)> {
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
fn check_pair<T>(u: usize, w1: &[T], m1: u32, w2: &[T], m2: u32) {
    assert!(u <= 32 && w1.len() == u && w2.len() == u);
    let all = if u == 32 { u32::MAX } else { (1u32 << u) - 1 };
    assert!(m1 != 0 && m2 != 0 && m1 & !all == 0 && m2 & !all == 0);
}

/// The start of every input (at most 32), null past them.
fn input_ptrs<T>(src: &[&[T]]) -> [*const T; 32] {
    std::array::from_fn(|k| src.get(k).map_or(std::ptr::null(), |s| s.as_ptr()))
}

/// [`combine_pair`] as one [`combine`] per output (the patterns without an AVX2 build,
/// and the reference the tests compare with).
#[allow(clippy::too_many_arguments)]
fn pair_by_parts<T: Sample>(
    o1: &mut [T],
    o2: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
    simd: Simd,
) {
    for (o, w, m) in [(o1, w1, m1), (o2, w2, m2)] {
        let mut s: [&[T]; 32] = [&[]; 32];
        let mut wk = [T::default(); 32];
        let mut n = 0;
        for k in (0..src.len()).filter(|&k| m >> k & 1 == 1) {
            (s[n], wk[n]) = (src[k], w[k]);
            n += 1;
        }
        combine_with(simd, o, &s[..n], &wk[..n]);
    }
}

/// The tap patterns `(inputs, m1, m2)` with vector builds (AVX2 and AVX-512): the regular rows of the three
/// schemes, analysis (coarse, detail) and synthesis (even, odd fine rows), as
/// [`super::polyphase`] pairs them.
#[cfg(target_arch = "x86_64")]
macro_rules! pair_patterns {
    ($m:ident) => {
        $m!(
            // (U, M1, M2, P1, N1, P2, N2, R1, R2): inputs, the masks of the two outputs,
            // the terms of weight +1 and −1 of each (added or subtracted, not
            // multiplied), and the pairs of each (see `pattern_of`)
            (2, 0b11, 0b11, 0, 0, 0, 0, 0, 0),
            (4, 0b1111, 0b1111, 0, 0, 0, 0, 0, 0),
            (6, 0b001111, 0b111100, 0, 0, 0, 0, 0, 0),
            (7, 0b0111011, 0b1111111, 0, 0, 0, 0, 0, 0),
            (7, 0b1111111, 0b1111100, 0, 0, 0, 0, 0, 0),
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0, 0, 0),
            (7, 0b1111111, 0b0011111, 0, 0, 0, 0, 0, 0),
            // the regular rows of the schemes, their symmetric taps paired: Haar's
            // analysis and synthesis
            (2, 0b11, 0b11, 0, 0, 0, 0, 0x2, 0),
            (2, 0b11, 0b11, 0b1, 0, 0b1, 0b10, 0x2, 0),
            // Chaikin's analysis and synthesis
            (4, 0b1111, 0b1111, 0, 0, 0, 0, 0x34, 0),
            (6, 0b001111, 0b111100, 0, 0, 0, 0, 0, 0x5600),
            (4, 0b1111, 0b1111, 0, 0, 0, 0, 0x3, 0x3),
            // cubic's analysis (`a`'s centre of weight 1) and synthesis (`q`'s of −1)
            (7, 0b1111111, 0b0011111, 0b0001000, 0, 0, 0, 0x567, 0x45),
            (7, 0b1111111, 0b1111100, 0b0001000, 0, 0, 0, 0x567, 0x6700),
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0b0100000, 0x67003, 0x70030),
            (7, 0b0111011, 0b1111111, 0, 0b0010000, 0, 0, 0x6002, 0x67003)
        )
    };
}

/// The pairs and the unit weights of one output of a pair over the inputs `w` (its taps
/// those of `mask`, in increasing `k`): `(p, n, r)` with `p` / `n` the terms (single taps
/// and pairs' first taps) of weight +1 / −1, which the kernels add or subtract instead of
/// multiplying (the same bits), and `r` the pairs of [`pair_taps`], nibble `k` of it
/// `j + 1` for a pair `(k, j)`.
fn pattern_of<T: Sample>(w: &[T], mask: u32) -> (u32, u32, u64) {
    let (mut p, mut n, mut r) = (0u32, 0u32, 0u64);
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
                r |= ((j + 1) as u64) << (4 * k);
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

/// The patterns `(P1, N1, P2, N2, R1, R2)` of the table entries that serve the pair
/// `(w1, m1)`, `(w2, m2)`, best first: the entry with its unit taps and pairs; then,
/// when no taps pair, the plain entry (every tap multiplied: the same bits).
#[allow(clippy::type_complexity)]
fn pair_wants<T: Sample>(
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) -> [Option<(u32, u32, u32, u32, u64, u64)>; 2] {
    let ((p1, n1, r1), (p2, n2, r2)) = (pattern_of(w1, m1), pattern_of(w2, m2));
    let exact = (p1, n1, p2, n2, r1, r2);
    let plain = (0, 0, 0, 0, 0, 0);
    let also = ((r1, r2) == (0, 0) && exact != plain).then_some(plain);
    [Some(exact), also]
}

/// [`seconds`] of a pattern's pairs, as a constant of the kernel built for it.
struct Seconds<const R: u64>;
impl<const R: u64> Seconds<R> {
    const MASK: u32 = seconds(R);
}

/// The second taps of the pairs `r` (as [`pattern_of`] gives them).
const fn seconds(r: u64) -> u32 {
    let mut m = 0u32;
    let mut k = 0;
    while k < 16 {
        let j = (r >> (4 * k)) & 15;
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
    if u > 16 || w2.len() != u {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    {
        let wants = pair_wants(w1, m1, w2, m2);
        macro_rules! find {
            ($(($U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal, $R1:literal, $R2:literal)),*) => {
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
type MemoKey<T> = (usize, u32, u32, [T; PAIR_INPUTS], [T; PAIR_INPUTS]);

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
    fn entry(&mut self, w1: &[T], m1: u32, w2: &[T], m2: u32) -> Option<u8> {
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

/// Dispatch of [`combine_pair`] to [`pair_avx2_f32`] / [`pair_avx2_f64`]: the kernel of
/// table entry `entry` ([`pair_entry`] of the pair), for `count`
/// steps: step `t` reads `src[k] + t·in_step` and writes `o1 + t·out_step[0]`,
/// `o2 + t·out_step[1]` (`len` samples each). `false` (nothing written) when the type has
/// no AVX2 build, or the entry is not one of the inputs' count and masks.
///
/// # Safety
/// AVX2 present, AVX-512F too when `wide` (then the steps of at least one 512-bit vector
/// use it); every access inside its allocation, outputs distinct from each other
/// and from the inputs; the masks as [`combine_pair`] checks them.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn pair_avx2_at<T: Sample>(
    entry: u8,
    o: [*mut T; 2],
    len: usize,
    src: &[*const T],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
    count: usize,
    in_step: usize,
    out_step: [usize; 2],
    merge: bool,
    split: bool,
    wide: bool,
) -> bool {
    use std::any::TypeId;
    let u = src.len();
    if u > 16 || w1.len() != u || w2.len() != u {
        return false;
    }
    debug_assert_eq!(pair_entry(w1, m1, w2, m2), Some(entry));
    macro_rules! go {
        ($t:ty, $f:ident, $g:ident, $U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal, $R1:literal, $R2:literal) => {{
            let wide = wide && len >= 64 / std::mem::size_of::<$t>();
            // (plain loops: the closures of `array::from_fn` were not inlined here)
            let (mut a, mut b) = ([0.0 as $t; $U], [0.0 as $t; $U]);
            for k in 0..$U {
                (a[k], b[k]) = (w1[k].to_f64() as $t, w2[k].to_f64() as $t);
            }
            for t in 0..count {
                // SAFETY: the caller's bounds; T is $t.
                unsafe {
                    let mut p = [std::ptr::null::<$t>(); $U];
                    for k in 0..$U {
                        p[k] = src[k].add(t * in_step) as *const $t;
                    }
                    let q1 = o[0].add(t * out_step[0]) as *mut $t;
                    let q2 = o[1].add(t * out_step[1]) as *mut $t;
                    match (wide, merge, split) {
                        (true, true, _) => {
                            $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2, true, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (true, false, true) => {
                            $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2, false, true>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (true, false, false) => {
                            $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2, false, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, true, _) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2, true, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, false, true) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2, false, true>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, false, false) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2, false, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                    }
                }
            }
            return true;
        }};
    }
    // the entry's kernel (its inputs' count and masks checked: they decide what it reads)
    macro_rules! table {
        ($(($U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal, $R1:literal, $R2:literal)),*) => {
            let mut idx = 0u8;
            $(
                if entry == idx && (u, m1, m2) == ($U, $M1, $M2) {
                    if TypeId::of::<T>() == TypeId::of::<f32>() {
                        go!(f32, pair_avx2_f32, pair_avx512_f32, $U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2)
                    } else if TypeId::of::<T>() == TypeId::of::<f64>() {
                        go!(f64, pair_avx2_f64, pair_avx512_f64, $U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2)
                    }
                }
                idx += 1;
            )*
            let _ = idx;
        };
    }
    pair_patterns!(table);
    false
}

/// Whether [`combine_pair`] has a vector build for the pair `(w1, m1)`, `(w2, m2)` (its
/// inputs' count, masks, unit weights and pairs one of the built patterns): the regular
/// rows of every scheme have one (tested), other pairs go one output at a time.
pub fn combine_pair_has_build<T: Sample>(w1: &[T], m1: u32, w2: &[T], m2: u32) -> bool {
    pair_entry(w1, m1, w2, m2).is_some()
}

/// [`combine_pair`] with its two outputs interleaved into `out`: `out[2i]` the first,
/// `out[2i + 1]` the second (the even and the odd fine samples of synthesis, without a
/// pass through two buffers and [`interleave`]). The same bits; `false` (nothing written)
/// where there is no AVX2 build for the pattern or the type.
pub fn combine_pair_merged<T: Sample>(
    out: &mut [T],
    src: &[&[T]],
    w1: &[T],
    m1: u32,
    w2: &[T],
    m2: u32,
) -> bool {
    combine_pair_merged_at(pair_entry(w1, m1, w2, m2), out, src, w1, m1, w2, m2)
}

/// [`combine_pair_merged`] with the pair's [`pair_entry`] looked up before (`entry` must
/// be it).
pub fn combine_pair_merged_at<T: Sample>(
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
    if let (true, Some(entry)) = (super::sparse::cpu_has_avx2(), entry) {
        let p = input_ptrs(src);
        let o = [out.as_mut_ptr(), out.as_mut_ptr()];
        let wide = Simd::detected() == Simd::Avx512;
        // SAFETY: AVX2 is present, AVX-512F when `wide` (detected); `out` holds 2·len
        // samples, every input len; one step, the merged output written through the
        // first pointer only.
        return unsafe {
            pair_avx2_at(
                entry,
                o,
                len,
                &p[..u],
                w1,
                m1,
                w2,
                m2,
                1,
                0,
                [0, 0],
                true,
                false,
                wide,
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
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_rows<T: Sample>(
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
    pair_rows(
        src, len, cols, in_step, w1, w2, dst, rows, out_step, count, false,
    )
}

/// [`combine_pair_rows`] with every output row split into its even samples, then its
/// odd ones (as [`deinterleave`] makes them, for a next axis that reads them so): the
/// same bits, placed as `deinterleave` places them, without a pass of its own.
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_rows_split<T: Sample>(
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
    pair_rows(
        src, len, cols, in_step, w1, w2, dst, rows, out_step, count, true,
    )
}

#[allow(clippy::too_many_arguments)]
fn pair_rows<T: Sample>(
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
            false,
            split,
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
#[allow(clippy::too_many_arguments)]
pub fn combine_pair_lanes<T: Sample>(
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
            src, off, in_step, w1, w2, dst, out, steps, len, count, merge, false,
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
unsafe fn pair_steps<T: Sample>(
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
    merge: bool,
    split: bool,
) {
    let u = off.len();
    let p = input_ptrs_at(src, off);
    #[cfg(target_arch = "x86_64")]
    if super::sparse::cpu_has_avx2() {
        let d = dst.as_mut_ptr();
        // SAFETY: AVX2 is present (AVX-512F too when detected, the last argument); every
        // input and output stretch lies inside its slice and the outputs of all steps are
        // disjoint (the caller's contract), and `src`, `dst` are distinct slices
        // (borrowed shared and exclusive).
        let done = pair_entry(w1, m1, w2, m2).is_some_and(|entry| unsafe {
            // (merged: both through the first pointer)
            let o = [d.add(out[0]), d.add(if merge { out[0] } else { out[1] })];
            pair_avx2_at(
                entry,
                o,
                len,
                &p[..u],
                w1,
                m1,
                w2,
                m2,
                count,
                in_step,
                out_step,
                merge,
                split,
                Simd::detected() == Simd::Avx512,
            )
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
        pair_by_parts(&mut a, &mut b, &s[..u], w1, m1, w2, m2, Simd::detected());
        let at = [out[0] + out_step[0] * t, out[1] + out_step[1] * t];
        if merge {
            let o = &mut dst[at[0]..][..2 * len];
            for i in 0..len {
                (o[2 * i], o[2 * i + 1]) = (a[i], b[i]);
            }
        } else if split {
            deinterleave(&a, 1, &mut dst[at[0]..][..len]);
            deinterleave(&b, 1, &mut dst[at[1]..][..len]);
        } else {
            dst[at[0]..][..len].copy_from_slice(&a);
            dst[at[1]..][..len].copy_from_slice(&b);
        }
    }
}

/// The inputs at `off[k]` of `src` (at most 32), null past them.
fn input_ptrs_at<T>(src: &[T], off: &[usize]) -> [*const T; 32] {
    assert!(off.len() <= 32);
    std::array::from_fn(|k| off.get(k).map_or(std::ptr::null(), |&o| src[o..].as_ptr()))
}

/// `$body` for `$k` = 0, 1, … 15, each copy with its `$k` a constant (the pair kernels'
/// tap loops, which the compiler must see whole to fold their masks).
macro_rules! unroll16 {
    ($k:ident, $body:block) => {
        unroll16!(@ $k, $body, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
    };
    (@ $k:ident, $body:block, $($n:literal),*) => {
        $( { let $k: usize = $n; $body } )*
    };
}

/// The body of [`combine_pair`] for one pattern: a vector of each output per step, every
/// input loaded once; then scalars.
macro_rules! pair_avx2_body {
    ($name:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $zero:ident, $mul:ident, $add:ident, $sub:ident, $fma:ident, $load:ident, $store:ident, $merge:ident, $split:ident) => {
        /// See [`pair_avx2_body`].
        ///
        /// # Safety
        /// The target feature present; `o1`, `o2` and every `p[k]` valid for `len` samples; `M1`, `M2`
        /// non-empty within `U` bits.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feat)]
        unsafe fn $name<
            const U: usize,
            const M1: u32,
            const M2: u32,
            const P1: u32,
            const N1: u32,
            const P2: u32,
            const N2: u32,
            const R1: u64,
            const R2: u64,
            const MERGE: bool,
            const SPLIT: bool,
        >(
            o1: *mut $t,
            o2: *mut $t,
            len: usize,
            p: &[*const $t; U],
            w1: &[$t; U],
            w2: &[$t; U],
        ) {
            use std::arch::x86_64::*;
            const L: usize = $lanes;
            let (f1, f2) = (M1.trailing_zeros() as usize, M2.trailing_zeros() as usize);
            let mut v1 = [$zero(); U];
            let mut v2 = [$zero(); U];
            for k in 0..U {
                v1[k] = $set1(w1[k]);
                v2[k] = $set1(w2[k]);
            }
            let (s1, s2) = (Seconds::<R1>::MASK, Seconds::<R2>::MASK);
            let minus = $set1(-1.0);
            // one vector of each output at `i`: the terms of `pair_taps` in order, a tap of
            // weight ±1 added or subtracted (`w·x` is `±x` exactly: the same bits)
            macro_rules! calc {
                ($i:expr) => {{
                    let i = $i;
                    let x: [_; U] = std::array::from_fn(|k| {
                        if (M1 | M2) >> k & 1 == 1 {
                            $load(p[k].add(i))
                        } else {
                            $zero()
                        }
                    });
                    macro_rules! out {
                        ($v:ident, $m:ident, $f:ident, $p:ident, $n:ident, $r:ident, $s:ident) => {{
                            let mut acc = $zero();
                            unroll16!(k, {
                                if k < U && $m >> k & 1 == 1 && $s >> k & 1 == 0 {
                                    let j = ($r >> (4 * k) & 15) as usize;
                                    let v = if j > 0 { $add(x[k], x[j - 1]) } else { x[k] };
                                    acc = if k == $f {
                                        if $p >> k & 1 == 1 {
                                            v
                                        } else if $n >> k & 1 == 1 {
                                            $mul(minus, v)
                                        } else {
                                            $mul($v[k], v)
                                        }
                                    } else if $p >> k & 1 == 1 {
                                        $add(acc, v)
                                    } else if $n >> k & 1 == 1 {
                                        $sub(acc, v)
                                    } else if j > 0 {
                                        $fma(v, $v[k], acc)
                                    } else {
                                        $add(acc, $mul($v[k], v))
                                    };
                                }
                            });
                            acc
                        }};
                    }
                    (
                        out!(v1, M1, f1, P1, N1, R1, s1),
                        out!(v2, M2, f2, P2, N2, R2, s2),
                    )
                }};
            }
            // scalars at `i`
            macro_rules! calc1 {
                ($i:expr) => {{
                    let i = $i;
                    let x: [$t; U] = std::array::from_fn(|k| {
                        if (M1 | M2) >> k & 1 == 1 {
                            *p[k].add(i)
                        } else {
                            0.0
                        }
                    });
                    macro_rules! out {
                        ($w:ident, $m:ident, $f:ident, $p:ident, $n:ident, $r:ident, $s:ident) => {{
                            let mut acc: $t = 0.0;
                            unroll16!(k, {
                                if k < U && $m >> k & 1 == 1 && $s >> k & 1 == 0 {
                                    let j = ($r >> (4 * k) & 15) as usize;
                                    let v = if j > 0 { x[k] + x[j - 1] } else { x[k] };
                                    acc = if k == $f {
                                        if $p >> k & 1 == 1 {
                                            v
                                        } else if $n >> k & 1 == 1 {
                                            -v
                                        } else {
                                            $w[k] * v
                                        }
                                    } else if $p >> k & 1 == 1 {
                                        acc + v
                                    } else if $n >> k & 1 == 1 {
                                        acc - v
                                    } else if j > 0 {
                                        v.mul_add($w[k], acc)
                                    } else {
                                        acc + $w[k] * v
                                    };
                                }
                            });
                            acc
                        }};
                    }
                    (
                        out!(w1, M1, f1, P1, N1, R1, s1),
                        out!(w2, M2, f2, P2, N2, R2, s2),
                    )
                }};
            }
            if SPLIT {
                // each output split into its even samples, then its odd ones (as
                // `deinterleave` does), two vectors at a time
                let ne = len.div_ceil(2);
                let mut i = 0;
                // SAFETY: i + 2L <= len; the even outputs i/2.. < ne, the odd ones
                // ne + i/2 + L <= ne + len/2 <= len.
                unsafe {
                    while i + 2 * L <= len {
                        let (a1, a2) = calc!(i);
                        let (b1, b2) = calc!(i + L);
                        let (e1, d1) = $split!(a1, b1);
                        let (e2, d2) = $split!(a2, b2);
                        $store(o1.add(i / 2), e1);
                        $store(o1.add(ne + i / 2), d1);
                        $store(o2.add(i / 2), e2);
                        $store(o2.add(ne + i / 2), d2);
                        i += 2 * L;
                    }
                    while i < len {
                        let (a1, a2) = calc1!(i);
                        let at = if i % 2 == 0 { i / 2 } else { ne + i / 2 };
                        *o1.add(at) = a1;
                        *o2.add(at) = a2;
                        i += 1;
                    }
                }
                return;
            }
            macro_rules! step {
                ($i:expr) => {{
                    let i = $i;
                    let (a1, a2) = calc!(i);
                    if MERGE {
                        // o1[2i] = a1[i], o1[2i + 1] = a2[i]
                        let (lo, hi) = $merge!(a1, a2);
                        $store(o1.add(2 * i), lo);
                        $store(o1.add(2 * i + L), hi);
                    } else {
                        $store(o1.add(i), a1);
                        $store(o2.add(i), a2);
                    }
                }};
            }
            let mut i = 0;
            // SAFETY (all blocks): i + width <= len, so every access is inside the runs.
            unsafe {
                while i + L <= len {
                    step!(i);
                    i += L;
                }
                if i < len && len >= L {
                    // the last vector again, ending at `len` (its first samples
                    // recomputed: the same sums, the same bits, no aliasing as the
                    // outputs and inputs are apart) instead of scalars; outside the
                    // loop, whose control it would otherwise lengthen by a third
                    step!(len - L);
                    i = len;
                }
                while i < len {
                    let (a1, a2) = calc1!(i);
                    if MERGE {
                        *o1.add(2 * i) = a1;
                        *o1.add(2 * i + 1) = a2;
                    } else {
                        *o1.add(i) = a1;
                        *o2.add(i) = a2;
                    }
                    i += 1;
                }
            }
        }
    };
}

/// The two vectors `a`, `b` interleaved, `(a0 b0 a1 b1 …)`, as two vectors (macros, so
/// that they inline into the kernels).
macro_rules! merge_ps256 {
    ($a:expr, $b:expr) => {{
        let (lo, hi) = (_mm256_unpacklo_ps($a, $b), _mm256_unpackhi_ps($a, $b));
        (
            _mm256_permute2f128_ps::<0x20>(lo, hi),
            _mm256_permute2f128_ps::<0x31>(lo, hi),
        )
    }};
}
macro_rules! merge_pd256 {
    ($a:expr, $b:expr) => {{
        let (lo, hi) = (_mm256_unpacklo_pd($a, $b), _mm256_unpackhi_pd($a, $b));
        (
            _mm256_permute2f128_pd::<0x20>(lo, hi),
            _mm256_permute2f128_pd::<0x31>(lo, hi),
        )
    }};
}
macro_rules! merge_ps512 {
    ($a:expr, $b:expr) => {{
        let lo = _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
        let hi = _mm512_setr_epi32(8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31);
        (
            _mm512_permutex2var_ps($a, lo, $b),
            _mm512_permutex2var_ps($a, hi, $b),
        )
    }};
}
macro_rules! merge_pd512 {
    ($a:expr, $b:expr) => {{
        let lo = _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11);
        let hi = _mm512_setr_epi64(4, 12, 5, 13, 6, 14, 7, 15);
        (
            _mm512_permutex2var_pd($a, lo, $b),
            _mm512_permutex2var_pd($a, hi, $b),
        )
    }};
}
/// Two vectors `a`, `b` of consecutive samples `(x0 x1 … )` split into their even samples
/// `(x0 x2 …)` and their odd ones `(x1 x3 …)` (the inverse of the `merge_*` macros).
macro_rules! split_ps256 {
    ($a:expr, $b:expr) => {{
        let ev = _mm256_shuffle_ps::<0x88>($a, $b); // x0 x2 x8 x10 | x4 x6 x12 x14
        let od = _mm256_shuffle_ps::<0xDD>($a, $b); // x1 x3 x9 x11 | x5 x7 x13 x15
        (
            _mm256_castpd_ps(_mm256_permute4x64_pd::<0xD8>(_mm256_castps_pd(ev))),
            _mm256_castpd_ps(_mm256_permute4x64_pd::<0xD8>(_mm256_castps_pd(od))),
        )
    }};
}
macro_rules! split_pd256 {
    ($a:expr, $b:expr) => {{
        let (ev, od) = (_mm256_unpacklo_pd($a, $b), _mm256_unpackhi_pd($a, $b));
        (
            _mm256_permute4x64_pd::<0xD8>(ev),
            _mm256_permute4x64_pd::<0xD8>(od),
        )
    }};
}
macro_rules! split_ps512 {
    ($a:expr, $b:expr) => {{
        let ev = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
        let od = _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
        (
            _mm512_permutex2var_ps($a, ev, $b),
            _mm512_permutex2var_ps($a, od, $b),
        )
    }};
}
macro_rules! split_pd512 {
    ($a:expr, $b:expr) => {{
        let ev = _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14);
        let od = _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15);
        (
            _mm512_permutex2var_pd($a, ev, $b),
            _mm512_permutex2var_pd($a, od, $b),
        )
    }};
}
/// The four builds of the tap loops ([`taps_avx2_body`]) and of the pair loops
/// ([`pair_avx2_body`]): one line each, its names, target feature, type, lanes and
/// intrinsics.
macro_rules! builds {
    ($($taps:ident, $pair:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $zero:ident, $mul:ident, $add:ident, $sub:ident, $fma:ident, $load:ident, $store:ident, $merge:ident, $split:ident;)*) => {
        $(
            taps_avx2_body!($taps, $feat, $t, $lanes, $set1, $zero, $mul, $add, $load, $store);
            pair_avx2_body!($pair, $feat, $t, $lanes, $set1, $zero, $mul, $add, $sub, $fma, $load, $store, $merge, $split);
        )*
    };
}

builds! {
    taps_avx2_f32, pair_avx2_f32, "avx2,fma", f32, 8, _mm256_set1_ps, _mm256_setzero_ps, _mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps, _mm256_fmadd_ps, _mm256_loadu_ps, _mm256_storeu_ps, merge_ps256, split_ps256;
    taps_avx2_f64, pair_avx2_f64, "avx2,fma", f64, 4, _mm256_set1_pd, _mm256_setzero_pd, _mm256_mul_pd, _mm256_add_pd, _mm256_sub_pd, _mm256_fmadd_pd, _mm256_loadu_pd, _mm256_storeu_pd, merge_pd256, split_pd256;
    taps_avx512_f32, pair_avx512_f32, "avx512f,fma", f32, 16, _mm512_set1_ps, _mm512_setzero_ps, _mm512_mul_ps, _mm512_add_ps, _mm512_sub_ps, _mm512_fmadd_ps, _mm512_loadu_ps, _mm512_storeu_ps, merge_ps512, split_ps512;
    taps_avx512_f64, pair_avx512_f64, "avx512f,fma", f64, 8, _mm512_set1_pd, _mm512_setzero_pd, _mm512_mul_pd, _mm512_add_pd, _mm512_sub_pd, _mm512_fmadd_pd, _mm512_loadu_pd, _mm512_storeu_pd, merge_pd512, split_pd512;
}

/// Most samples of a lane [`combine_lane_taps`] reads in registers (8 windows of 8).
const LANE_TAPS_SLOTS: usize = 64;

/// `y[t·ys + r] = Σ_k w_k · x[t·w + c_k]` for every lane `t < h` of `x` (lane `t` at
/// `x[t·w ..][..w]`) and every row `(r, taps)` of `rows` (`taps` the `(c_k, w_k)`, summed
/// as [`sum_terms`] says: the bits of [`super::sparse::Csr`]'s row kernel). For the few rows near the ends of a volume's lanes, which read a handful
/// of samples at either end of every lane: with AVX2 and 4-byte samples, 8 lanes at a
/// time, the windows of 8 samples the rows read transposed in registers (one load per
/// lane and window instead of one per tap and row), and the sums of 8 rows that follow
/// one another transposed back (one store per lane instead of one per row and lane).
/// [`LaneTaps`] prepares the rows once for many calls ([`combine_lane_taps_with`]).
pub fn combine_lane_taps<T: Sample>(
    x: &[T],
    w: usize,
    h: usize,
    rows: &[(usize, Vec<(usize, T)>)],
    y: &mut [T],
    ys: usize,
) {
    let rows = rows
        .iter()
        .map(|(r, t)| (*r, t.iter().map(|&(c, wk)| (c, wk.to_f64())).collect()))
        .collect();
    combine_lane_taps_with(&LaneTaps::new(rows, w), x, h, y, ys)
}

/// The rows of [`combine_lane_taps`] (weights as `f64`, each used as `T::from_f64` of
/// it) for lanes of `w` samples, with what the vector build needs worked out once: the
/// windows of 8 samples that cover the taps and the groups of rows stored together.
#[derive(Clone, Debug)]
pub struct LaneTaps {
    w: usize,
    rows: Vec<(usize, Vec<(usize, f64)>)>,
    /// The windows' first samples (a tap at sample `c` of window `i` reads slot
    /// `8·i + c − bases[i]`); empty when they take more than [`LANE_TAPS_SLOTS`] slots or
    /// `w < 8`, and then no vector build runs.
    bases: Vec<usize>,
    /// Every row's terms ([`sum_terms`] of its `f32` weights) as `(slot, slot of the
    /// pair's second tap or usize::MAX, weight)`, row `i`'s at
    /// `slots[ends[i]..ends[i + 1]]`.
    slots: Vec<(usize, usize, f32)>,
    ends: Vec<usize>,
    /// Every row's pairs ([`pair_taps`]) with its weights as `f32`, and as `f64`.
    pairs32: Vec<Vec<usize>>,
    pairs64: Vec<Vec<usize>>,
    /// Rows summed and stored together: `(first row index, count ≤ 8)`, their outputs
    /// `r` following one another. A stretch of 8 or more such rows is covered by groups
    /// of 8 (the last overlapping the one before; its rows written twice, the same
    /// values), shorter ones by one group.
    groups: Vec<(usize, usize)>,
}

impl LaneTaps {
    /// `rows` as [`combine_lane_taps`] takes them, for lanes of `w` samples.
    pub fn new(rows: Vec<(usize, Vec<(usize, f64)>)>, w: usize) -> Self {
        for (_, taps) in &rows {
            assert!(taps.iter().all(|&(c, _)| c < w));
        }
        let mut cols: Vec<usize> = rows
            .iter()
            .flat_map(|(_, t)| t.iter().map(|p| p.0))
            .collect();
        cols.sort_unstable();
        cols.dedup();
        let mut bases: Vec<usize> = Vec::new();
        if w >= 8 {
            for &c in &cols {
                if bases.last().is_none_or(|&b| c >= b + 8) {
                    bases.push(c.min(w - 8));
                }
            }
        }
        if bases.len() * 8 > LANE_TAPS_SLOTS {
            bases.clear();
        }
        let slot = |c: usize| {
            let i = bases
                .iter()
                .position(|&b| b <= c && c < b + 8)
                .expect("covered");
            i * 8 + c - bases[i]
        };
        let (mut slots, mut ends) = (Vec::new(), vec![0]);
        if !bases.is_empty() {
            for (_, t) in &rows {
                let wf: Vec<f32> = t.iter().map(|&(_, wk)| wk as f32).collect();
                let mut partner = vec![0; t.len()];
                pair_taps(&wf, &mut partner);
                for (k, &(c, _)) in t.iter().enumerate() {
                    match partner[k] {
                        SECOND => {}
                        q if q == k => slots.push((slot(c), usize::MAX, wf[k])),
                        q => slots.push((slot(c), slot(t[q].0), wf[k])),
                    }
                }
                ends.push(slots.len());
            }
        }
        // stretches of rows whose outputs follow one another
        let mut groups = Vec::new();
        let mut i = 0;
        while i < rows.len() {
            let mut n = 1;
            while i + n < rows.len() && rows[i + n].0 == rows[i].0 + n {
                n += 1;
            }
            if n < 8 {
                groups.push((i, n));
            } else {
                groups.extend((0..n / 8).map(|g| (i + 8 * g, 8)));
                if n % 8 != 0 {
                    groups.push((i + n - 8, 8));
                }
            }
            i += n;
        }
        let pairs = |to: &dyn Fn(f64) -> f64| -> Vec<Vec<usize>> {
            rows.iter()
                .map(|(_, t)| {
                    let ws: Vec<f64> = t.iter().map(|&(_, wk)| to(wk)).collect();
                    let mut partner = vec![0; ws.len()];
                    pair_taps(&ws, &mut partner);
                    partner
                })
                .collect()
        };
        // (an f32 weight widened to f64 compares as the f32 did)
        let (pairs32, pairs64) = (pairs(&|v| v as f32 as f64), pairs(&|v| v));
        LaneTaps {
            w,
            rows,
            bases,
            slots,
            ends,
            pairs32,
            pairs64,
            groups,
        }
    }
}

/// [`combine_lane_taps`] with its rows prepared (`taps`, for lanes of `taps.w` samples).
pub fn combine_lane_taps_with<T: Sample>(
    taps: &LaneTaps,
    x: &[T],
    h: usize,
    y: &mut [T],
    ys: usize,
) {
    let (w, rows) = (taps.w, &taps.rows);
    if h == 0 || rows.is_empty() {
        return;
    }
    assert!(x.len() >= h * w);
    for (r, _) in rows {
        assert!((h - 1) * ys + r < y.len());
    }
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if std::mem::size_of::<T>() == 4 && !taps.bases.is_empty() && super::sparse::cpu_has_avx2() {
        // SAFETY: AVX2 is present; T is a 4-byte float (f32), bounds checked above and
        // in `LaneTaps::new`.
        done = unsafe { lane_taps_avx2_f32(taps, x, h, y, ys) };
    }
    if done == h {
        return;
    }
    // the rows' pairs as `T` compares their weights (worked out once, in `LaneTaps::new`)
    let pairs = if std::mem::size_of::<T>() == 4 {
        &taps.pairs32
    } else {
        &taps.pairs64
    };
    for ((r, row), partner) in rows.iter().zip(pairs) {
        let mut ws = [T::default(); 32];
        let heap: Vec<T>;
        let ws: &[T] = if row.len() <= 32 {
            for (w, &(_, v)) in ws.iter_mut().zip(row) {
                *w = T::from_f64(v);
            }
            &ws[..row.len()]
        } else {
            heap = row.iter().map(|&(_, v)| T::from_f64(v)).collect();
            &heap
        };
        for t in done..h {
            let lane = &x[t * w..t * w + w];
            y[t * ys + r] = sum_terms(ws, partner, |k| lane[row[k].0]);
        }
    }
}

/// The lanes `..h / 8 · 8` of [`combine_lane_taps_with`] (returned), 8 at a time.
///
/// # Safety
/// AVX2 present, `T` is `f32`, `taps.bases` not empty, and the bounds of
/// [`combine_lane_taps_with`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn lane_taps_avx2_f32<T: Sample>(
    taps: &LaneTaps,
    x: &[T],
    h: usize,
    y: &mut [T],
    ys: usize,
) -> usize {
    use std::arch::x86_64::*;
    let (w, bases) = (taps.w, &taps.bases);
    let px = x.as_ptr() as *const f32;
    let py = y.as_mut_ptr() as *mut f32;
    let mut reg = [_mm256_setzero_ps(); LANE_TAPS_SLOTS];
    let h8 = h / 8 * 8;
    for t0 in (0..h8).step_by(8) {
        for (i, &b) in bases.iter().enumerate() {
            // SAFETY: lanes t0..t0+8 < h, samples b..b+8 <= w of each.
            let l = |j: usize| unsafe { _mm256_loadu_ps(px.add((t0 + j) * w + b)) };
            let a = [l(0), l(1), l(2), l(3), l(4), l(5), l(6), l(7)];
            let t = transpose8_ps(a);
            for (j, v) in t.into_iter().enumerate() {
                reg[i * 8 + j] = v;
            }
        }
        for &(i0, n) in &taps.groups {
            // the sums of rows i0.. for the 8 lanes, one register per row (each sum in a
            // local, so that it stays in a register and the rows' chains overlap)
            let mut acc = [_mm256_setzero_ps(); 8];
            for (q, a) in acc.iter_mut().enumerate().take(n) {
                let i = i0 + q;
                let row = &taps.slots[taps.ends[i]..taps.ends[i + 1]];
                let Some((&(s, s2, wk), rest)) = row.split_first() else {
                    continue;
                };
                // SAFETY: every slot is below `8·bases.len()` ≤ LANE_TAPS_SLOTS (made so
                // by `LaneTaps::new`)
                let r = |s: usize| unsafe { *reg.get_unchecked(s) };
                let wv = _mm256_set1_ps(wk);
                let mut sum = if s2 == usize::MAX {
                    _mm256_mul_ps(wv, r(s))
                } else {
                    _mm256_mul_ps(wv, _mm256_add_ps(r(s), r(s2)))
                };
                for &(s, s2, wk) in rest {
                    let wv = _mm256_set1_ps(wk);
                    sum = if s2 == usize::MAX {
                        _mm256_add_ps(sum, _mm256_mul_ps(wv, r(s)))
                    } else {
                        _mm256_fmadd_ps(_mm256_add_ps(r(s), r(s2)), wv, sum)
                    };
                }
                *a = sum;
            }
            // one register per lane: its outputs r0..r0 + n
            let out = transpose8_ps(acc);
            let r0 = taps.rows[i0].0;
            for (j, &o) in out.iter().enumerate() {
                // SAFETY: (t0 + j)·ys + r0 + n − 1 < y.len(): the rows r0..r0 + n are
                // rows of `taps`, checked by the caller for the last lane.
                let at = unsafe { py.add((t0 + j) * ys + r0) };
                if n == 8 {
                    unsafe { _mm256_storeu_ps(at, o) };
                } else {
                    // the first n samples of o: 4, 2 and 1 at a time
                    let (mut v, mut q) = (_mm256_castps256_ps128(o), 0);
                    if n >= 4 {
                        // SAFETY: as above (q + 4 <= n).
                        unsafe { _mm_storeu_ps(at, v) };
                        (v, q) = (_mm256_extractf128_ps(o, 1), 4);
                    }
                    if n - q >= 2 {
                        // SAFETY: as above (q + 2 <= n).
                        unsafe { _mm_storel_epi64(at.add(q) as *mut __m128i, _mm_castps_si128(v)) };
                        (v, q) = (_mm_movehl_ps(v, v), q + 2);
                    }
                    if n > q {
                        // SAFETY: as above (q < n).
                        unsafe { _mm_store_ss(at.add(q), v) };
                    }
                }
            }
        }
    }
    h8
}

/// Most taps of a row in an [`EdgeGroup`].
pub const EDGE_SPAN: usize = 32;

/// Up to 8 rows `r0..r0 + n` of a sparse operator, one output sample each on a lane of
/// single samples (the rows near the ends of a long lane), computed 8 at once
/// ([`edge_rows`]) with the bits of one row at a time. Rows without pairs go sample by
/// sample: per sample read, the rows' weights and which rows start their sum there or
/// add to it. When some row pairs, step `s` takes instead the `s`-th term of every row's
/// [`sum_terms`] (its one or two inputs gathered, per row).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeGroup {
    pub r0: usize,
    pub n: usize,
    /// The largest sample the rows read.
    last: usize,
    /// Rows without pairs: per sample they read (`cols`, increasing), the rows' weights
    /// and which rows start their sum there or add to it (one broadcast per sample).
    cols: Vec<usize>,
    weights: Vec<[f32; 8]>,
    first: Vec<[u32; 8]>,
    add: Vec<[u32; 8]>,
    /// Rows with pairs: their terms, step by step (empty when no row pairs).
    steps: Vec<EdgeStep>,
    /// Rows with pairs whose inputs lie in at most 4 stretches of 8 samples (e.g. the
    /// first and the last samples of the lane): the starts of those stretches and their
    /// count; the steps then pick their inputs from those vectors in registers
    /// ([`EdgeStep::la`]) instead of gathering them from memory.
    window: Option<([usize; 4], usize)>,
}

/// One term of each of the 8 rows of an [`EdgeGroup`] (masks: all bits set where true).
#[derive(Clone, Debug, PartialEq)]
struct EdgeStep {
    /// The term's input, and its pair's second input (the first again for a single tap).
    a: [i32; 8],
    b: [i32; 8],
    /// `a` and `b` in [`EdgeGroup::window`]: `8·v + o` for sample `o` of vector `v`.
    la: [i32; 8],
    lb: [i32; 8],
    /// The term's weight (as `f32`).
    w: [f32; 8],
    /// The term is a pair (its input the sum of the two).
    paired: [u32; 8],
    /// The row's first term (assigns), a next single tap (adds `w·x`), a next pair (FMA).
    first: [u32; 8],
    single: [u32; 8],
    fused: [u32; 8],
}

impl EdgeGroup {
    /// The rows `r0..r0 + rows.len()` (at most 8), `rows[i]` the `(columns, weights)` of
    /// row `r0 + i`; `None` when a row has more than [`EDGE_SPAN`] taps or its columns do
    /// not increase, or when no row reads any.
    pub fn new(r0: usize, rows: &[(&[u32], &[f64])]) -> Option<EdgeGroup> {
        let n = rows.len();
        assert!((1..=8).contains(&n));
        if rows.iter().any(|(c, _)| c.windows(2).any(|p| p[0] >= p[1])) {
            return None;
        }
        let lo = rows.iter().filter_map(|(c, _)| c.first()).min();
        let hi = rows.iter().filter_map(|(c, _)| c.last()).max();
        let (lo, hi) = match (lo, hi) {
            (Some(&lo), Some(&hi)) => (lo as usize, hi as usize),
            _ => return None,
        };
        if rows.iter().any(|(c, _)| c.len() > EDGE_SPAN) || hi > i32::MAX as usize {
            return None;
        }
        let mut g = EdgeGroup {
            r0,
            n,
            last: hi,
            cols: Vec::new(),
            weights: Vec::new(),
            first: Vec::new(),
            add: Vec::new(),
            steps: Vec::new(),
            window: None,
        };
        let paired = rows.iter().any(|(_, ws)| {
            let wf: Vec<f32> = ws.iter().map(|&v| v as f32).collect();
            pair_taps(&wf, &mut vec![0; wf.len()])
        });
        if !paired {
            let mut cols: Vec<usize> = rows
                .iter()
                .flat_map(|(c, _)| c.iter().map(|&c| c as usize))
                .collect();
            cols.sort_unstable();
            cols.dedup();
            let u = cols.len();
            (g.weights, g.first, g.add) = (vec![[0.0; 8]; u], vec![[0; 8]; u], vec![[0; 8]; u]);
            for (i, (cs, ws)) in rows.iter().enumerate() {
                for (k, (&c, &w)) in cs.iter().zip(ws.iter()).enumerate() {
                    let j = cols.binary_search(&(c as usize)).expect("in the union");
                    g.weights[j][i] = w as f32;
                    if k == 0 {
                        g.first[j][i] = u32::MAX;
                    } else {
                        g.add[j][i] = u32::MAX;
                    }
                }
            }
            g.cols = cols;
            return Some(g);
        }
        let empty = EdgeStep {
            a: [lo as i32; 8],
            b: [lo as i32; 8],
            la: [0; 8],
            lb: [0; 8],
            w: [0.0; 8],
            paired: [0; 8],
            first: [0; 8],
            single: [0; 8],
            fused: [0; 8],
        };
        for (i, (cs, ws)) in rows.iter().enumerate() {
            let wf: Vec<f32> = ws.iter().map(|&v| v as f32).collect();
            let mut partner = vec![0; wf.len()];
            pair_taps(&wf, &mut partner);
            let mut s = 0;
            for k in 0..wf.len() {
                let q = partner[k];
                if q == SECOND {
                    continue;
                }
                if g.steps.len() == s {
                    g.steps.push(empty.clone());
                }
                let st = &mut g.steps[s];
                st.a[i] = cs[k] as i32;
                st.b[i] = cs[k] as i32;
                if q != k {
                    st.b[i] = cs[q] as i32;
                    st.paired[i] = u32::MAX;
                }
                st.w[i] = wf[k];
                if s == 0 {
                    st.first[i] = u32::MAX;
                } else if q == k {
                    st.single[i] = u32::MAX;
                } else {
                    st.fused[i] = u32::MAX;
                }
                s += 1;
            }
        }
        // the stretches of 8 samples that hold the inputs, from the last input down
        let mut used: Vec<usize> = g
            .steps
            .iter()
            .flat_map(|st| st.a[..n].iter().chain(&st.b[..n]))
            .map(|&c| c as usize)
            .collect();
        used.sort_unstable_by(|x, y| y.cmp(x));
        let mut bases = Vec::new();
        for &c in &used {
            if !bases.iter().any(|&b| (b..b + 8).contains(&c)) {
                bases.push(c.saturating_sub(7));
            }
        }
        if (1..=4).contains(&bases.len()) {
            let local = |c: i32| {
                let c = c as usize;
                let v = bases.iter().position(|&b| (b..b + 8).contains(&c));
                let v = v.expect("every input in a stretch");
                (8 * v + c - bases[v]) as i32
            };
            for st in &mut g.steps {
                for i in 0..8 {
                    // (the lanes past `n` read input 0 of the first stretch)
                    (st.la[i], st.lb[i]) = if i < n {
                        (local(st.a[i]), local(st.b[i]))
                    } else {
                        (0, 0)
                    };
                }
            }
            let mut starts = [0; 4];
            starts[..bases.len()].copy_from_slice(&bases);
            g.window = Some((starts, bases.len()));
        }
        Some(g)
    }
}

/// `y[r] = Σ_k w_rk · x[c_rk]` for the rows of every group (`y` and `x` one lane of
/// single samples), 8 rows at a time, when the build has it (AVX2, `f32`); `false`
/// (nothing written) otherwise.
pub fn edge_rows<T: Sample>(groups: &[EdgeGroup], x: &[T], y: &mut [T]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::any::TypeId::of::<T>() == std::any::TypeId::of::<f32>() && super::sparse::cpu_has_avx2()
    {
        for g in groups {
            assert!(g.last < x.len() && g.r0 + g.n <= y.len());
        }
        let (px, py) = (x.as_ptr() as *const f32, y.as_mut_ptr() as *mut f32);
        // SAFETY: AVX2 is present; T is f32; every group's samples and outputs lie inside
        // `x` and `y` (asserted).
        unsafe { edge_rows_avx2_f32(groups, px, x.len(), py) };
        return true;
    }
    let _ = (groups, x, y);
    false
}

/// [`edge_rows`] with AVX2 on `f32`.
///
/// # Safety
/// AVX2 with FMA present; `x` valid for `x_len` samples, past the `last` sample of every
/// group, and `y` for `r0 + n`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn edge_rows_avx2_f32(groups: &[EdgeGroup], x: *const f32, x_len: usize, y: *mut f32) {
    use std::arch::x86_64::*;
    let mut part = [0f32; 8];
    for g in groups {
        let mut acc = _mm256_setzero_ps();
        for (j, &c) in g.cols.iter().enumerate() {
            // SAFETY: c is inside `x`; the arrays are 8 lanes wide.
            unsafe {
                let xv = _mm256_set1_ps(*x.add(c));
                let v = _mm256_mul_ps(_mm256_loadu_ps(g.weights[j].as_ptr()), xv);
                let fm = _mm256_loadu_ps(g.first[j].as_ptr() as *const f32);
                let am = _mm256_loadu_ps(g.add[j].as_ptr() as *const f32);
                acc = _mm256_blendv_ps(acc, v, fm);
                acc = _mm256_blendv_ps(acc, _mm256_add_ps(acc, v), am);
            }
        }
        // the inputs of a step: picked from the window's vectors, or gathered
        let window = g
            .window
            .filter(|(bases, v)| bases[..*v].iter().all(|&b| b + 8 <= x_len));
        let vs = match window {
            // SAFETY: every stretch inside `x` (filtered above).
            Some((bases, v)) => unsafe {
                let at = |i: usize| _mm256_loadu_ps(x.add(bases[i.min(v - 1)]));
                [at(0), at(1), at(2), at(3)]
            },
            None => [_mm256_setzero_ps(); 4],
        };
        // sample `idx` (< 32) of the window in each lane: bit 3 of the index picks
        // between vectors 0 and 1 (2 and 3), bit 4 between those two
        let pick = |idx: __m256i| {
            let p0 = _mm256_permutevar8x32_ps(vs[0], idx);
            let p1 = _mm256_permutevar8x32_ps(vs[1], idx);
            let bit3 = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(idx));
            let lo = _mm256_blendv_ps(p0, p1, bit3);
            if window.is_some_and(|(_, v)| v <= 2) {
                return lo;
            }
            let p2 = _mm256_permutevar8x32_ps(vs[2], idx);
            let p3 = _mm256_permutevar8x32_ps(vs[3], idx);
            let hi = _mm256_blendv_ps(p2, p3, bit3);
            let bit4 = _mm256_castsi256_ps(_mm256_slli_epi32::<27>(idx));
            _mm256_blendv_ps(lo, hi, bit4)
        };
        for st in &g.steps {
            // SAFETY: every index is a sample the group reads, inside `x` (gathered), or
            // inside the window (picked); the arrays are 8 lanes wide.
            unsafe {
                let load = |a: &[i32; 8]| _mm256_loadu_si256(a.as_ptr() as *const __m256i);
                let (xa, xb) = if window.is_some() {
                    (pick(load(&st.la)), pick(load(&st.lb)))
                } else {
                    (
                        _mm256_i32gather_ps::<4>(x, load(&st.a)),
                        _mm256_i32gather_ps::<4>(x, load(&st.b)),
                    )
                };
                let mask = |m: &[u32; 8]| _mm256_loadu_ps(m.as_ptr() as *const f32);
                let v = _mm256_blendv_ps(xa, _mm256_add_ps(xa, xb), mask(&st.paired));
                let w = _mm256_loadu_ps(st.w.as_ptr());
                let m = _mm256_mul_ps(w, v);
                // the three ways from the same `acc` (each lane takes at most one), so
                // that the add and the FMA overlap instead of following one another
                let (add, fma) = (_mm256_add_ps(acc, m), _mm256_fmadd_ps(v, w, acc));
                acc = _mm256_blendv_ps(acc, m, mask(&st.first));
                acc = _mm256_blendv_ps(acc, add, mask(&st.single));
                acc = _mm256_blendv_ps(acc, fma, mask(&st.fused));
            }
        }
        // SAFETY: r0 + n <= y.len().
        unsafe {
            if g.n == 8 {
                _mm256_storeu_ps(y.add(g.r0), acc);
            } else {
                _mm256_storeu_ps(part.as_mut_ptr(), acc);
                std::ptr::copy_nonoverlapping(part.as_ptr(), y.add(g.r0), g.n);
            }
        }
    }
}

/// An 8 × 8 block of `f32` transposed in registers: `out[c]` lane `r` = `a[r]` lane `c`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn transpose8_ps(a: [std::arch::x86_64::__m256; 8]) -> [std::arch::x86_64::__m256; 8] {
    use std::arch::x86_64::*;
    let t0 = _mm256_unpacklo_ps(a[0], a[1]);
    let t1 = _mm256_unpackhi_ps(a[0], a[1]);
    let t2 = _mm256_unpacklo_ps(a[2], a[3]);
    let t3 = _mm256_unpackhi_ps(a[2], a[3]);
    let t4 = _mm256_unpacklo_ps(a[4], a[5]);
    let t5 = _mm256_unpackhi_ps(a[4], a[5]);
    let t6 = _mm256_unpacklo_ps(a[6], a[7]);
    let t7 = _mm256_unpackhi_ps(a[6], a[7]);
    let u0 = _mm256_shuffle_ps(t0, t2, 0x44);
    let u1 = _mm256_shuffle_ps(t0, t2, 0xEE);
    let u2 = _mm256_shuffle_ps(t1, t3, 0x44);
    let u3 = _mm256_shuffle_ps(t1, t3, 0xEE);
    let u4 = _mm256_shuffle_ps(t4, t6, 0x44);
    let u5 = _mm256_shuffle_ps(t4, t6, 0xEE);
    let u6 = _mm256_shuffle_ps(t5, t7, 0x44);
    let u7 = _mm256_shuffle_ps(t5, t7, 0xEE);
    [
        _mm256_permute2f128_ps(u0, u4, 0x20),
        _mm256_permute2f128_ps(u1, u5, 0x20),
        _mm256_permute2f128_ps(u2, u6, 0x20),
        _mm256_permute2f128_ps(u3, u7, 0x20),
        _mm256_permute2f128_ps(u0, u4, 0x31),
        _mm256_permute2f128_ps(u1, u5, 0x31),
        _mm256_permute2f128_ps(u2, u6, 0x31),
        _mm256_permute2f128_ps(u3, u7, 0x31),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edge groups of the schemes' lanes pick their inputs from registers (a window
    /// of at most 4 vectors), with the bits of the gathered inputs.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn edge_windows_give_the_bits_of_gathers() {
        use crate::scheme::{polyphase::Polyphase, two_scale::TwoScale, Boundary, Scheme};
        if !super::super::sparse::cpu_has_avx2() {
            // said past the harness's capture, so that a passing run shows the skip
            assert!(
                std::env::var("MRA_REQUIRE_AVX2").as_deref() != Ok("1"),
                "MRA_REQUIRE_AVX2=1 but the AVX2 build of the kernels does not run here"
            );
            use std::io::Write;
            let _ = writeln!(
                std::io::stderr(),
                "skipped: edge_windows_give_the_bits_of_gathers: no AVX2 build here"
            );
            return;
        }
        let mut windows = 0;
        for scheme in [Scheme::Haar, Scheme::Chaikin, Scheme::Cubic] {
            for boundary in [
                Boundary::Interpolating,
                Boundary::Periodic,
                Boundary::Symmetric,
            ] {
                for m in [8, 9, 16, 33, 64, 101] {
                    let t = TwoScale::new(scheme, boundary, m);
                    for op in [&t.analysis, &t.synthesis] {
                        let p = Polyphase::new(op);
                        let x: Vec<f32> = (0..m)
                            .map(|i| ((i * 37 % 23) as f32 - 11.0) / 7.0)
                            .collect();
                        let mut gathered = p.edges.clone();
                        for g in &mut gathered {
                            windows += usize::from(g.window.is_some() && !g.steps.is_empty());
                            g.window = None;
                        }
                        let (mut y1, mut y2) = (vec![0f32; m], vec![0f32; m]);
                        assert!(edge_rows(&p.edges, &x, &mut y1));
                        assert!(edge_rows(&gathered, &x, &mut y2));
                        let bits = |y: &[f32]| y.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&y1), bits(&y2), "{scheme:?} {boundary:?} {m}");
                    }
                }
            }
        }
        assert!(windows > 0, "no edge group picks from registers");
    }

    /// The memo answers what [`pair_entry`] answers, also when a pair with the same
    /// inputs and masks but other weights (or unit taps) comes between.
    #[test]
    fn pair_memo_follows_the_weights() {
        // cubic's analysis pair (coarse `a` with its centre of weight 1, detail `b`)
        let a = [0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125];
        let b = [0.0, 0.0, -0.125, 0.5, -0.75, 0.5, -0.125];
        // the same masks, weights without pairs or unit taps
        let c = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7];
        let d = [0.0, 0.0, 0.8, 0.9, 1.1, 1.2, 1.3];
        let (m1, m2) = (0b1111111, 0b1111100);
        let mut memo = PairMemo::<f32>::default();
        for (w1, w2) in [(a, b), (c, d), (c, d), (a, b), (a, b), (c, d)] {
            let (w1, w2) = (w1.map(|x| x as f32), w2.map(|x| x as f32));
            let want = pair_entry(&w1, m1, &w2, m2);
            assert_eq!(memo.entry(&w1, m1, &w2, m2), want);
        }
        #[cfg(target_arch = "x86_64")]
        {
            let (w1, w2) = (a.map(|x| x as f32), b.map(|x| x as f32));
            let (v1, v2) = (c.map(|x| x as f32), d.map(|x| x as f32));
            // both have builds, and different ones
            let (e1, e2) = (pair_entry(&w1, m1, &w2, m2), pair_entry(&v1, m1, &v2, m2));
            assert!(e1.is_some() && e2.is_some() && e1 != e2);
        }
    }
}
