//! A small dense grid of `h × w` positions with `c` interleaved channels, in f64: the
//! working form of heightmaps and images inside the terrain module.

use crate::tensor::Array;
use crate::{Error, Result};

/// `h × w × c` samples, row-major, channels last.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub h: usize,
    pub w: usize,
    pub c: usize,
    pub data: Vec<f64>,
}

impl Grid {
    /// Zeros of the given size.
    pub fn zeros(h: usize, w: usize, c: usize) -> Grid {
        Grid {
            h,
            w,
            c,
            data: vec![0.0; h * w * c],
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
        Ok(Grid { h, w, c, data })
    }

    #[inline]
    pub fn at(&self, y: usize, x: usize, k: usize) -> f64 {
        self.data[(y * self.w + x) * self.c + k]
    }

    #[inline]
    pub fn at_mut(&mut self, y: usize, x: usize, k: usize) -> &mut f64 {
        &mut self.data[(y * self.w + x) * self.c + k]
    }

    /// Mean over channels at a position (the "height" used for matching).
    #[inline]
    pub fn mean_at(&self, y: usize, x: usize) -> f64 {
        let o = (y * self.w + x) * self.c;
        self.data[o..o + self.c].iter().sum::<f64>() / self.c as f64
    }

    /// The top-left `h × w` block.
    pub fn crop(&self, h: usize, w: usize) -> Grid {
        let mut g = Grid::zeros(h, w, self.c);
        for y in 0..h {
            let src = &self.data[y * self.w * self.c..(y * self.w + w) * self.c];
            g.data[y * w * self.c..(y + 1) * w * self.c].copy_from_slice(src);
        }
        g
    }

    /// Copy `src` into the top-left corner.
    pub fn paste(&mut self, src: &Grid) {
        for y in 0..src.h {
            let d = &mut self.data[y * self.w * self.c..(y * self.w + src.w) * self.c];
            d.copy_from_slice(&src.data[y * src.w * src.c..(y + 1) * src.w * src.c]);
        }
    }

    /// The engine's array: `[h, w]` or `[h, w, c]`, with the spatial axes to transform.
    pub fn to_array(&self) -> Result<(Array<f64>, Vec<usize>)> {
        let shape = if self.c == 1 {
            vec![self.h, self.w]
        } else {
            vec![self.h, self.w, self.c]
        };
        Ok((
            Array::from_shape_vec(&shape, self.data.clone())?,
            vec![0, 1],
        ))
    }

    /// The engine's array by move (no copy): `[h, w]` or `[h, w, c]`.
    pub fn into_array(self) -> Result<Array<f64>> {
        let shape = if self.c == 1 {
            vec![self.h, self.w]
        } else {
            vec![self.h, self.w, self.c]
        };
        Array::from_shape_vec(&shape, self.data)
    }

    /// `(min, max)` over all samples.
    pub fn range(&self) -> (f64, f64) {
        self.data
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| {
                (l.min(v), u.max(v))
            })
    }
}
