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
