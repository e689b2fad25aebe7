//! Jobs handed to the thread pool a few at a time, so that the pool goes from one
//! slab's tiles to the next slab's without waiting while memory holds only the tiles
//! being coded.
//!
//! Every queued job could be handed to the pool at once (`rayon::spawn`), but a thread
//! of the pool that waits inside a job (a tile's bands coded in parallel) runs other
//! queued jobs meanwhile: with all the tiles of a slab queued, that stacks tile upon
//! tile, each with its pyramid in memory. A [`Feed`] keeps at most `limit` jobs
//! (one per thread) in the pool and hands over the next when one ends.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

/// A job of the feed.
pub(super) type Job = Box<dyn FnOnce() + Send + 'static>;

/// Jobs waiting for the pool, and how many are in it.
pub(super) struct Feed {
    state: Mutex<(VecDeque<Job>, usize)>,
    limit: usize,
}

impl Feed {
    /// A feed keeping one job per thread of the current pool in it.
    pub(super) fn new() -> Arc<Feed> {
        Arc::new(Feed {
            state: Mutex::new((VecDeque::new(), 0)),
            limit: rayon::current_num_threads().max(1),
        })
    }

    /// Queue `jobs` behind those already queued.
    pub(super) fn push(self: &Arc<Self>, jobs: impl IntoIterator<Item = Job>) {
        self.lock().0.extend(jobs);
        self.top_up();
    }

    /// A guard dropping the jobs still queued when it goes (the caller stopped early).
    pub(super) fn stop_on_drop(self: &Arc<Self>) -> StopOnDrop {
        StopOnDrop(self.clone())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, (VecDeque<Job>, usize)> {
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
pub(super) struct StopOnDrop(Arc<Feed>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        let jobs = std::mem::take(&mut self.0.lock().0);
        drop(jobs);
    }
}
