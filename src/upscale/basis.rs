//! The one-dimensional functions an upscaled lane is made of: the limit functions of the
//! subdivision rules of `src/scheme/subdivide.rs` (§7.2.2, §7.6.1), centred on the
//! control point, with their antiderivatives (for cell averages).
//!
//! **Uniform B-spline of order k** (degree k − 1), centred: the curve module's basis
//! function `N_{0,k}` on the integer knots (`crate::curve::basis`, §3.4), shifted by k/2
//! so that it is symmetric about 0:
//! ```text
//! β_k(x) = N_{0,k}(x + k/2)                              support [−k/2, k/2]
//! ∫_{−∞}^x β_k = Σ_{i≥0} N_{i,k+1}(x + k/2)              (d/dt N_{i,k+1} = N_{i,k} − N_{i+1,k})
//! ```
//! Order 1 is the box (nearest neighbour), 2 the hat (linear), 3 Chaikin's quadratic,
//! 4 the cubic, 5 the quartic. The k-fold subdivided control polygon of these rules
//! converges to `Σ P_i β_k(x − i)` (§7.2), so evaluating β_k at the fine positions is
//! subdivision carried to its limit.
//!
//! **Dyn–Levin 4-point**: the scheme's fundamental function φ (the limit of subdividing
//! a single 1), support [−3, 3], tabulated at level [`FOUR_POINT_LEVEL`] by running the
//! closed refinement rule on a delta, and linearly interpolated between the dyadic points
//! (exact at every dyadic position up to that level, e.g. every pixel centre of a ×2^k
//! upscale with k < 12).

use crate::curve::basis::basis_funs;
use crate::scheme::subdivide::{refine_steps, Ends, Refinement};

/// Dyadic level of the tabulated 4-point function (4096 samples per unit).
pub const FOUR_POINT_LEVEL: u32 = 12;

/// A centred one-dimensional basis function with its antiderivative.
#[derive(Clone, Debug)]
pub enum Basis {
    /// Uniform B-spline of this order (1 ≤ k ≤ [`MAX_ORDER`]).
    BSpline(usize),
    /// Tabulated 4-point fundamental function: values and running integral on
    /// `x = −3 + i / 2^L`.
    FourPoint { value: Vec<f64>, integral: Vec<f64> },
}

/// Highest B-spline order [`Basis::BSpline`] evaluates (the CLI offers 1–12; the
/// antiderivative needs order + 1).
pub const MAX_ORDER: usize = 12;

/// Integer knots `t_j = j − KNOT_SHIFT`, so that every span `[m, m + 1)` with
/// `0 ≤ m ≤ MAX_ORDER` has `MAX_ORDER + 1` knots on each side (what the triangular
/// Cox–de Boor recursion reads for order ≤ `MAX_ORDER + 1`).
const KNOT_SHIFT: usize = MAX_ORDER + 2;
const KNOT_COUNT: usize = 2 * KNOT_SHIFT + MAX_ORDER + 2;

/// `N_{m−k+1,k}(t) … N_{m,k}(t)` on the integer knots, `m = ⌊t⌋`, written to `out[0..k]`
/// (the curve module's triangular Cox–de Boor recursion, §3.9.4: O(k²), where the plain
/// recursion of §3.4.1 costs O(2^k)). Requires `0 ≤ t < MAX_ORDER + 1`, `k ≤ MAX_ORDER + 1`.
fn cardinal_span(k: usize, t: f64, out: &mut [f64; MAX_ORDER + 1]) -> usize {
    debug_assert!((1..=MAX_ORDER + 1).contains(&k) && (0.0..(MAX_ORDER + 1) as f64).contains(&t));
    let knots: [f64; KNOT_COUNT] = std::array::from_fn(|j| j as f64 - KNOT_SHIFT as f64);
    let m = t.floor() as usize;
    let (mut left, mut right) = ([0.0; MAX_ORDER + 1], [0.0; MAX_ORDER + 1]);
    basis_funs(&knots, m + KNOT_SHIFT, t, k, out, &mut left, &mut right);
    m
}

impl Basis {
    /// The basis of a refinement rule.
    pub fn of(rule: Refinement) -> Basis {
        match rule.order() {
            Some(k) => Basis::BSpline(k),
            None => four_point(),
        }
    }

    /// Half-width of the support.
    pub fn radius(&self) -> f64 {
        match self {
            Basis::BSpline(k) => *k as f64 / 2.0,
            Basis::FourPoint { .. } => 3.0,
        }
    }

    /// φ(x).
    pub fn value(&self, x: f64) -> f64 {
        match self {
            Basis::BSpline(k) => {
                let h = *k as f64 / 2.0;
                // half-open support [−k/2, k/2) so that the box sums to one everywhere
                if x < -h || x >= h {
                    0.0
                } else {
                    // N_{0,k}(t) is entry (k − 1) − m of the span's k functions
                    let mut out = [0.0; MAX_ORDER + 1];
                    let m = cardinal_span(*k, x + h, &mut out);
                    out[*k - 1 - m]
                }
            }
            Basis::FourPoint { value, .. } => table(value, x, 0.0, 0.0),
        }
    }

    /// ∫_{−∞}^x φ.
    pub fn integral(&self, x: f64) -> f64 {
        match self {
            Basis::BSpline(k) => {
                let h = *k as f64 / 2.0;
                if x <= -h {
                    0.0
                } else if x >= h {
                    1.0
                } else {
                    // d/dt N_{i,k+1} = N_{i,k} − N_{i+1,k} on unit knots, so the running
                    // integral of N_{0,k} is Σ_{i≥0} N_{i,k+1}
                    // (span functions N_{m−k..m, k+1}; those with i ≥ 0 are entries k − m …)
                    let mut out = [0.0; MAX_ORDER + 1];
                    let m = cardinal_span(k + 1, x + h, &mut out);
                    out[*k - m..=*k].iter().sum()
                }
            }
            Basis::FourPoint { integral, .. } => table(integral, x, 0.0, 1.0),
        }
    }

    /// Mean of φ over the cell `[x − w/2, x + w/2]` (`w = 0`: the value at `x`).
    pub fn cell_mean(&self, x: f64, w: f64) -> f64 {
        if w <= 0.0 {
            self.value(x)
        } else {
            (self.integral(x + w / 2.0) - self.integral(x - w / 2.0)) / w
        }
    }
}

/// Linear interpolation in a table on `x = −3 + i/2^L`, `below`/`above` outside.
fn table(t: &[f64], x: f64, below: f64, above: f64) -> f64 {
    let s = (x + 3.0) * (1u64 << FOUR_POINT_LEVEL) as f64;
    if s <= 0.0 {
        return below;
    }
    let i = s.floor() as usize;
    if i + 1 >= t.len() {
        return above;
    }
    let f = s - i as f64;
    t[i] * (1.0 - f) + t[i + 1] * f
}

/// Subdivide a delta on a closed lane of 8 points `L` times: point `j` of level `L`
/// sits at `j / 2^L` (the 4-point rule keeps the old points at even positions).
fn four_point() -> Basis {
    let n = 8usize;
    let mut delta = vec![0.0; n];
    delta[4] = 1.0;
    let fine = refine_steps(
        &delta,
        1,
        Refinement::FourPoint,
        Ends::Closed,
        FOUR_POINT_LEVEL as usize,
    )
    .expect("8 points refine with the closed 4-point rule");
    let per = 1usize << FOUR_POINT_LEVEL;
    // x = −3 … 3  ↔  index (4 − 3)·per … (4 + 3)·per
    let value: Vec<f64> = fine[per..=7 * per].to_vec();
    let dx = 1.0 / per as f64;
    let mut integral = Vec::with_capacity(value.len());
    let mut acc = 0.0;
    integral.push(0.0);
    for w in value.windows(2) {
        acc += 0.5 * (w[0] + w[1]) * dx;
        integral.push(acc);
    }
    Basis::FourPoint { value, integral }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_integrals() {
        for rule in Refinement::ALL {
            let b = Basis::of(rule);
            for x in [0.0, 0.1, 0.25, 0.5, 0.77] {
                let s: f64 = (-6..=6).map(|i| b.value(x - i as f64)).sum();
                assert!((s - 1.0).abs() < 1e-9, "{rule:?} x={x} sum={s}");
            }
            assert!((b.integral(10.0) - 1.0).abs() < 1e-6, "{rule:?}");
            assert!(b.integral(-10.0).abs() < 1e-12);
        }
    }

    #[test]
    fn every_offered_order_matches_the_plain_recursion_and_sums_to_one() {
        use crate::curve::basis::basis_brute;
        let knots: Vec<f64> = (0..32).map(|j| j as f64).collect();
        for k in 1..=MAX_ORDER {
            let b = Basis::BSpline(k);
            let h = k as f64 / 2.0;
            for x in [-h, -h + 0.3, -0.5, 0.0, 0.25, h - 0.01] {
                let brute = basis_brute(&knots, 31, 0, k, x + h);
                assert!((b.value(x) - brute).abs() < 1e-12, "k={k} x={x}");
                if k <= 9 {
                    let brute_int: f64 = (0..=k)
                        .map(|i| basis_brute(&knots, 31, i, k + 1, x + h))
                        .sum();
                    assert!((b.integral(x) - brute_int).abs() < 1e-12, "k={k} x={x}");
                }
                let s: f64 = (-20..=20).map(|i| b.value(x - i as f64)).sum();
                assert!((s - 1.0).abs() < 1e-9, "k={k} x={x} sum={s}");
            }
            assert!((b.integral(h - 1e-9) - 1.0).abs() < 1e-6, "k={k}");
        }
    }

    #[test]
    fn known_values() {
        let c = Basis::BSpline(4);
        assert!((c.value(0.0) - 4.0 / 6.0).abs() < 1e-12);
        assert!((c.value(1.0) - 1.0 / 6.0).abs() < 1e-12);
        let q = Basis::BSpline(3);
        assert!((q.value(0.0) - 0.75).abs() < 1e-12);
        assert!((q.value(0.5) - 0.5).abs() < 1e-12);
        // cell mean of the cubic over a unit cell is the quartic B-spline
        let q5 = Basis::BSpline(5);
        for x in [0.0, 1.0, 0.3] {
            assert!((c.cell_mean(x, 1.0) - q5.value(x)).abs() < 1e-12);
        }
        let f = Basis::of(Refinement::FourPoint);
        assert!((f.value(0.0) - 1.0).abs() < 1e-12 && f.value(1.0).abs() < 1e-12);
        assert!((f.value(0.5) - 9.0 / 16.0).abs() < 1e-12);
    }
}
