//! A small dense grid of `h × w` positions with `c` interleaved channels, in f64: the
//! working form of heightmaps and images inside the terrain module, held as the engine's
//! [`Array`] (shape `[h, w]`, or `[h, w, c]` when `c > 1`), so that it goes to the
//! transforms and back by move.

use rayon::prelude::*;

use crate::tensor::Array;
use crate::{Error, Result};

/// The sample accessors of a type that holds its samples as `values: Array<f64>`
/// (row-major, channels last): `data`, `data_mut`, `into_data`.
macro_rules! samples_access {
    () => {
        /// The samples, row-major, channels last.
        #[inline]
        pub fn data(&self) -> &[f64] {
            self.values.data()
        }

        /// The samples, mutable.
        #[inline]
        pub fn data_mut(&mut self) -> &mut [f64] {
            self.values.data_mut()
        }

        /// The samples by move.
        pub fn into_data(self) -> Vec<f64> {
            self.values.into_data()
        }
    };
}
pub(super) use samples_access;

/// `h × w × c` samples, row-major, channels last.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    values: Array<f64>,
}

/// The engine's shape of an `h × w × c` grid: `[h, w]` or `[h, w, c]`.
fn shape(h: usize, w: usize, c: usize) -> Vec<usize> {
    if c == 1 {
        vec![h, w]
    } else {
        vec![h, w, c]
    }
}

impl Grid {
    /// Zeros of the given size.
    pub fn zeros(h: usize, w: usize, c: usize) -> Grid {
        Grid {
            values: Array::zeros(&shape(h, w, c)),
        }
    }

    /// Wrap `data`; errors when the length is not `h·w·c` or a size is zero.
    pub fn new(h: usize, w: usize, c: usize, data: Vec<f64>) -> Result<Grid> {
        if h == 0 || w == 0 || c == 0 || data.len() != h * w * c {
            return Err(Error::parameter(
                "grid data length",
                data.len(),
                "h × w × channels, all non-zero",
            ));
        }
        Ok(Grid {
            values: Array::from_shape_vec(&shape(h, w, c), data)?,
        })
    }

    /// Rows.
    #[inline]
    pub fn h(&self) -> usize {
        self.values.shape()[0]
    }

    /// Columns.
    #[inline]
    pub fn w(&self) -> usize {
        self.values.shape()[1]
    }

    /// Channels.
    #[inline]
    pub fn c(&self) -> usize {
        self.values.shape().get(2).copied().unwrap_or(1)
    }

    samples_access!();

    #[inline]
    pub fn at(&self, y: usize, x: usize, k: usize) -> f64 {
        let (w, c) = (self.w(), self.c());
        self.data()[(y * w + x) * c + k]
    }

    #[inline]
    pub fn at_mut(&mut self, y: usize, x: usize, k: usize) -> &mut f64 {
        let (w, c) = (self.w(), self.c());
        &mut self.data_mut()[(y * w + x) * c + k]
    }

    /// Mean over channels at a position (the "height" used for matching).
    #[inline]
    pub fn mean_at(&self, y: usize, x: usize) -> f64 {
        let c = self.c();
        let o = (y * self.w() + x) * c;
        self.data()[o..o + c].iter().sum::<f64>() / c as f64
    }

    /// The top-left `h × w` block.
    pub fn crop(&self, h: usize, w: usize) -> Grid {
        let (sw, c) = (self.w(), self.c());
        let mut g = Grid::zeros(h, w, c);
        let src = self.data();
        for (y, row) in g.data_mut().chunks_exact_mut(w * c).enumerate() {
            row.copy_from_slice(&src[y * sw * c..(y * sw + w) * c]);
        }
        g
    }

    /// Copy `src` into the top-left corner.
    pub fn paste(&mut self, src: &Grid) {
        let (w, c, sw) = (self.w(), self.c(), src.w());
        let s = src.data();
        let d = self.data_mut();
        for y in 0..src.h() {
            d[y * w * c..(y * w + sw) * c].copy_from_slice(&s[y * sw * c..(y + 1) * sw * c]);
        }
    }

    /// The engine's array (a copy): `[h, w]` or `[h, w, c]`, with the spatial axes to transform.
    pub fn to_array(&self) -> Result<(Array<f64>, Vec<usize>)> {
        Ok((self.values.clone(), vec![0, 1]))
    }

    /// The engine's array by move (no copy): `[h, w]` or `[h, w, c]`.
    pub fn into_array(self) -> Array<f64> {
        self.values
    }

    /// The engine's array, borrowed.
    pub fn array(&self) -> &Array<f64> {
        &self.values
    }

    /// A grid from the engine's array of shape `[h, w]` or `[h, w, c]` (by move); errors on
    /// another rank or an empty side.
    pub fn from_array(values: Array<f64>) -> Result<Grid> {
        let s = values.shape();
        if !(s.len() == 2 || s.len() == 3) || s.contains(&0) || (s.len() == 3 && s[2] == 1) {
            return Err(Error::parameter(
                "grid shape",
                format!("{s:?}"),
                "[h, w] or [h, w, c] with c > 1, all non-zero",
            ));
        }
        Ok(Grid { values })
    }

    /// `(min, max)` over all samples.
    pub fn range(&self) -> (f64, f64) {
        self.data()
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| {
                (l.min(v), u.max(v))
            })
    }
}

/// Means of the `f_y × f_x` blocks of `g` (`n_y·f_y × n_x·f_x`).
pub fn block_means(g: &Grid, n_y: usize, n_x: usize, (f_y, f_x): (usize, usize)) -> Grid {
    let c = g.c();
    let inv = 1.0 / (f_y * f_x) as f64;
    let mut out = Grid::zeros(n_y, n_x, c);
    out.data_mut()
        .par_chunks_mut(n_x * c)
        .enumerate()
        .for_each(|(by, orow)| {
            for y in by * f_y..(by + 1) * f_y {
                let row = &g.data()[y * g.w() * c..(y + 1) * g.w() * c];
                for (x, v) in row[..n_x * f_x * c].chunks_exact(c).enumerate() {
                    let o = &mut orow[(x / f_x) * c..(x / f_x + 1) * c];
                    o.iter_mut().zip(v).for_each(|(o, v)| *o += v * inv);
                }
            }
        });
    out
}

/// PSNR (dB) of `g` against `reference` (the same size), the reference's range as peak:
/// `10 log₁₀(range² / mean (g − r)²)`.
pub fn psnr(g: &Grid, reference: &Grid) -> f64 {
    let (lo, hi) = reference.range();
    let mse = g
        .data()
        .iter()
        .zip(reference.data())
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / reference.data().len() as f64;
    10.0 * ((hi - lo).max(1e-12).powi(2) / mse.max(1e-300)).log10()
}
