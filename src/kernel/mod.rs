//! How rows are combined on this machine: the inner loops every transform ends in,
//! written over whole runs of samples so they vectorise, with AVX2 (with FMA) and
//! AVX-512 builds beside the plain loops.
//!
//! Every build and every path gives the same bits: each output sums its row's taps as
//! [`pair_taps`] and [`sum_terms`] say (`scheme::sparse` states the order; this module
//! only decides how fast it runs). The build is a [`Kernels`] table, chosen once per
//! plan from a [`CpuLevel`] and passed to every entry; the tests run every level the CPU
//! has and compare it with [`CpuLevel::Scalar`].
//!
//! - `combine.rs`: one row, `out = Σ_k w_k · src_k`, and an operator's rows in one call;
//! - `pair.rs`: two rows over the inputs they share, in one pass (the regular rows);
//! - `lanes.rs`, `edge.rs`: the boundary rows, many short lanes or 8 rows at a time;
//! - `layout.rs`: even/odd splits and merges, transposes, streaming stores;
//! - `polyphase.rs`: an operator cut into regular runs and boundary rows, applied;
//! - `scalar.rs`: the plain loops; `x86/`: the AVX2 and AVX-512 builds.

use crate::scheme::sparse::{Csr, Term};
use crate::scheme::Sample;

pub use crate::scheme::sparse::{pair_taps, row_sum, sum_terms, SECOND};
pub use crate::tuning::CpuLevel;

#[macro_use]
mod patterns;
mod combine;
mod edge;
mod lanes;
mod layout;
mod pair;
pub mod polyphase;
mod scalar;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use combine::*;
pub use edge::*;
pub use lanes::*;
pub use layout::*;
pub use pair::*;
pub(crate) use scalar::*;
#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{avx2::*, pair::*};

/// The kernel table of one plan: the build every kernel entry runs, fixed when the plan
/// is made (from a [`CpuLevel`] it is given: `tuning` caps the process's level with
/// `MRA_CPU` in [`CpuLevel::detected`], read only where a plan is made) and passed down
/// to every call. Each entry dispatches on it once, at its top; every build gives the
/// same bits, so the table changes speed only.
///
/// A table never holds a build the CPU does not run: [`Kernels::new`] caps the level at
/// [`CpuLevel::widest`], which is what makes the vector builds' `unsafe` calls sound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Kernels {
    level: CpuLevel,
}

impl Kernels {
    /// The table of `level`, capped at what this CPU runs.
    pub fn new(level: CpuLevel) -> Kernels {
        Kernels {
            level: level.min(CpuLevel::widest()),
        }
    }

    /// The table of the plain loops (every CPU).
    pub const fn scalar() -> Kernels {
        Kernels {
            level: CpuLevel::Scalar,
        }
    }

    /// The table of [`CpuLevel::detected`] (the widest build, capped by `tuning`): for a
    /// plan made without a level of its own.
    pub fn detected() -> Kernels {
        Kernels::new(CpuLevel::detected())
    }

    /// The build of every entry.
    pub fn level(self) -> CpuLevel {
        self.level
    }

    /// Whether the AVX2 build (or a wider one) runs.
    #[inline]
    pub fn avx2(self) -> bool {
        self.level >= CpuLevel::Avx2
    }

    /// Whether the combines run their AVX-512 build.
    #[inline]
    pub fn avx512(self) -> bool {
        self.level == CpuLevel::Avx512
    }
}

/// `dst_r = Σ w · src_c` for every row `r` of `op`; element `e` of `src` is
/// `src[e*src_stride .. e*src_stride + width]`, likewise for `dst`: [`Csr::apply`] in
/// the build of `k` (the same bits).
pub fn apply<T: Sample>(
    k: Kernels,
    op: &Csr,
    src: &[T],
    src_stride: usize,
    dst: &mut [T],
    dst_stride: usize,
    width: usize,
) {
    assert!(op.cols() == 0 || (op.cols() - 1) * src_stride + width <= src.len());
    assert!(op.rows() == 0 || (op.rows() - 1) * dst_stride + width <= dst.len());
    let lanes = RawLanes {
        src: src.as_ptr(),
        src_stride,
        dst: dst.as_mut_ptr(),
        dst_stride,
        width,
    };
    // SAFETY: the asserts bound every element read and written; `src` and `dst` are
    // distinct borrows.
    unsafe { apply_raw(k, op, lanes) }
}

/// Lanes of a raw array for [`apply_raw`]: element `e` of the source is
/// `src + e·src_stride .. + width`, likewise for the destination.
#[derive(Debug)]
pub struct RawLanes<T> {
    pub src: *const T,
    pub src_stride: usize,
    pub dst: *mut T,
    pub dst_stride: usize,
    pub width: usize,
}

impl<T> Clone for RawLanes<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for RawLanes<T> {}

/// [`apply`] on raw element pointers, for lanes that live inside a larger array other
/// threads are writing elsewhere. Only the elements this call reads
/// (`src + c·src_stride .. + width` for the columns it uses) and writes
/// (`dst + r·dst_stride .. + width`) are turned into slices.
///
/// # Safety
/// Every element read must be valid for reads and not written concurrently, every
/// element written must be valid for writes and touched by no other thread, and the
/// two sets must not overlap.
#[inline]
pub unsafe fn apply_raw<T: Sample>(k: Kernels, op: &Csr, lanes: RawLanes<T>) {
    #[cfg(target_arch = "x86_64")]
    if k.avx2() {
        // SAFETY: AVX2 with FMA is present (a table holds no build the CPU lacks); the
        // caller's guarantees pass through.
        return unsafe { apply_avx2(op, lanes) };
    }
    // SAFETY: the caller's guarantees.
    unsafe { apply_scalar(op, lanes) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edge groups of the schemes' lanes pick their inputs from registers (a window
    /// of at most 4 vectors), with the bits of the gathered inputs.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn edge_windows_give_the_bits_of_gathers() {
        use crate::kernel::polyphase::Polyphase;
        use crate::scheme::{Boundary, Scheme, TwoScale};
        let k = Kernels::detected();
        if !k.avx2() {
            return;
        }
        let mut windows = 0;
        for scheme in [Scheme::Haar, Scheme::Chaikin, Scheme::Cubic] {
            for boundary in [
                Boundary::Interpolating,
                Boundary::Periodic,
                Boundary::Symmetric,
            ] {
                for m in [8, 9, 16, 33, 64, 101] {
                    let t = TwoScale::new(scheme, boundary, m);
                    for op in [&t.analysis, &t.synthesis] {
                        let p = Polyphase::new(op, k);
                        let x: Vec<f32> = (0..m)
                            .map(|i| ((i * 37 % 23) as f32 - 11.0) / 7.0)
                            .collect();
                        let mut gathered = p.edges.clone();
                        for g in &mut gathered {
                            windows += usize::from(g.window.is_some() && !g.steps.is_empty());
                            g.window = None;
                        }
                        let (mut y1, mut y2) = (vec![0f32; m], vec![0f32; m]);
                        assert!(edge_rows(k, &p.edges, &x, &mut y1));
                        assert!(edge_rows(k, &gathered, &x, &mut y2));
                        let bits = |y: &[f32]| y.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&y1), bits(&y2), "{scheme:?} {boundary:?} {m}");
                    }
                }
            }
        }
        assert!(windows > 0, "no edge group picks from registers");
    }

    /// The memo answers what [`pair_entry`] answers, also when a pair with the same
    /// inputs and masks but other weights (or unit taps) comes between.
    #[test]
    fn pair_memo_follows_the_weights() {
        // cubic's analysis pair (coarse `a` with its centre of weight 1, detail `b`)
        let a = [0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125];
        let b = [0.0, 0.0, -0.125, 0.5, -0.75, 0.5, -0.125];
        // the same masks, weights without pairs or unit taps
        let c = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7];
        let d = [0.0, 0.0, 0.8, 0.9, 1.1, 1.2, 1.3];
        let (m1, m2) = (0b1111111, 0b1111100);
        let mut memo = PairMemo::<f32>::default();
        for (w1, w2) in [(a, b), (c, d), (c, d), (a, b), (a, b), (c, d)] {
            let (w1, w2) = (w1.map(|x| x as f32), w2.map(|x| x as f32));
            let want = pair_entry(&w1, m1, &w2, m2);
            assert_eq!(memo.entry(&w1, m1, &w2, m2), want);
        }
        #[cfg(target_arch = "x86_64")]
        {
            let (w1, w2) = (a.map(|x| x as f32), b.map(|x| x as f32));
            let (v1, v2) = (c.map(|x| x as f32), d.map(|x| x as f32));
            // both have builds, and different ones
            let (e1, e2) = (pair_entry(&w1, m1, &w2, m2), pair_entry(&v1, m1, &v2, m2));
            assert!(e1.is_some() && e2.is_some() && e1 != e2);
        }
    }
}
