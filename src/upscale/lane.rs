//! Lane operators of the upscaler: where the new samples sit, the evaluation matrix
//! `E` (new samples from control points) and the banded system `K` (samples from
//! control points at the old positions) whose solution makes the limit function pass
//! through the samples (§7.7: the tensor-product surface `Σ P_ij N_i(u) N_j(v)` with the
//! control points `P` chosen so that the surface interpolates).
//!
//! **Geometry.** Sample `i` of a lane of `n` is the centre of cell `[i − ½, i + ½]`
//! (coordinates in old samples). With `m` new samples:
//! ```text
//! centre (pixels, voxels):  x_j = (j + ½)·n/m − ½,  cell width n/m   (×2: i − ¼, i + ¼)
//! vertex (frames in time):  x_j = j·(n − 1)/(m − 1)                   (old frames at x = i)
//! ```
//! The grid of new cells tiles exactly the old one: no half-pixel shift.
//!
//! **Ends.** Control points beyond the ends are defined by reflection, applied
//! recursively until the index falls inside:
//! ```text
//! linear (default): P_{−k} = 2P_0 − P_k,  P_{n−1+k} = 2P_{n−1} − P_{n−1−k}  (reproduces lines)
//! mirror          : P_{−k} = P_{k−1},     P_{n−1+k} = P_{n−k}              (half-sample symmetric)
//! ```
//! Both keep constants (no dark edges) and lose nothing at the ends (no shrinkage).

use super::basis::Basis;
use crate::scheme::sparse::{Csr, Triplets};
use crate::scheme::Sample;
use crate::{Error, Result};

/// How control points beyond the ends of a lane are defined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edge {
    /// Point reflection about the end sample: linear functions continue exactly.
    Linear,
    /// Mirror about the end of the last cell.
    Mirror,
}

/// Where new samples sit along one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Geometry {
    /// Samples are cell centres (images, volumes, heightmaps).
    Centre,
    /// Samples are instants; the first and last stay where they are (time axis).
    Vertex,
}

/// What the samples are taken to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Control points: plain subdivision carried to its limit (smooth, blurs).
    Control,
    /// Values of the limit function at the sample positions (B-spline interpolation).
    Interpolate,
    /// Means of the limit function over the cells: the new cells' means average back
    /// exactly to the old samples (what a sensor, or a block-mean downscale, measures).
    Area,
}

impl std::str::FromStr for Mode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "control" | "subdivide" | "smooth" => Ok(Mode::Control),
            "interpolate" | "interpolating" | "sharp" => Ok(Mode::Interpolate),
            "area" | "cell" | "mean" => Ok(Mode::Area),
            _ => Err(Error::parameter("mode", s, "area, interpolate or control")),
        }
    }
}

impl std::str::FromStr for Edge {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "linear" => Ok(Edge::Linear),
            "mirror" | "symmetric" => Ok(Edge::Mirror),
            _ => Err(Error::parameter("edge", s, "linear or mirror")),
        }
    }
}

/// Positions (old-sample coordinates) of `m` new samples on a lane of `n`, and the width
/// of a new cell.
pub fn positions(n: usize, m: usize, g: Geometry) -> (Vec<f64>, f64) {
    match g {
        Geometry::Vertex if n >= 2 && m >= 2 => {
            let s = (n - 1) as f64 / (m - 1) as f64;
            ((0..m).map(|j| j as f64 * s).collect(), s)
        }
        Geometry::Vertex => (vec![0.0; m], 1.0),
        Geometry::Centre => {
            let s = n as f64 / m as f64;
            ((0..m).map(|j| (j as f64 + 0.5) * s - 0.5).collect(), s)
        }
    }
}

/// Add `w · P_i` (any integer `i`) to row `r`, resolving `i` by the edge rule.
fn add_extended(t: &mut Triplets, r: usize, i: isize, n: usize, w: f64, edge: Edge) {
    let last = n as isize - 1;
    if (0..=last).contains(&i) {
        t.add(r, i as usize, w);
    } else if n == 1 {
        t.add(r, 0, w);
    } else {
        match (edge, i < 0) {
            (Edge::Linear, true) => {
                t.add(r, 0, 2.0 * w);
                add_extended(t, r, -i, n, -w, edge);
            }
            (Edge::Linear, false) => {
                t.add(r, n - 1, 2.0 * w);
                add_extended(t, r, 2 * last - i, n, -w, edge);
            }
            (Edge::Mirror, true) => add_extended(t, r, -1 - i, n, w, edge),
            (Edge::Mirror, false) => add_extended(t, r, 2 * last + 1 - i, n, w, edge),
        }
    }
}

/// Most distinct offsets memoised per evaluation matrix.
const MEMO: usize = 4096;

/// `E[j][i]` = basis (or its mean over a cell of `width`) at `x_j − i`, ends folded in:
/// new samples from `n` control points.
///
/// The weights are memoised on the exact offset `x_j − i`: for an integer factor the
/// offsets repeat with the factor's period (×2: `±¼ + k`), so only one period is
/// evaluated (the recursion of [`Basis::cell_mean`] dominated building the operators);
/// the matrix is bit-identical to evaluating every entry.
pub fn eval_matrix(basis: &Basis, n: usize, xs: &[f64], width: f64, edge: Edge) -> Csr {
    let r = basis.radius() + width / 2.0;
    let mut t = Triplets::new(xs.len(), n);
    let mut memo: std::collections::HashMap<u64, f64> = std::collections::HashMap::new();
    for (j, &x) in xs.iter().enumerate() {
        let lo = (x - r).floor() as isize;
        let hi = (x + r).ceil() as isize;
        for i in lo..=hi {
            let d = x - i as f64;
            let w = match memo.get(&d.to_bits()) {
                Some(&w) => w,
                None => {
                    let w = basis.cell_mean(d, width);
                    // bounded: a non-integer ratio has (almost) no repeats
                    if memo.len() < MEMO {
                        memo.insert(d.to_bits(), w);
                    }
                    w
                }
            };
            if w.abs() > 1e-13 {
                add_extended(&mut t, j, i, n, w, edge);
            }
        }
    }
    t.into_csr()
}

/// A banded matrix factored as `LU` (no pivoting: the systems of B-spline interpolation
/// are diagonally dominant, §7.7).
#[derive(Clone, Debug)]
pub struct Banded {
    n: usize,
    b: usize,
    /// Row `i`, column `j` at `a[i*(2b+1) + j + b − i]`; L below the diagonal (unit
    /// diagonal implied), U on and above.
    a: Vec<f64>,
}

impl Banded {
    /// Factor a square matrix given as CSR.
    pub fn factor(k: &Csr) -> Result<Banded> {
        let n = k.rows();
        let mut b = 0;
        for r in 0..n {
            for (c, _) in k.row(r) {
                b = b.max(r.abs_diff(c));
            }
        }
        let wd = 2 * b + 1;
        let mut a = vec![0.0; n * wd];
        for r in 0..n {
            for (c, w) in k.row(r) {
                a[r * wd + c + b - r] += w;
            }
        }
        let at = |i: usize, j: usize| i * wd + j + b - i;
        for p in 0..n {
            let piv = a[at(p, p)];
            if piv.abs() < 1e-9 {
                return Err(Error::Unsupported {
                    what: "interpolation system",
                    value: format!("singular for a lane of {n} samples"),
                });
            }
            for i in p + 1..(p + b + 1).min(n) {
                let l = a[at(i, p)] / piv;
                a[at(i, p)] = l;
                for j in p + 1..(p + b + 1).min(n) {
                    a[at(i, j)] -= l * a[at(p, j)];
                }
            }
        }
        Ok(Banded { n, b, a })
    }

    /// Solve `K x = s` in place on a lane of `n` elements of `width` samples (element
    /// `i` at `lane[i*width..]`): forward then back substitution, whole elements at once.
    pub fn solve<T: Sample>(&self, lane: &mut [T], width: usize) {
        let (n, b) = (self.n, self.b);
        let wd = 2 * b + 1;
        assert_eq!(lane.len(), n * width);
        for i in 1..n {
            let (done, rest) = lane.split_at_mut(i * width);
            let xi = &mut rest[..width];
            for p in i.saturating_sub(b)..i {
                let l = T::from_f64(self.a[i * wd + p + b - i]);
                for (x, &y) in xi.iter_mut().zip(&done[p * width..p * width + width]) {
                    *x = *x - l * y;
                }
            }
        }
        for i in (0..n).rev() {
            let (head, tail) = lane.split_at_mut((i + 1) * width);
            let xi = &mut head[i * width..];
            for p in i + 1..(i + b + 1).min(n) {
                let u = T::from_f64(self.a[i * wd + p + b - i]);
                let q = p - i - 1;
                for (x, &y) in xi.iter_mut().zip(&tail[q * width..q * width + width]) {
                    *x = *x - u * y;
                }
            }
            let d = T::from_f64(1.0 / self.a[i * wd + b]);
            for x in xi.iter_mut() {
                *x = *x * d;
            }
        }
    }
}

/// The system whose solution turns `n` samples into control points for `mode`
/// (`None` for [`Mode::Control`], where the samples are the control points).
pub fn system(basis: &Basis, n: usize, mode: Mode, edge: Edge) -> Result<Option<Banded>> {
    let width = match mode {
        Mode::Control => return Ok(None),
        Mode::Interpolate => 0.0,
        Mode::Area => 1.0,
    };
    let xs: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let k = eval_matrix(basis, n, &xs, width, edge);
    Banded::factor(&k).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheme::subdivide::Refinement;

    fn apply(e: &Csr, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; e.rows()];
        e.apply(x, 1, &mut y, 1, 1);
        y
    }

    #[test]
    fn solve_then_evaluate_reproduces_samples() {
        for rule in Refinement::ALL {
            let basis = Basis::of(rule);
            for mode in [Mode::Interpolate, Mode::Area] {
                for edge in [Edge::Linear, Edge::Mirror] {
                    for n in [1usize, 2, 3, 5, 17] {
                        let s: Vec<f64> = (0..n).map(|i| ((i * 7) % 5) as f64).collect();
                        let k = system(&basis, n, mode, edge).unwrap().unwrap();
                        let mut c = s.clone();
                        k.solve(&mut c, 1);
                        let xs: Vec<f64> = (0..n).map(|i| i as f64).collect();
                        let w = if mode == Mode::Area { 1.0 } else { 0.0 };
                        let back = apply(&eval_matrix(&basis, n, &xs, w, edge), &c);
                        for (a, b) in back.iter().zip(&s) {
                            assert!((a - b).abs() < 1e-9, "{rule:?} {mode:?} {edge:?} n={n}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn centre_positions_tile_the_old_cells() {
        let (xs, w) = positions(3, 6, Geometry::Centre);
        assert_eq!(xs, vec![-0.25, 0.25, 0.75, 1.25, 1.75, 2.25]);
        assert_eq!(w, 0.5);
        let (xs, _) = positions(3, 5, Geometry::Vertex);
        assert_eq!(xs, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
    }
}
