//! Nodata, one way for every command: a sample is **void** when it is NaN or equals the
//! raster's `meta.nodata` (SRTM −32768, an ASCII grid's `NODATA_value`). Void samples
//! never enter a filter:
//!
//! 1. [`Voids::find`] records which samples are void, the marker they carry and the
//!    range `[lo, hi]` of the valid samples;
//! 2. the voids are filled for the computation, by pull-push ([`Voids::fill`], any
//!    number of axes) or by a membrane ([`Voids::fill_membrane`], 2-D, smooth);
//! 3. after the operation, an output sample whose footprint on the input is all void is
//!    void again ([`Voids::footprint`]), and [`Voids::restore`] writes the marker there
//!    and, for a resampling, clamps every valid output into `[lo, hi]`.
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
//! **Membrane** (2-D): each void takes the mean of its valid 4-neighbours, front by
//! front from the rim inwards, then Jacobi sweeps of `h = (h_N + h_S + h_E + h_W)/4` on
//! the void cells only, so that the patch joins its rim without creases.
//!
//! **Footprint.** With the new grid placed on the old one by [`AxisMap`]s (new sample
//! `j` at old index `x_j = offset + j·step`), the footprint of `j` along an axis is the
//! old cells whose centres lie within `step/2` of `x_j`, `|i − x_j| ≤ step/2` (at least
//! the nearest cell; an old cell straddling two new cells is in the footprint of the one
//! holding its centre); a new sample is void when every cell of its box footprint is.

use super::AxisMap;
use crate::{Error, Result};

/// Jacobi sweeps after the membrane's front fill.
const SWEEPS: usize = 64;

/// A sample value the mechanism works on.
pub trait Value: Copy + Send + Sync {
    fn to_f64(self) -> f64;
    fn from_f64(v: f64) -> Self;
}

impl Value for f32 {
    fn to_f64(self) -> f64 {
        self as f64
    }
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Value for f64 {
    fn to_f64(self) -> f64 {
        self
    }
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// Integers: rounded to nearest and saturated (NaN → 0), as `Samples::from_f64` does.
macro_rules! int_value {
    ($($t:ty),*) => {$(
        impl Value for $t {
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn from_f64(v: f64) -> Self {
                v.round() as $t
            }
        }
    )*};
}
int_value!(u8, i8, u16, i16, u32, i32);

impl Value for half::f16 {
    fn to_f64(self) -> f64 {
        half::f16::to_f64(self)
    }
    fn from_f64(v: f64) -> Self {
        half::f16::from_f64(v)
    }
}

/// Is `v` void for the marker `nodata`?
pub fn is_void(v: f64, nodata: Option<f64>) -> bool {
    v.is_nan() || nodata.is_some_and(|n| v == n)
}

/// The void samples of one array and what the valid ones span.
#[derive(Clone, Debug, PartialEq)]
pub struct Voids {
    /// One flag per sample (channels interleaved, as the data).
    pub mask: Vec<bool>,
    /// The value written at void outputs: `meta.nodata`, else NaN.
    pub marker: f64,
    /// `(lo, hi)` of the valid samples.
    pub range: (f64, f64),
}

impl Voids {
    /// The voids of `data` (`None` when no sample is void).
    pub fn find<T: Value>(data: &[T], nodata: Option<f64>) -> Option<Voids> {
        let mut any = false;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mask: Vec<bool> = data
            .iter()
            .map(|&v| {
                let v = v.to_f64();
                let void = is_void(v, nodata);
                if void {
                    any = true;
                } else {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                void
            })
            .collect();
        any.then(|| Voids {
            mask,
            marker: nodata.unwrap_or(f64::NAN),
            range: (lo, hi),
        })
    }

    /// Number of void samples.
    pub fn count(&self) -> usize {
        self.mask.iter().filter(|&&v| v).count()
    }

    fn all_void_error() -> Error {
        Error::parameter(
            "input",
            "every sample void (nodata)",
            "at least one valid sample",
        )
    }

    /// Replace the void samples of `data` (row-major `shape`, the first `spatial` axes
    /// spatial, e.g. a trailing channel axis not) by pull-push values.
    pub fn fill<T: Value>(&self, data: &mut [T], shape: &[usize], spatial: usize) -> Result<()> {
        if self.mask.iter().all(|&v| v) {
            return Err(Self::all_void_error());
        }
        let w: Vec<f64> = self
            .mask
            .iter()
            .map(|&v| if v { 0.0 } else { 1.0 })
            .collect();
        let s: Vec<f64> = data
            .iter()
            .zip(&w)
            .map(|(&v, &w)| if w > 0.0 { v.to_f64() } else { 0.0 })
            .collect();
        let filled = push_pull(s, w, shape, spatial);
        for ((d, f), &v) in data.iter_mut().zip(filled).zip(&self.mask) {
            if v {
                *d = T::from_f64(f);
            }
        }
        Ok(())
    }

    /// Fill the voids of an `h × w` grid of `c` interleaved channels (flags of channel
    /// 0 decide) by the membrane; returns how many cells were filled.
    pub fn fill_membrane(&self, data: &mut [f64], h: usize, w: usize, c: usize) -> Result<usize> {
        let mut void: Vec<bool> = (0..h * w).map(|i| self.mask[i * c]).collect();
        let total = void.iter().filter(|&&v| v).count();
        if total == 0 {
            return Ok(0);
        }
        if total == h * w {
            return Err(Self::all_void_error());
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
                let (mut s, mut k) = (vec![0.0; c], 0);
                for j in neighbours(i) {
                    if j != usize::MAX && !void[j] {
                        for (ch, acc) in s.iter_mut().enumerate() {
                            *acc += data[j * c + ch];
                        }
                        k += 1;
                    }
                }
                if k > 0 {
                    front.push((i, s.iter().map(|v| v / k as f64).collect::<Vec<_>>()));
                }
            }
            for (i, v) in front {
                data[i * c..(i + 1) * c].copy_from_slice(&v);
                void[i] = false;
                left -= 1;
            }
        }
        for _ in 0..SWEEPS {
            for &i in &holes {
                for ch in 0..c {
                    let (mut s, mut k) = (0.0, 0.0);
                    for j in neighbours(i) {
                        if j != usize::MAX {
                            s += data[j * c + ch];
                            k += 1.0;
                        }
                    }
                    data[i * c + ch] = s / k;
                }
            }
        }
        Ok(total)
    }

    /// The void flags of a new grid: `shape` is the old row-major shape (spatial axes
    /// first, then any non-spatial ones, e.g. channels), `maps` place the new spatial
    /// axes of lengths `new_dims` on the old ones; a new sample is void when every old
    /// sample of its footprint is.
    pub fn footprint(&self, shape: &[usize], new_dims: &[usize], maps: &[AxisMap]) -> Vec<bool> {
        // propagate "valid" separably: valid_new[j] = any valid in the footprint of j
        let mut valid: Vec<bool> = self.mask.iter().map(|&v| !v).collect();
        let mut cur = shape.to_vec();
        for (a, &m) in new_dims.iter().enumerate() {
            let n = cur[a];
            let map = maps.get(a).copied().unwrap_or(AxisMap::IDENTITY);
            if n == m && map == AxisMap::IDENTITY {
                continue;
            }
            let cells: Vec<(usize, usize)> = (0..m)
                .map(|j| {
                    let x = map.offset + j as f64 * map.step;
                    let half = map.step / 2.0;
                    let nearest = (x.round().max(0.0) as usize).min(n - 1);
                    // old cells whose centre lies in [x − half, x + half]: every old cell
                    // falls in the footprint of the new cell covering its centre
                    let first = ((x - half - 1e-9).ceil().max(0.0) as usize).min(n - 1);
                    let last = ((x + half + 1e-9).floor().max(0.0) as usize).min(n - 1);
                    if last < first || x + half < 0.0 || x - half > n as f64 - 1.0 {
                        (nearest, nearest)
                    } else {
                        (first, last)
                    }
                })
                .collect();
            let outer: usize = cur[..a].iter().product();
            let inner: usize = cur[a + 1..].iter().product();
            let mut out = vec![false; outer * m * inner];
            for o in 0..outer {
                for (j, &(c0, c1)) in cells.iter().enumerate() {
                    let dst = (o * m + j) * inner;
                    for c in c0..=c1 {
                        let src = (o * n + c) * inner;
                        for k in 0..inner {
                            out[dst + k] |= valid[src + k];
                        }
                    }
                }
            }
            valid = out;
            cur[a] = m;
        }
        valid.into_iter().map(|v| !v).collect()
    }

    /// Write the marker where `void` is set; with `clamp`, every other sample is
    /// clamped into the valid input range `[lo, hi]` (for resamplings).
    pub fn restore<T: Value>(&self, out: &mut [T], void: &[bool], clamp: bool) {
        let (lo, hi) = self.range;
        let marker = T::from_f64(self.marker);
        for (v, &m) in out.iter_mut().zip(void) {
            if m {
                *v = marker;
            } else if clamp {
                let x = v.to_f64();
                if x.is_nan() {
                    *v = T::from_f64(lo);
                } else if x < lo || x > hi {
                    *v = T::from_f64(x.clamp(lo, hi));
                }
            }
        }
    }
}

/// Strides of a row-major shape.
fn strides(shape: &[usize]) -> Vec<usize> {
    (0..shape.len())
        .map(|a| shape[a + 1..].iter().product())
        .collect()
}

/// Index of the coarse cell holding fine sample `i`.
fn parent(i: usize, fs: &[usize], shape: &[usize], cstr: &[usize], spatial: usize) -> usize {
    (0..shape.len())
        .map(|a| {
            let x = i / fs[a] % shape[a];
            (if a < spatial { x / 2 } else { x }) * cstr[a]
        })
        .sum()
}

/// Sum pairs along each of the first `spatial` axes (lengths `⌈n/2⌉`).
fn pull(s: &[f64], w: &[f64], shape: &[usize], spatial: usize) -> (Vec<f64>, Vec<f64>, Vec<usize>) {
    let coarse: Vec<usize> = shape
        .iter()
        .enumerate()
        .map(|(a, &n)| if a < spatial { n.div_ceil(2) } else { n })
        .collect();
    let len: usize = coarse.iter().product();
    let (mut cs, mut cw) = (vec![0f64; len], vec![0f64; len]);
    let (fs, cstr) = (strides(shape), strides(&coarse));
    for (i, (&sv, &wv)) in s.iter().zip(w).enumerate() {
        let ci = parent(i, &fs, shape, &cstr, spatial);
        cs[ci] += sv;
        cw[ci] += wv;
    }
    (cs, cw, coarse)
}

/// Fill values where `w == 0` from the coarser levels; returns the filled values.
fn push_pull(s: Vec<f64>, w: Vec<f64>, shape: &[usize], spatial: usize) -> Vec<f64> {
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
                cv[parent(i, &fs, shape, &cstr, spatial)]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pull_push_fills_with_block_means() {
        // 1-D: a hole between 2 and 4 takes the mean of its first non-empty block
        let mut d = vec![2.0f32, f32::NAN, f32::NAN, 4.0];
        let v = Voids::find(&d, None).unwrap();
        v.fill(&mut d, &[4], 1).unwrap();
        assert_eq!(d, vec![2.0, 2.0, 4.0, 4.0]);
        let mut d = vec![1.0f64, -9.0, 5.0];
        let v = Voids::find(&d, Some(-9.0)).unwrap();
        assert_eq!(v.range, (1.0, 5.0));
        v.fill(&mut d, &[3], 1).unwrap();
        assert_eq!(d, vec![1.0, 1.0, 5.0]);
        let v = Voids::find(&[f32::NAN], None).unwrap();
        assert!(v.fill(&mut [0.0f32], &[1], 1).is_err());
        assert_eq!(Voids::find(&[1.0f32, 2.0], Some(-9.0)), None);
    }

    #[test]
    fn a_hole_in_a_plane_is_filled_with_the_plane_by_the_membrane() {
        let want: Vec<f64> = (0..64)
            .map(|i| (i / 8) as f64 + 2.0 * (i % 8) as f64)
            .collect();
        let mut g = want.clone();
        for &(y, x) in &[(3, 3), (3, 4), (4, 3), (4, 4), (5, 4)] {
            g[y * 8 + x] = -32768.0;
        }
        let v = Voids::find(&g, Some(-32768.0)).unwrap();
        assert_eq!(v.fill_membrane(&mut g, 8, 8, 1).unwrap(), 5);
        for (a, b) in g.iter().zip(&want) {
            assert!((a - b).abs() < 0.05, "{a} vs {b}");
        }
    }

    #[test]
    fn footprint_is_void_only_when_every_cell_under_it_is() {
        let v = Voids::find(&[1.0f32, f32::NAN, f32::NAN, f32::NAN, 5.0, 6.0], None).unwrap();
        // halving: cells (0,1) (2,3) (4,5)
        let m = v.footprint(&[6], &[3], &[AxisMap::centred(6, 3)]);
        assert_eq!(m, vec![false, true, false]);
        // doubling: each new sample has its nearest old cell
        let v = Voids::find(&[1.0f32, f32::NAN, 3.0], None).unwrap();
        let m = v.footprint(&[3], &[6], &[AxisMap::centred(3, 6)]);
        assert_eq!(m, vec![false, false, true, true, false, false]);
    }

    #[test]
    fn restore_marks_voids_and_clamps_the_rest_into_the_valid_range() {
        let v = Voids::find(&[10.0f64, -32768.0, 20.0], Some(-32768.0)).unwrap();
        let mut out = vec![5.0f64, 0.0, 25.0, 15.0];
        v.restore(&mut out, &[false, true, false, false], true);
        assert_eq!(out, vec![10.0, -32768.0, 20.0, 15.0]);
    }
}
