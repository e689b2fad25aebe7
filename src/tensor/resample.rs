//! Rectangular operators along one axis (added for `src/upscale`): a lane of `n`
//! elements becomes a lane of `m = op.rows()` elements (`op` is `m × n`), written into a
//! new array; and in-place lane functions (a banded solve per lane).
//!
//! The array is seen as `[outer, n, inner]` around `axis`: an element of a lane is a
//! contiguous run of `inner` samples. Wide elements (`inner ≥ 32`) are cut into strips
//! and fed to the kernel in place; narrow ones (the last axis, or channels only) are
//! gathered `G` lanes side by side into a scratch lane whose elements are `G·inner`
//! wide, so the inner loop always runs over ≥ 32 contiguous samples. Scratch is per
//! worker, never per lane.

use super::par::{for_each_task, SharedMut, Strips};
use super::workspace::Planner;
use crate::kernel::Kernels;
use crate::scheme::sparse::Csr;
use crate::scheme::Sample;

/// Elements at least this wide are processed in place (strip mode).
const ROW_MIN: usize = 32;
/// Samples per strip in strip mode.
const STRIP: usize = 256;
/// Target width of a gathered element.
const GATHER: usize = 32;

fn split(shape: &[usize], axis: usize) -> (usize, usize, usize) {
    let outer = shape[..axis].iter().product();
    let inner = shape[axis + 1..].iter().product();
    (outer, shape[axis], inner)
}

/// `dst = op` applied along `axis` of `src` (row-major, `shape`), each result converted
/// by `store`. `dst` has `shape` with `shape[axis]` replaced by `op.rows()`; `op.cols()`
/// must equal `shape[axis]`.
pub fn resample_axis<T: Sample, U: Copy + Send + Sync>(
    src: &[T],
    shape: &[usize],
    axis: usize,
    op: &Csr,
    dst: &mut [U],
    store: impl Fn(T) -> U + Sync + Send,
) {
    resample_axis_with(src, shape, axis, op, dst, |d: &mut U, x| *d = store(x))
}

/// [`resample_axis`] with every result `x` put into its destination sample `d` by
/// `put(d, x)` (e.g. `*d += x` to add the resampled lane to what `dst` holds), in the
/// kernels of the shared planner ([`Planner::shared`]).
pub fn resample_axis_with<T: Sample, U: Copy + Send + Sync>(
    src: &[T],
    shape: &[usize],
    axis: usize,
    op: &Csr,
    dst: &mut [U],
    put: impl Fn(&mut U, T) + Sync + Send,
) {
    let k = Planner::shared().kernels();
    resample_axis_in(k, op, src, shape, axis, dst, put)
}

/// [`resample_axis_with`] in the kernel table `k` (a planner's,
/// [`Planner::kernels`]), the operator first as in [`crate::kernel::apply`].
pub fn resample_axis_in<T: Sample, U: Copy + Send + Sync>(
    k: Kernels,
    op: &Csr,
    src: &[T],
    shape: &[usize],
    axis: usize,
    dst: &mut [U],
    put: impl Fn(&mut U, T) + Sync + Send,
) {
    assert!(axis < shape.len());
    assert_eq!(src.len(), shape.iter().product::<usize>());
    let (outer, n, inner) = split(shape, axis);
    let m = op.rows();
    assert_eq!(op.cols(), n);
    assert_eq!(dst.len(), outer * m * inner);
    let out = SharedMut(dst.as_mut_ptr());
    if inner >= ROW_MIN {
        let strips = Strips::new(inner, STRIP);
        for_each_task(
            outer * strips.count,
            m * strips.max,
            || vec![T::default(); m * strips.max],
            |task, scratch| {
                let o = task / strips.count;
                let (off, sw) = strips.get(task % strips.count);
                let base = &src[o * n * inner + off..];
                crate::kernel::apply(k, op, base, inner, scratch, sw, sw);
                let p = out;
                for i in 0..m {
                    // SAFETY: task (o, s) alone writes columns off..off+sw of lane o.
                    let d = unsafe {
                        std::slice::from_raw_parts_mut(p.0.add((o * m + i) * inner + off), sw)
                    };
                    for (d, &x) in d.iter_mut().zip(&scratch[i * sw..i * sw + sw]) {
                        put(d, x);
                    }
                }
            },
        );
    } else {
        let g = GATHER.div_ceil(inner).clamp(1, outer);
        let groups = outer.div_ceil(g);
        let gw = g * inner;
        for_each_task(
            groups,
            (n + m) * gw,
            || (vec![T::default(); n * gw], vec![T::default(); m * gw]),
            |task, (sin, sout)| {
                let first = task * g;
                let lanes = g.min(outer - first);
                for l in 0..lanes {
                    let lane = &src[(first + l) * n * inner..(first + l + 1) * n * inner];
                    spread(lane, inner, &mut sin[l * inner..], gw, n, |d, x| *d = x);
                }
                let cw = lanes * inner;
                crate::kernel::apply(k, op, sin, gw, sout, gw, cw);
                let p = out;
                for l in 0..lanes {
                    // SAFETY: lanes first..first+lanes belong to this task alone.
                    let d = unsafe {
                        std::slice::from_raw_parts_mut(p.0.add((first + l) * m * inner), m * inner)
                    };
                    spread(&sout[l * inner..], gw, d, inner, m, &put);
                }
            },
        );
    }
}

/// Run `f(lane, width)` on every lane along `axis`, in place. `lane` holds `shape[axis]`
/// elements of `width` samples each (element `i` at `lane[i*width .. i*width + width]`);
/// several lanes, or strips of one lane set, may be packed side by side into one call.
/// `f` must treat the `width` columns independently (as a banded solve does).
pub fn map_lanes<T: Sample>(
    data: &mut [T],
    shape: &[usize],
    axis: usize,
    f: impl Fn(&mut [T], usize) + Sync + Send,
) {
    assert!(axis < shape.len());
    assert_eq!(data.len(), shape.iter().product::<usize>());
    let (outer, n, inner) = split(shape, axis);
    let ptr = SharedMut(data.as_mut_ptr());
    // every task gathers a block of `lanes` lanes × columns `off..off+sw` of the element
    let (g, strips) = if inner >= ROW_MIN {
        (1, Strips::new(inner, STRIP))
    } else {
        (GATHER.div_ceil(inner).clamp(1, outer), Strips::of(inner, 1))
    };
    let groups = outer.div_ceil(g);
    let gw = g * strips.max;
    for_each_task(
        groups * strips.count,
        n * gw,
        || vec![T::default(); n * gw],
        |task, scratch| {
            let first = task / strips.count * g;
            let lanes = g.min(outer - first);
            let (off, sw) = strips.get(task % strips.count);
            let cw = lanes * sw;
            let p = ptr;
            for l in 0..lanes {
                if g > 1 {
                    // whole lanes (sw = inner): one slice per lane
                    // SAFETY: this task alone touches these lanes.
                    let lane = unsafe {
                        std::slice::from_raw_parts(p.0.add((first + l) * n * inner), n * inner)
                    };
                    spread(lane, inner, &mut scratch[l * sw..], cw, n, |d, x| *d = x);
                    continue;
                }
                for i in 0..n {
                    // SAFETY: this task alone touches columns off..off+sw of these lanes.
                    let e = unsafe {
                        std::slice::from_raw_parts(p.0.add(((first + l) * n + i) * inner + off), sw)
                    };
                    scratch[i * cw + l * sw..i * cw + l * sw + sw].copy_from_slice(e);
                }
            }
            f(&mut scratch[..n * cw], cw);
            for l in 0..lanes {
                if g > 1 {
                    // SAFETY: as above.
                    let lane = unsafe {
                        std::slice::from_raw_parts_mut(p.0.add((first + l) * n * inner), n * inner)
                    };
                    spread(&scratch[l * sw..], cw, lane, inner, n, |d, x| *d = x);
                    continue;
                }
                for i in 0..n {
                    // SAFETY: as above.
                    let e = unsafe {
                        std::slice::from_raw_parts_mut(
                            p.0.add(((first + l) * n + i) * inner + off),
                            sw,
                        )
                    };
                    e.copy_from_slice(&scratch[i * cw + l * sw..i * cw + l * sw + sw]);
                }
            }
        },
    );
}

/// Elements `0..count` (`w` samples each, `w` the smaller stride: one side is packed)
/// of `src` at stride `ss` go to `dst` at stride `ds`, each sample through `put(d, x)`.
/// Narrow elements (1–4 samples: channels, the last axis) are copied with their width
/// known at compile time (no call per element).
fn spread<T: Copy, U>(
    src: &[T],
    ss: usize,
    dst: &mut [U],
    ds: usize,
    count: usize,
    put: impl Fn(&mut U, T),
) {
    let w = ss.min(ds);
    match w {
        1 => spread_w::<T, U, 1>(src, ss, dst, ds, count, w, put),
        2 => spread_w::<T, U, 2>(src, ss, dst, ds, count, w, put),
        3 => spread_w::<T, U, 3>(src, ss, dst, ds, count, w, put),
        4 => spread_w::<T, U, 4>(src, ss, dst, ds, count, w, put),
        _ => spread_w::<T, U, 0>(src, ss, dst, ds, count, w, put),
    }
}

fn spread_w<T: Copy, U, const C: usize>(
    src: &[T],
    ss: usize,
    dst: &mut [U],
    ds: usize,
    count: usize,
    w: usize,
    put: impl Fn(&mut U, T),
) {
    let w = if C == 0 { w } else { C };
    for i in 0..count {
        let (d, s) = (&mut dst[i * ds..i * ds + w], &src[i * ss..i * ss + w]);
        for (d, &x) in d.iter_mut().zip(s) {
            put(d, x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheme::sparse::Triplets;

    /// A `m × n` operator with 1–3 taps per row (deterministic pseudo-random).
    fn op(m: usize, n: usize) -> Csr {
        let mut t = Triplets::new(m, n);
        for r in 0..m {
            for k in 0..1 + r % 3 {
                let c = (r * 7 + k * 5) % n;
                t.add(r, c, 0.25 + ((r + 3 * k) % 5) as f64 * 0.5);
            }
        }
        t.into_csr()
    }

    fn data(len: usize) -> Vec<f64> {
        (0..len).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect()
    }

    /// Every element layout (narrow gathered elements of 1–5 samples, wide strips,
    /// strips split in several pieces, a single lane) against the definition.
    #[test]
    fn resample_and_lane_maps_match_the_definition() {
        for shape in [
            vec![7usize, 5, 1],
            vec![9, 6, 3],
            vec![4, 5, 4],
            vec![3, 4, 5],
            vec![2, 3, 2],
            vec![1, 6, 3],
            vec![3, 4, 40],
            vec![2, 3, 600],
        ] {
            for axis in 0..shape.len() {
                let (outer, n, inner) = split(&shape, axis);
                let m = 2 * n + 1;
                let e = op(m, n);
                let src = data(outer * n * inner);
                let mut want = vec![0.0; outer * m * inner];
                for o in 0..outer {
                    for k in 0..inner {
                        for r in 0..m {
                            want[(o * m + r) * inner + k] = e
                                .row(r)
                                .map(|(c, w)| w * src[(o * n + c) * inner + k])
                                .sum();
                        }
                    }
                }
                let mut got = vec![0.0; want.len()];
                resample_axis(&src, &shape, axis, &e, &mut got, |x| x);
                for (g, w) in got.iter().zip(&want) {
                    assert!((g - w).abs() < 1e-9, "{shape:?} axis {axis}");
                }
                // put: add to what the destination holds
                resample_axis_with(&src, &shape, axis, &e, &mut got, |d, x| *d += x);
                for (g, w) in got.iter().zip(&want) {
                    assert!((g - 2.0 * w).abs() < 1e-9, "{shape:?} axis {axis} (put)");
                }
                // an in-place lane map: running sum along the lane, column by column
                let mut lanes = src.clone();
                map_lanes(&mut lanes, &shape, axis, |lane, width| {
                    for i in 1..lane.len() / width {
                        for k in 0..width {
                            lane[i * width + k] += lane[(i - 1) * width + k];
                        }
                    }
                });
                for o in 0..outer {
                    for k in 0..inner {
                        let mut acc = 0.0;
                        for i in 0..n {
                            let at = (o * n + i) * inner + k;
                            acc += src[at];
                            assert_eq!(lanes[at], acc, "{shape:?} axis {axis} (map_lanes)");
                        }
                    }
                }
            }
        }
    }
}
