//! Filling void cells (SRTM −32768, an ASCII grid's NODATA_value, NaN) before
//! synthesis: each void takes the mean of its valid 4-neighbours, front by front from
//! the void's rim inwards, then Jacobi sweeps of the discrete Laplace equation
//! `h = (h_N + h_S + h_E + h_W)/4` on the void cells only smooth the patch so that it
//! joins its rim without creases (a membrane over the hole).

use super::Grid;
use crate::{Error, Result};

/// Jacobi sweeps after the front fill.
const SWEEPS: usize = 64;

/// Fill the cells of channel 0 that equal `nodata` (or are NaN). Returns how many were
/// filled; errors when every cell is void.
pub fn fill(g: &mut Grid, nodata: Option<f64>) -> Result<usize> {
    let is_void = |v: f64| v.is_nan() || nodata.is_some_and(|nd| v == nd);
    let (h, w) = (g.h, g.w);
    let mut void: Vec<bool> = (0..h * w).map(|i| is_void(g.data[i * g.c])).collect();
    let total = void.iter().filter(|&&v| v).count();
    if total == 0 {
        return Ok(0);
    }
    if total == h * w {
        return Err(Error::format(
            "every cell is void (nodata)",
            "a heightmap with valid cells",
        ));
    }
    let holes: Vec<usize> = (0..h * w).filter(|&i| void[i]).collect();
    let neighbours = |i: usize| {
        let (y, x) = (i / w, i % w);
        let mut n = [usize::MAX; 4];
        if y > 0 {
            n[0] = i - w;
        }
        if y + 1 < h {
            n[1] = i + w;
        }
        if x > 0 {
            n[2] = i - 1;
        }
        if x + 1 < w {
            n[3] = i + 1;
        }
        n
    };
    let mut left = total;
    while left > 0 {
        let mut front = Vec::new();
        for &i in &holes {
            if !void[i] {
                continue;
            }
            let (mut s, mut k) = (vec![0.0; g.c], 0);
            for j in neighbours(i) {
                if j != usize::MAX && !void[j] {
                    for (ch, acc) in s.iter_mut().enumerate() {
                        *acc += g.data[j * g.c + ch];
                    }
                    k += 1;
                }
            }
            if k > 0 {
                front.push((i, s.iter().map(|v| v / k as f64).collect::<Vec<_>>()));
            }
        }
        for (i, v) in front {
            g.data[i * g.c..(i + 1) * g.c].copy_from_slice(&v);
            void[i] = false;
            left -= 1;
        }
    }
    for _ in 0..SWEEPS {
        for &i in &holes {
            for ch in 0..g.c {
                let (mut s, mut k) = (0.0, 0.0);
                for j in neighbours(i) {
                    if j != usize::MAX {
                        s += g.data[j * g.c + ch];
                        k += 1.0;
                    }
                }
                g.data[i * g.c + ch] = s / k;
            }
        }
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hole_in_a_plane_is_filled_with_the_plane() {
        let mut g = Grid::new(
            8,
            8,
            1,
            (0..64)
                .map(|i| (i / 8) as f64 + 2.0 * (i % 8) as f64)
                .collect(),
        )
        .unwrap();
        let want = g.clone();
        for &(y, x) in &[(3, 3), (3, 4), (4, 3), (4, 4), (5, 4)] {
            *g.at_mut(y, x, 0) = -32768.0;
        }
        assert_eq!(fill(&mut g, Some(-32768.0)).unwrap(), 5);
        for (a, b) in g.data.iter().zip(&want.data) {
            assert!((a - b).abs() < 0.05, "{a} vs {b}");
        }
    }
}
