//! Eigen-analysis of uniform curve subdivision schemes (notes §7.5.1, §7.6.1).
//!
//! A scheme is given by its mask `a_0 … a_{L−1}`: `F_i = Σ_j a_{i−2j} C_j`. The even-indexed and
//! odd-indexed mask entries are the two rules (e.g. Chaikin `¼ ¾ ¾ ¼`, cubic `⅛ ½ ¾ ½ ⅛`,
//! Dyn–Levin `−1/16 0 9/16 1 9/16 0 −1/16`). Local analysis looks at `N` consecutive coarse points
//! and the `N` fine points that depend only on them: `L^{j+1} = S L^j` with
//!
//! ```text
//! S[r][c] = a_{i0 + r − 2c},   i0 = (N + L − 2)/2   (windows centred on the same parameter)
//! ```
//!
//! (for odd `N + L` the fine window sits half a step to either side; the first invariant one is
//! used). `N = L` is the notes' choice (4 points for Chaikin, 5 for cubic, Figure 7.4; 7 for the
//! four-point scheme) and always leaves the window invariant. The scheme is affine invariant
//! when both rules sum to one (then `S·1 = 1`). If the spectrum reads `1 > |λ_1|` and
//! `λ_j = 2^{−j}` for `j ≤ m` with `|λ_{m+1}| < 2^{−m}`, it is consistent with a `C^m` limit
//! curve — a necessary condition suggested by the spectrum, not a proof.

use super::eigen::{eigenvalues, Eigenvalue};
use crate::{Error, Result};

/// The result of analysing one mask.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// The mask as given.
    pub mask: Vec<f64>,
    /// The local subdivision matrix, `n × n`, row-major.
    pub matrix: Vec<f64>,
    /// Its size.
    pub n: usize,
    /// Eigenvalues by decreasing modulus.
    pub eigenvalues: Vec<Eigenvalue>,
    /// Both rules (even and odd mask entries) sum to one.
    pub affine_invariant: bool,
    /// Smoothness order `m` suggested by the spectrum (`C^m`), or `None` when the leading
    /// eigenvalue is not a simple, dominant 1 (no convergent, continuous limit suggested).
    pub smoothness: Option<usize>,
}

/// The masks of the named schemes of the notes (Table 1 and §7.6.1).
pub fn named_mask(name: &str) -> Option<Vec<f64>> {
    let m: Vec<f64> = match name {
        "box" | "haar" => vec![1.0, 1.0],
        "linear" | "faber" => vec![0.5, 1.0, 0.5],
        "chaikin" => vec![0.25, 0.75, 0.75, 0.25],
        "cubic" => vec![0.125, 0.5, 0.75, 0.5, 0.125],
        "quartic" => [1.0, 5.0, 10.0, 10.0, 5.0, 1.0]
            .iter()
            .map(|x| x / 16.0)
            .collect(),
        "four-point" | "dyn-levin" => [-1.0, 0.0, 9.0, 16.0, 9.0, 0.0, -1.0]
            .iter()
            .map(|x| x / 16.0)
            .collect(),
        _ => return None,
    };
    Some(m)
}

/// Parse a mask such as `"1/16,-1/16,9/16"` or `"0.25 0.75 0.75 0.25"` (fractions or decimals,
/// separated by commas or spaces).
pub fn parse_mask(text: &str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    for tok in text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
    {
        let v = if let Some((a, b)) = tok.split_once('/') {
            let a: f64 = a.trim().parse().map_err(|_| bad(tok))?;
            let b: f64 = b.trim().parse().map_err(|_| bad(tok))?;
            if b == 0.0 {
                return Err(bad(tok));
            }
            a / b
        } else {
            tok.parse().map_err(|_| bad(tok))?
        };
        if !v.is_finite() {
            return Err(bad(tok));
        }
        out.push(v);
    }
    if out.len() < 2 {
        return Err(Error::parameter(
            "mask length",
            out.len(),
            "at least 2 coefficients",
        ));
    }
    Ok(out)
}

fn bad(tok: &str) -> Error {
    Error::parameter("mask coefficient", tok, "a number or a fraction like 9/16")
}

/// Candidate offsets `i0` of the fine window: centred, `(n + L − 2)/2`, when `n + L` is even;
/// otherwise the two half-step neighbours (dual schemes on odd windows, e.g. Chaikin with 3).
fn offsets(n: usize, l: usize) -> Vec<usize> {
    if n + l < 2 {
        return vec![];
    }
    if (n + l).is_multiple_of(2) {
        vec![(n + l - 2) / 2]
    } else if n + l >= 3 {
        vec![(n + l - 3) / 2, (n + l - 1) / 2]
    } else {
        vec![]
    }
}

/// The `n × n` local subdivision matrix `S[r][c] = a_{i0 + r − 2c}` (row-major).
pub fn local_matrix(mask: &[f64], n: usize, i0: usize) -> Vec<f64> {
    let l = mask.len();
    let mut s = vec![0.0; n * n];
    for r in 0..n {
        for c in 0..n {
            let j = (i0 + r) as isize - 2 * c as isize;
            if j >= 0 && (j as usize) < l {
                s[r * n + c] = mask[j as usize];
            }
        }
    }
    s
}

/// True when fine points `i0 … i0 + n − 1` depend only on coarse points `0 … n − 1`.
pub fn window_is_invariant(mask: &[f64], n: usize, i0: usize) -> bool {
    for r in 0..n {
        for (idx, &a) in mask.iter().enumerate() {
            if a == 0.0 {
                continue;
            }
            let num = (i0 + r) as isize - idx as isize;
            if num % 2 == 0 {
                let j = num / 2;
                if j < 0 || j >= n as isize {
                    return false;
                }
            }
        }
    }
    true
}

/// Analyse `mask` on a window of `n` points (default `n = L`, the mask length).
pub fn analyze(mask: &[f64], n: Option<usize>) -> Result<Analysis> {
    let l = mask.len();
    let n = n.unwrap_or(l);
    let i0 = offsets(n, l)
        .into_iter()
        .find(|&i0| n > 0 && window_is_invariant(mask, n, i0))
        .ok_or_else(|| {
            Error::parameter(
                "window size",
                n,
                "a window whose fine points depend only on its coarse points (the mask length always is)",
            )
        })?;
    let matrix = local_matrix(mask, n, i0);
    let eigenvalues = eigenvalues(&matrix, n)?;
    let even: f64 = mask.iter().step_by(2).sum();
    let odd: f64 = mask.iter().skip(1).step_by(2).sum();
    let affine_invariant = (even - 1.0).abs() < 1e-12 && (odd - 1.0).abs() < 1e-12;
    let smoothness = suggested_smoothness(&eigenvalues);
    Ok(Analysis {
        mask: mask.to_vec(),
        matrix,
        n,
        eigenvalues,
        affine_invariant,
        smoothness,
    })
}

/// `C^m` suggested by a spectrum sorted by decreasing modulus (see the module doc):
/// `λ_0 = 1 > |λ_1|`, then `m` grows while `λ_{m+1} = 2^{−(m+1)}` and `|λ_{m+2}| < 2^{−(m+1)}`.
pub fn suggested_smoothness(ev: &[Eigenvalue]) -> Option<usize> {
    // defective eigenvalues (Jordan blocks) are only accurate to about √ε: tolerance 1e-6
    const TOL: f64 = 1e-6;
    let close = |e: &Eigenvalue, v: f64| (e.re - v).abs() < TOL && e.im.abs() < TOL;
    if ev.is_empty() || !close(&ev[0], 1.0) {
        return None;
    }
    if ev.len() > 1 && ev[1].modulus() >= 1.0 - TOL {
        return None;
    }
    let mut m = 0;
    while let Some(e) = ev.get(m + 1) {
        let target = 0.5f64.powi(m as i32 + 1);
        let rest_smaller = ev.get(m + 2).is_none_or(|f| f.modulus() < target - TOL);
        if close(e, target) && rest_smaller {
            m += 1;
        } else {
            break;
        }
    }
    Some(m)
}
