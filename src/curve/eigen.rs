//! Eigenvalues of small dense real matrices (not necessarily symmetric), for the local
//! subdivision matrices of §7.5.1.
//!
//! Two classical steps: reduction to upper Hessenberg form by stabilised elementary similarity
//! transforms (Gaussian elimination with partial pivoting, `A ← M⁻¹ A M`), then the Francis
//! double-shift QR iteration on the Hessenberg matrix, deflating 1×1 and 2×2 blocks from the
//! bottom (EISPACK `hqr`; Golub & Van Loan §7.5). Complex eigenvalues come in conjugate pairs.
//! Written here rather than pulling in `nalgebra`: the matrices are at most a few dozen rows and
//! this keeps the crate's compile time down.

// Index loops follow the formulas of the notes (several arrays indexed together).
#![allow(clippy::needless_range_loop)]

use crate::{Error, Result};

/// A (possibly complex) eigenvalue `re + i·im`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eigenvalue {
    pub re: f64,
    pub im: f64,
}

impl Eigenvalue {
    /// `|λ|`.
    pub fn modulus(&self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// All eigenvalues of the `n × n` row-major matrix `a`, sorted by decreasing modulus (ties:
/// larger real part first).
pub fn eigenvalues(a: &[f64], n: usize) -> Result<Vec<Eigenvalue>> {
    if a.len() != n * n {
        return Err(Error::parameter("matrix size", a.len(), "n × n entries"));
    }
    if let Some(x) = a.iter().find(|x| !x.is_finite()) {
        return Err(Error::parameter("matrix entry", x, "a finite number"));
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    let mut m: Vec<Vec<f64>> = (0..n).map(|i| a[i * n..(i + 1) * n].to_vec()).collect();
    hessenberg(&mut m);
    let mut ev = hqr(&mut m)?;
    ev.sort_by(|x, y| {
        y.modulus()
            .partial_cmp(&x.modulus())
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(y.re.partial_cmp(&x.re).unwrap_or(std::cmp::Ordering::Equal))
    });
    Ok(ev)
}

/// Reduce to upper Hessenberg form in place (similarity, so eigenvalues are kept).
fn hessenberg(a: &mut [Vec<f64>]) {
    let n = a.len();
    for m in 1..n.saturating_sub(1) {
        // pivot: largest |a[j][m-1]| for j >= m
        let mut x: f64 = 0.0;
        let mut piv = m;
        for (j, row) in a.iter().enumerate().skip(m) {
            if row[m - 1].abs() > x.abs() {
                x = row[m - 1];
                piv = j;
            }
        }
        if piv != m {
            a.swap(piv, m);
            for row in a.iter_mut() {
                row.swap(piv, m);
            }
        }
        if x != 0.0 {
            for i in m + 1..n {
                let mut y = a[i][m - 1];
                if y != 0.0 {
                    y /= x;
                    a[i][m - 1] = y;
                    for j in m..n {
                        a[i][j] -= y * a[m][j];
                    }
                    for row in a.iter_mut() {
                        row[m] += y * row[i];
                    }
                }
            }
        }
    }
    // clear the multipliers left below the subdiagonal
    for (i, row) in a.iter_mut().enumerate() {
        for v in row.iter_mut().take(i.saturating_sub(1)) {
            *v = 0.0;
        }
    }
}

fn sign(a: f64, b: f64) -> f64 {
    if b >= 0.0 {
        a.abs()
    } else {
        -a.abs()
    }
}

/// Francis double-shift QR on an upper Hessenberg matrix (destroyed).
fn hqr(a: &mut [Vec<f64>]) -> Result<Vec<Eigenvalue>> {
    let n = a.len();
    let mut wr = vec![0.0; n];
    let mut wi = vec![0.0; n];
    let mut anorm = 0.0;
    for i in 0..n {
        for j in i.saturating_sub(1)..n {
            anorm += a[i][j].abs();
        }
    }
    let mut nn = n as isize - 1;
    let mut t = 0.0;
    while nn >= 0 {
        let mut its = 0;
        loop {
            let nu = nn as usize;
            // look for a single small subdiagonal element
            let mut l = nu;
            while l >= 1 {
                let mut s = a[l - 1][l - 1].abs() + a[l][l].abs();
                if s == 0.0 {
                    s = anorm;
                }
                if a[l][l - 1].abs() + s == s {
                    a[l][l - 1] = 0.0;
                    break;
                }
                l -= 1;
            }
            let mut x = a[nu][nu];
            if l == nu {
                // one root found
                wr[nu] = x + t;
                wi[nu] = 0.0;
                nn -= 1;
                break;
            }
            let mut y = a[nu - 1][nu - 1];
            let mut w = a[nu][nu - 1] * a[nu - 1][nu];
            if l == nu - 1 {
                // two roots found
                let p = 0.5 * (y - x);
                let q = p * p + w;
                let mut z = q.abs().sqrt();
                x += t;
                if q >= 0.0 {
                    z = p + sign(z, p);
                    wr[nu - 1] = x + z;
                    wr[nu] = x + z;
                    if z != 0.0 {
                        wr[nu] = x - w / z;
                    }
                    wi[nu - 1] = 0.0;
                    wi[nu] = 0.0;
                } else {
                    wr[nu - 1] = x + p;
                    wr[nu] = x + p;
                    wi[nu - 1] = -z;
                    wi[nu] = z;
                }
                nn -= 2;
                break;
            }
            if its == 60 {
                return Err(Error::LimitsExceeded {
                    what: "QR iterations for one eigenvalue",
                    requested: its,
                    limit: 60,
                });
            }
            if its == 10 || its == 20 || its == 40 {
                // exceptional shift
                t += x;
                for (i, row) in a.iter_mut().enumerate().take(nu + 1) {
                    row[i] -= x;
                }
                let s = a[nu][nu - 1].abs() + a[nu - 1][nu - 2].abs();
                x = 0.75 * s;
                y = x;
                w = -0.4375 * s * s;
            }
            its += 1;
            // form the shift and look for two consecutive small subdiagonal elements
            let (m, [p, q, r]) = shift_start(a, [l, nu], [x, y, w]);
            for i in m + 2..=nu {
                a[i][i - 2] = 0.0;
                if i != m + 2 {
                    a[i][i - 3] = 0.0;
                }
            }
            // double QR step on rows l..nn and columns m..nn
            double_qr_step(a, [l, m, nu], [p, q, r]);
        }
    }
    Ok(wr
        .into_iter()
        .zip(wi)
        .map(|(re, im)| Eigenvalue { re, im })
        .collect())
}

/// The row `m ≥ l` where the double shift of `[x, y, w]` starts (two consecutive small
/// subdiagonal elements, or `l`), and the shift's first column `[p, q, r]` there, scaled.
fn shift_start(a: &[Vec<f64>], [l, nu]: [usize; 2], [x, y, w]: [f64; 3]) -> (usize, [f64; 3]) {
    let mut m = nu - 2;
    let mut z;
    let (mut p, mut q, mut r);
    loop {
        z = a[m][m];
        let r0 = x - z;
        let s0 = y - z;
        p = (r0 * s0 - w) / a[m + 1][m] + a[m][m + 1];
        q = a[m + 1][m + 1] - z - r0 - s0;
        r = a[m + 2][m + 1];
        let s = p.abs() + q.abs() + r.abs();
        p /= s;
        q /= s;
        r /= s;
        if m == l {
            break;
        }
        let u = a[m][m - 1].abs() * (q.abs() + r.abs());
        let v = p.abs() * (a[m - 1][m - 1].abs() + z.abs() + a[m + 1][m + 1].abs());
        if u + v == v {
            break;
        }
        m -= 1;
    }
    (m, [p, q, r])
}

/// One Francis double-shift QR step on rows `l..=nu` and columns `m..=nu` of `a`, from the
/// shift's first column `[p, q, r]` at row `m`.
fn double_qr_step(a: &mut [Vec<f64>], [l, m, nu]: [usize; 3], [p, q, r]: [f64; 3]) {
    let (mut p, mut q, mut r) = (p, q, r);
    let mut x = 0.0;
    let mut k = m;
    while k < nu {
        if k != m {
            p = a[k][k - 1];
            q = a[k + 1][k - 1];
            r = 0.0;
            if k != nu - 1 {
                r = a[k + 2][k - 1];
            }
            x = p.abs() + q.abs() + r.abs();
            if x != 0.0 {
                p /= x;
                q /= x;
                r /= x;
            }
        }
        let s = sign((p * p + q * q + r * r).sqrt(), p);
        if s != 0.0 {
            if k == m {
                if l != m {
                    a[k][k - 1] = -a[k][k - 1];
                }
            } else {
                a[k][k - 1] = -s * x;
            }
            p += s;
            x = p / s;
            let y = q / s;
            let z = r / s;
            q /= p;
            r /= p;
            for j in k..=nu {
                let mut pp = a[k][j] + q * a[k + 1][j];
                if k != nu - 1 {
                    pp += r * a[k + 2][j];
                    a[k + 2][j] -= pp * z;
                }
                a[k + 1][j] -= pp * y;
                a[k][j] -= pp * x;
            }
            let mmin = if nu < k + 3 { nu } else { k + 3 };
            for row in a.iter_mut().take(mmin + 1).skip(l) {
                let mut pp = x * row[k] + y * row[k + 1];
                if k != nu - 1 {
                    pp += z * row[k + 2];
                    row[k + 2] -= pp * r;
                }
                row[k + 1] -= pp * q;
                row[k] -= pp;
            }
        }
        k += 1;
    }
}
