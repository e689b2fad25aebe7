//! Sparse two-scale operators, and the order in which a row's sum is taken.
//!
//! A level of a scheme is two square operators on a lane of `m` elements:
//! analysis `[A; B]` (rows `0..n` give the coarse `C = A F`, rows `n..m` the details
//! `D = B F`) and synthesis `[P | Q]` (fine row `i` is `F_i = Σ P_ij C_j + Σ Q_ij D_j`,
//! with `D_j` stored at packed position `n + j`). Both are stored row-wise (CSR), so
//! applying either is one gather pass: `out_r = Σ_k w_rk · in_{c_rk}`, where every
//! `in_c`/`out_r` is an element of `width` samples and the inner loop runs over the
//! element (whole rows vectorise).
//!
//! **How a row's sum is taken** ([`pair_taps`], [`sum_terms`]; every build of the
//! kernels gives these bits). The taps in increasing column order; scanning them so, a
//! tap not yet paired pairs with the next tap of the same weight not yet paired, if any
//! (the symmetric taps of the regular filters: cubic's `a` sums `(x₀ + x₆)`, `(x₁ + x₅)`,
//! `(x₂ + x₄)` and takes `x₃` alone). The terms — single taps, and pairs at their first
//! tap — in column order: the first is `w·x` (a pair's `x` the sum of its two inputs, the
//! earlier first), each next single tap adds the rounded product `w·x`, each next pair is
//! `fma(x_a + x_b, w, acc)`, rounded once. A row without equal weights is the plain
//! sum `((w₀x₀ + w₁x₁) + w₂x₂) + …`. Pairs halve the multiplies of the regular rows and
//! move half of the rest into FMAs: the arithmetic of cubic's pair of rows goes from 12
//! multiplies and 10 adds per pair of outputs to 6 FMAs or multiplies and 5–7 adds.

use super::sample::Sample;

/// Row-compressed sparse matrix with `f64` weights (the filters are dyadic rationals,
/// exact in any float type except where a derived boundary weight is not).
///
/// Each row also carries its sum as [`sum_terms`] takes it, worked out once when the
/// matrix is made ([`Csr::terms32`], [`Csr::terms64`]: the pairs of [`pair_taps`] differ
/// between `f32` and `f64` weights where two weights round to the same `f32`), so that
/// the kernels that apply a row many times never pair its taps again.
#[derive(Clone, Debug, PartialEq)]
pub struct Csr {
    rows: usize,
    cols: usize,
    offsets: Vec<u32>,
    index: Vec<u32>,
    weight: Vec<f64>,
    terms32: RowTerms<f32>,
    terms64: RowTerms<f64>,
}

/// One term of a row's sum ([`sum_terms`]): the input at column `a`, plus the input at
/// column `b` for a pair ([`Term::SINGLE`] for a single tap), times `w`. The first term of
/// a row assigns `w·x`; a next single tap adds the rounded product `w·x`; a next pair is
/// `fma(x_a + x_b, w, acc)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term<W> {
    pub a: u32,
    pub b: u32,
    pub w: W,
}

impl<W> Term<W> {
    /// [`Term::b`] of a single tap.
    pub const SINGLE: u32 = u32::MAX;
}

/// The terms of every row, row `r`'s at `terms[ends[r]..ends[r + 1]]`.
#[derive(Clone, Debug, PartialEq, Default)]
struct RowTerms<W> {
    ends: Vec<u32>,
    terms: Vec<Term<W>>,
}

impl<W: Sample> RowTerms<W> {
    /// The terms of the rows of `(offsets, index, weight)`, weights as `W`.
    fn new(offsets: &[u32], index: &[u32], weight: &[f64]) -> Self {
        let mut t = RowTerms {
            ends: Vec::with_capacity(offsets.len()),
            terms: Vec::with_capacity(index.len()),
        };
        t.ends.push(0);
        let (mut ws, mut partner) = (Vec::new(), Vec::new());
        for r in offsets.windows(2) {
            let (cols, w) = (
                &index[r[0] as usize..r[1] as usize],
                &weight[r[0] as usize..r[1] as usize],
            );
            ws.clear();
            ws.extend(w.iter().map(|&v| W::from_f64(v)));
            partner.resize(cols.len(), 0);
            pair_taps(&ws, &mut partner);
            for k in 0..cols.len() {
                let b = match partner[k] {
                    SECOND => continue,
                    q if q == k => Term::<W>::SINGLE,
                    q => cols[q],
                };
                t.terms.push(Term {
                    a: cols[k],
                    b,
                    w: ws[k],
                });
            }
            t.ends.push(t.terms.len() as u32);
        }
        t
    }

    #[inline]
    fn row(&self, r: usize) -> &[Term<W>] {
        &self.terms[self.ends[r] as usize..self.ends[r + 1] as usize]
    }
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
    /// The terms of row `r`'s sum with `f32` weights ([`Term`]; the same sum as
    /// [`sum_terms`] over the row's taps as `f32`).
    #[inline]
    pub fn terms32(&self, r: usize) -> &[Term<f32>] {
        self.terms32.row(r)
    }
    /// [`Csr::terms32`] with `f64` weights.
    #[inline]
    pub fn terms64(&self, r: usize) -> &[Term<f64>] {
        self.terms64.row(r)
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
    /// Each row summed as [`sum_terms`] says (its first term assigns, so `dst` needs no
    /// clearing). The reference loops: `kernel::apply` gives the same bits faster.
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
        let (mut ws, mut partner) = (Vec::new(), Vec::new());
        for r in 0..self.rows {
            let (cols, weights) = self.row_slices(r);
            let out = &mut dst[r * dst_stride..r * dst_stride + width];
            if cols.is_empty() {
                out.fill(T::default());
                continue;
            }
            ws.clear();
            ws.extend(weights.iter().map(|&v| T::from_f64(v)));
            partner.resize(cols.len(), 0);
            pair_taps(&ws, &mut partner);
            let input = |k: usize| {
                let at = cols[k] as usize * src_stride;
                &src[at..at + width]
            };
            // the terms of `sum_terms`, whole elements at a time
            let mut first = true;
            for k in 0..cols.len() {
                let q = partner[k];
                if q == SECOND {
                    continue;
                }
                let (x, w) = (input(k), ws[k]);
                if q == k {
                    for (o, &x) in out.iter_mut().zip(x) {
                        *o = if first { w * x } else { *o + w * x };
                    }
                } else {
                    for ((o, &x), &y) in out.iter_mut().zip(x).zip(input(q)) {
                        *o = if first {
                            w * (x + y)
                        } else {
                            (x + y).fused_mul_add(w, *o)
                        };
                    }
                }
                first = false;
            }
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
            terms32: RowTerms::new(&offsets, &index, &weight),
            terms64: RowTerms::new(&offsets, &index, &weight),
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

/// [`pair_taps`]' mark of the second tap of a pair.
pub const SECOND: usize = usize::MAX;

/// The pairs of a row whose weights are `w` (in column order): `partner[k]` is `k` for a
/// single tap, `j > k` for the first tap of a pair whose second is `j`, and [`SECOND`] for
/// a pair's second tap. Scanning in order, a tap not yet paired pairs with the next tap
/// of the same weight not yet paired. `true` when some taps pair.
#[inline]
pub fn pair_taps<T: Sample>(w: &[T], partner: &mut [usize]) -> bool {
    let n = w.len();
    assert!(partner.len() >= n);
    for (k, p) in partner.iter_mut().enumerate().take(n) {
        *p = k;
    }
    let mut any = false;
    for k in 0..n {
        if partner[k] != k {
            continue;
        }
        if let Some(j) = (k + 1..n).find(|&j| partner[j] == j && w[j] == w[k]) {
            (partner[k], partner[j]) = (j, SECOND);
            any = true;
        }
    }
    any
}

/// One output of a row, `x(k)` the input of tap `k`: the sum [`pair_taps`] plans (see the
/// module's documentation; the reference every build and path gives the bits of).
#[inline(always)]
pub fn sum_terms<T: Sample>(w: &[T], partner: &[usize], x: impl Fn(usize) -> T) -> T {
    let mut acc = T::default();
    let mut first = true;
    for k in 0..w.len() {
        let p = partner[k];
        if p == SECOND {
            continue;
        }
        let v = if p == k { x(k) } else { x(k) + x(p) };
        acc = if first {
            w[k] * v
        } else if p == k {
            acc + w[k] * v
        } else {
            v.fused_mul_add(w[k], acc)
        };
        first = false;
    }
    acc
}

/// [`sum_terms`] of a row given as weights alone (pairs worked out here).
pub fn row_sum<T: Sample>(w: &[T], x: impl Fn(usize) -> T) -> T {
    let mut partner = vec![0; w.len()];
    pair_taps(w, &mut partner);
    sum_terms(w, &partner, x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheme::{Boundary, Scheme, TwoScale};

    /// The terms a matrix keeps for each row are the sum [`sum_terms`] takes over the
    /// row's taps (pairs as [`pair_taps`] makes them, for `f32` and for `f64` weights):
    /// evaluated term by term they give its bits, on every row of every scheme.
    #[test]
    fn every_rows_terms_are_the_sum_of_its_taps() {
        fn eval<W: Sample>(terms: &[Term<W>], x: &[W]) -> W {
            let mut acc = W::default();
            for (t, term) in terms.iter().enumerate() {
                let v = if term.b == Term::<W>::SINGLE {
                    x[term.a as usize]
                } else {
                    x[term.a as usize] + x[term.b as usize]
                };
                acc = if t == 0 {
                    term.w * v
                } else if term.b == Term::<W>::SINGLE {
                    acc + term.w * v
                } else {
                    v.fused_mul_add(term.w, acc)
                };
            }
            acc
        }
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                for m in [1usize, 2, 5, 22, 33, 35, 64, 101] {
                    let t = TwoScale::new(scheme, boundary, m);
                    for op in [&t.analysis, &t.synthesis] {
                        let x: Vec<f64> = (0..m)
                            .map(|i| ((i * 7919 % 211) as f64 - 105.0) / 13.0)
                            .collect();
                        let x32: Vec<f32> = x.iter().map(|&v| v as f32).collect();
                        for r in 0..m {
                            let (cols, ws) = op.row_slices(r);
                            let w64: Vec<f64> = ws.to_vec();
                            let w32: Vec<f32> = ws.iter().map(|&v| v as f32).collect();
                            let want64 = row_sum(&w64, |k| x[cols[k] as usize]);
                            let want32 = row_sum(&w32, |k| x32[cols[k] as usize]);
                            let (t32, t64) = (op.terms32(r), op.terms64(r));
                            if cols.is_empty() {
                                assert!(t32.is_empty() && t64.is_empty());
                                continue;
                            }
                            assert_eq!(
                                eval(t64, &x).to_bits(),
                                want64.to_bits(),
                                "{scheme} {boundary} {m} row {r}"
                            );
                            assert_eq!(
                                eval(t32, &x32).to_bits(),
                                want32.to_bits(),
                                "{scheme} {boundary} {m} row {r}"
                            );
                        }
                    }
                }
            }
        }
    }
}
