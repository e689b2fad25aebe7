//! Scratch buffers that start on a page boundary.
//!
//! Where a buffer starts decides how its vectors meet cache lines and cache sets: the
//! allocator hands out blocks 16 bytes past a page (large blocks, mapped) or anywhere on
//! 16 bytes (reused heap), so a 32-byte load or store may cross a line every other time,
//! and where two planes a transpose reads and writes fall relative to each other changes
//! from run to run. The planes of [`super::fused`] (then transposed) start on page
//! boundaries, which measured faster. Measured and not kept: every scratch buffer on a page (slower,
//! loads then fall on the same place in a page as the stores of the same loop), and
//! buffers placed half a page apart (no change).

use crate::scheme::Sample;

/// Where every [`Aligned`] buffer starts: a multiple of this many bytes.
pub const ALIGN: usize = 4096;

/// `len` zeroed samples starting at a multiple of [`ALIGN`] bytes (a vector with room to
/// skip to the boundary).
pub struct Aligned<T> {
    buf: Vec<T>,
    skip: usize,
    len: usize,
}

impl<T: Sample> Aligned<T> {
    /// `len` zeroed samples wherever the allocator puts them.
    pub fn heap(len: usize) -> Self {
        Aligned {
            buf: vec![T::default(); len],
            skip: 0,
            len,
        }
    }

    /// `len` zeroed samples starting at a multiple of [`ALIGN`] bytes.
    pub fn zeroed(len: usize) -> Self {
        let size = std::mem::size_of::<T>();
        debug_assert!(size > 0 && ALIGN.is_multiple_of(size));
        if len == 0 {
            return Self::heap(0);
        }
        let buf = vec![T::default(); len + ALIGN / size];
        // samples are aligned to their size (f32, f64), which divides ALIGN
        let skip = (ALIGN - buf.as_ptr() as usize % ALIGN) % ALIGN / size;
        Aligned { buf, skip, len }
    }
}

impl<T> std::ops::Deref for Aligned<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.buf[self.skip..self.skip + self.len]
    }
}

impl<T> std::ops::DerefMut for Aligned<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        &mut self.buf[self.skip..self.skip + self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buffers_start_on_a_page() {
        for len in [0usize, 1, 5, 1000, 70_000] {
            let mut a = Aligned::<f32>::zeroed(len);
            assert_eq!(a.len(), len);
            assert!(a.iter().all(|&x| x == 0.0));
            if len > 0 {
                assert_eq!(a.as_ptr() as usize % ALIGN, 0);
                a[len - 1] = 1.0;
            }
            let b = Aligned::<f64>::zeroed(len);
            assert_eq!(b.len(), len);
            if len > 0 {
                assert_eq!(b.as_ptr() as usize % ALIGN, 0);
            }
        }
    }
}
