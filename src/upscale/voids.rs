//! Nodata (SRTM voids −32768, an ASCII grid's `NODATA_value`, NaN): filled for the
//! computation by pull-push over the MRA's Haar pyramid, and written back at the void
//! positions of the output.
//!
//! **Pull** (reduce with weights, §9 REDUCE-RESOLUTION with the box filter): with
//! `w = 0` on voids and `1` elsewhere, every level sums pairs along each spatial axis,
//! ```text
//! S_{k+1}[i] = S_k[2i] + S_k[2i+1],   W_{k+1}[i] = W_k[2i] + W_k[2i+1],   S_0 = w·v
//! ```
//! so `S/W` is the mean of the valid samples of a block, until a level has no empty
//! block. **Push** (reconstruct into the holes): an empty cell of level `k` takes the
//! filled value of its parent at level `k + 1`; valid cells keep their value.
//!
//! **Output.** New sample `j` at position `x_j` (old-sample units) maps to the cell
//! `round(x_j)` along every axis (nearest cell); where that cell is void the output gets
//! the nodata value (NaN stays NaN).

use super::{lane, AxisPlan};
use crate::{Error, Result};

/// Which samples are void (`None`: none is).
pub fn mask(data: &[f32], nodata: Option<f64>) -> Option<Vec<bool>> {
    let nd = nodata.map(|v| v as f32);
    let is_void = |v: f32| v.is_nan() || nd.is_some_and(|n| v == n);
    if !data.iter().any(|&v| is_void(v)) {
        return None;
    }
    Some(data.iter().map(|&v| is_void(v)).collect())
}

/// Strides of a row-major shape.
fn strides(shape: &[usize]) -> Vec<usize> {
    (0..shape.len())
        .map(|a| shape[a + 1..].iter().product())
        .collect()
}

/// Sum pairs along each of the first `spatial` axes (lengths `⌈n/2⌉`).
fn pull(s: &[f32], w: &[f32], shape: &[usize], spatial: usize) -> (Vec<f32>, Vec<f32>, Vec<usize>) {
    let coarse: Vec<usize> = shape
        .iter()
        .enumerate()
        .map(|(a, &n)| if a < spatial { n.div_ceil(2) } else { n })
        .collect();
    let len: usize = coarse.iter().product();
    let (mut cs, mut cw) = (vec![0f32; len], vec![0f32; len]);
    let (fs, cstr) = (strides(shape), strides(&coarse));
    for (i, (&sv, &wv)) in s.iter().zip(w).enumerate() {
        let ci: usize = (0..shape.len())
            .map(|a| {
                let x = i / fs[a] % shape[a];
                (if a < spatial { x / 2 } else { x }) * cstr[a]
            })
            .sum();
        cs[ci] += sv;
        cw[ci] += wv;
    }
    (cs, cw, coarse)
}

/// Fill values where `w == 0` from the coarser levels; returns the filled values.
fn push_pull(s: Vec<f32>, w: Vec<f32>, shape: &[usize], spatial: usize) -> Vec<f32> {
    if w.iter().all(|&w| w > 0.0) || shape[..spatial].iter().all(|&n| n == 1) {
        return s
            .iter()
            .zip(&w)
            .map(|(s, w)| if *w > 0.0 { s / w } else { 0.0 })
            .collect();
    }
    let (cs, cw, coarse) = pull(&s, &w, shape, spatial);
    let cv = push_pull(cs, cw, &coarse, spatial);
    let (fs, cstr) = (strides(shape), strides(&coarse));
    (0..s.len())
        .map(|i| {
            if w[i] > 0.0 {
                s[i] / w[i]
            } else {
                let ci: usize = (0..shape.len())
                    .map(|a| {
                        let x = i / fs[a] % shape[a];
                        (if a < spatial { x / 2 } else { x }) * cstr[a]
                    })
                    .sum();
                cv[ci]
            }
        })
        .collect()
}

/// Replace the void samples of `data` (row-major `shape`, the first `spatial` axes
/// spatial, e.g. a trailing channel axis not) by pull-push values.
pub fn fill(data: &mut [f32], void: &[bool], shape: &[usize], spatial: usize) -> Result<()> {
    if void.iter().all(|&v| v) {
        return Err(Error::parameter(
            "input",
            "every sample void (nodata)",
            "at least one valid sample",
        ));
    }
    let w: Vec<f32> = void.iter().map(|&v| if v { 0.0 } else { 1.0 }).collect();
    let s: Vec<f32> = data
        .iter()
        .zip(&w)
        .map(|(&v, &w)| if w > 0.0 { v } else { 0.0 })
        .collect();
    let filled = push_pull(s, w, shape, spatial);
    data.copy_from_slice(&filled);
    Ok(())
}

/// The void mask of the output: each new sample takes its nearest old cell's flag.
pub fn output_mask(void: &[bool], shape: &[usize], plans: &[AxisPlan]) -> Vec<bool> {
    let mut cur = void.to_vec();
    let mut shape = shape.to_vec();
    for p in plans {
        let n = shape[p.axis];
        let (xs, _) = lane::positions(n, p.len, p.geometry);
        let cell: Vec<usize> = xs
            .iter()
            .map(|&x| ((x + 0.5).floor().max(0.0) as usize).min(n - 1))
            .collect();
        let outer: usize = shape[..p.axis].iter().product();
        let inner: usize = shape[p.axis + 1..].iter().product();
        let mut out = Vec::with_capacity(outer * p.len * inner);
        for o in 0..outer {
            for &c in &cell {
                let at = (o * n + c) * inner;
                out.extend_from_slice(&cur[at..at + inner]);
            }
        }
        cur = out;
        shape[p.axis] = p.len;
    }
    cur
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::upscale::Geometry;

    #[test]
    fn pull_push_fills_with_block_means() {
        // 1-D: a hole between 2 and 4 takes the mean of its first non-empty block
        let mut d = vec![2.0, f32::NAN, f32::NAN, 4.0];
        let m = mask(&d, None).unwrap();
        fill(&mut d, &m, &[4], 1).unwrap();
        assert_eq!(d, vec![2.0, 2.0, 4.0, 4.0]);
        let mut d = vec![1.0, -9.0, 5.0];
        let m = mask(&d, Some(-9.0)).unwrap();
        fill(&mut d, &m, &[3], 1).unwrap();
        assert_eq!(d, vec![1.0, 1.0, 5.0]);
        assert!(fill(&mut [0.0], &[true], &[1], 1).is_err());
    }

    #[test]
    fn output_mask_is_nearest_cell() {
        let plans = [AxisPlan {
            axis: 0,
            len: 6,
            geometry: Geometry::Centre,
        }];
        let m = output_mask(&[false, true, false], &[3], &plans);
        assert_eq!(m, vec![false, false, true, true, false, false]);
    }
}
