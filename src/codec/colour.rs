//! The colour transform of a lossy file: real YCoCg on the first three channels
//! before the pyramid, its inverse after synthesis, and the synthesis gain of each
//! channel it weights the quantization step by. (The integer YCoCg-R of `--lossless`
//! is in [`super::lossless`].)

use crate::format::header::Colour;
use crate::io::{RasterView, SamplesRef};

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
    let mut planes = match r.samples {
        SamplesRef::U8(v) => split(v, c, n, |x| x as f32),
        SamplesRef::I8(v) => split(v, c, n, |x| x as f32),
        SamplesRef::U16(v) => split(v, c, n, |x| x as f32),
        SamplesRef::I16(v) => split(v, c, n, |x| x as f32),
        SamplesRef::U32(v) => split(v, c, n, |x| x as f32),
        SamplesRef::I32(v) => split(v, c, n, |x| x as f32),
        SamplesRef::F32(v) => split(v, c, n, |x| if x.is_finite() { x } else { 0.0 }),
        SamplesRef::F64(v) => split(v, c, n, |x| if x.is_finite() { x as f32 } else { 0.0 }),
        SamplesRef::F16(v) => split(v, c, n, |x| {
            let x = x.to_f64();
            if x.is_finite() {
                x as f32
            } else {
                0.0
            }
        }),
    };
    if colour == Colour::YCoCg {
        map3(&mut planes, |r, g, b| {
            let co = r - b;
            let t = b + co * 0.5;
            let cg = g - t;
            (t + cg * 0.5, co, cg)
        });
    }
    planes
}

/// The `c` planes of `n` interleaved positions, `f` applied to every sample.
fn split<T: Copy>(v: &[T], c: usize, n: usize, f: impl Fn(T) -> f32) -> Vec<Vec<f32>> {
    if c == 1 {
        return vec![v[..n].iter().map(|&x| f(x)).collect()];
    }
    // fresh zeroed planes on huge pages where the kernel allows (`vec![plane; c]` would
    // copy the first plane's zeros into the others, a page fault and a copy per page)
    let mut planes: Vec<Vec<f32>> = (0..c).map(|_| crate::tensor::zeroed_vec(n)).collect();
    for (i, px) in v[..n * c].chunks_exact(c).enumerate() {
        for (p, &x) in planes.iter_mut().zip(px) {
            p[i] = f(x);
        }
    }
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
}
