//! Copies of strided boxes: the lines of a box, and a box copied without an inner
//! box (the cascade's parts that stay where a level leaves them).

use crate::kernel::{stream_copy_unfenced, Kernels};
use crate::scheme::Sample;

/// Lines of a box `bx` (axes `1..k`, the last of `e`-sample elements): calls
/// `f(line offset in a, line offset in b, line index)` for every line.
fn for_lines(
    a_st: &[usize],
    b_st: &[usize],
    bx: &[usize],
    mut f: impl FnMut(usize, usize, &[usize]),
) {
    let m = bx.len();
    let lines: usize = bx[..m - 1].iter().product();
    let mut idx = vec![0usize; m - 1];
    for _ in 0..lines {
        let (mut ao, mut bo) = (0, 0);
        for j in 0..m - 1 {
            ao += idx[j] * a_st[j];
            bo += idx[j] * b_st[j];
        }
        f(ao, bo, &idx);
        for j in (0..m - 1).rev() {
            idx[j] += 1;
            if idx[j] < bx[j] {
                break;
            }
            idx[j] = 0;
        }
    }
}

/// Copy the box `bx` without the box `inner` from `a` (strides `a_st`) to `b` (strides
/// `b_st`), with non-temporal stores (in the build of the table) when `stream` has one.
#[allow(clippy::too_many_arguments)]
pub(super) fn copy_box_outside<T: Sample>(
    a: &[T],
    a_st: &[usize],
    b: &mut [T],
    b_st: &[usize],
    bx: &[usize],
    inner: &[usize],
    e: usize,
    stream: Option<Kernels>,
) {
    let m = bx.len();
    let run = bx[m - 1] * e;
    let mut copy = |ao: usize, bo: usize, len: usize| {
        let (s, d) = (&a[ao..ao + len], &mut b[bo..bo + len]);
        if let Some(k) = stream {
            stream_copy_unfenced(k, s, d);
        } else {
            d.copy_from_slice(s);
        }
    };
    // pieces that follow one another in both `a` and `b` are copied as one run
    let mut pending: Option<(usize, usize, usize)> = None;
    for_lines(a_st, b_st, bx, |ao, bo, idx| {
        let inside = idx.iter().zip(inner).all(|(&i, &n)| i < n);
        let from = if inside { inner[m - 1] * e } else { 0 };
        let (ao, bo, len) = (ao + from, bo + from, run - from);
        match &mut pending {
            Some((pa, pb, pl)) if *pa + *pl == ao && *pb + *pl == bo => *pl += len,
            _ => {
                if let Some((pa, pb, pl)) = pending.replace((ao, bo, len)) {
                    copy(pa, pb, pl);
                }
            }
        }
    });
    if let Some((pa, pb, pl)) = pending {
        copy(pa, pb, pl);
    }
}
