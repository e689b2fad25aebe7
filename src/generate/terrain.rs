//! Fractal terrain by diamond-square (Fournier, Fussell, Carpenter 1982): on a
//! `(2^k + 1)²` grid, each pass sets square centres to the mean of their four corners
//! plus a random offset, then edge midpoints ("diamonds") to the mean of their (up to)
//! four neighbours plus an offset; the offset amplitude shrinks by `roughness` per pass
//! (roughness `2^−H` for Hurst exponent H). The grid is cropped to the requested size
//! and normalised to [0, 1].

use super::rng::SplitMix64;
use super::Field;
use crate::io::DataKind;

/// Diamond-square terrain of `h × w` samples.
pub fn diamond_square(h: usize, w: usize, seed: u64, roughness: f64) -> Field {
    let mut n = 1usize;
    while n + 1 < h.max(w) {
        n *= 2;
    }
    let size = n + 1;
    let mut g = vec![0.0f64; size * size];
    let mut rng = SplitMix64::new(seed);
    for &(y, x) in &[(0, 0), (0, n), (n, 0), (n, n)] {
        g[y * size + x] = rng.symmetric();
    }
    let mut step = n;
    let mut amp = 1.0;
    while step > 1 {
        let half = step / 2;
        // squares
        for y in (half..size).step_by(step) {
            for x in (half..size).step_by(step) {
                let m = (g[(y - half) * size + x - half]
                    + g[(y - half) * size + x + half]
                    + g[(y + half) * size + x - half]
                    + g[(y + half) * size + x + half])
                    / 4.0;
                g[y * size + x] = m + amp * rng.symmetric();
            }
        }
        // diamonds
        for y in (0..size).step_by(half) {
            let start = if (y / half).is_multiple_of(2) {
                half
            } else {
                0
            };
            for x in (start..size).step_by(step) {
                let mut sum = 0.0;
                let mut cnt = 0.0;
                if y >= half {
                    sum += g[(y - half) * size + x];
                    cnt += 1.0;
                }
                if y + half < size {
                    sum += g[(y + half) * size + x];
                    cnt += 1.0;
                }
                if x >= half {
                    sum += g[y * size + x - half];
                    cnt += 1.0;
                }
                if x + half < size {
                    sum += g[y * size + x + half];
                    cnt += 1.0;
                }
                g[y * size + x] = sum / cnt + amp * rng.symmetric();
            }
        }
        amp *= roughness;
        step = half;
    }
    let mut data: Vec<f64> = (0..h)
        .flat_map(|y| g[y * size..y * size + w].to_vec())
        .collect();
    let (lo, hi) = data
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| {
            (l.min(v), u.max(v))
        });
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    data.iter_mut().for_each(|v| *v = (*v - lo) / span);
    Field::new(&[h, w], 1, data, DataKind::Heightmap)
}
