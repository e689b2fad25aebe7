//! The inner loops every transform ends in, written over whole runs of samples so they
//! vectorise, with an AVX2 build picked at run time (no FMA: the AVX2 and baseline builds
//! give the same bits, see [`crate::scheme::sparse::cpu_has_avx2`]).

use super::sample::Sample;

/// Most taps fused into one pass; longer rows accumulate in further passes.
const MAX_FUSED: usize = 8;

/// `out[i] = Σ_k w[k] · src[k][i]` for every `i < out.len()`, summed in the order of `k`
/// (the first tap assigns, the others accumulate: the rounding of [`super::sparse::Csr`]'s
/// row kernel, so both paths give the same bits).
///
/// Every `src[k]` must hold at least `out.len()` samples.
#[inline]
pub fn combine<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T]) {
    assert_eq!(src.len(), w.len());
    assert!(src.iter().all(|s| s.len() >= out.len()));
    #[cfg(target_arch = "x86_64")]
    if super::sparse::cpu_has_avx2() {
        // SAFETY: AVX2 is present.
        return unsafe { combine_avx2(out, src, w) };
    }
    combine_generic(out, src, w)
}

/// [`combine`] always with the baseline build (tests compare the two).
pub fn combine_baseline<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T]) {
    assert_eq!(src.len(), w.len());
    assert!(src.iter().all(|s| s.len() >= out.len()));
    combine_generic(out, src, w)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn combine_avx2<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T]) {
    combine_generic(out, src, w)
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
        for j in 2 * pairs..m {
            let at = if j % 2 == 0 { j / 2 } else { ne + j / 2 };
            dst[at] = x[j];
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

/// `dst[(first + step·i)·e ..][..e] = src[i·e ..][..e]` for `i < src.len() / e`: put a
/// computed run back at every `step`-th element.
#[inline]
pub fn scatter_every<T: Sample>(src: &[T], e: usize, dst: &mut [T], first: usize, step: usize) {
    if step == 1 {
        dst[first * e..first * e + src.len()].copy_from_slice(src);
    } else if e == 1 {
        for (i, &v) in src.iter().enumerate() {
            dst[first + step * i] = v;
        }
    } else {
        for (i, el) in src.chunks_exact(e).enumerate() {
            let at = (first + step * i) * e;
            dst[at..at + e].copy_from_slice(el);
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
