//! What pyramids reuse between levels and between calls, owned by a [`Planner`]: the
//! assembled operators of a lane length (with their regular/boundary split) and one
//! scratch array per sample type.
//!
//! The scratch array is what makes a level out of place (read every sample once, write
//! it once): a transform holds at most the array plus one array of the same size, the
//! engine's memory bound of 2×. After a call the scratch is kept for the next one (its
//! pages are already mapped, which on a 64 MB array saves as much time as a level takes);
//! dropping the planner, or [`Planner::clear`], returns it to the allocator.
//!
//! A library user who wants that memory back, or several independent caches, creates a
//! [`Planner`] and passes it (`pyramid::analyze_in`, `synthesize_in`). The functions
//! without a planner use [`Planner::shared`], one instance for the process (what the
//! command line uses); [`Planner::clear`] empties it.

use super::fused::pair_parts;
use crate::kernel::polyphase::Polyphase;
use crate::kernel::{CpuLevel, Kernels};
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

/// The operators and the scratch arrays that transforms reuse (see the module's
/// documentation), and the CPU level whose kernel table ([`Kernels`]) every plan it
/// makes runs. Results never depend on it: a fresh planner and a warm one, and every
/// level, give the same bits.
#[derive(Default)]
pub struct Planner {
    levels: Mutex<Option<HashMap<Key, Arc<LevelOps>>>>,
    scratch: Mutex<Vec<Box<dyn Any + Send>>>,
    /// `None`: [`CpuLevel::detected`] (the widest build, capped by `tuning`).
    cpu: Option<CpuLevel>,
}

impl Planner {
    /// An empty planner (nothing cached, nothing allocated) whose plans run the kernels
    /// of [`CpuLevel::detected`].
    pub const fn new() -> Planner {
        Planner {
            levels: Mutex::new(None),
            scratch: Mutex::new(Vec::new()),
            cpu: None,
        }
    }

    /// An empty planner whose plans run the kernels of `level` (capped at what the CPU
    /// runs): the same bits at every level, the speed of that build.
    pub const fn with_cpu(level: CpuLevel) -> Planner {
        Planner {
            levels: Mutex::new(None),
            scratch: Mutex::new(Vec::new()),
            cpu: Some(level),
        }
    }

    /// The kernel table of this planner's plans, chosen from its CPU level.
    pub fn kernels(&self) -> Kernels {
        Kernels::new(self.cpu.unwrap_or_else(CpuLevel::detected))
    }

    /// The planner of the functions that take none, one for the process.
    pub fn shared() -> &'static Planner {
        static SHARED: Planner = Planner::new();
        &SHARED
    }

    /// The level of `scheme`/`boundary` for lanes of `m` elements (built once, then
    /// shared).
    pub fn level_ops(&self, scheme: Scheme, boundary: Boundary, m: usize) -> Arc<LevelOps> {
        let key = (scheme, boundary, m);
        if let Some(l) = self
            .levels
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
            .and_then(|c| c.get(&key))
        {
            return l.clone();
        }
        let two_scale = TwoScale::new(scheme, boundary, m);
        let k = self.kernels();
        let analysis_order = order_by_first_column(&two_scale.analysis);
        let synthesis_order = order_by_first_column(&two_scale.synthesis);
        let l = Arc::new(LevelOps {
            analysis: Polyphase::new(&two_scale.analysis, k),
            synthesis: Polyphase::new(&two_scale.synthesis, k),
            analysis_parts: pair_parts(&analysis_order, &two_scale.analysis),
            synthesis_parts: pair_parts(&synthesis_order, &two_scale.synthesis),
            analysis_order,
            synthesis_order,
            two_scale,
        });
        let mut guard = self.levels.lock().unwrap_or_else(|e| e.into_inner());
        let cache = guard.get_or_insert_with(HashMap::new);
        if cache.len() >= MAX_CACHED {
            cache.clear();
        }
        cache.insert(key, l.clone());
        l
    }

    /// A scratch vector of exactly `len` samples (contents unspecified).
    pub fn take_scratch<T: Sample>(&self, len: usize) -> Vec<T> {
        let mut pool = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
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
    pub fn give_scratch<T: Sample>(&self, v: Vec<T>) {
        let mut pool = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
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
    pub fn clear(&self) {
        self.scratch
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
        *self.levels.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }

    /// Bytes of scratch arrays kept.
    pub fn scratch_bytes(&self) -> usize {
        let pool = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        pool.iter()
            .map(|b| {
                if let Some(v) = b.downcast_ref::<Vec<f32>>() {
                    v.capacity() * 4
                } else if let Some(v) = b.downcast_ref::<Vec<f64>>() {
                    v.capacity() * 8
                } else {
                    0
                }
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::super::fused::ROWS_PER_TASK;
    use super::*;
    use crate::kernel;
    use crate::scheme::sparse::Csr;

    #[test]
    fn a_planner_keeps_its_scratch_until_cleared() {
        let p = Planner::new();
        assert_eq!(p.scratch_bytes(), 0);
        let v: Vec<f32> = p.take_scratch(1000);
        assert_eq!(v.len(), 1000);
        p.give_scratch(v);
        assert!(p.scratch_bytes() >= 4000);
        let a = p.level_ops(Scheme::Cubic, Boundary::Symmetric, 64);
        let b = p.level_ops(Scheme::Cubic, Boundary::Symmetric, 64);
        assert!(Arc::ptr_eq(&a, &b), "the operators are built once");
        p.clear();
        assert_eq!(p.scratch_bytes(), 0);
        let c = p.level_ops(Scheme::Cubic, Boundary::Symmetric, 64);
        assert!(!Arc::ptr_eq(&a, &c), "clear drops the operators");
    }

    /// The pairs the task loop makes over `rows`: greedily, each row with the next when
    /// they pair.
    fn greedy_pairs(rows: &[usize], op: &Csr) -> Vec<(usize, usize)> {
        let (mut pairs, mut i) = (Vec::new(), 0);
        while i < rows.len() {
            if i + 1 < rows.len()
                && kernel::rows_pair(op.row_slices(rows[i]).0, op.row_slices(rows[i + 1]).0)
            {
                pairs.push((rows[i], rows[i + 1]));
                i += 2;
            } else {
                i += 1;
            }
        }
        pairs
    }

    #[test]
    fn parts_keep_every_pair_of_the_whole_order() {
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                for m in [5, 16, 64, 67, 130, 256] {
                    let o = Planner::new().level_ops(scheme, boundary, m);
                    for (op, order) in [
                        (&o.two_scale.analysis, &o.analysis_order),
                        (&o.two_scale.synthesis, &o.synthesis_order),
                    ] {
                        let parts = pair_parts(order, op);
                        // consecutive, covering, at most one row over the size
                        assert_eq!(parts.first().map(|p| p.start), Some(0));
                        assert_eq!(parts.last().map(|p| p.end), Some(order.len()));
                        for w in parts.windows(2) {
                            assert_eq!(w[0].end, w[1].start);
                        }
                        assert!(parts.iter().all(|p| p.len() <= ROWS_PER_TASK + 1));
                        let by_parts: Vec<_> = parts
                            .iter()
                            .flat_map(|p| greedy_pairs(&order[p.clone()], op))
                            .collect();
                        let whole = greedy_pairs(order, op);
                        assert_eq!(by_parts, whole, "{scheme:?} {boundary:?} {m}");
                        // the regular rows do pair: at most a few rows near the ends and
                        // the middle of the order are left alone
                        // (the order is tuned for filters of up to 7 taps; the wide schemes' rows
                        // pair less often in it, which costs time, not bits)
                        let reach = scheme.regular().map_or(0, |f| f.a.w.len().max(f.q.w.len()));
                        if m >= 64 && reach <= 7 {
                            assert!(2 * whole.len() + 12 >= m, "{scheme:?} {boundary:?} {m}");
                        }
                    }
                }
            }
        }
    }
}
