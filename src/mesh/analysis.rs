//! Eigen analysis of the local subdivision matrix at an extraordinary vertex (§7.5.1).
//!
//! The local matrix S maps the coarse neighbourhood of a vertex of valence n to the same
//! neighbourhood one level finer:
//!
//! ```text
//!   Loop (1-ring, n + 1 points: v, e_1..e_n):
//!       v' = (1 − nβ) v + β Σ e_j,   e'_j = 3/8 v + 3/8 e_j + 1/8 (e_{j−1} + e_{j+1})
//!   Catmull-Clark (quads around v, 2n + 1 points: v, edge neighbours e_j, diagonal d_j):
//!       f'_j = ¼ (v + e_j + d_j + e_{j+1}),   e'_j = ¼ (v + e_j + f'_{j−1} + f'_j),
//!       v'   = (n−2)/n v + 1/n² Σ e_j + 1/n² Σ f'_j           (the rows use f'_j as d'_j)
//! ```
//!
//! S is block-circulant around the centre, so the discrete Fourier transform splits it into
//! one block per frequency k = 0..n−1 (the centre only couples to k = 0):
//! `B_k[s][t] = Σ_m S[(s,0),(t,m)] ω^{km}`, ω = e^{2πi/n}. Each block has size ≤ 3; its
//! eigenvalues come in closed form (see `small_eigenvalues`). Results are real up to rounding and are returned sorted descending.

use super::loop_subdivision::{beta, LoopWeights};
use crate::{Error, Result};
use std::f64::consts::PI;

/// Surface schemes with a local analysis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    Loop(LoopWeights),
    CatmullClark,
}

impl Surface {
    pub fn parse(s: &str) -> Result<Surface> {
        match s {
            "loop" => Ok(Surface::Loop(LoopWeights::Loop)),
            "loop-warren" => Ok(Surface::Loop(LoopWeights::Warren)),
            "catmull-clark" | "cc" => Ok(Surface::CatmullClark),
            _ => Err(Error::parameter(
                "surface scheme",
                s,
                "loop, loop-warren or catmull-clark",
            )),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct C(f64, f64);

impl C {
    fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    fn sub(self, o: C) -> C {
        C(self.0 - o.0, self.1 - o.1)
    }
    fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn scale(self, s: f64) -> C {
        C(self.0 * s, self.1 * s)
    }
    fn abs(self) -> f64 {
        self.0.hypot(self.1)
    }
}

/// The dense local subdivision matrix (row-major, size N × N) and the number of ring types.
pub fn local_matrix(scheme: Surface, n: usize) -> Result<(Vec<f64>, usize, usize)> {
    if !(3..=64).contains(&n) {
        return Err(Error::parameter("valence", n, "3 to 64"));
    }
    match scheme {
        Surface::Loop(w) => {
            let size = n + 1;
            let mut s = vec![0.0; size * size];
            let b = beta(n, w);
            s[0] = 1.0 - n as f64 * b;
            for j in 0..n {
                s[1 + j] = b;
                let r = (1 + j) * size;
                s[r] = 3.0 / 8.0;
                s[r + 1 + j] += 3.0 / 8.0;
                s[r + 1 + (j + n - 1) % n] += 1.0 / 8.0;
                s[r + 1 + (j + 1) % n] += 1.0 / 8.0;
            }
            Ok((s, size, 1))
        }
        Surface::CatmullClark => {
            // indices: 0 = v, 1 + j = e_j, 1 + n + j = d_j
            let size = 2 * n + 1;
            let e = |j: usize| 1 + j % n;
            let d = |j: usize| 1 + n + j % n;
            // face point rows f'_j as vectors over the coarse points
            let face = |j: usize| {
                let mut r = vec![0.0; size];
                r[0] += 0.25;
                r[e(j)] += 0.25;
                r[d(j)] += 0.25;
                r[e(j + 1)] += 0.25;
                r
            };
            let mut s = vec![0.0; size * size];
            let nf = n as f64;
            s[0] = (nf - 2.0) / nf;
            for j in 0..n {
                s[e(j)] += 1.0 / (nf * nf);
                for (k, x) in face(j).iter().enumerate() {
                    s[k] += x / (nf * nf);
                }
                let re = e(j) * size;
                s[re] += 0.25;
                s[re + e(j)] += 0.25;
                for (k, x) in face(j + n - 1).iter().chain(face(j).iter()).enumerate() {
                    s[re + k % size] += 0.25 * x;
                }
                let rd = d(j) * size;
                for (k, x) in face(j).iter().enumerate() {
                    s[rd + k] += x;
                }
            }
            Ok((s, size, 2))
        }
    }
}

fn csqrt(z: C) -> C {
    let r = z.abs();
    let re = ((r + z.0) / 2.0).max(0.0).sqrt();
    let im = ((r - z.0) / 2.0).max(0.0).sqrt();
    C(re, if z.1 < 0.0 { -im } else { im })
}

/// Roots of λ² − p λ + q.
fn quadratic(p: C, q: C) -> [C; 2] {
    let h = p.scale(0.5);
    let s = csqrt(h.mul(h).sub(q));
    [h.add(s), h.sub(s)]
}

/// Eigenvalues of a block of size 1, 2 or 3. Size 3 only occurs for the k = 0 block, whose
/// rows sum to 1 (affine invariance), so 1 is an eigenvalue and the other two solve
/// λ² − (tr − 1) λ + det = 0. Closed forms keep double eigenvalues exact (a polynomial root
/// finder would give them only to √ε).
fn small_eigenvalues(a: &[C], m: usize) -> Vec<C> {
    match m {
        1 => vec![a[0]],
        2 => {
            let tr = a[0].add(a[3]);
            let det = a[0].mul(a[3]).sub(a[1].mul(a[2]));
            quadratic(tr, det).to_vec()
        }
        _ => {
            let e = |i: usize, j: usize| a[i * 3 + j];
            let tr = e(0, 0).add(e(1, 1)).add(e(2, 2));
            let det = e(0, 0)
                .mul(e(1, 1).mul(e(2, 2)).sub(e(1, 2).mul(e(2, 1))))
                .sub(e(0, 1).mul(e(1, 0).mul(e(2, 2)).sub(e(1, 2).mul(e(2, 0)))))
                .add(e(0, 2).mul(e(1, 0).mul(e(2, 1)).sub(e(1, 1).mul(e(2, 0)))));
            let [x, y] = quadratic(tr.sub(C(1.0, 0.0)), det);
            vec![C(1.0, 0.0), x, y]
        }
    }
}

/// Eigenvalues (sorted descending) of the local subdivision matrix of `scheme` at a vertex
/// of valence `valence` (Loop: n + 1 of them; Catmull-Clark: 2n + 1).
pub fn local_eigenvalues(scheme: Surface, valence: usize) -> Result<Vec<f64>> {
    let (s, size, types) = local_matrix(scheme, valence)?;
    let n = valence;
    let row = |t: usize| 1 + t * n; // first index of ring type t
    let mut out = Vec::with_capacity(size);
    for k in 0..n {
        let w = |m: usize| {
            let a = 2.0 * PI * (k * m % n) as f64 / n as f64;
            C(a.cos(), a.sin())
        };
        let centre = k == 0;
        let m = types + centre as usize;
        let off = centre as usize;
        let mut b = vec![C(0.0, 0.0); m * m];
        if centre {
            b[0] = C(s[0], 0.0);
            for t in 0..types {
                let mut sum = 0.0;
                for j in 0..n {
                    sum += s[row(t) + j];
                }
                b[1 + t] = C(sum, 0.0);
                b[(1 + t) * m] = C(s[row(t) * size], 0.0);
            }
        }
        for si in 0..types {
            for t in 0..types {
                let mut acc = C(0.0, 0.0);
                for j in 0..n {
                    acc = acc.add(w(j).scale(s[row(si) * size + row(t) + j]));
                }
                b[(off + si) * m + off + t] = acc;
            }
        }
        for z in small_eigenvalues(&b, m) {
            out.push(z.0);
        }
    }
    out.sort_by(|a, b| b.total_cmp(a));
    Ok(out)
}
