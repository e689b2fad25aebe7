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

/// A coefficient type of the median predictor: `i64` (bands) or `i32` (code-blocks).
pub trait Coef: Copy + Ord + Default {
    fn wrapping_add(self, o: Self) -> Self;
    fn wrapping_sub(self, o: Self) -> Self;
    /// `a + b − c` without overflow: the caller knows the result lies between `a` and `b`.
    fn plane(a: Self, b: Self, c: Self) -> Self;
}

macro_rules! coef {
    ($($t:ty => $wide:ty),*) => {$(
        impl Coef for $t {
            #[inline(always)]
            fn wrapping_add(self, o: Self) -> Self {
                <$t>::wrapping_add(self, o)
            }
            #[inline(always)]
            fn wrapping_sub(self, o: Self) -> Self {
                <$t>::wrapping_sub(self, o)
            }
            #[inline(always)]
            fn plane(a: Self, b: Self, c: Self) -> Self {
                (a as $wide + b as $wide - c as $wide) as $t
            }
        }
    )*};
}
coef!(i64 => i128, i32 => i64);

/// LOCO-I median predictor `med(W, N, W + N − NW)` of sample `i` at `(y, x)` of a
/// plane with `cols` columns (W falls back to N in column 0, N to W in row 0); always
/// between W and N.
pub fn med<T: Coef>(v: &[T], i: usize, y: usize, x: usize, cols: usize) -> T {
    let w = if x > 0 {
        v[i - 1]
    } else if y > 0 {
        v[i - cols]
    } else {
        T::default()
    };
    let n = if y > 0 { v[i - cols] } else { w };
    let nw = if x > 0 && y > 0 { v[i - cols - 1] } else { n };
    let (lo, hi) = if w < n { (w, n) } else { (n, w) };
    if nw >= hi {
        lo
    } else if nw <= lo {
        hi
    } else {
        T::plane(w, n, nw)
    }
}

/// Residuals of the median predictor over every plane of a band.
pub fn median_residuals<T: Coef>(q: &[T], w: Walk) -> Vec<T> {
    let mut r = vec![T::default(); q.len()];
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
pub fn undo_median<T: Coef>(v: &mut [T], w: Walk) {
    for p in 0..w.planes {
        for y in 0..w.rows {
            for x in 0..w.cols {
                let i = (p * w.rows + y) * w.cols + x;
                v[i] = v[i].wrapping_add(med(v, i, y, x, w.cols));
            }
        }
    }
}

/// Whether the parent band of `dims` has values: as many axes, none empty, and the
/// product of its extents in values.
pub fn parent_fits<T>(data: &[T], pdims: &[usize], dims: &[usize]) -> bool {
    pdims.len() == dims.len()
        && pdims.iter().all(|&d| d > 0)
        && data.len() == pdims.iter().product::<usize>()
}

/// The class of `s` in the table `t` of [`classes`]: `t[s]` for `s < N`, else `above`.
#[inline(always)]
pub fn class_in<const N: usize>(t: &[u8; N], s: u64, above: usize) -> usize {
    if s < N as u64 {
        t[s as usize] as usize
    } else {
        above
    }
}

/// The class table `t[s]` of `s < N`: the number of `ends` (increasing, the last
/// value of each class) below `s`.
pub const fn classes<const N: usize>(ends: &[usize]) -> [u8; N] {
    let mut t = [0u8; N];
    let mut s = 0;
    while s < N {
        let mut c = 0;
        while c < ends.len() && s > ends[c] {
            c += 1;
        }
        t[s] = c as u8;
        s += 1;
    }
    t
}

/// Test data shared by the band coders' tests.
#[cfg(test)]
pub(crate) mod testing {
    /// The tests' linear congruential generator (Knuth's MMIX constants): `s` moved to
    /// its next state `6364136223846793005·s + 1442695040888963407 (mod 2^64)`.
    pub(crate) fn lcg(s: &mut u64) -> u64 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *s
    }

    /// `n` values, a third of them nonzero in `−spread..=spread`, from an LCG seeded by
    /// `seed`.
    pub(crate) fn sample(n: usize, seed: u64, spread: i64) -> Vec<i64> {
        let mut x = seed;
        (0..n)
            .map(|_| {
                lcg(&mut x);
                let r = (x >> 33) as i64;
                if r % 3 == 0 {
                    (r % (2 * spread + 1)) - spread
                } else {
                    0
                }
            })
            .collect()
    }

    /// A test band and its parent: `(dims, values, parent dims, parent values)`.
    pub(crate) type Band = (Vec<usize>, Vec<i64>, Vec<usize>, Vec<i64>);

    /// Band extents of 1 to 4 axes, single positions among them.
    pub(crate) fn shapes() -> [Vec<usize>; 6] {
        [
            vec![1usize],
            vec![7],
            vec![5, 9],
            vec![1, 1],
            vec![3, 4, 5],
            vec![2, 2, 3, 3],
        ]
    }

    /// Bands of 1 to 4 axes (single positions among them) with `i64::MIN` first and
    /// `i64::MAX` last, and their parents.
    pub(crate) fn bands() -> Vec<Band> {
        shapes()
            .into_iter()
            .map(|dims| {
                let n: usize = dims.iter().product();
                let mut q = sample(n, n as u64, 300);
                q[0] = i64::MIN;
                q[n - 1] = if n > 1 { i64::MAX } else { q[0] };
                let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
                let pq = sample(pdims.iter().product(), 9, 3);
                (dims, q, pdims, pq)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tables of the class ends give each value the class of the range it is in.
    #[test]
    fn class_tables_follow_their_ranges() {
        let t: [u8; 41] = classes(&[0, 2, 4, 8, 16]);
        let ranges = [(0, 0), (1, 2), (3, 4), (5, 8), (9, 16), (17, 40)];
        let u: [u8; 61] = classes(&[0, 1, 2, 3, 4, 6, 9, 14, 22, 35]);
        let more = [(5, 6), (7, 9), (10, 14), (15, 22), (23, 35), (36, 60)];
        let ranges_u: Vec<(usize, usize)> = (0..5).map(|i| (i, i)).chain(more).collect();
        for (table, ranges) in [(&t[..], &ranges[..]), (&u[..], &ranges_u[..])] {
            for (c, &(lo, hi)) in ranges.iter().enumerate() {
                assert!(table[lo..=hi].iter().all(|&v| v as usize == c), "{c}");
            }
            assert_eq!(ranges.last().map(|r| r.1 + 1), Some(table.len()));
        }
    }

    /// The median predictor of `i32` code-blocks is that of `i64` bands, and its
    /// residuals undo, at the extremes too.
    #[test]
    fn median_residuals_undo_in_both_widths() {
        let w = Walk::new(&[2, 3, 5]);
        let q: Vec<i64> = (0..30i64)
            .map(|i| match i % 7 {
                0 => i64::from(i32::MIN),
                3 => i64::from(i32::MAX),
                k => (i * 37 + k) % 101 - 50,
            })
            .collect();
        let q32: Vec<i32> = q.iter().map(|&v| v as i32).collect();
        let (r, r32) = (median_residuals(&q, w), median_residuals(&q32, w));
        for i in 0..30 {
            let (y, x) = ((i / 5) % 3, i % 5);
            assert_eq!(med(&q, i, y, x, 5), med(&q32, i, y, x, 5) as i64);
        }
        let (mut back, mut back32) = (r.clone(), r32.clone());
        undo_median(&mut back, w);
        undo_median(&mut back32, w);
        assert_eq!(back, q);
        assert_eq!(back32, q32);
    }
}
