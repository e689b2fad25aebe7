//! Moving blocks between a plane (row-major, extents `shape`) and a packed band.

use std::ops::Range;

/// Call `f(flat_offset, run_length, band_offset)` for every row of the block `ranges`.
pub fn rows(shape: &[usize], ranges: &[Range<usize>], mut f: impl FnMut(usize, usize, usize)) {
    let nd = shape.len();
    let last = ranges[nd - 1].clone();
    let run = last.len();
    if run == 0 || ranges.iter().any(|r| r.is_empty()) {
        return;
    }
    let mut strides = vec![1usize; nd];
    for k in (0..nd - 1).rev() {
        strides[k] = strides[k + 1] * shape[k + 1];
    }
    let mut idx: Vec<usize> = ranges[..nd - 1].iter().map(|r| r.start).collect();
    let mut band = 0;
    loop {
        let base: usize = idx.iter().zip(&strides).map(|(i, s)| i * s).sum::<usize>() + last.start;
        f(base, run, band);
        band += run;
        let mut k = nd - 1;
        loop {
            if k == 0 {
                return;
            }
            k -= 1;
            idx[k] += 1;
            if idx[k] < ranges[k].end {
                break;
            }
            idx[k] = ranges[k].start;
            if k == 0 {
                return;
            }
        }
    }
}

/// Copy the block `ranges` of `plane` out into a packed vector.
pub fn gather<T: Copy + Default>(plane: &[T], shape: &[usize], ranges: &[Range<usize>]) -> Vec<T> {
    let n: usize = ranges.iter().map(|r| r.len()).product();
    let mut out = vec![T::default(); n];
    rows(shape, ranges, |off, run, b| {
        out[b..b + run].copy_from_slice(&plane[off..off + run])
    });
    out
}

/// Copy a packed block back into `plane`.
pub fn scatter<T: Copy>(plane: &mut [T], shape: &[usize], ranges: &[Range<usize>], band: &[T]) {
    rows(shape, ranges, |off, run, b| {
        plane[off..off + run].copy_from_slice(&band[b..b + run])
    });
}

#[cfg(test)]
mod tests {
    #[test]
    fn gather_scatter_round_trip() {
        let shape = [3usize, 4, 5];
        let plane: Vec<u32> = (0..60).collect();
        let ranges = [1..3, 0..2, 2..5];
        let b = super::gather(&plane, &shape, &ranges);
        assert_eq!(b.len(), 12);
        assert_eq!(b[0], 20 + 2);
        let mut p2 = vec![0u32; 60];
        super::scatter(&mut p2, &shape, &ranges, &b);
        assert_eq!(p2[22], 22);
        assert_eq!(p2[59], 0);
    }
}
