//! Integer-reversible pieces of `--lossless`: the reversible 5/3 lifting of the linear
//! B-spline scheme ([`crate::scheme::linear::lift_forward`], format 2 writers) or the
//! S-transform (integer Haar, notes §9.2 with the averages floored; format 1 files) on
//! every spatial axis in the non-standard order, the integer YCoCg-R colour lifting,
//! and the order-preserving map from float bit patterns to integers. All arithmetic
//! wraps, so every step inverts exactly for any input.

use crate::io::Samples;
use crate::scheme::{Boundary, Scheme};
use crate::tensor::{Order, Pyramid, PyramidSpec};

/// The integer transforms `--lossless` files use: the 5/3 lifting (scheme `linear`) and
/// the S-transform (scheme `haar`).
pub fn supports(scheme: Scheme) -> bool {
    matches!(scheme, Scheme::Linear | Scheme::Haar)
}

/// Sample types whose lossless planes are `i32` ([`Store`]): 8 and 16 bits. The 5/3
/// lifting's gain keeps every value of a real raster far below 2^31; the transforms
/// check each value they store, and the codec falls back to `i64` planes (the same
/// file, the same samples) when one does not fit.
pub fn narrow(t: crate::io::SampleType) -> bool {
    use crate::io::SampleType as T;
    matches!(t, T::U8 | T::I8 | T::U16 | T::I16)
}

/// Plan of an integer pyramid of `scheme` ([`supports`]): lane lengths halve (rounding
/// up) while ≥ 2.
pub fn plan(dims: &[usize], levels: usize, scheme: Scheme) -> Pyramid {
    let lengths = dims
        .iter()
        .map(|&n| {
            let mut v = vec![n];
            while v.len() <= levels && *v.last().unwrap() >= 2 {
                let m = *v.last().unwrap();
                v.push(m.div_ceil(2));
            }
            v
        })
        .collect();
    Pyramid {
        spec: PyramidSpec {
            scheme,
            boundary: if scheme == Scheme::Haar {
                Boundary::Interpolating
            } else {
                Boundary::Symmetric
            },
            levels,
            order: Order::NonStandard,
            axes: (0..dims.len()).collect(),
        },
        shape: dims.to_vec(),
        lengths,
    }
}

/// Storage of an integer plane: `i64`, or `i32` for samples of 8 and 16 bits, whose
/// transform is computed in `i64` a lane at a time and stored back only when it fits.
pub trait Store: Copy + Default + Send + Sync {
    fn wide(self) -> i64;
    /// `v` stored, `None` when it does not fit.
    fn narrow(v: i64) -> Option<Self>;
    /// One inverse level of `scheme` on every lane along `axis` inside `region` (as
    /// [`lanes`] with [`level_inverse`]); false when a result does not fit.
    fn inverse_level(
        data: &mut [Self],
        shape: &[usize],
        region: &[usize],
        axis: usize,
        scheme: Scheme,
    ) -> bool {
        lanes(data, shape, region, axis, &mut level_inverse(scheme))
    }
}

impl Store for i64 {
    #[inline(always)]
    fn wide(self) -> i64 {
        self
    }
    #[inline(always)]
    fn narrow(v: i64) -> Option<Self> {
        Some(v)
    }
}

impl Store for i32 {
    #[inline(always)]
    fn wide(self) -> i64 {
        self as i64
    }
    #[inline(always)]
    fn narrow(v: i64) -> Option<Self> {
        i32::try_from(v).ok()
    }
    /// The 5/3 level in `i32` arithmetic ([`inverse_53_narrow`]), the S-transform's
    /// through `i64` lanes.
    fn inverse_level(
        data: &mut [Self],
        shape: &[usize],
        region: &[usize],
        axis: usize,
        scheme: Scheme,
    ) -> bool {
        if scheme == Scheme::Linear {
            inverse_53_narrow(data, shape, region, axis)
        } else {
            lanes(data, shape, region, axis, &mut level_inverse(scheme))
        }
    }
}

/// Inputs of a 5/3 inverse level below this in magnitude give outputs below 2^30, every
/// intermediate sum inside `i32`: `|C|, |D| < 2^28` ⇒ even outputs `< 2^28 + 2^27 + 1`,
/// their pair sums `< 2^30`, odd outputs `< 2^28 + 2^29`.
const NARROW_BOUND: i32 = 1 << 28;

/// Columns of the lanes [`inverse_53_narrow`] lifts together across an axis other than
/// the last (adjacent in memory, so each lifting step runs along rows of this many).
const STRIP: usize = 64;

/// The offsets of the positions of `region` whose indices on the axes `skip` are 0, in
/// raster order (`strides` of the plane).
fn bases(region: &[usize], strides: &[usize], skip: &[usize]) -> Vec<usize> {
    let mut out = vec![0usize];
    for (k, (&r, &st)) in region.iter().zip(strides).enumerate() {
        if skip.contains(&k) {
            continue;
        }
        out = out
            .iter()
            .flat_map(|&b| (0..r).map(move |i| b + i * st))
            .collect();
    }
    out
}

/// [`crate::scheme::linear::lift_inverse`] on every lane along `axis` inside `region`
/// of an `i32` plane, computed in `i32` where a group of lanes holds only values below
/// [`NARROW_BOUND`] (the same integers as the `i64` lifting: the floors are arithmetic
/// shifts, no sum overflows) and through `i64` lanes elsewhere: lanes along the last
/// axis one at a time, those along another axis [`STRIP`] adjacent lanes together,
/// each lifting step a pass over rows of the strip. False when a result does not fit
/// 32 bits (the plane then holds garbage).
fn inverse_53_narrow(data: &mut [i32], shape: &[usize], region: &[usize], axis: usize) -> bool {
    let nd = shape.len();
    let m = region[axis];
    if m < 2 || region.contains(&0) {
        return true;
    }
    let mut strides = vec![1usize; nd];
    for k in (0..nd - 1).rev() {
        strides[k] = strides[k + 1] * shape[k + 1];
    }
    let st = strides[axis];
    let mut fits = true;
    let last = nd - 1;
    if axis == last {
        let mut buf = vec![0i32; m];
        for b in bases(region, &strides, &[axis]) {
            if !row_53_inverse(&mut data[b..b + m], &mut buf) {
                fits &= lane_wide(data, b, 1, m);
            }
        }
        return fits;
    }
    let w = region[last];
    let mut buf = vec![0i32; m * STRIP.min(w)];
    for b in bases(region, &strides, &[axis, last]) {
        for x0 in (0..w).step_by(STRIP) {
            let cw = STRIP.min(w - x0);
            if !strip_53_inverse(data, b + x0, st, m, cw, &mut buf[..m * cw]) {
                for x in x0..x0 + cw {
                    fits &= lane_wide(data, b + x, st, m);
                }
            }
        }
    }
    fits
}

/// The 5/3 inverse of one lane (`m` values from `base`, `stride` apart) through `i64`;
/// false when a result does not fit 32 bits.
fn lane_wide(data: &mut [i32], base: usize, stride: usize, m: usize) -> bool {
    let mut lane: Vec<i64> = (0..m).map(|j| data[base + j * stride] as i64).collect();
    let mut scratch = vec![0i64; m];
    crate::scheme::linear::lift_inverse(&mut lane, &mut scratch);
    let mut fits = true;
    for (j, &v) in lane.iter().enumerate() {
        match i32::try_from(v) {
            Ok(v) => data[base + j * stride] = v,
            Err(_) => fits = false,
        }
    }
    fits
}

/// `|v|` or `|v| − 1` of every value OR-ed together: below [`NARROW_BOUND`] exactly
/// when every `|v|` is.
#[inline(always)]
fn magnitudes(v: &[i32]) -> i32 {
    v.iter().fold(0, |a, &x| a | (x ^ (x >> 31)))
}

/// The 5/3 inverse of a contiguous lane in `i32`, `buf` as long; false (the lane
/// untouched) when a value is not below [`NARROW_BOUND`].
fn row_53_inverse(lane: &mut [i32], buf: &mut [i32]) -> bool {
    let m = lane.len();
    if magnitudes(lane) >= NARROW_BOUND {
        return false;
    }
    buf.copy_from_slice(lane);
    let (n, s) = (m.div_ceil(2), m / 2);
    let (c, d) = buf.split_at(n);
    for j in 0..n {
        let (dl, dr) = (d[j.saturating_sub(1)], d[j.min(s - 1)]);
        lane[2 * j] = c[j] - ((dl + dr + 2) >> 2);
    }
    for j in 0..s {
        let right = if 2 * j + 2 < m {
            lane[2 * j + 2]
        } else {
            lane[2 * j]
        };
        lane[2 * j + 1] = d[j] + ((lane[2 * j] + right) >> 1);
    }
    true
}

/// The 5/3 inverse of `cw` adjacent lanes of `m` values from `base`, `st` apart (each
/// lane's values a row of `buf`, `m × cw`, then each lifting step a pass over rows);
/// false (the lanes untouched) when a value is not below [`NARROW_BOUND`].
fn strip_53_inverse(
    data: &mut [i32],
    base: usize,
    st: usize,
    m: usize,
    cw: usize,
    buf: &mut [i32],
) -> bool {
    let mut big = 0;
    for (j, row) in buf.chunks_exact_mut(cw).enumerate() {
        let src = &data[base + j * st..][..cw];
        big |= magnitudes(src);
        row.copy_from_slice(src);
    }
    if big >= NARROW_BOUND {
        return false;
    }
    let (n, s) = (m.div_ceil(2), m / 2);
    let row = |j: usize| &buf[j * cw..(j + 1) * cw];
    for j in 0..n {
        let (c, dl, dr) = (row(j), row(n + j.saturating_sub(1)), row(n + j.min(s - 1)));
        let out = &mut data[base + 2 * j * st..][..cw];
        for (((o, &c), &l), &r) in out.iter_mut().zip(c).zip(dl).zip(dr) {
            *o = c - ((l + r + 2) >> 2);
        }
    }
    for j in 0..s {
        let d = row(n + j);
        let (head, tail) = data.split_at_mut(base + (2 * j + 1) * st);
        let left = &head[base + 2 * j * st..][..cw];
        let (out, after) = tail.split_at_mut(cw);
        let right = if 2 * j + 2 < m {
            &after[st - cw..][..cw]
        } else {
            left
        };
        for (((o, &d), &l), &r) in out.iter_mut().zip(d).zip(left).zip(right) {
            *o = d + ((l + r) >> 1);
        }
    }
    true
}

/// Apply `f` to every lane along `axis` inside `region` (extents from the origin), each
/// lane taken to `i64`; false when a result does not fit the storage (the plane then
/// holds garbage).
fn lanes<T: Store>(
    data: &mut [T],
    shape: &[usize],
    region: &[usize],
    axis: usize,
    f: &mut dyn FnMut(&mut [i64]),
) -> bool {
    let nd = shape.len();
    let mut strides = vec![1usize; nd];
    for k in (0..nd.saturating_sub(1)).rev() {
        strides[k] = strides[k + 1] * shape[k + 1];
    }
    let n = region[axis];
    let mut buf = vec![0i64; n];
    let mut idx = vec![0usize; nd];
    let mut fits = true;
    let total: usize = region
        .iter()
        .enumerate()
        .filter(|&(k, _)| k != axis)
        .map(|(_, &r)| r)
        .product();
    for _ in 0..total {
        let base: usize = idx.iter().zip(&strides).map(|(i, s)| i * s).sum();
        for (j, b) in buf.iter_mut().enumerate() {
            *b = data[base + j * strides[axis]].wide();
        }
        f(&mut buf);
        for (j, b) in buf.iter().enumerate() {
            match T::narrow(*b) {
                Some(v) => data[base + j * strides[axis]] = v,
                None => fits = false,
            }
        }
        // next index, skipping `axis`
        for k in (0..nd).rev() {
            if k == axis {
                continue;
            }
            idx[k] += 1;
            if idx[k] < region[k] {
                break;
            }
            idx[k] = 0;
        }
    }
    fits
}

/// One S-transform level on a lane: pairs `(a, b)` → `h = a − b`, `l = b + ⌊h/2⌋`
/// (= ⌊(a+b)/2⌋), packed `[l… (odd tail) | h…]`.
fn s_forward(lane: &mut [i64]) {
    let n = lane.len();
    let c = n.div_ceil(2);
    let mut out = vec![0i64; n];
    for k in 0..n / 2 {
        let (a, b) = (lane[2 * k], lane[2 * k + 1]);
        let h = a.wrapping_sub(b);
        out[k] = b.wrapping_add(h >> 1);
        out[c + k] = h;
    }
    if n % 2 == 1 {
        out[c - 1] = lane[n - 1];
    }
    lane.copy_from_slice(&out);
}

pub(super) fn s_inverse(lane: &mut [i64]) {
    let n = lane.len();
    let c = n.div_ceil(2);
    let mut out = vec![0i64; n];
    for k in 0..n / 2 {
        let (l, h) = (lane[k], lane[c + k]);
        let b = l.wrapping_sub(h >> 1);
        out[2 * k] = b.wrapping_add(h);
        out[2 * k + 1] = b;
    }
    if n % 2 == 1 {
        out[n - 1] = lane[c - 1];
    }
    lane.copy_from_slice(&out);
}

/// One level of the integer transform of `scheme` on a lane.
fn level_forward(scheme: Scheme) -> impl FnMut(&mut [i64]) {
    let mut scratch = Vec::new();
    move |lane: &mut [i64]| {
        if scheme == Scheme::Linear {
            scratch.resize(lane.len(), 0);
            crate::scheme::linear::lift_forward(lane, &mut scratch);
        } else {
            s_forward(lane);
        }
    }
}

/// The inverse of [`level_forward`].
fn level_inverse(scheme: Scheme) -> impl FnMut(&mut [i64]) {
    let mut scratch = Vec::new();
    move |lane: &mut [i64]| {
        if scheme == Scheme::Linear {
            scratch.resize(lane.len(), 0);
            crate::scheme::linear::lift_inverse(lane, &mut scratch);
        } else {
            s_inverse(lane);
        }
    }
}

/// Forward integer pyramid of `plan` in place; false when an intermediate value did
/// not fit the storage `T` (never for `i64`: the arithmetic wraps), the plane then
/// holding garbage.
pub fn forward<T: Store>(data: &mut [T], pyr: &Pyramid) -> bool {
    let mut f = level_forward(pyr.spec.scheme);
    let mut region = pyr.shape.clone();
    let mut fits = true;
    for l in 0..pyr.depth() {
        let before = region.clone();
        for (i, &a) in pyr.spec.axes.iter().enumerate() {
            if l < pyr.axis_levels(i) {
                fits &= lanes(data, &pyr.shape, &before, a, &mut f);
                if !fits {
                    return false;
                }
                region[a] = pyr.lengths[i][l + 1];
            }
        }
    }
    fits
}

/// Inverse of [`forward`], stopping `skip` levels early (the result then holds the
/// coarse block of level `skip` at the origin); false as [`forward`].
pub fn inverse<T: Store>(data: &mut [T], pyr: &Pyramid, skip: usize) -> bool {
    let mut regions = vec![pyr.shape.clone()];
    for l in 0..pyr.depth() {
        let mut r = regions[l].clone();
        for (i, &a) in pyr.spec.axes.iter().enumerate() {
            if l < pyr.axis_levels(i) {
                r[a] = pyr.lengths[i][l + 1];
            }
        }
        regions.push(r);
    }
    for l in (skip..pyr.depth()).rev() {
        for (i, &a) in pyr.spec.axes.iter().enumerate().rev() {
            if l < pyr.axis_levels(i)
                && !T::inverse_level(data, &pyr.shape, &regions[l], a, pyr.spec.scheme)
            {
                return false;
            }
        }
    }
    true
}

/// YCoCg-R forward lifting on one pixel: `Co = R − B`, `t = B + ⌊Co/2⌋`, `Cg = G − t`,
/// `Y = t + ⌊Cg/2⌋`.
#[inline]
pub fn ycocg_r(r: i64, g: i64, b: i64) -> (i64, i64, i64) {
    let co = r.wrapping_sub(b);
    let t = b.wrapping_add(co >> 1);
    let cg = g.wrapping_sub(t);
    (t.wrapping_add(cg >> 1), co, cg)
}

/// Positions `range` of the channel planes interleaved into `out` (from its sample
/// `range.start × planes.len()` on; an 8- or 16-bit type): the first three channels
/// taken back from YCoCg-R when `ycocg`, every sample clamped to the type's range — the
/// samples of a lossless decode.
pub(crate) fn interleave<P: Store>(
    planes: &[&[P]],
    range: std::ops::Range<usize>,
    ycocg: bool,
    out: &mut Samples,
) {
    let c = planes.len();
    let (lo, hi) = out.sample_type().range();
    let (lo, hi) = (lo as i64, hi as i64);
    macro_rules! fill {
        ($v:expr, $t:ty) => {{
            let out = &mut $v[range.start * c..range.end * c];
            for (px, at) in out.chunks_exact_mut(c).zip(range.clone()) {
                let first = if ycocg && c >= 3 {
                    let (r, g, b) = ycocg_r_inv(
                        planes[0][at].wide(),
                        planes[1][at].wide(),
                        planes[2][at].wide(),
                    );
                    px[0] = r.clamp(lo, hi) as $t;
                    px[1] = g.clamp(lo, hi) as $t;
                    px[2] = b.clamp(lo, hi) as $t;
                    3
                } else {
                    0
                };
                for (o, p) in px[first..].iter_mut().zip(&planes[first..]) {
                    *o = p[at].wide().clamp(lo, hi) as $t;
                }
            }
        }};
    }
    match out {
        Samples::U8(v) => fill!(v, u8),
        Samples::I8(v) => fill!(v, i8),
        Samples::U16(v) => fill!(v, u16),
        Samples::I16(v) => fill!(v, i16),
        _ => unreachable!("lossless::interleave of a type over 16 bits"),
    }
}

/// Inverse of [`ycocg_r`].
#[inline]
pub fn ycocg_r_inv(y: i64, co: i64, cg: i64) -> (i64, i64, i64) {
    let t = y.wrapping_sub(cg >> 1);
    let g = cg.wrapping_add(t);
    let b = t.wrapping_sub(co >> 1);
    (b.wrapping_add(co), g, b)
}

/// The quantum `q = 2^-p` (0 ≤ p ≤ 40) of float samples when every sample is an integer
/// multiple `k·q` with `|k| < 2^40` and none is −0 or non-finite; `None` otherwise. Such
/// samples (heights stored as whole metres in f32, fixed-point data) are coded as the
/// integers `k = x/q`, which the transform predicts far better than bit patterns;
/// `k·q` gives `x` back exactly in any float type that held it.
pub fn float_quantum(values: impl Iterator<Item = f64>) -> Option<f64> {
    const LIMIT: i32 = 40;
    let (mut p, mut top) = (0i32, 0i32);
    for v in values {
        if !v.is_finite() || v.to_bits() == (-0.0f64).to_bits() {
            return None;
        }
        if v == 0.0 {
            continue;
        }
        let bits = v.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        if exp == 0 {
            return None; // subnormal
        }
        let m = (bits & ((1u64 << 52) - 1)) | (1u64 << 52);
        let tz = m.trailing_zeros() as i32;
        // v = ±(m >> tz)·2^e with (m >> tz) odd, of 53 − tz bits
        let e = exp - 1075 + tz;
        p = p.max(-e);
        top = top.max(e + 53 - tz);
        if p > LIMIT || top + p > LIMIT {
            return None;
        }
    }
    Some((-(p as f64)).exp2())
}

/// Order-preserving map of a float's bit pattern (`bits` wide) to a signed integer.
#[inline]
pub fn float_bits_to_int(bits: u64, width: u32) -> i64 {
    let sign = 1u64 << (width - 1);
    if bits & sign != 0 {
        -((bits & !sign) as i64) - 1
    } else {
        bits as i64
    }
}

/// Inverse of [`float_bits_to_int`].
#[inline]
pub fn int_to_float_bits(v: i64, width: u32) -> u64 {
    let sign = 1u64 << (width - 1);
    let mask = if width == 64 {
        u64::MAX
    } else {
        (1u64 << width) - 1
    };
    if v < 0 {
        ((-(v + 1)) as u64 | sign) & mask
    } else {
        v as u64 & mask
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_transforms_invert_on_odd_shapes_and_extremes() {
        for scheme in [Scheme::Haar, Scheme::Linear] {
            for dims in [vec![1usize], vec![2], vec![7], vec![5, 3], vec![3, 4, 5]] {
                let n: usize = dims.iter().product();
                let mut v: Vec<i64> = (0..n as i64).map(|i| (i * 7919) % 601 - 300).collect();
                v[0] = i64::MIN;
                if n > 2 {
                    v[1] = i64::MAX;
                    v[2] = i64::MIN + 1;
                }
                let orig = v.clone();
                let p = plan(&dims, 5, scheme);
                forward(&mut v[..], &p);
                if n > 3 {
                    assert_ne!(v, orig, "{scheme:?} {dims:?} did nothing");
                }
                inverse(&mut v[..], &p, 0);
                assert_eq!(v, orig, "{scheme:?} {dims:?}");
            }
        }
    }

    /// On 16-bit samples the `i32` planes hold the very values of the `i64` ones, every
    /// level and the inverse included; a value past 32 bits is reported, not wrapped.
    #[test]
    fn narrow_planes_hold_the_values_of_wide_ones_or_say_they_cannot() {
        for scheme in [Scheme::Haar, Scheme::Linear] {
            for dims in [
                vec![37usize],
                vec![19, 23],
                vec![9, 8, 13],
                vec![2, 3, 4, 5],
            ] {
                let n: usize = dims.iter().product();
                let mut s = 7u64;
                let wide: Vec<i64> = (0..n)
                    .map(|i| {
                        crate::entropy::testing::lcg(&mut s);
                        // noise over the full 16-bit range, and its extremes
                        match i % 5 {
                            0 => 65535,
                            1 => 0,
                            _ => (s >> 48) as i64,
                        }
                    })
                    .collect();
                let p = plan(&dims, 6, scheme);
                let mut w = wide.clone();
                let mut q: Vec<i32> = wide.iter().map(|&v| v as i32).collect();
                assert!(forward(&mut w[..], &p));
                assert!(forward(&mut q[..], &p), "{scheme:?} {dims:?}");
                assert!(q.iter().zip(&w).all(|(&a, &b)| a as i64 == b));
                for skip in [0, 1] {
                    let (mut w2, mut q2) = (w.clone(), q.clone());
                    assert!(inverse(&mut w2[..], &p, skip));
                    assert!(inverse(&mut q2[..], &p, skip));
                    assert!(q2.iter().zip(&w2).all(|(&a, &b)| a as i64 == b));
                }
                let mut q3 = q.clone();
                assert!(inverse(&mut q3[..], &p, 0));
                assert!(q3.iter().zip(&wide).all(|(&a, &b)| a as i64 == b));
            }
        }
        let mut big = [i32::MAX, i32::MIN, i32::MAX, i32::MIN, 0, 5];
        assert!(!forward(&mut big[..], &plan(&[6], 2, Scheme::Linear)));
    }

    /// The `i32` 5/3 inverse (lanes in `i32` where their values are below
    /// [`NARROW_BOUND`], through `i64` elsewhere) gives the `i64` lifting's integers:
    /// lanes along the last axis and strips across the others (narrower than, as wide
    /// as and wider than [`STRIP`]), odd and even lengths, some lanes past the bound.
    #[test]
    fn narrow_5_3_inverse_is_the_wide_one_past_the_bound_too() {
        for dims in [
            vec![2usize],
            vec![3],
            vec![37],
            vec![5, 70],
            vec![6, 129],
            vec![33, 7],
            vec![3, 5, 66],
        ] {
            let n: usize = dims.iter().product();
            let mut s = 11u64;
            let wide: Vec<i64> = (0..n)
                .map(|i| {
                    crate::entropy::testing::lcg(&mut s);
                    let v = (s >> 40) as i64 - (1 << 23);
                    // a few values past the bound, most far below
                    if i % 97 == 5 {
                        v.signum() * (NARROW_BOUND as i64 + 12345)
                    } else {
                        v
                    }
                })
                .collect();
            for axis in 0..dims.len() {
                let mut region = dims.clone();
                region[0] = region[0].div_ceil(2).max(1).max(region[0] - 1);
                let mut w = wide.clone();
                let mut q: Vec<i32> = wide.iter().map(|&v| v as i32).collect();
                assert!(i64::inverse_level(
                    &mut w,
                    &dims,
                    &region,
                    axis,
                    Scheme::Linear
                ));
                let ok = i32::inverse_level(&mut q, &dims, &region, axis, Scheme::Linear);
                let fit = w.iter().all(|&v| i32::try_from(v).is_ok());
                assert_eq!(ok, fit, "{dims:?} axis {axis}");
                if ok {
                    assert!(
                        q.iter().zip(&w).all(|(&a, &b)| a as i64 == b),
                        "{dims:?} {axis}"
                    );
                }
            }
        }
    }

    /// On a smooth ramp the 5/3 details vanish (two zeros at π: it predicts lines
    /// exactly), where the S-transform's stay at the slope.
    #[test]
    fn the_5_3_lifting_predicts_lines() {
        let mut v: Vec<i64> = (0..16).map(|i| 3 * i + 5).collect();
        let p = plan(&[16], 1, Scheme::Linear);
        forward(&mut v[..], &p);
        assert!(v[8..15].iter().all(|&d| d == 0), "{v:?}");
        let mut h: Vec<i64> = (0..16).map(|i| 3 * i + 5).collect();
        forward(&mut h[..], &plan(&[16], 1, Scheme::Haar));
        assert!(h[8..].iter().all(|&d| d == -3), "{h:?}");
    }

    #[test]
    fn float_quantum_finds_the_power_of_two_every_sample_is_a_multiple_of() {
        assert_eq!(
            float_quantum([908.0, -3.0, 0.0, 2543.0].into_iter()),
            Some(1.0)
        );
        assert_eq!(float_quantum([0.5, 0.25, 12.0].into_iter()), Some(0.25));
        assert_eq!(float_quantum([1024.0, 4096.0].into_iter()), Some(1.0));
        assert_eq!(float_quantum([0.1f64].into_iter()), None);
        // 0.1 as f32 is exactly 13421773·2^−27
        assert_eq!(
            float_quantum([0.1f32 as f64].into_iter()),
            Some(2f64.powi(-27))
        );
        assert_eq!(float_quantum([1.0, -0.0].into_iter()), None);
        assert_eq!(float_quantum([1.0, f64::NAN].into_iter()), None);
        assert_eq!(float_quantum([(1u64 << 41) as f64].into_iter()), None);
        assert_eq!(float_quantum(std::iter::empty()), Some(1.0));
        for x in [0.75f64, -1e6, 3.0 * 2f64.powi(-30)] {
            let q = float_quantum([x].into_iter()).unwrap();
            assert_eq!((x / q).fract(), 0.0);
            assert_eq!((x / q) as i64 as f64 * q, x);
        }
    }

    #[test]
    fn ycocg_r_and_float_maps_invert() {
        for &(r, g, b) in &[
            (0, 0, 0),
            (255, 0, 17),
            (65535, 1, 40000),
            (-5, 3, i64::MAX),
        ] {
            let (y, co, cg) = ycocg_r(r, g, b);
            assert_eq!(ycocg_r_inv(y, co, cg), (r, g, b));
        }
        for x in [-1.5f32, -0.0, 0.0, 1e-30, 3.0, f32::INFINITY] {
            let v = float_bits_to_int(x.to_bits() as u64, 32);
            assert_eq!(int_to_float_bits(v, 32) as u32, x.to_bits());
        }
        assert!(
            float_bits_to_int((-1.0f32).to_bits() as u64, 32)
                < float_bits_to_int(1.0f32.to_bits() as u64, 32)
        );
    }
}
