//! Sparse two-scale operators and the one kernel that applies them.
//!
//! A level of a scheme is two square operators on a lane of `m` elements:
//! analysis `[A; B]` (rows `0..n` give the coarse `C = A F`, rows `n..m` the details
//! `D = B F`) and synthesis `[P | Q]` (fine row `i` is `F_i = Σ P_ij C_j + Σ Q_ij D_j`,
//! with `D_j` stored at packed position `n + j`). Both are stored row-wise (CSR), so
//! applying either is one gather pass: `out_r = Σ_k w_rk · in_{c_rk}`, where every
//! `in_c`/`out_r` is an element of `width` samples and the inner loop runs over the
//! element (whole rows vectorise).

use super::sample::Sample;

/// Row-compressed sparse matrix with `f64` weights (the filters are dyadic rationals,
/// exact in any float type except where a derived boundary weight is not).
#[derive(Clone, Debug, PartialEq)]
pub struct Csr {
    rows: usize,
    cols: usize,
    offsets: Vec<u32>,
    index: Vec<u32>,
    weight: Vec<f64>,
}

impl Csr {
    pub fn rows(&self) -> usize {
        self.rows
    }
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// The nonzero entries `(column, weight)` of row `r`, by increasing column.
    pub fn row(&self, r: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (a, b) = (self.offsets[r] as usize, self.offsets[r + 1] as usize);
        self.index[a..b]
            .iter()
            .zip(&self.weight[a..b])
            .map(|(&c, &w)| (c as usize, w))
    }
    /// Row `r` as its column and weight slices (the hot-loop form of [`Csr::row`]).
    #[inline]
    pub fn row_slices(&self, r: usize) -> (&[u32], &[f64]) {
        let (a, b) = (self.offsets[r] as usize, self.offsets[r + 1] as usize);
        (&self.index[a..b], &self.weight[a..b])
    }
    /// Dense copy, row-major (tests and eigen analysis only).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.cols]; self.rows];
        for (r, row) in d.iter_mut().enumerate() {
            for (c, w) in self.row(r) {
                row[c] += w;
            }
        }
        d
    }

    /// `dst_r = Σ w · src_c` for every row `r`; element `e` of `src` is
    /// `src[e*src_stride .. e*src_stride + width]`, likewise for `dst`.
    ///
    /// Each row summed as [`super::kernel::sum_terms`] says (its first term assigns, so
    /// `dst` needs no clearing).
    #[inline]
    pub fn apply<T: Sample>(
        &self,
        src: &[T],
        src_stride: usize,
        dst: &mut [T],
        dst_stride: usize,
        width: usize,
    ) {
        assert!(self.cols == 0 || (self.cols - 1) * src_stride + width <= src.len());
        assert!(self.rows == 0 || (self.rows - 1) * dst_stride + width <= dst.len());
        // SAFETY: the asserts bound every element read and written; `src` and `dst` are
        // distinct borrows.
        unsafe {
            self.apply_raw(
                src.as_ptr(),
                src_stride,
                dst.as_mut_ptr(),
                dst_stride,
                width,
            )
        }
    }
}

/// Entries collected in any order (duplicates add up), then compressed.
#[derive(Default, Debug)]
pub struct Triplets {
    rows: usize,
    cols: usize,
    entries: Vec<(u32, u32, f64)>,
}

impl Triplets {
    pub fn new(rows: usize, cols: usize) -> Self {
        Triplets {
            rows,
            cols,
            entries: Vec::new(),
        }
    }
    /// Add `w` at `(r, c)`. Panics on out-of-range indices: builders are internal and
    /// their index arithmetic is covered by the perfect-reconstruction tests.
    #[inline]
    pub fn add(&mut self, r: usize, c: usize, w: f64) {
        assert!(
            r < self.rows && c < self.cols,
            "entry ({r},{c}) outside {}x{}",
            self.rows,
            self.cols
        );
        self.entries.push((r as u32, c as u32, w));
    }
    /// Add a run of taps `w[t]` at columns `first + t` of row `r`.
    pub fn add_run(&mut self, r: usize, first: usize, w: &[f64]) {
        for (t, &x) in w.iter().enumerate() {
            self.add(r, first + t, x);
        }
    }
    pub fn into_csr(mut self) -> Csr {
        self.entries.sort_unstable_by_key(|&(r, c, _)| (r, c));
        let mut offsets = Vec::with_capacity(self.rows + 1);
        let mut index = Vec::with_capacity(self.entries.len());
        let mut weight: Vec<f64> = Vec::with_capacity(self.entries.len());
        offsets.push(0u32);
        let mut it = self.entries.into_iter().peekable();
        for r in 0..self.rows as u32 {
            while let Some(&(rr, c, w)) = it.peek() {
                if rr != r {
                    break;
                }
                it.next();
                if index.len() > *offsets.last().unwrap() as usize && *index.last().unwrap() == c {
                    *weight.last_mut().unwrap() += w;
                } else {
                    index.push(c);
                    weight.push(w);
                }
            }
            // drop entries that cancelled exactly
            let start = *offsets.last().unwrap() as usize;
            let mut k = start;
            for j in start..index.len() {
                if weight[j] != 0.0 {
                    index[k] = index[j];
                    weight[k] = weight[j];
                    k += 1;
                }
            }
            index.truncate(k);
            weight.truncate(k);
            offsets.push(index.len() as u32);
        }
        Csr {
            rows: self.rows,
            cols: self.cols,
            offsets,
            index,
            weight,
        }
    }
}

impl Triplets {
    /// Move every entry through `f(row, col) -> (row, col)` into a `rows × cols` set.
    pub fn remap(
        self,
        rows: usize,
        cols: usize,
        f: impl Fn(usize, usize) -> (usize, usize),
    ) -> Triplets {
        let mut t = Triplets::new(rows, cols);
        for (r, c, w) in self.entries {
            let (r2, c2) = f(r as usize, c as usize);
            t.add(r2, c2, w);
        }
        t
    }
}

impl Csr {
    /// [`Csr::apply`] on raw element pointers, for lanes that live inside a larger
    /// array other threads are writing elsewhere. Only the elements this call reads
    /// (`src + c*src_stride .. + width` for the columns it uses) and writes
    /// (`dst + r*dst_stride .. + width`) are turned into slices.
    ///
    /// # Safety
    /// Every element read must be valid for reads and not written concurrently, every
    /// element written must be valid for writes and touched by no other thread, and the
    /// two sets must not overlap.
    #[inline]
    pub unsafe fn apply_raw<T: Sample>(
        &self,
        src: *const T,
        src_stride: usize,
        dst: *mut T,
        dst_stride: usize,
        width: usize,
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::scheme::sparse::cpu_has_avx2() {
            // SAFETY: AVX2 is present; the caller's guarantees pass through.
            return unsafe { self.apply_avx2(src, src_stride, dst, dst_stride, width) };
        }
        unsafe { self.apply_generic(src, src_stride, dst, dst_stride, width) }
    }

    /// [`Csr::apply`] with the baseline (non-AVX2) build of the kernel, for tests that
    /// check every CPU level gives the same bits.
    pub fn apply_baseline<T: Sample>(
        &self,
        src: &[T],
        ss: usize,
        dst: &mut [T],
        ds: usize,
        width: usize,
    ) {
        assert!(self.cols == 0 || (self.cols - 1) * ss + width <= src.len());
        assert!(self.rows == 0 || (self.rows - 1) * ds + width <= dst.len());
        // SAFETY: bounds checked above; distinct borrows.
        unsafe { self.apply_generic(src.as_ptr(), ss, dst.as_mut_ptr(), ds, width) }
    }

    /// [`Csr::apply_generic`] compiled for AVX2 and FMA (bit-identical to the baseline
    /// build, whose FMAs are a software routine).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn apply_avx2<T: Sample>(
        &self,
        src: *const T,
        ss: usize,
        dst: *mut T,
        ds: usize,
        width: usize,
    ) {
        unsafe { self.apply_generic(src, ss, dst, ds, width) }
    }

    #[inline(always)]
    unsafe fn apply_generic<T: Sample>(
        &self,
        src: *const T,
        src_stride: usize,
        dst: *mut T,
        dst_stride: usize,
        width: usize,
    ) {
        // the rows' weights and pairs (on the stack up to 32 taps, the schemes' rows)
        let (mut ws_stack, mut partner_stack) = ([T::default(); 32], [0usize; 32]);
        let (mut ws_heap, mut partner_heap): (Vec<T>, Vec<usize>) = (Vec::new(), Vec::new());
        for r in 0..self.rows {
            let (a, b) = (self.offsets[r] as usize, self.offsets[r + 1] as usize);
            // SAFETY: the caller guarantees this element is ours alone.
            let out = unsafe { std::slice::from_raw_parts_mut(dst.add(r * dst_stride), width) };
            if a == b {
                out.fill(T::default());
                continue;
            }
            // the row's sum as `kernel::sum_terms` takes it (pairs of equal weights)
            let (ws, partner) = if b - a <= 32 {
                (&mut ws_stack[..b - a], &mut partner_stack[..b - a])
            } else {
                ws_heap.resize(b - a, T::default());
                partner_heap.resize(b - a, 0);
                (&mut ws_heap[..], &mut partner_heap[..])
            };
            for (w, &v) in ws.iter_mut().zip(&self.weight[a..b]) {
                *w = T::from_f64(v);
            }
            crate::scheme::kernel::pair_taps(ws, partner);
            let input = |k: usize| unsafe {
                std::slice::from_raw_parts(src.add(self.index[a + k] as usize * src_stride), width)
            };
            let mut first = true;
            for k in 0..b - a {
                let q = partner[k];
                if q == crate::scheme::kernel::SECOND {
                    continue;
                }
                let (x, w) = (input(k), ws[k]);
                if q == k {
                    if first {
                        for (o, &x) in out.iter_mut().zip(x) {
                            *o = w * x;
                        }
                    } else {
                        for (o, &x) in out.iter_mut().zip(x) {
                            *o += w * x;
                        }
                    }
                } else {
                    let y = input(q);
                    if first {
                        for ((o, &x), &y) in out.iter_mut().zip(x).zip(y) {
                            *o = w * (x + y);
                        }
                    } else {
                        for ((o, &x), &y) in out.iter_mut().zip(x).zip(y) {
                            *o = (x + y).fused_mul_add(w, *o);
                        }
                    }
                }
                first = false;
            }
        }
    }
}

/// The builds of the kernels, narrowest first. All give the same bits: each output's
/// taps summed as [`super::kernel::sum_terms`] says (its FMAs in software in the
/// baseline build).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Simd {
    /// Plain loops (whatever the compiler makes of them for the baseline target).
    Baseline,
    /// 256-bit vectors (AVX2 with FMA).
    Avx2,
    /// 512-bit vectors for the combines (the rest as [`Simd::Avx2`]).
    Avx512,
}

impl Simd {
    /// The widest build this CPU runs, detected once. `MRA_CPU=scalar` or `MRA_CPU=avx2`
    /// in the environment caps it (to compare builds).
    pub fn detected() -> Simd {
        static LEVEL: std::sync::OnceLock<Simd> = std::sync::OnceLock::new();
        *LEVEL.get_or_init(|| {
            let cap = match std::env::var("MRA_CPU").as_deref() {
                Ok("scalar") => Simd::Baseline,
                Ok("avx2") => Simd::Avx2,
                _ => Simd::Avx512,
            };
            #[cfg(target_arch = "x86_64")]
            let fma = std::arch::is_x86_feature_detected!("fma");
            let found = if fma && std::arch::is_x86_feature_detected!("avx512f") {
                Simd::Avx512
            } else if fma && std::arch::is_x86_feature_detected!("avx2") {
                Simd::Avx2
            } else {
                Simd::Baseline
            };
            #[cfg(not(target_arch = "x86_64"))]
            let found = Simd::Baseline;
            found.min(cap)
        })
    }

    /// Every build this CPU runs, up to [`Simd::detected`] (tests compare them).
    pub fn available() -> Vec<Simd> {
        [Simd::Baseline, Simd::Avx2, Simd::Avx512]
            .into_iter()
            .filter(|&s| s <= Simd::detected())
            .collect()
    }
}

/// Whether the AVX2 build (or a wider one) of the kernels is used ([`Simd::detected`]).
#[cfg(target_arch = "x86_64")]
pub fn cpu_has_avx2() -> bool {
    Simd::detected() >= Simd::Avx2
}
