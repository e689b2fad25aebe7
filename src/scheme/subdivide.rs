//! Subdivision (refinement only, §7): uniform B-splines of order 1–5 from Pascal's
//! triangle (§7.2.2), their open end rules (§7.4: the refinement of a clamped,
//! multiple-knot B-spline, end points interpolated) and the Dyn–Levin 4-point
//! interpolating scheme (§7.6.1). Points are elements of `dim` samples, so the same
//! code refines curves, and whole rows of a grid (refining along columns).
//!
//! Closed masks: order `k` has column weights `binom(k, t) / 2^(k−1)`, t = 0 … k:
//! ```text
//! box (1,1)   linear (1,2,1)/2   Chaikin (1,3,3,1)/4   cubic (1,4,6,4,1)/8   quartic (1,5,10,10,5,1)/16
//! 4-point: F_{2j} = C_j,  F_{2j+1} = (−C_{j−1} + 9C_j + 9C_{j+1} − C_{j+2}) / 16
//! ```
//! Open end rules (start block; the end block is its mirror image):
//! ```text
//! linear : F_{2j} = C_j, F_{2j+1} = ½(C_j + C_{j+1})                         m = 2n − 1
//! Chaikin: F_0 = C_0, F_1 = ½(C_0 + C_1), then ¾ ¼ / ¼ ¾                    m = 2n − 2, n ≥ 3
//! cubic  : F_0 = C_0, F_1 = ½(C_0+C_1), F_2 = ¾C_1 + ¼C_2,
//!          F_3 = 3⁄16 C_1 + 11⁄16 C_2 + ⅛C_3, F_4 = ½(C_2+C_3), then ⅛ ¾ ⅛ / ½ ½   m = 2n − 3, n ≥ 4
//! quartic: … F_4 = 5⁄12 C_2 + 25⁄48 C_3 + 1⁄16 C_4, F_5 = 1⁄12 C_2 + 29⁄48 C_3 + 5⁄16 C_4,
//!          then 5⁄16 ⅝ 1⁄16 / 1⁄16 ⅝ 5⁄16                                    m = 2n − 4, n ≥ 5
//! 4-point: F_1 = (5C_0 + 15C_1 − 5C_2 + C_3)/16 (cubic through the first four)  m = 2n − 1, n ≥ 4
//! ```
//! The start and end blocks above need n ≥ 6 (cubic) and n ≥ 8 (quartic) to stay apart; with
//! fewer points (down to the order, the fewest a clamped B-spline has) the rows come from
//! the same refinement done directly: Boehm's insertion of the midpoint of every span into
//! the clamped knots `0^k, 1, …, n−k, (n−k+1)^k` (§7.4), new knot `u` in `[t_s, t_{s+1})`:
//! ```text
//! Q_i = P_i (i ≤ s−k+1),  Q_i = (1−a_i) P_{i−1} + a_i P_i,  a_i = (u − t_i)/(t_{i+k−1} − t_i)
//!       (s−k+2 ≤ i ≤ s),  Q_i = P_{i−1} (i > s)
//! ```

use super::sparse::{Csr, Triplets};
use crate::{Error, Result};
use std::str::FromStr;

/// A refinement rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Refinement {
    /// Order 1 (piecewise constant): every point doubled.
    Box,
    /// Order 2 (Faber): midpoints inserted.
    Linear,
    /// Order 3 (quadratic B-spline).
    Chaikin,
    /// Order 4.
    Cubic,
    /// Order 5.
    Quartic,
    /// Dyn–Levin 4-point interpolating scheme.
    FourPoint,
}

/// Closed (periodic) or open (end points interpolated) curves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Ends {
    Closed,
    Open,
}

impl Refinement {
    pub const ALL: [Refinement; 6] = [
        Refinement::Box,
        Refinement::Linear,
        Refinement::Chaikin,
        Refinement::Cubic,
        Refinement::Quartic,
        Refinement::FourPoint,
    ];
    /// B-spline order (`None` for the 4-point scheme).
    pub fn order(self) -> Option<usize> {
        match self {
            Refinement::Box => Some(1),
            Refinement::Linear => Some(2),
            Refinement::Chaikin => Some(3),
            Refinement::Cubic => Some(4),
            Refinement::Quartic => Some(5),
            Refinement::FourPoint => None,
        }
    }
    /// Fewest points the rule refines with the given ends.
    pub fn min_points(self, ends: Ends) -> usize {
        match (self, ends) {
            (Refinement::Box, _) | (Refinement::Linear, Ends::Open) => 1,
            (Refinement::Linear, Ends::Closed) => 2,
            (Refinement::Chaikin, Ends::Open) => 3,
            (Refinement::Cubic, Ends::Open) => 4,
            (Refinement::Quartic, Ends::Open) => 5,
            (Refinement::FourPoint, Ends::Open) => 4,
            (Refinement::Chaikin, Ends::Closed) => 2,
            (Refinement::Cubic, Ends::Closed) | (Refinement::Quartic, Ends::Closed) => 3,
            (Refinement::FourPoint, Ends::Closed) => 4,
        }
    }
    /// Number of points after one step from `n`.
    pub fn refined_len(self, ends: Ends, n: usize) -> usize {
        match ends {
            Ends::Closed => 2 * n,
            Ends::Open => match self {
                Refinement::Box => 2 * n,
                Refinement::Linear | Refinement::FourPoint => 2 * n - 1,
                Refinement::Chaikin => 2 * n - 2,
                Refinement::Cubic => 2 * n - 3,
                Refinement::Quartic => 2 * n - 4,
            },
        }
    }
}

impl FromStr for Refinement {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s.to_ascii_lowercase().as_str() {
            "box" | "haar" => Refinement::Box,
            "linear" => Refinement::Linear,
            "chaikin" | "quadratic" => Refinement::Chaikin,
            "cubic" => Refinement::Cubic,
            "quartic" => Refinement::Quartic,
            "four-point" | "fourpoint" | "4-point" | "dyn-levin" => Refinement::FourPoint,
            _ => {
                return Err(Error::parameter(
                    "subdivision scheme",
                    s,
                    "box, linear, chaikin, cubic, quartic or four-point",
                ))
            }
        })
    }
}

fn binomial_mask(k: usize) -> Vec<f64> {
    let mut row = vec![1.0f64];
    for _ in 0..k {
        let mut next = vec![1.0; row.len() + 1];
        for i in 1..row.len() {
            next[i] = row[i - 1] + row[i];
        }
        row = next;
    }
    let scale = 2f64.powi(k as i32 - 1);
    row.iter().map(|x| x / scale).collect()
}

/// The refinement matrix `S` (fine × coarse) for `n` points.
pub fn matrix(rule: Refinement, ends: Ends, n: usize) -> Result<Csr> {
    let min = rule.min_points(ends);
    if n < min {
        return Err(Error::parameter(
            "number of points",
            n,
            "at least the rule's minimum (see `Refinement::min_points`)",
        ));
    }
    let m = rule.refined_len(ends, n);
    let mut t = Triplets::new(m, n);
    match ends {
        Ends::Closed => closed(rule, n, &mut t),
        Ends::Open => open(rule, n, m, &mut t),
    }
    Ok(t.into_csr())
}

fn closed(rule: Refinement, n: usize, t: &mut Triplets) {
    let (m, ni) = (2 * n as isize, n as isize);
    match rule.order() {
        Some(k) => {
            let mask = binomial_mask(k);
            let first = -((k / 2) as isize) - if k % 2 == 1 && k > 1 { 1 } else { 0 };
            for j in 0..ni {
                for (tt, &w) in mask.iter().enumerate() {
                    t.add(
                        (2 * j + first + tt as isize).rem_euclid(m) as usize,
                        j as usize,
                        w,
                    );
                }
            }
        }
        None => {
            for j in 0..ni {
                let r = 2 * j as usize;
                t.add(r, j as usize, 1.0);
                for (d, w) in [
                    (-1, -1.0 / 16.0),
                    (0, 9.0 / 16.0),
                    (1, 9.0 / 16.0),
                    (2, -1.0 / 16.0),
                ] {
                    t.add(r + 1, (j + d).rem_euclid(ni) as usize, w);
                }
            }
        }
    }
}

fn open(rule: Refinement, n: usize, m: usize, t: &mut Triplets) {
    let both = |t: &mut Triplets, i: usize, row: &[(usize, f64)]| both_ends(t, n, m, i, row);
    match rule {
        Refinement::Box => {
            for j in 0..n {
                t.add(2 * j, j, 1.0);
                t.add(2 * j + 1, j, 1.0);
            }
        }
        Refinement::Linear => {
            for j in 0..n {
                t.add(2 * j, j, 1.0);
                if j + 1 < n {
                    t.add(2 * j + 1, j, 0.5);
                    t.add(2 * j + 1, j + 1, 0.5);
                }
            }
        }
        Refinement::Chaikin => {
            both(t, 0, &[(0, 1.0)]);
            both(t, 1, &[(0, 0.5), (1, 0.5)]);
            for i in 1..n - 2 {
                t.add(2 * i, i, 0.75);
                t.add(2 * i, i + 1, 0.25);
                t.add(2 * i + 1, i, 0.25);
                t.add(2 * i + 1, i + 1, 0.75);
            }
        }
        Refinement::Cubic if n < 6 => clamped_midpoints(4, n, t),
        Refinement::Quartic if n < 8 => clamped_midpoints(5, n, t),
        Refinement::Cubic => open_cubic(n, m, t),
        Refinement::Quartic => open_quartic(n, m, t),
        Refinement::FourPoint => {
            for j in 0..n {
                t.add(2 * j, j, 1.0);
            }
            both(
                t,
                1,
                &[
                    (0, 5.0 / 16.0),
                    (1, 15.0 / 16.0),
                    (2, -5.0 / 16.0),
                    (3, 1.0 / 16.0),
                ],
            );
            for j in 1..n - 2 {
                for (d, w) in [
                    (0, -1.0 / 16.0),
                    (1, 9.0 / 16.0),
                    (2, 9.0 / 16.0),
                    (3, -1.0 / 16.0),
                ] {
                    t.add(2 * j + 1, j - 1 + d, w);
                }
            }
        }
    }
}

/// Row `i` (weights on old points) and its mirror image `m − 1 − i` (on `n − 1 − c`): the
/// `start` rows of an open rule are written for the first points and mirrored for the last.
fn both_ends(t: &mut Triplets, n: usize, m: usize, i: usize, row: &[(usize, f64)]) {
    for &(c, w) in row {
        t.add(i, c, w);
        t.add(m - 1 - i, n - 1 - c, w);
    }
}

/// Open cubic B-spline refinement (`n ≥ 6`): clamped end rows, then `½ ½` and `⅛ ¾ ⅛`.
fn open_cubic(n: usize, m: usize, t: &mut Triplets) {
    let both = |t: &mut Triplets, i: usize, row: &[(usize, f64)]| both_ends(t, n, m, i, row);
    let start: [&[(usize, f64)]; 4] = [
        &[(0, 1.0)],
        &[(0, 0.5), (1, 0.5)],
        &[(1, 0.75), (2, 0.25)],
        &[(1, 3.0 / 16.0), (2, 11.0 / 16.0), (3, 0.125)],
    ];
    for (i, row) in start.iter().enumerate() {
        both(t, i, row);
    }
    for i in 4..m - 4 {
        if i % 2 == 0 {
            t.add(i, i / 2, 0.5);
            t.add(i, i / 2 + 1, 0.5);
        } else {
            let v = i.div_ceil(2);
            t.add(i, v - 1, 0.125);
            t.add(i, v, 0.75);
            t.add(i, v + 1, 0.125);
        }
    }
}

/// Open quartic B-spline refinement (`n ≥ 8`): clamped end rows, then `5/16 ⅝ 1/16` and
/// its mirror image.
fn open_quartic(n: usize, m: usize, t: &mut Triplets) {
    let both = |t: &mut Triplets, i: usize, row: &[(usize, f64)]| both_ends(t, n, m, i, row);
    let start: [&[(usize, f64)]; 6] = [
        &[(0, 1.0)],
        &[(0, 0.5), (1, 0.5)],
        &[(1, 0.75), (2, 0.25)],
        &[(1, 3.0 / 16.0), (2, 11.0 / 16.0), (3, 0.125)],
        &[(2, 5.0 / 12.0), (3, 25.0 / 48.0), (4, 1.0 / 16.0)],
        &[(2, 1.0 / 12.0), (3, 29.0 / 48.0), (4, 5.0 / 16.0)],
    ];
    for (i, row) in start.iter().enumerate() {
        both(t, i, row);
    }
    for i in 6..m - 6 {
        let j = i / 2;
        let w = if i % 2 == 0 {
            [5.0 / 16.0, 0.625, 1.0 / 16.0]
        } else {
            [1.0 / 16.0, 0.625, 5.0 / 16.0]
        };
        for (d, &x) in w.iter().enumerate() {
            t.add(i, j + d, x);
        }
    }
}

/// The open rule of order `k` for `n ≥ k` points as Boehm's insertion of every span's
/// midpoint into the clamped knots (module doc), each new point as weights of the old ones.
fn clamped_midpoints(k: usize, n: usize, t: &mut Triplets) {
    let spans = n + 1 - k;
    let mut knots: Vec<f64> = (0..k).map(|_| 0.0).collect();
    knots.extend((1..spans).map(|j| j as f64));
    knots.extend((0..k).map(|_| spans as f64));
    // rows[i][c]: weight of coarse point c in the current point i (the identity at first)
    let mut rows: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|c| (i == c) as u8 as f64).collect())
        .collect();
    for j in 0..spans {
        let u = j as f64 + 0.5;
        // the span [t_s, t_{s+1}) holding u
        let s = (0..knots.len() - 1)
            .rfind(|&s| knots[s] <= u && u < knots[s + 1])
            .expect("u lies inside the clamped knots");
        let mut next = Vec::with_capacity(rows.len() + 1);
        for i in 0..=rows.len() {
            if i + k - 1 <= s {
                next.push(rows[i].clone());
            } else if i > s {
                next.push(rows[i - 1].clone());
            } else {
                let a = (u - knots[i]) / (knots[i + k - 1] - knots[i]);
                let row = rows[i - 1]
                    .iter()
                    .zip(&rows[i])
                    .map(|(p, q)| (1.0 - a) * p + a * q)
                    .collect();
                next.push(row);
            }
        }
        rows = next;
        let at = knots.partition_point(|&x| x <= u);
        knots.insert(at, u);
    }
    for (i, row) in rows.iter().enumerate() {
        for (c, &w) in row.iter().enumerate() {
            if w != 0.0 {
                t.add(i, c, w);
            }
        }
    }
}

/// One refinement step of `points` (`n` elements of `dim` values, row-major).
pub fn refine(points: &[f64], dim: usize, rule: Refinement, ends: Ends) -> Result<Vec<f64>> {
    if dim == 0 || !points.len().is_multiple_of(dim) {
        return Err(Error::parameter(
            "point data length",
            points.len(),
            "a multiple of the dimension",
        ));
    }
    let n = points.len() / dim;
    let s = matrix(rule, ends, n)?;
    let mut out = vec![0.0; s.rows() * dim];
    s.apply(points, dim, &mut out, dim, dim);
    Ok(out)
}

/// `steps` refinement steps.
pub fn refine_steps(
    points: &[f64],
    dim: usize,
    rule: Refinement,
    ends: Ends,
    steps: usize,
) -> Result<Vec<f64>> {
    let mut p = points.to_vec();
    for _ in 0..steps {
        p = refine(&p, dim, rule, ends)?;
    }
    Ok(p)
}
