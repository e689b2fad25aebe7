//! The ring of rows a level of the cascade holds (`cascade.rs`): a few rows of the level
//! below, in the caches, instead of the whole level in the array.

use crate::scheme::Sample;

/// Samples between the slots of a ring: rows of a power-of-two length one after another
/// would put the same column of every slot in one L1 cache set (eight ways), and a combine
/// reads up to eight slots at once.
const RING_PAD: usize = 16;

/// A ring of rows: slots `0..coarse` for rows `< split`, the others for rows `≥ split`.
pub(super) struct Ring<T> {
    data: Vec<T>,
    row: usize,
    /// Samples from one slot to the next: a row and [`RING_PAD`].
    stride: usize,
    coarse: usize,
    detail: usize,
    split: usize,
    tags: Vec<usize>,
}

impl<T: Sample> Ring<T> {
    pub(super) fn new(row: usize, coarse: usize, detail: usize, split: usize) -> Self {
        let stride = row + RING_PAD;
        Ring {
            data: vec![T::default(); stride * (coarse + detail)],
            row,
            stride,
            coarse,
            detail,
            split,
            tags: vec![usize::MAX; coarse + detail],
        }
    }
    pub(super) fn slot_of(&self, c: usize) -> usize {
        if c < self.split {
            c % self.coarse
        } else {
            self.coarse + (c - self.split) % self.detail
        }
    }
    pub(super) fn has(&self, c: usize) -> bool {
        self.tags[self.slot_of(c)] == c
    }
    pub(super) fn get(&self, c: usize) -> &[T] {
        let s = self.slot_of(c);
        assert_eq!(self.tags[s], c, "cascade ring: row {c} is not held");
        &self.data[s * self.stride..s * self.stride + self.row]
    }
    /// The slot for row `c` (now holding it).
    pub(super) fn put(&mut self, c: usize) -> &mut [T] {
        let s = self.slot_of(c);
        self.tags[s] = c;
        &mut self.data[s * self.stride..s * self.stride + self.row]
    }
}
