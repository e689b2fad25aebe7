//! The plain loops: the baseline build, and the tails and fallbacks of the vector builds.

use super::*;

#[inline(always)]
pub(crate) fn combine_generic<T: Sample>(out: &mut [T], src: &[&[T]], w: &[T]) {
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
pub(crate) fn taps<T: Sample, const N: usize>(out: &mut [T], src: &[&[T]], w: &[T]) {
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

#[inline(always)]
pub(crate) fn deinterleave_generic<T: Sample>(x: &[T], e: usize, dst: &mut [T]) {
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

#[inline(always)]
pub(crate) fn interleave_generic<T: Sample>(a: &[T], b: &[T], e: usize, dst: &mut [T]) {
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

/// The tiles of [`transpose`] from row `r0` and column `c0` on (the rest of the block is
/// done), plain loops.
pub(crate) fn transpose_generic<T: Sample>(
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

/// [`super::apply_raw`]'s plain loops: each row summed as [`sum_terms`] says (its first
/// term assigns, so `dst` needs no clearing).
///
/// # Safety
/// As [`super::apply_raw`].
#[inline(always)]
pub(crate) unsafe fn apply_scalar<T: Sample>(op: &Csr, lanes: RawLanes<T>) {
    let RawLanes {
        src,
        src_stride,
        dst,
        dst_stride,
        width,
    } = lanes;
    // the rows' weights and pairs (on the stack up to 32 taps, the schemes' rows)
    let (mut ws_stack, mut partner_stack) = ([T::default(); 32], [0usize; 32]);
    let (mut ws_heap, mut partner_heap): (Vec<T>, Vec<usize>) = (Vec::new(), Vec::new());
    for r in 0..op.rows() {
        let (cols, weights) = op.row_slices(r);
        let n = cols.len();
        // SAFETY: the caller guarantees this element is ours alone.
        let out = unsafe { std::slice::from_raw_parts_mut(dst.add(r * dst_stride), width) };
        if n == 0 {
            out.fill(T::default());
            continue;
        }
        // the row's sum as `sum_terms` takes it (pairs of equal weights)
        let (ws, partner) = if n <= 32 {
            (&mut ws_stack[..n], &mut partner_stack[..n])
        } else {
            ws_heap.resize(n, T::default());
            partner_heap.resize(n, 0);
            (&mut ws_heap[..], &mut partner_heap[..])
        };
        for (w, &v) in ws.iter_mut().zip(weights) {
            *w = T::from_f64(v);
        }
        pair_taps(ws, partner);
        // SAFETY: the caller guarantees every element read is valid.
        let input = |k: usize| unsafe {
            std::slice::from_raw_parts(src.add(cols[k] as usize * src_stride), width)
        };
        let mut first = true;
        for k in 0..n {
            let q = partner[k];
            if q == SECOND {
                continue;
            }
            let (x, w) = (input(k), ws[k]);
            if q == k {
                if first {
                    for (o, &x) in out.iter_mut().zip(x) {
                        *o = w * x;
                    }
                } else {
                    for (o, &x) in out.iter_mut().zip(x) {
                        *o += w * x;
                    }
                }
            } else {
                let y = input(q);
                if first {
                    for ((o, &x), &y) in out.iter_mut().zip(x).zip(y) {
                        *o = w * (x + y);
                    }
                } else {
                    for ((o, &x), &y) in out.iter_mut().zip(x).zip(y) {
                        *o = (x + y).fused_mul_add(w, *o);
                    }
                }
            }
            first = false;
        }
    }
}
