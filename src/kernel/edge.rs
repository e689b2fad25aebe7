//! Up to 8 boundary rows of one lane, one output sample each, at a time.

use super::*;

/// Most taps of a row in an [`EdgeGroup`].
pub const EDGE_SPAN: usize = 32;

/// Up to 8 rows `r0..r0 + n` of a sparse operator, one output sample each on a lane of
/// single samples (the rows near the ends of a long lane), computed 8 at once
/// ([`edge_rows`]) with the bits of one row at a time. Rows without pairs go sample by
/// sample: per sample read, the rows' weights and which rows start their sum there or
/// add to it. When some row pairs, step `s` takes instead the `s`-th term of every row's
/// [`sum_terms`] (its one or two inputs gathered, per row).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeGroup {
    pub r0: usize,
    pub n: usize,
    /// The largest sample the rows read.
    pub(crate) last: usize,
    /// Rows without pairs: per sample they read (`cols`, increasing), the rows' weights
    /// and which rows start their sum there or add to it (one broadcast per sample).
    pub(crate) cols: Vec<usize>,
    pub(crate) weights: Vec<[f32; 8]>,
    pub(crate) first: Vec<[u32; 8]>,
    pub(crate) add: Vec<[u32; 8]>,
    /// Rows with pairs: their terms, step by step (empty when no row pairs).
    pub(crate) steps: Vec<EdgeStep>,
    /// Rows with pairs whose inputs lie in at most 4 stretches of 8 samples (e.g. the
    /// first and the last samples of the lane): the starts of those stretches and their
    /// count; the steps then pick their inputs from those vectors in registers
    /// ([`EdgeStep::la`]) instead of gathering them from memory.
    pub(crate) window: Option<([usize; 4], usize)>,
}

/// One term of each of the 8 rows of an [`EdgeGroup`] (masks: all bits set where true).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct EdgeStep {
    /// The term's input, and its pair's second input (the first again for a single tap).
    pub(crate) a: [i32; 8],
    pub(crate) b: [i32; 8],
    /// `a` and `b` in [`EdgeGroup::window`]: `8·v + o` for sample `o` of vector `v`.
    pub(crate) la: [i32; 8],
    pub(crate) lb: [i32; 8],
    /// The term's weight (as `f32`).
    pub(crate) w: [f32; 8],
    /// The term is a pair (its input the sum of the two).
    pub(crate) paired: [u32; 8],
    /// The row's first term (assigns), a next single tap (adds `w·x`), a next pair (FMA).
    pub(crate) first: [u32; 8],
    pub(crate) single: [u32; 8],
    pub(crate) fused: [u32; 8],
}

impl EdgeGroup {
    /// The rows `r0..r0 + rows.len()` (at most 8), `rows[i]` the `(columns, weights)` of
    /// row `r0 + i`; `None` when a row has more than [`EDGE_SPAN`] taps or its columns do
    /// not increase, or when no row reads any.
    pub fn new(r0: usize, rows: &[(&[u32], &[f64])]) -> Option<EdgeGroup> {
        let n = rows.len();
        assert!((1..=8).contains(&n));
        if rows.iter().any(|(c, _)| c.windows(2).any(|p| p[0] >= p[1])) {
            return None;
        }
        let lo = rows.iter().filter_map(|(c, _)| c.first()).min();
        let hi = rows.iter().filter_map(|(c, _)| c.last()).max();
        let (lo, hi) = match (lo, hi) {
            (Some(&lo), Some(&hi)) => (lo as usize, hi as usize),
            _ => return None,
        };
        if rows.iter().any(|(c, _)| c.len() > EDGE_SPAN) || hi > i32::MAX as usize {
            return None;
        }
        let mut g = EdgeGroup {
            r0,
            n,
            last: hi,
            cols: Vec::new(),
            weights: Vec::new(),
            first: Vec::new(),
            add: Vec::new(),
            steps: Vec::new(),
            window: None,
        };
        let paired = rows.iter().any(|(_, ws)| {
            let wf: Vec<f32> = ws.iter().map(|&v| v as f32).collect();
            pair_taps(&wf, &mut vec![0; wf.len()])
        });
        if !paired {
            g.fill_samples(rows);
            return Some(g);
        }
        g.fill_steps(rows, lo);
        g.window = g.find_window();
        Some(g)
    }

    /// Rows without pairs: the union of their columns (increasing), and per column the
    /// rows' weights and whether the row starts its sum there or adds to it.
    fn fill_samples(&mut self, rows: &[(&[u32], &[f64])]) {
        let mut cols: Vec<usize> = rows
            .iter()
            .flat_map(|(c, _)| c.iter().map(|&c| c as usize))
            .collect();
        cols.sort_unstable();
        cols.dedup();
        let u = cols.len();
        (self.weights, self.first, self.add) =
            (vec![[0.0; 8]; u], vec![[0; 8]; u], vec![[0; 8]; u]);
        for (i, (cs, ws)) in rows.iter().enumerate() {
            for (k, (&c, &w)) in cs.iter().zip(ws.iter()).enumerate() {
                let j = cols.binary_search(&(c as usize)).expect("in the union");
                self.weights[j][i] = w as f32;
                if k == 0 {
                    self.first[j][i] = u32::MAX;
                } else {
                    self.add[j][i] = u32::MAX;
                }
            }
        }
        self.cols = cols;
    }

    /// Rows with pairs: step `s` holds the `s`-th term of every row's [`pair_taps`]
    /// terms (rows with fewer terms read sample `lo` with weight 0 there).
    fn fill_steps(&mut self, rows: &[(&[u32], &[f64])], lo: usize) {
        let empty = EdgeStep {
            a: [lo as i32; 8],
            b: [lo as i32; 8],
            la: [0; 8],
            lb: [0; 8],
            w: [0.0; 8],
            paired: [0; 8],
            first: [0; 8],
            single: [0; 8],
            fused: [0; 8],
        };
        for (i, (cs, ws)) in rows.iter().enumerate() {
            let wf: Vec<f32> = ws.iter().map(|&v| v as f32).collect();
            let mut partner = vec![0; wf.len()];
            pair_taps(&wf, &mut partner);
            let mut s = 0;
            for k in 0..wf.len() {
                let q = partner[k];
                if q == SECOND {
                    continue;
                }
                if self.steps.len() == s {
                    self.steps.push(empty.clone());
                }
                let st = &mut self.steps[s];
                st.a[i] = cs[k] as i32;
                st.b[i] = cs[k] as i32;
                if q != k {
                    st.b[i] = cs[q] as i32;
                    st.paired[i] = u32::MAX;
                }
                st.w[i] = wf[k];
                if s == 0 {
                    st.first[i] = u32::MAX;
                } else if q == k {
                    st.single[i] = u32::MAX;
                } else {
                    st.fused[i] = u32::MAX;
                }
                s += 1;
            }
        }
    }

    /// The stretches of 8 samples that hold the steps' inputs (from the last input
    /// down) when there are at most 4, with each step's inputs set as places in them
    /// ([`EdgeStep::la`], [`EdgeStep::lb`]); `None` otherwise.
    fn find_window(&mut self) -> Option<([usize; 4], usize)> {
        let n = self.n;
        let mut used: Vec<usize> = self
            .steps
            .iter()
            .flat_map(|st| st.a[..n].iter().chain(&st.b[..n]))
            .map(|&c| c as usize)
            .collect();
        used.sort_unstable_by(|x, y| y.cmp(x));
        let mut bases = Vec::new();
        for &c in &used {
            if !bases.iter().any(|&b| (b..b + 8).contains(&c)) {
                bases.push(c.saturating_sub(7));
            }
        }
        if !(1..=4).contains(&bases.len()) {
            return None;
        }
        let local = |c: i32| {
            let c = c as usize;
            let v = bases.iter().position(|&b| (b..b + 8).contains(&c));
            let v = v.expect("every input in a stretch");
            (8 * v + c - bases[v]) as i32
        };
        for st in &mut self.steps {
            for i in 0..8 {
                // (the lanes past `n` read input 0 of the first stretch)
                (st.la[i], st.lb[i]) = if i < n {
                    (local(st.a[i]), local(st.b[i]))
                } else {
                    (0, 0)
                };
            }
        }
        let mut starts = [0; 4];
        starts[..bases.len()].copy_from_slice(&bases);
        Some((starts, bases.len()))
    }
}

/// `y[r] = Σ_k w_rk · x[c_rk]` for the rows of every group (`y` and `x` one lane of
/// single samples), 8 rows at a time, when the build has it (AVX2, `f32`); `false`
/// (nothing written) otherwise.
pub fn edge_rows<T: Sample>(k: Kernels, groups: &[EdgeGroup], x: &[T], y: &mut [T]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if let (true, Some(px), Some(py)) = (
        k.avx2(),
        T::f32_ptr(x.as_ptr().cast_mut()),
        T::f32_ptr(y.as_mut_ptr()),
    ) {
        for g in groups {
            assert!(g.last < x.len() && g.r0 + g.n <= y.len());
        }
        // SAFETY: AVX2 is present (a table holds no build the CPU lacks); the samples are
        // f32; every group's samples and outputs lie inside `x` and `y` (asserted).
        unsafe { edge_rows_avx2_f32(groups, px.cast_const(), x.len(), py) };
        return true;
    }
    let _ = (k, groups, x, y);
    false
}
