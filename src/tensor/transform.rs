//! One level of a two-scale operator along one axis of an N-d array region.
//!
//! The region is the box `[0, region[k])` in every axis `k` of an array of `shape`.
//! Along `axis`, a lane holds `region[axis]` elements. Two ways to feed the kernel:
//! - **row mode** (axis is not the last one): an element is a contiguous run of the last
//!   axis, so the kernel's inner loop runs over whole rows in place; the run is cut into
//!   strips for cache and threads, and the result goes through a strip-sized scratch.
//! - **gather mode** (axis is the last one, or rows are short): `G` lanes are gathered
//!   side by side into a scratch lane whose elements are `G·w` wide, transformed, and
//!   scattered back — the transpose that lets the contiguous axis vectorise too.

use super::array::strides;
use super::par::{for_each_task, SharedMut, Strips};
use super::workspace::Planner;
use crate::kernel::Kernels;
use crate::scheme::sparse::Csr;
use crate::scheme::Sample;

/// Elements narrower than this go through gather mode.
const ROW_MIN: usize = 32;
/// Samples per strip in row mode.
const STRIP: usize = 128;
/// Target width of a gathered element in gather mode.
const GATHER: usize = 32;

/// Offsets of the first element of every lane set: all index combinations in the region
/// over the axes other than `skip` (and other than the last axis when `skip_last`).
fn lane_bases(shape: &[usize], region: &[usize], skip: usize, skip_last: bool) -> Vec<usize> {
    let st = strides(shape);
    let last = shape.len() - 1;
    let mut bases = vec![0usize];
    for k in 0..shape.len() {
        if k == skip || (skip_last && k == last) {
            continue;
        }
        let mut next = Vec::with_capacity(bases.len() * region[k]);
        for &b in &bases {
            for i in 0..region[k] {
                next.push(b + i * st[k]);
            }
        }
        bases = next;
    }
    bases
}

/// Apply `op` (`region[axis]` × `region[axis]`, an analysis `[A;B]` or synthesis `[P|Q]`
/// level) to every lane along `axis` inside `region`, with the kernels of the shared
/// planner ([`Planner::shared`]).
pub fn transform_axis<T: Sample>(
    data: &mut [T],
    shape: &[usize],
    region: &[usize],
    axis: usize,
    op: &Csr,
) {
    transform_axis_with(Planner::shared().kernels(), data, shape, region, axis, op)
}

/// [`transform_axis`] with the kernel table `k` (a plan's).
pub fn transform_axis_with<T: Sample>(
    k: Kernels,
    data: &mut [T],
    shape: &[usize],
    region: &[usize],
    axis: usize,
    op: &Csr,
) {
    let nd = shape.len();
    assert!(axis < nd && region.len() == nd);
    assert!(region.iter().zip(shape).all(|(r, s)| r <= s));
    assert_eq!(data.len(), shape.iter().product::<usize>());
    let len = region[axis];
    assert_eq!(op.rows(), len);
    if len <= 1 && op.rows() == 1 {
        // a one-element lane is its own coarse part (identity); nothing to do
        return;
    }
    let st = strides(shape);
    let last = nd - 1;
    let ptr = SharedMut(data.as_mut_ptr());
    let es = st[axis];
    if axis != last && region[last] >= ROW_MIN {
        let w = region[last];
        let bases = lane_bases(shape, region, axis, true);
        let strips = Strips::new(w, STRIP);
        for_each_task(
            bases.len() * strips.count,
            len * strips.max,
            || vec![T::default(); len * strips.max],
            |task, scratch| {
                let b = bases[task / strips.count];
                let (off, sw) = strips.get(task % strips.count);
                let p = ptr;
                // SAFETY: this task reads and writes only columns off..off+sw of the
                // elements of lane set `b`, which no other task touches.
                unsafe {
                    let base = p.0.add(b + off);
                    let lanes = crate::kernel::RawLanes {
                        src: base as *const T,
                        src_stride: es,
                        dst: scratch.as_mut_ptr(),
                        dst_stride: sw,
                        width: sw,
                    };
                    crate::kernel::apply_raw(k, op, lanes);
                    for i in 0..len {
                        std::ptr::copy_nonoverlapping(
                            scratch.as_ptr().add(i * sw),
                            base.add(i * es),
                            sw,
                        );
                    }
                }
            },
        );
    } else {
        // gather mode: w samples per element (the last axis' run, or 1 along the last axis)
        let (w, bases) = if axis == last {
            (1, lane_bases(shape, region, axis, false))
        } else {
            (region[last], lane_bases(shape, region, axis, true))
        };
        let g = GATHER.div_ceil(w).clamp(1, bases.len().max(1));
        let groups = bases.len().div_ceil(g);
        let gw = g * w;
        for_each_task(
            groups,
            len * gw,
            || (vec![T::default(); len * gw], vec![T::default(); len * gw]),
            |task, (sin, sout)| {
                let lanes = &bases[task * g..(task * g + g).min(bases.len())];
                let p = ptr;
                // SAFETY: the lanes of this group are disjoint from every other group's.
                unsafe { gather(p.0 as *const T, lanes, es, w, len, sin, gw) };
                let cw = lanes.len() * w;
                crate::kernel::apply(k, op, sin, gw, sout, gw, cw);
                unsafe { scatter(sout, gw, p.0, lanes, es, w, len) };
            },
        );
    }
}

/// Elements per tile of the blocked transposes below.
const TILE: usize = 16;

/// Gather lane `g` (elements of `w` samples at stride `es` from `data + bases[g]`) into
/// columns `g·w .. g·w + w` of `dst` (element stride `ds`). Blocked by tiles of [`TILE`]
/// elements: within a tile each source lane is read in order (one cache line for
/// contiguous lanes) and the few scratch rows it writes stay in L1; a plain
/// lane-by-lane loop streams the whole scratch once per lane, an element-by-element loop
/// touches every lane's page for every element.
///
/// # Safety
/// The lanes' elements must be valid for reads and not written concurrently.
#[inline]
unsafe fn gather<T: Sample>(
    data: *const T,
    bases: &[usize],
    es: usize,
    w: usize,
    len: usize,
    dst: &mut [T],
    ds: usize,
) {
    for i0 in (0..len).step_by(TILE) {
        let i1 = (i0 + TILE).min(len);
        for (g, &b) in bases.iter().enumerate() {
            if w == 1 {
                // a contiguous run of the lane: plain loads (no memcpy call per sample)
                let run = unsafe {
                    std::slice::from_raw_parts(data.add(b + i0 * es), (i1 - i0 - 1) * es + 1)
                };
                for (k, i) in (i0..i1).enumerate() {
                    dst[i * ds + g] = run[k * es];
                }
            } else {
                for i in i0..i1 {
                    let src = unsafe { std::slice::from_raw_parts(data.add(b + i * es), w) };
                    dst[i * ds + g * w..i * ds + g * w + w].copy_from_slice(src);
                }
            }
        }
    }
}

/// The inverse of [`gather`].
///
/// # Safety
/// The lanes' elements must be valid for writes and touched by no other thread.
#[inline]
unsafe fn scatter<T: Sample>(
    src: &[T],
    ss: usize,
    data: *mut T,
    bases: &[usize],
    es: usize,
    w: usize,
    len: usize,
) {
    for i0 in (0..len).step_by(TILE) {
        let i1 = (i0 + TILE).min(len);
        for (g, &b) in bases.iter().enumerate() {
            if w == 1 {
                let run = unsafe {
                    std::slice::from_raw_parts_mut(data.add(b + i0 * es), (i1 - i0 - 1) * es + 1)
                };
                for (k, i) in (i0..i1).enumerate() {
                    run[k * es] = src[i * ss + g];
                }
            } else {
                for i in i0..i1 {
                    let dst = unsafe { std::slice::from_raw_parts_mut(data.add(b + i * es), w) };
                    dst.copy_from_slice(&src[i * ss + g * w..i * ss + g * w + w]);
                }
            }
        }
    }
}
