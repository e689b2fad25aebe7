//! Raster walk of a band shared by the coefficient coders: rows, planes, the parent's
//! matching plane and the median predictor of the coarsest block.

/// Geometry of a band walked in raster order: `(planes, rows, cols)` with the plane
/// index split into the outer axes.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    pub planes: usize,
    pub rows: usize,
    pub cols: usize,
    /// extent of the third-last axis (for the Z neighbour), 0 when absent
    pub zdim: usize,
}

impl Walk {
    pub fn new(dims: &[usize]) -> Self {
        let nd = dims.len();
        let cols = if nd >= 1 { dims[nd - 1] } else { 1 };
        let rows = if nd >= 2 { dims[nd - 2] } else { 1 };
        let planes = if nd >= 3 {
            dims[..nd - 2].iter().product()
        } else {
            1
        };
        Walk {
            planes,
            rows,
            cols,
            zdim: if nd >= 3 { dims[nd - 3] } else { 0 },
        }
    }
}

/// Offset of the parent plane of child plane `p` (outer axes halved and clamped).
pub fn parent_plane(p: usize, dims: &[usize], pdims: &[usize]) -> usize {
    let nd = dims.len();
    if nd < 3 {
        return 0;
    }
    let mut rem = p;
    let mut coords = vec![0usize; nd - 2];
    for k in (0..nd - 2).rev() {
        coords[k] = rem % dims[k];
        rem /= dims[k];
    }
    let mut off = 0;
    for k in 0..nd - 2 {
        off = off * pdims[k] + (coords[k] / 2).min(pdims[k].saturating_sub(1));
    }
    off
}

/// LOCO-I median predictor `med(W, N, W + N − NW)` of sample `i` at `(y, x)` of a
/// plane with `cols` columns (W falls back to N in column 0, N to W in row 0).
pub fn med(v: &[i64], i: usize, y: usize, x: usize, cols: usize) -> i64 {
    let w = if x > 0 {
        v[i - 1]
    } else if y > 0 {
        v[i - cols]
    } else {
        0
    };
    let n = if y > 0 { v[i - cols] } else { w };
    let nw = if x > 0 && y > 0 { v[i - cols - 1] } else { n };
    let (lo, hi) = if w < n { (w, n) } else { (n, w) };
    if nw >= hi {
        lo
    } else if nw <= lo {
        hi
    } else {
        (w as i128 + n as i128 - nw as i128) as i64
    }
}

/// Residuals of the median predictor over every plane of a band.
pub fn median_residuals(q: &[i64], w: Walk) -> Vec<i64> {
    let mut r = vec![0i64; q.len()];
    for p in 0..w.planes {
        for y in 0..w.rows {
            for x in 0..w.cols {
                let i = (p * w.rows + y) * w.cols + x;
                r[i] = q[i].wrapping_sub(med(q, i, y, x, w.cols));
            }
        }
    }
    r
}

/// Invert [`median_residuals`] in place.
pub fn undo_median(v: &mut [i64], w: Walk) {
    for p in 0..w.planes {
        for y in 0..w.rows {
            for x in 0..w.cols {
                let i = (p * w.rows + y) * w.cols + x;
                v[i] = v[i].wrapping_add(med(v, i, y, x, w.cols));
            }
        }
    }
}
