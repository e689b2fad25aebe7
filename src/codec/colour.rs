//! The colour transform of a lossy file: real YCoCg on the first three channels
//! before the pyramid, its inverse after synthesis, and the synthesis gain of each
//! channel it weights the quantization step by. (The integer YCoCg-R of `--lossless`
//! is in [`super::lossless`].)

use crate::format::header::Colour;
use crate::io::{RasterView, SamplesRef};
use rayon::prelude::*;

/// Squared synthesis gain of each channel after the colour transform (inverse YCoCg
/// columns: Y → (1,1,1), Co → (½,0,−½), Cg → (−½,½,−½)).
pub(super) fn channel_weights(colour: Colour, channels: usize) -> Vec<f64> {
    let mut w = vec![1.0; channels];
    if colour == Colour::YCoCg {
        w[0] = 3.0f64.sqrt();
        w[1] = 0.5f64.sqrt();
        w[2] = 0.75f64.sqrt();
    }
    w
}

/// `(p0, p1, p2)[i] = f(p0[i], p1[i], p2[i])` on the first three planes (a colour
/// transform, one pixel at a time).
pub(super) fn map3<T: Copy>(planes: &mut [Vec<T>], f: impl Fn(T, T, T) -> (T, T, T)) {
    let [a, b, c, ..] = planes else {
        panic!("a colour transform on fewer than 3 planes")
    };
    for ((x, y), z) in a.iter_mut().zip(b.iter_mut()).zip(c.iter_mut()) {
        (*x, *y, *z) = f(*x, *y, *z);
    }
}

/// Inverse YCoCg in real arithmetic: `(Y, Co, Cg) → (R, G, B)`.
pub(super) fn ycocg_inverse(y: f32, co: f32, cg: f32) -> (f32, f32, f32) {
    let t = y - cg * 0.5;
    let g = cg + t;
    let b = t - co * 0.5;
    (b + co, g, b)
}

/// Split interleaved samples into per-channel f32 planes, NaN/∞ → 0, colour applied.
pub(super) fn planes_f32(r: &RasterView<'_>, colour: Colour) -> Vec<Vec<f32>> {
    let c = r.channels;
    let n = r.positions();
    // integers convert exactly through f64 or straight (one rounding either way)
    let ycocg = colour == Colour::YCoCg;
    match r.samples {
        SamplesRef::U8(v) => split(v, c, n, ycocg, |x| x as f32),
        SamplesRef::I8(v) => split(v, c, n, ycocg, |x| x as f32),
        SamplesRef::U16(v) => split(v, c, n, ycocg, |x| x as f32),
        SamplesRef::I16(v) => split(v, c, n, ycocg, |x| x as f32),
        SamplesRef::U32(v) => split(v, c, n, ycocg, |x| x as f32),
        SamplesRef::I32(v) => split(v, c, n, ycocg, |x| x as f32),
        SamplesRef::F32(v) => split(v, c, n, ycocg, |x| if x.is_finite() { x } else { 0.0 }),
        SamplesRef::F64(v) => split(
            v,
            c,
            n,
            ycocg,
            |x| {
                if x.is_finite() {
                    x as f32
                } else {
                    0.0
                }
            },
        ),
        SamplesRef::F16(v) => split(v, c, n, ycocg, |x| {
            let x = x.to_f64();
            if x.is_finite() {
                x as f32
            } else {
                0.0
            }
        }),
    }
}

/// Forward YCoCg in real arithmetic: `(R, G, B) → (Y, Co, Cg)`, the inverse of
/// [`ycocg_inverse`].
#[inline(always)]
fn ycocg_forward(r: f32, g: f32, b: f32) -> (f32, f32, f32) {
    let co = r - b;
    let t = b + co * 0.5;
    let cg = g - t;
    (t + cg * 0.5, co, cg)
}

/// The `c` planes of `n` interleaved positions, `f` applied to every sample, then the
/// first three taken to YCoCg when `ycocg` ([`ycocg_forward`]). Blocks of positions go
/// in parallel; each position is converted on its own, so the planes are the same on
/// any number of threads.
fn split<T: Copy + Sync>(
    v: &[T],
    c: usize,
    n: usize,
    ycocg: bool,
    f: impl Fn(T) -> f32 + Sync,
) -> Vec<Vec<f32>> {
    const BLOCK: usize = 1 << 15;
    // fresh zeroed planes on huge pages where the kernel allows (`vec![plane; c]` would
    // copy the first plane's zeros into the others, a page fault and a copy per page)
    let mut planes: Vec<Vec<f32>> = (0..c).map(|_| crate::tensor::zeroed_vec(n)).collect();
    // each block's slices of the planes
    let mut parts: Vec<Vec<&mut [f32]>> = (0..n.div_ceil(BLOCK)).map(|_| Vec::new()).collect();
    for p in planes.iter_mut() {
        for (k, part) in p.chunks_mut(BLOCK).enumerate() {
            parts[k].push(part);
        }
    }
    parts.into_par_iter().enumerate().for_each(|(k, mut part)| {
        let m = part[0].len();
        let src = &v[k * BLOCK * c..(k * BLOCK + m) * c];
        if let [p0, p1, p2] = &mut part[..] {
            // (zipped, not indexed: no bounds checks)
            let outs = p0.iter_mut().zip(p1.iter_mut()).zip(p2.iter_mut());
            for (((a, b), d), px) in outs.zip(src.chunks_exact(3)) {
                (*a, *b, *d) = (f(px[0]), f(px[1]), f(px[2]));
                if ycocg {
                    (*a, *b, *d) = ycocg_forward(*a, *b, *d);
                }
            }
            return;
        }
        for (i, px) in src.chunks_exact(c).enumerate() {
            for (p, &x) in part.iter_mut().zip(px) {
                p[i] = f(x);
            }
        }
        if let [p0, p1, p2, ..] = &mut part[..] {
            if ycocg {
                for ((a, b), d) in p0.iter_mut().zip(p1.iter_mut()).zip(p2.iter_mut()) {
                    (*a, *b, *d) = ycocg_forward(*a, *b, *d);
                }
            }
        }
    });
    planes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{DataKind, Raster, SampleType, Samples};

    /// The planes of every sample type, one and three channels, are the samples read as
    /// `f64`, cast to `f32`, with the values that are not finite as 0.
    #[test]
    fn planes_are_the_samples_as_f32() {
        let vals = [
            0.0,
            1.0,
            -3.0,
            255.0,
            65535.0,
            -40000.5,
            3.0e9,
            f64::NAN,
            f64::INFINITY,
            1.0e300,
            0.1,
            -7.25,
        ];
        for ty in SampleType::ALL {
            for c in [1usize, 3] {
                let v: Vec<f64> = (0..4 * c).map(|i| vals[i % vals.len()]).collect();
                let r =
                    Raster::new(vec![2, 2], c, Samples::from_f64(&v, ty), DataKind::Image).unwrap();
                let planes = planes_f32(&r.view(), Colour::None);
                for i in 0..4 {
                    for (k, p) in planes.iter().enumerate() {
                        let x = r.samples.get_f64(i * c + k);
                        let want = if x.is_finite() { x as f32 } else { 0.0 };
                        assert_eq!(p[i].to_bits(), want.to_bits(), "{ty:?} {c} {i} {k}");
                    }
                }
            }
        }
    }

    /// YCoCg planes of 3 and 4 channels over several blocks of positions are the
    /// samples as `f32` through the forward transform one position at a time (the 4th
    /// channel untouched), the same on one and two threads.
    #[test]
    fn ycocg_planes_are_the_per_position_transform() {
        let n = 3 * (1 << 15) + 17;
        for c in [3usize, 4] {
            let v: Vec<u16> = (0..n * c)
                .map(|i| (i as u32).wrapping_mul(2_654_435_761) as u16)
                .collect();
            let r = Raster::new(vec![n, 1], c, Samples::U16(v.clone()), DataKind::Image).unwrap();
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let planes = pool.install(|| planes_f32(&r.view(), Colour::YCoCg));
                for i in (0..n).step_by(7) {
                    let px: Vec<f32> = (0..c).map(|k| v[i * c + k] as f32).collect();
                    // Co = R − B, t = B + Co/2, Cg = G − t, Y = t + Cg/2
                    let co = px[0] - px[2];
                    let t = px[2] + co * 0.5;
                    let cg = px[1] - t;
                    let mut want = vec![t + cg * 0.5, co, cg];
                    want.extend_from_slice(&px[3..]);
                    for k in 0..c {
                        assert_eq!(
                            planes[k][i].to_bits(),
                            want[k].to_bits(),
                            "{c} {threads} {i} {k}"
                        );
                    }
                }
            }
        }
    }
}
