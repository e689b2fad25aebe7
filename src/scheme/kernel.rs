//! The inner loops every transform ends in, written over whole runs of samples so they
//! vectorise, with AVX2 and AVX-512 builds picked at run time (no FMA: every build gives
//! the same bits, see [`Simd`]).

use super::sample::Sample;
use super::sparse::Simd;

/// Most taps fused into one pass; longer rows accumulate in further passes.
const MAX_FUSED: usize = 8;

/// `out[i] = Σ_k w[k] · src[k][i]` for every `i < out.len()`, summed in the order of `k`
/// (the first tap assigns, the others accumulate: the rounding of [`super::sparse::Csr`]'s
/// row kernel, so both paths give the same bits).
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
/// vectors, then scalars. Separate multiply and add, no FMA: the same bits as the scalar
/// loop. Short runs (lanes of a few hundred samples) are common, so the set-up is kept to
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

/// `o[i] = Σ_k ws[k]·p[k][i]`, `i < len` (first tap assigns): blocks of four vectors, then
/// single vectors, then scalars. One body for `f32` and `f64` (their intrinsics differ).
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
/// not fit in cache is written once and read back only by the next level).
#[inline]
pub fn stream_copy<T: Sample>(src: &[T], dst: &mut [T]) {
    assert_eq!(src.len(), dst.len());
    #[cfg(target_arch = "x86_64")]
    if super::sparse::cpu_has_avx2() {
        // SAFETY: AVX2 is present.
        return unsafe { stream_copy_avx2(src, dst) };
    }
    dst.copy_from_slice(src)
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
    _mm_sfence();
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
#[target_feature(enable = "avx2")]
unsafe fn combine_rows_avx2_f32(
    op: &super::sparse::Csr,
    src: *const f32,
    len: usize,
    rows: std::ops::Range<usize>,
    dst: *mut f32,
) {
    for (i, r) in rows.enumerate() {
        let (cols, ws) = op.row_slices(r);
        // SAFETY (all): the caller's bounds; columns below op.cols().
        let o = unsafe { dst.add(i * len) };
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
                combine_generic(out, &t, &wv);
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
    let u = src.len();
    check_pair(u, w1, m1, w2, m2);
    assert!(o1.len() == o2.len() && src.iter().all(|s| s.len() >= o1.len()));
    assert!(simd <= Simd::detected(), "{simd:?} is not available");
    #[cfg(target_arch = "x86_64")]
    if simd >= Simd::Avx2 {
        let p = input_ptrs(src);
        let o = [o1.as_mut_ptr(), o2.as_mut_ptr()];
        let wide = simd == Simd::Avx512;
        // SAFETY: AVX2 (and AVX-512 when `wide`) present; lengths and masks checked
        // above; one step.
        if unsafe {
            pair_avx2(
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
                false,
                wide,
            )
        } {
            return;
        }
    }
    pair_by_parts(o1, o2, src, w1, m1, w2, m2, simd)
}

/// [`combine_pair`] over two sparse rows (`(columns, weights)`, columns increasing) and
/// the inputs `tap(c)` of their columns: `o1` the first row, `o2` the second, each input
/// they share read once. `false` (nothing written) when the rows share no column or read
/// more than [`PAIR_INPUTS`] inputs together (then two [`combine_taps`] do the same).
pub fn combine_pair_taps<'t, T: Sample + 't>(
    o1: &mut [T],
    o2: &mut [T],
    row1: (&[u32], &[f64]),
    row2: (&[u32], &[f64]),
    tap: impl Fn(u32) -> &'t [T],
) -> bool {
    let ((c1, w1), (c2, w2)) = (row1, row2);
    if c1.is_empty() || c2.is_empty() {
        return false;
    }
    // merge the two increasing column lists
    let mut cols = [0u32; PAIR_INPUTS];
    let (mut a, mut b) = ([T::default(); PAIR_INPUTS], [T::default(); PAIR_INPUTS]);
    let (mut m1, mut m2) = (0u32, 0u32);
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < c1.len() || j < c2.len() {
        if n == PAIR_INPUTS {
            return false;
        }
        let c = match (c1.get(i), c2.get(j)) {
            (Some(&x), Some(&y)) => x.min(y),
            (Some(&x), None) => x,
            (None, Some(&y)) => y,
            (None, None) => unreachable!("one list goes on"),
        };
        cols[n] = c;
        if c1.get(i) == Some(&c) {
            (a[n], m1) = (T::from_f64(w1[i]), m1 | 1 << n);
            i += 1;
        }
        if c2.get(j) == Some(&c) {
            (b[n], m2) = (T::from_f64(w2[j]), m2 | 1 << n);
            j += 1;
        }
        n += 1;
    }
    if m1 & m2 == 0 {
        return false; // nothing shared
    }
    let mut src: [&[T]; PAIR_INPUTS] = [&[]; PAIR_INPUTS];
    for k in 0..n {
        src[k] = tap(cols[k]);
    }
    combine_pair(o1, o2, &src[..n], &a[..n], m1, &b[..n], m2);
    true
}

/// Most inputs two rows combined together by [`combine_pair_taps`] may read.
pub const PAIR_INPUTS: usize = 8;

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
            // (U, M1, M2, P1, N1, P2, N2): inputs, the masks of the two outputs, then the
            // taps of weight +1 and −1 of each (added or subtracted, not multiplied)
            (2, 0b11, 0b11, 0, 0, 0, 0),
            (4, 0b1111, 0b1111, 0, 0, 0, 0),
            (6, 0b001111, 0b111100, 0, 0, 0, 0),
            (7, 0b0111011, 0b1111111, 0, 0, 0, 0),
            (7, 0b1111111, 0b1111100, 0, 0, 0, 0),
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0),
            (7, 0b1111111, 0b0011111, 0, 0, 0, 0),
            // Haar's synthesis: sums and differences
            (2, 0b11, 0b11, 0b11, 0, 0b01, 0b10),
            // cubic analysis: the centre of `a`
            (7, 0b1111111, 0b1111100, 0b0001000, 0, 0, 0),
            (7, 0b1111111, 0b0011111, 0b0001000, 0, 0, 0),
            // cubic synthesis: the centre of `q`
            (7, 0b0111011, 0b1111111, 0, 0b0010000, 0, 0),
            (7, 0b1111111, 0b1110110, 0, 0, 0, 0b0100000)
        )
    };
}

/// The taps of `mask` whose weight in `w` is exactly `v` (±1: the pair kernels add or
/// subtract those inputs instead of multiplying them, the same bits).
fn unit_taps<T: Sample>(w: &[T], mask: u32, v: f64) -> u32 {
    w.iter()
        .enumerate()
        .filter(|&(k, x)| mask >> k & 1 == 1 && x.to_f64() == v)
        .fold(0, |m, (k, _)| m | 1 << k)
}

/// Dispatch of [`combine_pair`] to [`pair_avx2_f32`] / [`pair_avx2_f64`], for `count`
/// steps: step `t` reads `src[k] + t·in_step` and writes `o1 + t·out_step[0]`,
/// `o2 + t·out_step[1]` (`len` samples each). `false` (nothing written) when the pattern or
/// the type has no AVX2 build.
///
/// # Safety
/// AVX2 present, AVX-512F too when `wide` (then the steps of at least one 512-bit vector
/// use it); every access inside its allocation, outputs distinct from each other
/// and from the inputs; the masks as [`combine_pair`] checks them.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn pair_avx2<T: Sample>(
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
    let units = (
        unit_taps(w1, m1, 1.0),
        unit_taps(w1, m1, -1.0),
        unit_taps(w2, m2, 1.0),
        unit_taps(w2, m2, -1.0),
    );
    macro_rules! go {
        ($t:ty, $f:ident, $g:ident, $U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal) => {{
            let wide = wide && len >= 64 / std::mem::size_of::<$t>();
            let a: [$t; $U] = std::array::from_fn(|k| w1[k].to_f64() as $t);
            let b: [$t; $U] = std::array::from_fn(|k| w2[k].to_f64() as $t);
            for t in 0..count {
                // SAFETY: the caller's bounds; T is $t.
                unsafe {
                    let p: [*const $t; $U] =
                        std::array::from_fn(|k| src[k].add(t * in_step) as *const $t);
                    let q1 = o[0].add(t * out_step[0]) as *mut $t;
                    let q2 = o[1].add(t * out_step[1]) as *mut $t;
                    match (wide, merge, split) {
                        (true, true, _) => $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, true, false>(
                            q1, q2, len, &p, &a, &b,
                        ),
                        (true, false, true) => $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, false, true>(
                            q1, q2, len, &p, &a, &b,
                        ),
                        (true, false, false) => {
                            $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, false, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, true, _) => $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, true, false>(
                            q1, q2, len, &p, &a, &b,
                        ),
                        (false, false, true) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, false, true>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, false, false) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, false, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                    }
                }
            }
            return true;
        }};
    }
    // the entry with the pattern's unit taps first, else the one without any
    macro_rules! table {
        ($(($U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal)),*) => {
            for plain in [false, true] {
                let want = if plain { (0, 0, 0, 0) } else { units };
                if TypeId::of::<T>() == TypeId::of::<f32>() {
                    $( if (u, m1, m2) == ($U, $M1, $M2) && want == ($P1, $N1, $P2, $N2) {
                        go!(f32, pair_avx2_f32, pair_avx512_f32, $U, $M1, $M2, $P1, $N1, $P2, $N2)
                    } )*
                } else if TypeId::of::<T>() == TypeId::of::<f64>() {
                    $( if (u, m1, m2) == ($U, $M1, $M2) && want == ($P1, $N1, $P2, $N2) {
                        go!(f64, pair_avx2_f64, pair_avx512_f64, $U, $M1, $M2, $P1, $N1, $P2, $N2)
                    } )*
                }
            }
        };
    }
    pair_patterns!(table);
    false
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
    let u = src.len();
    check_pair(u, w1, m1, w2, m2);
    assert!(out.len().is_multiple_of(2));
    let len = out.len() / 2;
    assert!(src.iter().all(|s| s.len() >= len));
    #[cfg(target_arch = "x86_64")]
    if super::sparse::cpu_has_avx2() {
        let p = input_ptrs(src);
        let o = [out.as_mut_ptr(), out.as_mut_ptr()];
        let wide = Simd::detected() == Simd::Avx512;
        // SAFETY: AVX2 is present, AVX-512F when `wide` (detected); `out` holds 2·len
        // samples, every input len; one step, the merged output written through the
        // first pointer only.
        return unsafe {
            pair_avx2(
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
        let done = unsafe {
            // (merged: both through the first pointer)
            let o = [d.add(out[0]), d.add(if merge { out[0] } else { out[1] })];
            pair_avx2(
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
        };
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

/// The body of [`combine_pair`] for one pattern: a vector of each output per step, every
/// input loaded once; then scalars.
macro_rules! pair_avx2_body {
    ($name:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $zero:ident, $mul:ident, $add:ident, $sub:ident, $load:ident, $store:ident, $merge:ident, $split:ident) => {
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
            // one vector of each output at `i`
            macro_rules! calc {
                ($i:expr) => {{
                    let i = $i;
                    let (mut a1, mut a2) = ($zero(), $zero());
                    for k in 0..U {
                        let x = $load(p[k].add(i));
                        // a tap of weight ±1 adds or subtracts its input: `w·x` is
                        // then `±x` exactly, so the sum has the same bits
                        macro_rules! tap {
                            ($acc:ident, $v:ident, $m:ident, $f:ident, $p:ident, $n:ident) => {
                                if $m >> k & 1 == 1 {
                                    if $p >> k & 1 == 1 {
                                        $acc = if k == $f { x } else { $add($acc, x) };
                                    } else if $n >> k & 1 == 1 {
                                        $acc = if k == $f {
                                            $mul($set1(-1.0), x)
                                        } else {
                                            $sub($acc, x)
                                        };
                                    } else {
                                        let m = $mul($v[k], x);
                                        $acc = if k == $f { m } else { $add($acc, m) };
                                    }
                                }
                            };
                        }
                        tap!(a1, v1, M1, f1, P1, N1);
                        tap!(a2, v2, M2, f2, P2, N2);
                    }
                    (a1, a2)
                }};
            }
            // scalars at `i`
            macro_rules! calc1 {
                ($i:expr) => {{
                    let i = $i;
                    let (mut a1, mut a2) = (0.0 as $t, 0.0 as $t);
                    for k in 0..U {
                        let x = *p[k].add(i);
                        macro_rules! tap {
                            ($acc:ident, $w:ident, $m:ident, $f:ident, $p:ident, $n:ident) => {
                                if $m >> k & 1 == 1 {
                                    if $p >> k & 1 == 1 {
                                        $acc = if k == $f { x } else { $acc + x };
                                    } else if $n >> k & 1 == 1 {
                                        $acc = if k == $f { -x } else { $acc - x };
                                    } else {
                                        let m = $w[k] * x;
                                        $acc = if k == $f { m } else { $acc + m };
                                    }
                                }
                            };
                        }
                        tap!(a1, w1, M1, f1, P1, N1);
                        tap!(a2, w2, M2, f2, P2, N2);
                    }
                    (a1, a2)
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
    ($($taps:ident, $pair:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $zero:ident, $mul:ident, $add:ident, $sub:ident, $load:ident, $store:ident, $merge:ident, $split:ident;)*) => {
        $(
            taps_avx2_body!($taps, $feat, $t, $lanes, $set1, $zero, $mul, $add, $load, $store);
            pair_avx2_body!($pair, $feat, $t, $lanes, $set1, $zero, $mul, $add, $sub, $load, $store, $merge, $split);
        )*
    };
}

builds! {
    taps_avx2_f32, pair_avx2_f32, "avx2", f32, 8, _mm256_set1_ps, _mm256_setzero_ps, _mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps, _mm256_loadu_ps, _mm256_storeu_ps, merge_ps256, split_ps256;
    taps_avx2_f64, pair_avx2_f64, "avx2", f64, 4, _mm256_set1_pd, _mm256_setzero_pd, _mm256_mul_pd, _mm256_add_pd, _mm256_sub_pd, _mm256_loadu_pd, _mm256_storeu_pd, merge_pd256, split_pd256;
    taps_avx512_f32, pair_avx512_f32, "avx512f", f32, 16, _mm512_set1_ps, _mm512_setzero_ps, _mm512_mul_ps, _mm512_add_ps, _mm512_sub_ps, _mm512_loadu_ps, _mm512_storeu_ps, merge_ps512, split_ps512;
    taps_avx512_f64, pair_avx512_f64, "avx512f", f64, 8, _mm512_set1_pd, _mm512_setzero_pd, _mm512_mul_pd, _mm512_add_pd, _mm512_sub_pd, _mm512_loadu_pd, _mm512_storeu_pd, merge_pd512, split_pd512;
}

/// Most samples of a lane [`combine_lane_taps`] reads in registers (8 windows of 8).
const LANE_TAPS_SLOTS: usize = 64;

/// `y[t·ys + r] = Σ_k w_k · x[t·w + c_k]` for every lane `t < h` of `x` (lane `t` at
/// `x[t·w ..][..w]`) and every row `(r, taps)` of `rows` (`taps` the `(c_k, w_k)`, the
/// first tap assigning, the others added in order: the bits of [`super::sparse::Csr`]'s
/// row kernel). For the few rows near the ends of a volume's lanes, which read a handful
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
    /// Every row's taps as `(slot, weight)`, row `i`'s at `slots[ends[i]..ends[i + 1]]`.
    slots: Vec<(usize, f32)>,
    ends: Vec<usize>,
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
                slots.extend(t.iter().map(|&(c, wk)| (slot(c), wk as f32)));
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
        LaneTaps {
            w,
            rows,
            bases,
            slots,
            ends,
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
    for t in done..h {
        let lane = &x[t * w..t * w + w];
        for (r, taps) in rows {
            let mut acc = T::default();
            for (k, &(c, wk)) in taps.iter().enumerate() {
                let v = T::from_f64(wk) * lane[c];
                acc = if k == 0 { v } else { acc + v };
            }
            y[t * ys + r] = acc;
        }
    }
}

/// The lanes `..h / 8 · 8` of [`combine_lane_taps_with`] (returned), 8 at a time.
///
/// # Safety
/// AVX2 present, `T` is `f32`, `taps.bases` not empty, and the bounds of
/// [`combine_lane_taps_with`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
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
    let mut part = [0f32; 8];
    let h8 = h / 8 * 8;
    for t0 in (0..h8).step_by(8) {
        for (i, &b) in bases.iter().enumerate() {
            // SAFETY: lanes t0..t0+8 < h, samples b..b+8 <= w of each.
            let l = |j: usize| unsafe { _mm256_loadu_ps(px.add((t0 + j) * w + b)) };
            let a = [l(0), l(1), l(2), l(3), l(4), l(5), l(6), l(7)];
            let t = transpose8_ps(a);
            reg[i * 8..i * 8 + 8].copy_from_slice(&t);
        }
        for &(i0, n) in &taps.groups {
            // the sums of rows i0.. for the 8 lanes, one register per row
            let mut acc = [_mm256_setzero_ps(); 8];
            for (q, a) in acc.iter_mut().enumerate().take(n) {
                let i = i0 + q;
                let row = &taps.slots[taps.ends[i]..taps.ends[i + 1]];
                for (k, &(s, wk)) in row.iter().enumerate() {
                    let v = _mm256_mul_ps(_mm256_set1_ps(wk), reg[s]);
                    *a = if k == 0 { v } else { _mm256_add_ps(*a, v) };
                }
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
                    _mm256_storeu_ps(part.as_mut_ptr(), o);
                    for (q, &v) in part.iter().enumerate().take(n) {
                        // SAFETY: as above.
                        unsafe { *at.add(q) = v };
                    }
                }
            }
        }
    }
    h8
}

/// Most samples one [`EdgeGroup`] reads.
pub const EDGE_SPAN: usize = 32;

/// Up to 8 rows `r0..r0 + n` of a sparse operator, one output sample each on a lane of
/// single samples, that read few samples together (the rows near the ends of a long
/// lane): per sample `cols[j]` they read, the rows' weights (0 where a row does not read
/// it) and which rows start their sum there or add to it. Computed 8 rows at once
/// ([`edge_rows`]), each row's sum still its taps in column order, the first assigning:
/// the bits of one row at a time.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeGroup {
    pub r0: usize,
    pub n: usize,
    /// The samples the rows read, increasing.
    pub cols: Vec<usize>,
    /// Per sample: the 8 rows' weights as `f32`.
    pub weights: Vec<[f32; 8]>,
    /// Per sample: all bits set in the rows whose first tap it is.
    pub first: Vec<[u32; 8]>,
    /// Per sample: all bits set in the rows that add it to their sum.
    pub add: Vec<[u32; 8]>,
}

impl EdgeGroup {
    /// The rows `r0..r0 + rows.len()` (at most 8), `rows[i]` the `(columns, weights)` of
    /// row `r0 + i`; `None` when they read more than [`EDGE_SPAN`] samples or a row's
    /// columns do not increase.
    pub fn new(r0: usize, rows: &[(&[u32], &[f64])]) -> Option<EdgeGroup> {
        let n = rows.len();
        assert!((1..=8).contains(&n));
        if rows.iter().any(|(c, _)| c.windows(2).any(|p| p[0] >= p[1])) {
            return None;
        }
        let mut cols: Vec<usize> = rows
            .iter()
            .flat_map(|(c, _)| c.iter().map(|&c| c as usize))
            .collect();
        cols.sort_unstable();
        cols.dedup();
        if cols.len() > EDGE_SPAN {
            return None;
        }
        let u = cols.len();
        let mut g = EdgeGroup {
            r0,
            n,
            cols,
            weights: vec![[0.0; 8]; u],
            first: vec![[0; 8]; u],
            add: vec![[0; 8]; u],
        };
        for (i, (cs, ws)) in rows.iter().enumerate() {
            for (k, (&c, &w)) in cs.iter().zip(ws.iter()).enumerate() {
                let j = g.cols.binary_search(&(c as usize)).expect("in the union");
                g.weights[j][i] = w as f32;
                if k == 0 {
                    g.first[j][i] = u32::MAX;
                } else {
                    g.add[j][i] = u32::MAX;
                }
            }
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
            assert!(g.cols.last().is_none_or(|&c| c < x.len()) && g.r0 + g.n <= y.len());
        }
        let (px, py) = (x.as_ptr() as *const f32, y.as_mut_ptr() as *mut f32);
        // SAFETY: AVX2 is present; T is f32; every group's samples and outputs lie inside
        // `x` and `y` (asserted).
        unsafe { edge_rows_avx2_f32(groups, px, py) };
        return true;
    }
    let _ = (groups, x, y);
    false
}

/// [`edge_rows`] with AVX2 on `f32`.
///
/// # Safety
/// AVX2 present; `x` valid past the last of `cols` and `y` for `r0 + n` of every group.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn edge_rows_avx2_f32(groups: &[EdgeGroup], x: *const f32, y: *mut f32) {
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
