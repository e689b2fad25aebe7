//! The only place that hands out mutable access to one array from several threads.

use rayon::prelude::*;

/// `width` columns cut into `count` strips of `max` columns (the last one narrower).
#[derive(Clone, Copy)]
pub(crate) struct Strips {
    pub count: usize,
    pub max: usize,
    width: usize,
}

impl Strips {
    /// Strips of at most `target` columns, of even widths.
    pub(crate) fn new(width: usize, target: usize) -> Self {
        Strips::of(width, width.div_ceil(target))
    }

    /// `width` cut into `count` strips of even widths.
    pub(crate) fn of(width: usize, count: usize) -> Self {
        Strips {
            count,
            max: width.div_ceil(count),
            width,
        }
    }

    /// Strip `s`: its first column and its width.
    #[inline]
    pub(crate) fn get(self, s: usize) -> (usize, usize) {
        let off = s * self.max;
        (off, self.max.min(self.width - off))
    }
}

/// A raw pointer to an array that tasks write at disjoint places.
#[derive(Clone, Copy)]
pub(crate) struct SharedMut<T>(pub *mut T);

// SAFETY: every user of SharedMut writes only elements no other task touches (lanes and
// strips of one transform are disjoint); see `transform.rs`.
unsafe impl<T: Send> Send for SharedMut<T> {}
unsafe impl<T: Send> Sync for SharedMut<T> {}

impl<T> SharedMut<T> {
    /// Store `v` at index `i` of the array.
    ///
    /// # Safety
    /// `i` inside the array, and no other task reads or writes index `i` meanwhile.
    #[inline]
    #[cfg_attr(not(feature = "geometry"), allow(dead_code))]
    pub(crate) unsafe fn write(&self, i: usize, v: T) {
        // SAFETY: the caller's guarantees.
        unsafe { *self.0.add(i) = v }
    }
}

/// Run `task(i, &mut scratch)` for `i in 0..count` on rayon's pool, one scratch buffer
/// per worker (allocated once, not per task). Small jobs run on the calling thread.
pub(crate) fn for_each_task<S: Send, F, I>(count: usize, work_per_task: usize, init: I, task: F)
where
    I: Fn() -> S + Sync + Send,
    F: Fn(usize, &mut S) + Sync + Send,
{
    if count <= 1 || count * work_per_task < 1 << 15 {
        let mut s = init();
        for i in 0..count {
            task(i, &mut s);
        }
    } else {
        (0..count)
            .into_par_iter()
            .for_each_init(init, |s, i| task(i, s));
    }
}

/// Run `task(&items[part], &mut scratch)` for each of `parts` (consecutive ranges of
/// `items`) on rayon's pool, one scratch per worker; all of `items` as one part on the
/// calling thread when `serial`.
pub(crate) fn for_each_part<S: Send, F, I>(
    items: &[usize],
    parts: &[std::ops::Range<usize>],
    serial: bool,
    init: I,
    task: F,
) where
    I: Fn() -> S + Sync + Send,
    F: Fn(&[usize], &mut S) + Sync + Send,
{
    if serial || parts.len() <= 1 {
        let mut s = init();
        task(items, &mut s);
    } else {
        parts
            .par_iter()
            .for_each_init(init, |s, part| task(&items[part.clone()], s));
    }
}
