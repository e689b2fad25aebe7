//! Samples moved, not combined: even/odd splits and merges, transposes, streaming stores.

use super::*;

/// Split `x` (elements of `e` samples) into its even elements, then its odd elements:
/// `dst = [x_0, x_2, x_4, … | x_1, x_3, …]`.
#[inline]
pub fn deinterleave<T: Sample>(k: Kernels, x: &[T], e: usize, dst: &mut [T]) {
    assert_eq!(x.len() % e, 0);
    assert!(dst.len() >= x.len());
    #[cfg(target_arch = "x86_64")]
    if k.avx2() {
        // SAFETY: AVX2 is present (a table holds no build the CPU lacks).
        return unsafe { deinterleave_avx2(x, e, dst) };
    }
    deinterleave_generic(x, e, dst)
}

/// `dst = [a_0, b_0, a_1, b_1, …]` for elements of `e` samples (`a`, `b` of equal length).
#[inline]
pub fn interleave<T: Sample>(k: Kernels, a: &[T], b: &[T], e: usize, dst: &mut [T]) {
    assert_eq!(a.len(), b.len());
    assert!(dst.len() >= 2 * a.len());
    #[cfg(target_arch = "x86_64")]
    if k.avx2() {
        // SAFETY: AVX2 is present (a table holds no build the CPU lacks).
        return unsafe { interleave_avx2(a, b, e, dst) };
    }
    interleave_generic(a, b, e, dst)
}

/// `dst.copy_from_slice(src)` with non-temporal stores where the CPU has AVX2: the
/// destination lines go to memory without being read first (a level's output that does
/// not fit in cache is written once and read back only by the next level). Ends with a
/// store fence ([`stream_fence`]).
#[inline]
pub fn stream_copy<T: Sample>(k: Kernels, src: &[T], dst: &mut [T]) {
    stream_copy_unfenced(k, src, dst);
    stream_fence();
}

/// [`stream_copy`] without its store fence, for many short copies in a row (the rows of
/// an image): the caller fences once after the last ([`stream_fence`]), before anything
/// another thread may read them. A fence per 16 KB row of a 4096² image costs about 5% of
/// the CPU time of a cubic pyramid forward and back (one thread).
#[inline]
pub fn stream_copy_unfenced<T: Sample>(k: Kernels, src: &[T], dst: &mut [T]) {
    assert_eq!(src.len(), dst.len());
    #[cfg(target_arch = "x86_64")]
    if k.avx2() {
        // SAFETY: AVX2 is present (a table holds no build the CPU lacks).
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

/// `dst[c·stride + r] = src[r·cols + c]` for a `rows × cols` block `src`: the lanes of one
/// axis become rows of another. 8 × 8 tiles in registers for 4-byte samples with AVX2.
pub fn transpose<T: Sample>(
    k: Kernels,
    src: &[T],
    rows: usize,
    cols: usize,
    dst: &mut [T],
    stride: usize,
) {
    assert!(src.len() >= rows * cols);
    assert!(cols == 0 || rows == 0 || (stride >= rows && dst.len() >= (cols - 1) * stride + rows));
    #[cfg(target_arch = "x86_64")]
    if std::mem::size_of::<T>() == 4 && k.avx2() {
        // SAFETY: AVX2 is present (a table holds no build the CPU lacks); T is a 4-byte float, moved as bits; bounds above.
        return unsafe { transpose_avx2_32(src, rows, cols, dst, stride) };
    }
    transpose_generic(src, rows, cols, dst, stride, 0, 0)
}
