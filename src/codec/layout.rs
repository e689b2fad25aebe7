//! Moving blocks between a plane (row-major, extents `shape`) and a packed band.

use std::ops::Range;

/// Call `f(flat_offset, run_length, band_offset)` for every row of the block `ranges`
/// ([`crate::tensor::for_each_run`]).
pub use crate::tensor::for_each_run as rows;

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
