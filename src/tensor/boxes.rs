//! Copies of strided boxes: the runs of a box of a row-major array, the lines of a
//! box, and a box copied without an inner box (the cascade's parts that stay where a
//! level leaves them).

use crate::kernel::{stream_copy_unfenced, Kernels};
use crate::scheme::Sample;

/// Call `f(offset, run, packed)` for every run (a row along the last axis) of the box
/// `ranges` of a row-major array of extents `shape`, in raster order: `offset` is the
/// run's first sample in the array, `offset = Σ_k y[k]·Π_{j>k} shape[j]` with
/// `y[last] = ranges[last].start`, `run = |ranges[last]|`, and `packed` the run's first
/// sample in the box laid out compactly (the runs before it times `run`). Nothing for an
/// empty box or an array of no axes.
pub fn for_each_run(
    shape: &[usize],
    ranges: &[std::ops::Range<usize>],
    mut f: impl FnMut(usize, usize, usize),
) {
    let nd = shape.len();
    if nd == 0 || ranges.len() != nd || ranges.iter().any(|r| r.is_empty()) {
        return;
    }
    let last = ranges[nd - 1].clone();
    let run = last.len();
    let mut strides = vec![1usize; nd];
    for k in (0..nd - 1).rev() {
        strides[k] = strides[k + 1] * shape[k + 1];
    }
    let mut idx: Vec<usize> = ranges[..nd - 1].iter().map(|r| r.start).collect();
    let mut packed = 0;
    loop {
        let base: usize = idx.iter().zip(&strides).map(|(i, s)| i * s).sum::<usize>() + last.start;
        f(base, run, packed);
        packed += run;
        // the odometer: the last axis of `idx` fastest
        let mut k = nd - 1;
        loop {
            if k == 0 {
                return;
            }
            k -= 1;
            idx[k] += 1;
            if idx[k] < ranges[k].end {
                break;
            }
            idx[k] = ranges[k].start;
        }
    }
}

/// Samples laid out by nested `strides` (slowest axis first, in samples): a box of an
/// array, or a compact copy of one.
#[derive(Clone, Copy, Debug)]
pub(super) struct Strided<'a, T> {
    pub data: &'a [T],
    pub strides: &'a [usize],
}

/// [`Strided`] for writing.
#[derive(Debug)]
pub(super) struct StridedMut<'a, T> {
    pub data: &'a mut [T],
    pub strides: &'a [usize],
}

/// `data` laid out by `strides`.
pub(super) fn strided<'a, T>(data: &'a [T], strides: &'a [usize]) -> Strided<'a, T> {
    Strided { data, strides }
}

/// `data` laid out by `strides`, for writing.
pub(super) fn strided_mut<'a, T>(data: &'a mut [T], strides: &'a [usize]) -> StridedMut<'a, T> {
    StridedMut { data, strides }
}

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

/// Copy the box `bx` without the box `inner` from `a` to `b` (elements of `e` samples),
/// with non-temporal stores (in the build of the table) when `stream` has one.
pub(super) fn copy_box_outside<T: Sample>(
    a: Strided<'_, T>,
    b: StridedMut<'_, T>,
    (bx, inner): (&[usize], &[usize]),
    e: usize,
    stream: Option<Kernels>,
) {
    let (
        Strided {
            data: a,
            strides: a_st,
        },
        StridedMut {
            data: b,
            strides: b_st,
        },
    ) = (a, b);
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
