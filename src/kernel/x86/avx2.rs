//! AVX2 and AVX-512 builds of the combines, splits, transposes and streaming stores.
//! Every function here gives the bits of its plain-loop twin in `scalar.rs`.

use crate::kernel::*;

/// [`combine`]'s AVX2 build (`wide`: AVX-512F present too, see [`taps_avx2`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn combine_avx2<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T], wide: bool) {
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

/// [`taps`] with AVX2 intrinsics for `f32`/`f64`: blocks of four vectors keep four
/// independent sums in flight (each output's sum is a chain of dependent adds in a fixed
/// order, for the bits, so one vector at a time would wait on add latency), then single
/// vectors, then scalars. Separate multiply and add (rows without pairs, so no FMA): the
/// same bits as the scalar loop. Short runs (lanes of a few hundred samples) are common, so the set-up is kept to
/// plain loops. `wide`: 512-bit vectors (AVX-512F, which the caller has checked) on runs
/// of at least one such vector.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn taps_avx2<T: Sample, const N: usize>(
    out: &mut [T],
    src: &[&[T]],
    w: &[T],
    wide: bool,
) {
    let len = out.len();
    debug_assert!(src.len() == N && src.iter().all(|s| s.len() >= len));
    let o = out.as_mut_ptr();
    if let Some(o) = T::f32_ptr(o) {
        let mut p = [std::ptr::null::<f32>(); N];
        let mut ws = [0f32; N];
        for k in 0..N {
            p[k] = T::f32_ptr(src[k].as_ptr().cast_mut()).map_or(p[k], |q| q.cast_const());
            ws[k] = w[k].to_f64() as f32;
        }
        // SAFETY: AVX2 is present, AVX-512F when `wide`; every source holds `len` samples (checked by
        // `combine`); the samples are f32.
        unsafe {
            if wide && len >= 16 {
                taps_avx512_f32::<N>(o, len, &p, &ws)
            } else {
                taps_avx2_f32::<N>(o, len, &p, &ws)
            }
        }
    } else if let Some(o) = T::f64_ptr(o) {
        let mut p = [std::ptr::null::<f64>(); N];
        let mut ws = [0f64; N];
        for k in 0..N {
            p[k] = T::f64_ptr(src[k].as_ptr().cast_mut()).map_or(p[k], |q| q.cast_const());
            ws[k] = w[k].to_f64();
        }
        // SAFETY: as above; the samples are f64.
        unsafe {
            if wide && len >= 8 {
                taps_avx512_f64::<N>(o, len, &p, &ws)
            } else {
                taps_avx2_f64::<N>(o, len, &p, &ws)
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
        pub(crate) unsafe fn $name<const N: usize>(
            o: *mut $t,
            len: usize,
            p: &[*const $t; N],
            ws: &[$t; N],
        ) {
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
/// rows whose taps pair outside [`combine_pair`]'s patterns (terms looked up per vector),
/// and rows of more than 8 taps without pairs (their terms are their taps in order: the
/// plain sum). `$name_at` takes the terms already made, as pointers: `(first input,
/// second input or null, weight)`.
macro_rules! terms_avx2_body {
    ($name:ident, $name_at:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $mul:ident, $add:ident, $fma:ident, $load:ident, $store:ident) => {
        /// See [`terms_avx2_body`].
        ///
        /// # Safety
        /// The target feature present; `o` and every `p[k]` valid for `len` samples;
        /// `partner` from [`pair_taps`] of `w`, as long as `p`.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feat)]
        pub(crate) unsafe fn $name(
            o: *mut $t,
            len: usize,
            p: &[*const $t],
            w: &[$t],
            partner: &[usize],
        ) {
            // the terms: (first input, second input or null, weight)
            let mut terms = [(std::ptr::null::<$t>(), std::ptr::null::<$t>(), 0.0 as $t); 32];
            let mut n = 0;
            for k in 0..w.len() {
                let q = partner[k];
                if q != SECOND {
                    let b = if q == k { std::ptr::null() } else { p[q] };
                    terms[n] = (p[k], b, w[k]);
                    n += 1;
                }
            }
            // SAFETY: the caller's guarantees, term by term.
            unsafe { $name_at(o, len, &terms[..n]) }
        }

        /// See [`terms_avx2_body`].
        ///
        /// # Safety
        /// The target feature present; `o` and every input of `terms` valid for `len`
        /// samples; at least one term.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feat)]
        pub(crate) unsafe fn $name_at(
            o: *mut $t,
            len: usize,
            terms: &[(*const $t, *const $t, $t)],
        ) {
            use std::arch::x86_64::*;
            const L: usize = $lanes;
            // `$n` vectors from `i` (four at once keep four independent sums in flight)
            macro_rules! at {
                ($i:expr, $n:literal) => {{
                    let i = $i;
                    let mut acc = [$set1(0.0); $n];
                    for (t, &(a, b, wk)) in terms.iter().enumerate() {
                        let wv = $set1(wk);
                        for (j, acc) in acc.iter_mut().enumerate() {
                            let x = $load(a.add(i + j * L));
                            *acc = if b.is_null() {
                                let m = $mul(wv, x);
                                if t == 0 {
                                    m
                                } else {
                                    $add(*acc, m)
                                }
                            } else {
                                let v = $add(x, $load(b.add(i + j * L)));
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
                    // the terms of `sum_terms`, one sample
                    let mut acc = 0.0 as $t;
                    for (t, &(a, b, wk)) in terms.iter().enumerate() {
                        let x = *a.add(i);
                        acc = if b.is_null() {
                            if t == 0 {
                                wk * x
                            } else {
                                acc + wk * x
                            }
                        } else {
                            let v = x + *b.add(i);
                            if t == 0 {
                                wk * v
                            } else {
                                v.mul_add(wk, acc)
                            }
                        };
                    }
                    *o.add(i) = acc;
                    i += 1;
                }
            }
        }
    };
}
terms_avx2_body!(
    terms_avx2_f32,
    terms_at_avx2_f32,
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
    terms_at_avx2_f64,
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
    terms_at_avx512_f32,
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
    terms_at_avx512_f64,
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

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn deinterleave_avx2<T: Sample>(x: &[T], e: usize, dst: &mut [T]) {
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

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn interleave_avx2<T: Sample>(a: &[T], b: &[T], e: usize, dst: &mut [T]) {
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

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn stream_copy_avx2<T: Sample>(src: &[T], dst: &mut [T]) {
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

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn transpose_avx2_32<T: Sample>(
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
            let t = transpose8_ps([l(0), l(1), l(2), l(3), l(4), l(5), l(6), l(7)]);
            for (i, v) in t.into_iter().enumerate() {
                _mm256_storeu_ps(pd.add((cb + i) * stride + rb), v);
            }
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

/// [`combine_rows`] for `f32` with AVX2: each row's terms as the operator made them once
/// ([`Csr::terms32`]: no pairing of taps per row, no copy of a long row), the rows with a
/// few taps and no pairs by the fused tap loops ([`taps_avx2_f32`]), the others by the
/// terms' loop ([`terms_at_avx2_f32`], AVX-512 when `k` has it) — the same sums as one
/// [`combine`] per row.
///
/// # Safety
/// AVX2 present; every column of `op` times `len` plus `len` within `src`; the output rows
/// `0..rows.len()` of `len` samples within `dst`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn combine_rows_avx2_f32(
    k: Kernels,
    op: &Csr,
    src: *const f32,
    len: usize,
    rows: std::ops::Range<usize>,
    dst: *mut f32,
) {
    type At = (*const f32, *const f32, f32);
    let mut at: [At; 32] = [(std::ptr::null(), std::ptr::null(), 0.0); 32];
    // SAFETY (all): the caller's bounds; every column (`a`, `b` of a term) below op.cols().
    let input = |c: u32| unsafe { src.add(c as usize * len) };
    for (i, r) in rows.enumerate() {
        let o = unsafe { dst.add(i * len) };
        let terms = op.terms32(r);
        let n = terms.len();
        let paired = terms.iter().any(|t| t.b != Term::<f32>::SINGLE);
        macro_rules! arm {
            ($n:literal) => {{
                let p: [*const f32; $n] = std::array::from_fn(|k| input(terms[k].a));
                let w: [f32; $n] = std::array::from_fn(|k| terms[k].w);
                unsafe { taps_avx2_f32::<$n>(o, len, &p, &w) }
            }};
        }
        match n {
            0 => unsafe { std::ptr::write_bytes(o, 0, len) },
            1..=8 if !paired => match n {
                1 => arm!(1),
                2 => arm!(2),
                3 => arm!(3),
                4 => arm!(4),
                5 => arm!(5),
                6 => arm!(6),
                7 => arm!(7),
                _ => arm!(8),
            },
            1..=32 => {
                for (a, t) in at.iter_mut().zip(terms) {
                    let b = if t.b == Term::<f32>::SINGLE {
                        std::ptr::null()
                    } else {
                        input(t.b)
                    };
                    *a = (input(t.a), b, t.w);
                }
                // SAFETY: AVX-512F present when the table has it; the inputs as above.
                if k.avx512() && len >= 16 {
                    unsafe { terms_at_avx512_f32(o, len, &at[..n]) };
                } else {
                    unsafe { terms_at_avx2_f32(o, len, &at[..n]) };
                }
            }
            _ => {
                // (no scheme's row has that many terms) one combine
                let (cols, ws) = op.row_slices(r);
                let out = unsafe { std::slice::from_raw_parts_mut(o, len) };
                let t: Vec<&[f32]> = cols
                    .iter()
                    .map(|&c| unsafe { std::slice::from_raw_parts(input(c), len) })
                    .collect();
                let wv: Vec<f32> = ws.iter().map(|&x| x as f32).collect();
                combine(k, out, &t, &wv);
            }
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
pub(crate) unsafe fn lane_taps_avx2_f32<T: Sample>(
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

/// [`edge_rows`] with AVX2 on `f32`.
///
/// # Safety
/// AVX2 with FMA present; `x` valid for `x_len` samples, past the `last` sample of every
/// group, and `y` for `r0 + n`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn edge_rows_avx2_f32(
    groups: &[EdgeGroup],
    x: *const f32,
    x_len: usize,
    y: *mut f32,
) {
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
pub(crate) unsafe fn transpose8_ps(
    a: [std::arch::x86_64::__m256; 8],
) -> [std::arch::x86_64::__m256; 8] {
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

/// [`apply_scalar`] compiled for AVX2 and FMA (bit-identical to the scalar build, whose
/// FMAs are a software routine).
///
/// # Safety
/// AVX2 with FMA present; as [`crate::kernel::apply_raw`].
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn apply_avx2<T: Sample>(op: &Csr, lanes: RawLanes<T>) {
    // SAFETY: the caller's guarantees pass through.
    unsafe { apply_scalar(op, lanes) }
}
