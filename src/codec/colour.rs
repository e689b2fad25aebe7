//! The colour transform of a lossy file: real YCoCg on the first three channels
//! before the pyramid, its inverse after synthesis, and the synthesis gain of each
//! channel it weights the quantization step by. (The integer YCoCg-R of `--lossless`
//! is in [`super::lossless`].)

use crate::format::header::Colour;
use crate::io::Raster;

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
pub(super) fn planes_f32(r: &Raster, colour: Colour) -> Vec<Vec<f32>> {
    let c = r.channels;
    let n = r.positions();
    let mut planes = vec![vec![0f32; n]; c];
    for i in 0..n {
        for (k, p) in planes.iter_mut().enumerate() {
            let x = r.samples.get_f64(i * c + k);
            p[i] = if x.is_finite() { x as f32 } else { 0.0 };
        }
    }
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
