//! What pyramids reuse between levels and between calls: the assembled operators of a
//! lane length (with their regular/boundary split) and one scratch array.
//!
//! The scratch array is what makes a level out of place (read every sample once, write
//! it once): a transform holds at most the array plus one array of the same size, the
//! engine's memory bound of 2×. After a call the scratch is kept for the next one (its
//! pages are already mapped, which on a 64 MB array saves as much time as a level takes);
//! [`release`] returns it to the allocator.

use super::fused::pair_parts;
use crate::scheme::polyphase::Polyphase;
use crate::scheme::{Boundary, Sample, Scheme, TwoScale};
use std::any::Any;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// One level of one lane length, ready to apply.
pub struct LevelOps {
    pub two_scale: TwoScale,
    pub analysis: Polyphase,
    pub synthesis: Polyphase,
    /// Rows of each operator by increasing first column.
    pub analysis_order: Vec<usize>,
    pub synthesis_order: Vec<usize>,
    /// Those orders cut into the parts that the tasks of a fused level take
    /// (`fused::pair_parts`: about 16 rows each, never through a pair of rows).
    pub analysis_parts: Vec<std::ops::Range<usize>>,
    pub synthesis_parts: Vec<std::ops::Range<usize>>,
}

fn order_by_first_column(op: &crate::scheme::sparse::Csr) -> Vec<usize> {
    let mut rows: Vec<(usize, usize)> = (0..op.rows())
        .map(|r| (op.row(r).next().map_or(usize::MAX, |(c, _)| c), r))
        .collect();
    rows.sort_unstable();
    rows.into_iter().map(|(_, r)| r).collect()
}

type Key = (Scheme, Boundary, usize);

/// Operators kept; beyond this the cache starts over.
const MAX_CACHED: usize = 256;

static LEVELS: Mutex<Option<HashMap<Key, Arc<LevelOps>>>> = Mutex::new(None);

/// The level of `scheme`/`boundary` for lanes of `m` elements (built once, then shared).
pub fn level_ops(scheme: Scheme, boundary: Boundary, m: usize) -> Arc<LevelOps> {
    let key = (scheme, boundary, m);
    if let Some(l) = LEVELS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .as_ref()
        .and_then(|c| c.get(&key))
    {
        return l.clone();
    }
    let two_scale = TwoScale::new(scheme, boundary, m);
    let analysis_order = order_by_first_column(&two_scale.analysis);
    let synthesis_order = order_by_first_column(&two_scale.synthesis);
    let l = Arc::new(LevelOps {
        analysis: Polyphase::new(&two_scale.analysis),
        synthesis: Polyphase::new(&two_scale.synthesis),
        analysis_parts: pair_parts(&analysis_order, &two_scale.analysis),
        synthesis_parts: pair_parts(&synthesis_order, &two_scale.synthesis),
        analysis_order,
        synthesis_order,
        two_scale,
    });
    let mut guard = LEVELS.lock().unwrap_or_else(|e| e.into_inner());
    let cache = guard.get_or_insert_with(HashMap::new);
    if cache.len() >= MAX_CACHED {
        cache.clear();
    }
    cache.insert(key, l.clone());
    l
}

static SCRATCH: Mutex<Vec<Box<dyn Any + Send>>> = Mutex::new(Vec::new());

/// A scratch vector of exactly `len` samples (contents unspecified).
pub fn take_scratch<T: Sample>(len: usize) -> Vec<T> {
    let mut pool = SCRATCH.lock().unwrap_or_else(|e| e.into_inner());
    let found = pool.iter().position(|b| b.is::<Vec<T>>());
    let mut v: Vec<T> = match found {
        Some(i) => *pool
            .swap_remove(i)
            .downcast::<Vec<T>>()
            .expect("checked type"),
        None => Vec::new(),
    };
    drop(pool);
    if v.capacity() < len {
        // a fresh allocation: zeroed pages handed out lazily, 2 MB at a time where the
        // kernel allows (`pages`)
        v = super::pages::zeroed_vec(len);
    } else {
        v.resize(len, T::default());
    }
    v
}

/// Give a scratch vector back for the next call (the larger of two is kept).
pub fn give_scratch<T: Sample>(v: Vec<T>) {
    let mut pool = SCRATCH.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(i) = pool.iter().position(|b| b.is::<Vec<T>>()) {
        let keep_old = pool[i]
            .downcast_ref::<Vec<T>>()
            .is_some_and(|o| o.capacity() >= v.capacity());
        if keep_old {
            return;
        }
        pool.swap_remove(i);
    }
    pool.push(Box::new(v));
}

/// Free the kept scratch arrays and operators.
pub fn release() {
    SCRATCH.lock().unwrap_or_else(|e| e.into_inner()).clear();
    *LEVELS.lock().unwrap_or_else(|e| e.into_inner()) = None;
}
