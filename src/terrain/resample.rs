//! Corner-aligned resampling with the Catmull–Rom cubic (Keys, a = −½): output sample
//! `i` of `m` sits at input position `u = i (n − 1)/(m − 1)`, so the first and last
//! samples coincide (the interpolating-boundary convention of the terrain lattice) and
//! the extent is kept. Weights of the four neighbours at fraction `t`:
//! `w₋₁ = (−t³ + 2t² − t)/2`, `w₀ = (3t³ − 5t² + 2)/2`, `w₁ = (−3t³ + 4t² + t)/2`,
//! `w₂ = (t³ − t²)/2`; indices beyond the ends are clamped.

use super::Grid;

fn weights(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// For each of `m` outputs: four input indices and their weights. A tap beyond an end
/// uses the linear extrapolation `f(−1) = 2f(0) − f(1)` (and likewise at `n`), so
/// straight lines are reproduced up to the ends.
fn taps(n: usize, m: usize) -> Vec<([usize; 4], [f64; 4])> {
    (0..m)
        .map(|i| {
            let u = if m > 1 {
                i as f64 * (n - 1) as f64 / (m - 1) as f64
            } else {
                0.0
            };
            let i0 = (u.floor() as usize).min(n - 1);
            let t = u - i0 as f64;
            let w = weights(t);
            let mut idx = [0usize; 4];
            let mut wt = [0.0f64; 4];
            let mut k = 0;
            let mut add = |j: usize, v: f64, idx: &mut [usize; 4], wt: &mut [f64; 4]| {
                if let Some(p) = idx[..k].iter().position(|&x| x == j) {
                    wt[p] += v;
                } else {
                    idx[k] = j;
                    wt[k] = v;
                    k += 1;
                }
            };
            for (d, &wd) in w.iter().enumerate() {
                let j = i0 as i64 + d as i64 - 1;
                if n == 1 {
                    add(0, wd, &mut idx, &mut wt);
                } else if j < 0 {
                    add(0, 2.0 * wd, &mut idx, &mut wt);
                    add(1, -wd, &mut idx, &mut wt);
                } else if j >= n as i64 {
                    add(n - 1, 2.0 * wd, &mut idx, &mut wt);
                    add(n - 2, -wd, &mut idx, &mut wt);
                } else {
                    add(j as usize, wd, &mut idx, &mut wt);
                }
            }
            (idx, wt)
        })
        .collect()
}

/// Resample `g` to `h × w` (each channel separately).
pub fn resample(g: &Grid, h: usize, w: usize) -> Grid {
    if g.h == h && g.w == w {
        return g.clone();
    }
    let c = g.c;
    // along x
    let tx = taps(g.w, w);
    let mut mid = Grid::zeros(g.h, w, c);
    for y in 0..g.h {
        for (x, (idx, wt)) in tx.iter().enumerate() {
            for k in 0..c {
                let mut s = 0.0;
                for j in 0..4 {
                    s += wt[j] * g.at(y, idx[j], k);
                }
                *mid.at_mut(y, x, k) = s;
            }
        }
    }
    // along y
    let ty = taps(g.h, h);
    let mut out = Grid::zeros(h, w, c);
    for (y, (idx, wt)) in ty.iter().enumerate() {
        for x in 0..w {
            for k in 0..c {
                let mut s = 0.0;
                for j in 0..4 {
                    s += wt[j] * mid.at(idx[j], x, k);
                }
                *out.at_mut(y, x, k) = s;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_and_linear_ramps_are_reproduced() {
        let g = Grid::new(3, 4, 1, (0..12).map(|v| v as f64).collect()).unwrap();
        assert_eq!(resample(&g, 3, 4), g);
        // a plane a + b y + c x is reproduced exactly by Catmull–Rom away from clamping
        let plane = Grid::new(
            9,
            9,
            1,
            (0..81)
                .map(|i| 2.0 + (i / 9) as f64 - 0.5 * (i % 9) as f64)
                .collect(),
        )
        .unwrap();
        let r = resample(&plane, 17, 17);
        for y in 0..17 {
            for x in 0..17 {
                let want = 2.0 + y as f64 * 0.5 - 0.25 * x as f64;
                assert!((r.at(y, x, 0) - want).abs() < 1e-9);
            }
        }
    }
}
