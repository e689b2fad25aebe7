//! Resampling with the Catmull–Rom cubic (Keys, a = −½) on an affine map: output sample
//! `i` sits at input position `u = offset + i·step` ([`Map`]); [`resample`] is the
//! corner-aligned map `u = i (n − 1)/(m − 1)` (first and last samples coincide). Weights of the four neighbours at fraction `t`:
//! `w₋₁ = (−t³ + 2t² − t)/2`, `w₀ = (3t³ − 5t² + 2)/2`, `w₁ = (−3t³ + 4t² + t)/2`,
//! `w₂ = (t³ − t²)/2`; indices beyond the ends are clamped.

use rayon::prelude::*;

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

/// Output sample `i` of an axis at input position `offset + i·step`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Map {
    pub offset: f64,
    pub step: f64,
}

impl Map {
    /// Corner-aligned: `n` inputs to `m` outputs with the first and last coinciding.
    pub fn corners(n: usize, m: usize) -> Map {
        let step = if m > 1 {
            (n.max(1) - 1) as f64 / (m - 1) as f64
        } else {
            0.0
        };
        Map { offset: 0.0, step }
    }

    /// Cell-centred: `n` cells to `m` cells over the same extent,
    /// `u = (i + ½)·n/m − ½`.
    pub fn centred(n: usize, m: usize) -> Map {
        let step = n as f64 / m.max(1) as f64;
        Map {
            offset: 0.5 * step - 0.5,
            step,
        }
    }

    /// Input position of output `i`.
    pub fn at(&self, i: usize) -> f64 {
        self.offset + i as f64 * self.step
    }
}

/// For each of `m` outputs: four input indices and their weights. A tap beyond an end
/// uses the linear extrapolation `f(−1) = 2f(0) − f(1)` (and likewise at `n`), so
/// straight lines are reproduced up to the ends; a position outside `[0, n − 1]` takes
/// the line through the two end samples, `f(u) = (1 − u) f(0) + u f(1)` below 0.
fn taps(n: usize, m: usize, map: Map) -> Vec<([usize; 4], [f64; 4])> {
    (0..m)
        .map(|i| {
            let u = map.at(i);
            if n > 1 && (u < 0.0 || u > (n - 1) as f64) {
                let (a, b, t) = if u < 0.0 {
                    (0, 1, u)
                } else {
                    (n - 1, n - 2, u - (n - 1) as f64)
                };
                return ([a, b, a, a], [1.0 + t.abs(), -t.abs(), 0.0, 0.0]);
            }
            let u = u.clamp(0.0, (n - 1) as f64);
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

/// Resample `g` to `h × w`, corner-aligned (each channel separately).
pub fn resample(g: &Grid, h: usize, w: usize) -> Grid {
    if g.h() == h && g.w() == w {
        return g.clone();
    }
    resample_map(g, (h, Map::corners(g.h(), h)), (w, Map::corners(g.w(), w)))
}

/// Resample `g` to `h` rows and `w` columns on the maps `my`, `mx`.
pub fn resample_map(g: &Grid, (h, my): (usize, Map), (w, mx): (usize, Map)) -> Grid {
    let mut out = Grid::zeros(h, w, g.c());
    resample_add(g, &mut out, my, mx);
    out
}

/// `out ← out + R g`, with `R` the resampling of `g` to `out`'s rows and columns on the
/// maps `my`, `mx` (the values of [`resample_map`], added in place: no grid of the
/// output's size is allocated).
pub fn resample_add(g: &Grid, out: &mut Grid, my: Map, mx: Map) {
    let (c, h, w) = (g.c(), out.h(), out.w());
    // along x
    let tx = taps(g.w(), w, mx);
    let mut mid = Grid::zeros(g.h(), w, c);
    for y in 0..g.h() {
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
    // along y, one output row per task
    let ty = taps(g.h(), h, my);
    out.data_mut()
        .par_chunks_mut(w * c)
        .zip(ty.par_iter())
        .for_each(|(row, (idx, wt))| {
            for x in 0..w {
                for k in 0..c {
                    let mut s = 0.0;
                    for j in 0..4 {
                        s += wt[j] * mid.at(idx[j], x, k);
                    }
                    row[x * c + k] += s;
                }
            }
        });
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
