//! The only place that hands out mutable access to one array from several threads, and
//! the only job queue and wait of the pool ([`Feed`], [`receive`]).

use rayon::prelude::*;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

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

/// A job of a [`Feed`].
pub(crate) type Job = Box<dyn FnOnce() + Send + 'static>;

/// Jobs handed to the thread pool a few at a time (the tiled codec's tiles), so that
/// the pool goes from one slab's tiles to the next slab's without waiting while memory
/// holds only the tiles being coded: the queued jobs and how many are in the pool.
///
/// Every queued job could be handed to the pool at once (`rayon::spawn`), but a thread
/// of the pool that waits inside a job (a tile's bands coded in parallel) runs other
/// queued jobs meanwhile: with all the tiles of a slab queued, that stacks tile upon
/// tile, each with its pyramid in memory. A feed keeps at most `limit` jobs (one per
/// thread) in the pool and hands over the next when one ends.
pub(crate) struct Feed {
    state: Mutex<(VecDeque<Job>, usize)>,
    limit: usize,
}

impl Feed {
    /// A feed keeping one job per thread of the current pool in it.
    pub(crate) fn new() -> Arc<Feed> {
        Arc::new(Feed {
            state: Mutex::new((VecDeque::new(), 0)),
            limit: rayon::current_num_threads().max(1),
        })
    }

    /// Queue `jobs` behind those already queued.
    pub(crate) fn push(self: &Arc<Self>, jobs: impl IntoIterator<Item = Job>) {
        self.lock().0.extend(jobs);
        self.top_up();
    }

    /// A guard dropping the jobs still queued when it goes (the caller stopped early).
    pub(crate) fn stop_on_drop(self: &Arc<Self>) -> StopOnDrop {
        StopOnDrop(self.clone())
    }

    fn lock(&self) -> MutexGuard<'_, (VecDeque<Job>, usize)> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Hand queued jobs to the pool while it holds fewer than `limit` of them.
    fn top_up(self: &Arc<Self>) {
        loop {
            let job = {
                let mut s = self.lock();
                if s.1 >= self.limit {
                    return;
                }
                let Some(job) = s.0.pop_front() else {
                    return;
                };
                s.1 += 1;
                job
            };
            let feed = self.clone();
            rayon::spawn(move || {
                job();
                feed.lock().1 -= 1;
                feed.top_up();
            });
        }
    }
}

/// Drops the queued jobs of a [`Feed`] when it goes (see [`Feed::stop_on_drop`]).
pub(crate) struct StopOnDrop(Arc<Feed>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        let jobs = std::mem::take(&mut self.0.lock().0);
        drop(jobs);
    }
}

/// The next message of `rx`, `None` when every sender is gone. On a thread of the pool
/// (a caller inside `ThreadPool::install`) the wait runs the pool's pending jobs, so that
/// the jobs it waits for run even when it is the pool's only thread.
pub(crate) fn receive<T>(rx: &std::sync::mpsc::Receiver<T>) -> Option<T> {
    use std::sync::mpsc::RecvTimeoutError;
    if rayon::current_thread_index().is_none() {
        return rx.recv().ok();
    }
    loop {
        match rx.try_recv() {
            Ok(v) => return Some(v),
            Err(std::sync::mpsc::TryRecvError::Disconnected) => return None,
            Err(std::sync::mpsc::TryRecvError::Empty) => {}
        }
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            match rx.recv_timeout(std::time::Duration::from_millis(1)) {
                Ok(v) => return Some(v),
                Err(RecvTimeoutError::Disconnected) => return None,
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
    }
}

/// `f()`, or `None` when it panics (a pool job whose panic must reach its waiter as an
/// error, not end the pool's thread).
pub(crate) fn caught<R>(f: impl FnOnce() -> R) -> Option<R> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).ok()
}
