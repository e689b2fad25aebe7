//! A small compressed-sparse-row matrix and a Jacobi-preconditioned conjugate-gradient solver,
//! enough for the Laplacian systems of implicit smoothing (§6.6.2).

use crate::{Error, Result};

/// Square sparse matrix in CSR form.
#[derive(Clone, Debug, PartialEq)]
pub struct Csr {
    pub n: usize,
    pub row_start: Vec<usize>,
    pub col: Vec<u32>,
    pub val: Vec<f64>,
}

impl Csr {
    /// Assemble from (row, col, value) triplets; duplicates are summed.
    pub fn from_triplets(n: usize, mut t: Vec<(u32, u32, f64)>) -> Csr {
        t.sort_unstable_by_key(|&(r, c, _)| ((r as u64) << 32) | c as u64);
        let mut row_start = vec![0usize; n + 1];
        let mut col = Vec::with_capacity(t.len());
        let mut val: Vec<f64> = Vec::with_capacity(t.len());
        let mut last: Option<(u32, u32)> = None;
        for (r, c, v) in t {
            if last == Some((r, c)) {
                *val.last_mut().unwrap() += v;
            } else {
                col.push(c);
                val.push(v);
                row_start[r as usize + 1] += 1;
                last = Some((r, c));
            }
        }
        for i in 0..n {
            row_start[i + 1] += row_start[i];
        }
        Csr {
            n,
            row_start,
            col,
            val,
        }
    }

    /// Entry (i, j), zero when absent.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let r = self.row_start[i]..self.row_start[i + 1];
        match self.col[r.clone()].binary_search(&(j as u32)) {
            Ok(k) => self.val[r.start + k],
            Err(_) => 0.0,
        }
    }

    /// y = A x for a column of 3-vectors.
    pub fn mul3(&self, x: &[[f64; 3]], y: &mut [[f64; 3]]) {
        use rayon::prelude::*;
        y.par_iter_mut()
            .with_min_len(2048)
            .enumerate()
            .for_each(|(i, yi)| {
                let mut s = [0.0; 3];
                for k in self.row_start[i]..self.row_start[i + 1] {
                    let xj = x[self.col[k] as usize];
                    let a = self.val[k];
                    s[0] += a * xj[0];
                    s[1] += a * xj[1];
                    s[2] += a * xj[2];
                }
                *yi = s;
            });
    }

    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.n).map(|i| self.get(i, i)).collect()
    }
}

/// Solve A X = B (three right-hand sides at once) for symmetric positive definite A by
/// conjugate gradients with a Jacobi preconditioner, to relative residual `tol`.
pub fn conjugate_gradient(
    a: &Csr,
    b: &[[f64; 3]],
    x0: &[[f64; 3]],
    tol: f64,
    max_iter: usize,
) -> Result<Vec<[f64; 3]>> {
    let n = a.n;
    let dinv: Vec<f64> = a
        .diagonal()
        .iter()
        .map(|&d| if d != 0.0 { 1.0 / d } else { 1.0 })
        .collect();
    let mut x = x0.to_vec();
    let mut ax = vec![[0.0; 3]; n];
    a.mul3(&x, &mut ax);
    let mut r: Vec<[f64; 3]> = (0..n)
        .map(|i| std::array::from_fn(|k| b[i][k] - ax[i][k]))
        .collect();
    let mut z: Vec<[f64; 3]> = (0..n)
        .map(|i| std::array::from_fn(|k| dinv[i] * r[i][k]))
        .collect();
    let mut p = z.clone();
    let dot = |u: &[[f64; 3]], v: &[[f64; 3]]| -> [f64; 3] {
        let mut s = [0.0; 3];
        for i in 0..u.len() {
            for k in 0..3 {
                s[k] += u[i][k] * v[i][k];
            }
        }
        s
    };
    let bnorm = dot(b, b).map(|s| s.sqrt().max(1e-300));
    let mut rz = dot(&r, &z);
    let mut ap = vec![[0.0; 3]; n];
    for _ in 0..max_iter {
        let rr = dot(&r, &r);
        if (0..3).all(|k| rr[k].sqrt() <= tol * bnorm[k]) {
            return Ok(x);
        }
        a.mul3(&p, &mut ap);
        let pap = dot(&p, &ap);
        let alpha: [f64; 3] =
            std::array::from_fn(|k| if pap[k] != 0.0 { rz[k] / pap[k] } else { 0.0 });
        for i in 0..n {
            for k in 0..3 {
                x[i][k] += alpha[k] * p[i][k];
                r[i][k] -= alpha[k] * ap[i][k];
                z[i][k] = dinv[i] * r[i][k];
            }
        }
        let rz_new = dot(&r, &z);
        let beta: [f64; 3] =
            std::array::from_fn(|k| if rz[k] != 0.0 { rz_new[k] / rz[k] } else { 0.0 });
        rz = rz_new;
        for i in 0..n {
            for k in 0..3 {
                p[i][k] = z[i][k] + beta[k] * p[i][k];
            }
        }
    }
    Err(Error::LimitsExceeded {
        what: "conjugate-gradient iterations",
        requested: max_iter as u64 + 1,
        limit: max_iter as u64,
    })
}
