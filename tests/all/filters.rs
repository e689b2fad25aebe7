//! The schemes with wide analysis filters (linear 5/3, chaikin-wide, cubic-wide, CDF 9/7): native
//! lengths, interior rows equal to the closed forms and to PyWavelets, the Nyquist zeros that stop
//! aliasing, and the reversible integer lifting of the 5/3 pair. (Perfect reconstruction for every
//! scheme × boundary × length is in `tests/scheme.rs`, which runs over `Scheme::ALL`.)

use mra::scheme::{
    cdf97, chaikin_wide, cubic_wide, linear, linear_wide, Boundary, LevelKind, Scheme, TwoScale,
};
use proptest::prelude::*;

const NEW: [Scheme; 5] = [
    Scheme::Linear,
    Scheme::LinearWide,
    Scheme::ChaikinWide,
    Scheme::CubicWide,
    Scheme::Cdf97,
];

fn regular_of(
    s: Scheme,
) -> (
    &'static [f64],
    &'static [f64],
    &'static [f64],
    &'static [f64],
) {
    match s {
        Scheme::Linear => (&linear::A, &linear::B, &linear::P, &linear::Q),
        Scheme::LinearWide => (
            &linear_wide::A,
            &linear_wide::B,
            &linear_wide::P,
            &linear_wide::Q,
        ),
        Scheme::ChaikinWide => (
            &chaikin_wide::A,
            &chaikin_wide::B,
            &chaikin_wide::P,
            &chaikin_wide::Q,
        ),
        Scheme::CubicWide => (
            &cubic_wide::A,
            &cubic_wide::B,
            &cubic_wide::P,
            &cubic_wide::Q,
        ),
        Scheme::Cdf97 => (&cdf97::A, &cdf97::B, &cdf97::P, &cdf97::Q),
        _ => unreachable!(),
    }
}

#[test]
fn native_lengths_start_where_the_table_says() {
    use Boundary::*;
    let cases = [
        (Scheme::Linear, Interpolating, 5, 2),
        (Scheme::Linear, Periodic, 6, 2),
        (Scheme::Linear, Symmetric, 3, 1),
        (Scheme::LinearWide, Interpolating, 17, 2),
        (Scheme::LinearWide, Periodic, 10, 2),
        (Scheme::LinearWide, Symmetric, 3, 1),
        (Scheme::ChaikinWide, Interpolating, 22, 2),
        (Scheme::ChaikinWide, Periodic, 12, 2),
        (Scheme::ChaikinWide, Symmetric, 3, 1),
        (Scheme::CubicWide, Interpolating, 35, 2),
        (Scheme::CubicWide, Periodic, 20, 2),
        (Scheme::CubicWide, Symmetric, 3, 1),
        (Scheme::Cdf97, Periodic, 10, 2),
        (Scheme::Cdf97, Symmetric, 3, 1),
    ];
    for (s, b, m, step) in cases {
        assert_eq!(
            TwoScale::new(s, b, m).kind,
            LevelKind::Native,
            "{s} {b} {m}"
        );
        assert_eq!(
            TwoScale::new(s, b, m + step).kind,
            LevelKind::Native,
            "{s} {b} {}",
            m + step
        );
        let below = m - step;
        assert_ne!(
            TwoScale::new(s, b, below).kind,
            LevelKind::Native,
            "{s} {b} {below}"
        );
    }
}

fn dense(t: &mra::scheme::sparse::Csr) -> Vec<Vec<f64>> {
    t.to_dense()
}

/// Nonzero run of a row or column, as (first index, weights).
fn run(v: &[f64]) -> (usize, Vec<f64>) {
    let first = v.iter().position(|&x| x != 0.0).unwrap();
    let last = v.iter().rposition(|&x| x != 0.0).unwrap();
    (first, v[first..=last].to_vec())
}

#[test]
fn interior_rows_and_columns_are_the_regular_filters_in_every_mode() {
    for s in NEW {
        let (a, b, p, q) = regular_of(s);
        for boundary in Boundary::ALL {
            // a length native for the mode, long enough for the interior
            let m = (80..90)
                .find(|&m| TwoScale::new(s, boundary, m).kind == LevelKind::Native)
                .unwrap();
            let t = TwoScale::new(s, boundary, m);
            let (n, an, sy) = (t.coarse, dense(&t.analysis), dense(&t.synthesis));
            let j = n / 2;
            let k = (m - n) / 2;
            let (fa, ra) = run(&an[j]);
            assert_eq!(ra, a, "{s} {boundary} m={m}: row {j} of A");
            let (fb, rb) = run(&an[n + k]);
            assert_eq!(rb, b, "{s} {boundary}: row {k} of B");
            let col = |c: usize| -> Vec<f64> { (0..m).map(|i| sy[i][c]).collect() };
            let (fp, rp) = run(&col(j));
            assert_eq!(rp, p, "{s} {boundary}: column {j} of P");
            let (fq, rq) = run(&col(n + k));
            assert_eq!(rq, q, "{s} {boundary}: column {k} of Q");
            // centres: C_j and P column j share one; D_k and Q column k share one
            let centre2 = |f: usize, l: usize| 2 * f + l - 1;
            assert_eq!(centre2(fa, a.len()), centre2(fp, p.len()), "{s} {boundary}");
            assert_eq!(centre2(fb, b.len()), centre2(fq, q.len()), "{s} {boundary}");
        }
    }
}

/// `Σ_t w_t (−1)^t t^z` for z < count: zero means `count` zeros of the filter at ω = π.
fn nyquist_moments(w: &[f64], count: u32) -> Vec<f64> {
    (0..count)
        .map(|z| {
            w.iter()
                .enumerate()
                .map(|(t, &x)| x * if t % 2 == 0 { 1.0 } else { -1.0 } * (t as f64).powi(z as i32))
                .sum()
        })
        .collect()
}

#[test]
fn analysis_filters_have_the_documented_zeros_at_nyquist() {
    // (scheme, zeros of a at π, zeros of p at π)
    for (s, za, zp) in [
        (Scheme::Linear, 2, 2),
        (Scheme::LinearWide, 4, 2),
        (Scheme::ChaikinWide, 3, 3),
        (Scheme::CubicWide, 4, 4),
        (Scheme::Cdf97, 4, 4),
    ] {
        let (a, _, p, _) = regular_of(s);
        for (name, w, z) in [("a", a, za), ("p", p, zp)] {
            let scale: f64 =
                w.iter().map(|x| x.abs()).sum::<f64>() * (w.len() as f64).powi(z as i32);
            for (k, m) in nyquist_moments(w, z).iter().enumerate() {
                assert!(m.abs() < 1e-13 * scale, "{s} {name}: moment {k} = {m}");
            }
            let next = nyquist_moments(w, z + 1)[z as usize];
            assert!(next.abs() > 1e-6, "{s} {name} has more than {z} zeros at π");
        }
    }
    // the notes' regular cubic row passes Nyquist at full gain, Chaikin's has one zero
    let notes_cubic = [0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125];
    assert_eq!(nyquist_moments(&notes_cubic, 1)[0].abs(), 1.0);
}

#[test]
fn chaikin_wide_is_the_window_12_least_squares_row_with_three_zeros_at_nyquist() {
    // closed form (exact fractions)
    let want = [
        -45.0, 135.0, 69.0, -567.0, 4.0, 1620.0, 1620.0, 4.0, -567.0, 69.0, 135.0, -45.0,
    ]
    .map(|x| x / 2432.0);
    assert_eq!(chaikin_wide::A, want);
    // the window-12 least-squares row over F_{−6} … F_5 (P = Chaikin, C_j centred at 2j − ½) is
    // (−9, 27, 3, −81, −1, 243, …) / 364; the scheme's row is a small correction of it
    let ls = least_squares_row(&chaikin_wide::P, -2, -6, 5);
    let closed = [
        -9.0, 27.0, 3.0, -81.0, -1.0, 243.0, 243.0, -1.0, -81.0, 3.0, 27.0, -9.0,
    ];
    for (x, y) in ls.iter().zip(closed.map(|x| x / 364.0)) {
        assert!((x - y).abs() < 1e-14, "{ls:?}");
    }
    let dist: f64 = ls
        .iter()
        .zip(&want)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(
        dist < 0.05,
        "chaikin-wide is a small correction of the LS row: {dist}"
    );
}

#[test]
fn cubic_wide_gives_a_p_equal_identity_and_is_near_the_window_19_least_squares_row() {
    let a = cubic_wide::A;
    let p = cubic_wide::P; // column j at fine rows 2j−2 … 2j+2; a row 0 over F_{−9} … F_9
    for j in -6i64..=6 {
        let mut s = 0.0;
        for (t, &x) in a.iter().enumerate() {
            let i = t as i64 - 9;
            let k = i - 2 * j + 2;
            if (0..5).contains(&k) {
                s += x * p[k as usize];
            }
        }
        let want = if j == 0 { 1.0 } else { 0.0 };
        assert!((s - want).abs() < 1e-14, "(A P)_0,{j} = {s}");
    }
    let ls = least_squares_row(&p, -2, -9, 9);
    let dist: f64 = ls
        .iter()
        .zip(&a)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    let norm: f64 = ls.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(
        dist < 0.05 * norm,
        "cubic-wide is a small correction of the LS row: {dist}"
    );
    // the plain LS row leaks Nyquist, the corrected one does not
    assert!(nyquist_moments(&ls, 1)[0].abs() > 0.05);
}

/// Row of coarse 0 of the local least-squares fit over fine `lo..=hi` for a regular `p` whose
/// column j starts at fine `2j + pfirst`.
fn least_squares_row(p: &[f64], pfirst: i64, lo: i64, hi: i64) -> Vec<f64> {
    let ks: Vec<i64> = (-20..=20)
        .filter(|&k| (lo..=hi).any(|i| (0..p.len() as i64).contains(&(i - 2 * k - pfirst))))
        .collect();
    let rows = (hi - lo + 1) as usize;
    let cols = ks.len();
    let pw = |i: usize, c: usize| -> f64 {
        let d = lo + i as i64 - 2 * ks[c] - pfirst;
        if (0..p.len() as i64).contains(&d) {
            p[d as usize]
        } else {
            0.0
        }
    };
    // normal equations G x = Pᵀ e_i, solved for every i by Gauss–Jordan on [G | Pᵀ]
    let mut g = vec![vec![0.0; cols + rows]; cols];
    for (r, row) in g.iter_mut().enumerate() {
        let (gram, rhs) = row.split_at_mut(cols);
        for (c, x) in gram.iter_mut().enumerate() {
            *x = (0..rows).map(|i| pw(i, r) * pw(i, c)).sum();
        }
        for (i, x) in rhs.iter_mut().enumerate() {
            *x = pw(i, r);
        }
    }
    for c in 0..cols {
        let piv = (c..cols)
            .max_by(|&x, &y| g[x][c].abs().total_cmp(&g[y][c].abs()))
            .unwrap();
        g.swap(c, piv);
        let d = g[c][c];
        for x in g[c].iter_mut() {
            *x /= d;
        }
        for r in 0..cols {
            if r != c {
                let f = g[r][c];
                let row_c = g[c].clone();
                for (x, y) in g[r].iter_mut().zip(row_c) {
                    *x -= f * y;
                }
            }
        }
    }
    let k0 = ks.iter().position(|&k| k == 0).unwrap();
    g[k0][cols..].to_vec()
}

#[test]
fn cdf97_is_the_closed_form_of_the_degree_3_daubechies_factorisation() {
    // a(ω) = cos⁴(ω/2) P₄(y) / (1 − y/y_r), p(ω) = 2 cos⁴(ω/2) (1 − y/y_r), y = sin²(ω/2)
    let p4 = |y: f64| 1.0 + 4.0 * y + 10.0 * y * y + 20.0 * y * y * y;
    // the real root of P₄ by Newton
    let mut yr = -0.34f64;
    for _ in 0..60 {
        yr -= p4(yr) / (4.0 + 20.0 * yr + 60.0 * yr * yr);
    }
    for k in 0..=16 {
        let w = std::f64::consts::PI * k as f64 / 16.0;
        let (c, y) = ((w / 2.0).cos().powi(4), (w / 2.0).sin().powi(2));
        let resp = |f: &[f64]| -> f64 {
            let h = (f.len() / 2) as f64;
            f.iter()
                .enumerate()
                .map(|(t, &x)| x * ((t as f64 - h) * w).cos())
                .sum()
        };
        let a = c * p4(y) / (1.0 - y / yr);
        let p = 2.0 * c * (1.0 - y / yr);
        assert!((resp(&cdf97::A) - a).abs() < 1e-14, "a at ω = {w}");
        assert!((resp(&cdf97::P) - p).abs() < 1e-14, "p at ω = {w}");
    }
}

fn pywt_bank(name: &str) -> serde_json::Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/reference/pywt_filters.json"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v[name].clone()
}

/// A pywt filter without its zero padding, scaled by `scale`.
fn trimmed(v: &serde_json::Value, scale: f64) -> Vec<f64> {
    let x: Vec<f64> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() * scale)
        .collect();
    let (_, r) = run(&x);
    r
}

#[test]
fn linear_linear_wide_and_cdf97_are_pywavelets_bior22_bior24_and_bior44() {
    let r2 = std::f64::consts::SQRT_2;
    for (scheme, name) in [
        (Scheme::Linear, "bior2.2"),
        (Scheme::LinearWide, "bior2.4"),
        (Scheme::Cdf97, "bior4.4"),
    ] {
        let (a, b, p, q) = regular_of(scheme);
        let w = pywt_bank(name);
        // dec_lo reversed = analysis row (symmetric, so as is), rec_lo = synthesis column
        let close = |x: &[f64], y: &[f64], what: &str| {
            assert_eq!(x.len(), y.len(), "{name} {what}");
            let sign = if (x[x.len() / 2] > 0.0) == (y[y.len() / 2] > 0.0) {
                1.0
            } else {
                -1.0
            };
            for (u, v) in x.iter().zip(y) {
                assert!(
                    (u - sign * v).abs() < 1e-12,
                    "{name} {what}: {x:?} vs {y:?}"
                );
            }
        };
        close(a, &trimmed(&w["dec_lo"], 1.0 / r2), "a = dec_lo/√2");
        close(p, &trimmed(&w["rec_lo"], r2), "p = rec_lo·√2");
        // the highpass pair up to sign and the √2 split between b and q
        let mut dh = trimmed(&w["dec_hi"], r2);
        dh.reverse();
        close(b, &dh, "b = reversed dec_hi·√2");
        close(q, &trimmed(&w["rec_hi"], 1.0 / r2), "q = rec_hi/√2");
    }
}

fn lcg_ints(seed: u64, n: usize, range: i64) -> Vec<i64> {
    let mut x = seed | 1;
    (0..n)
        .map(|_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 33) as i64 % (2 * range + 1)) - range
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn integer_lifting_is_exactly_reversible(len in 1usize..=300, seed in any::<u64>(), bits in 1u32..=24) {
        let x = lcg_ints(seed, len, 1i64 << bits);
        let mut y = x.clone();
        let mut scratch = vec![0i64; len];
        linear::lift_forward(&mut y, &mut scratch);
        linear::lift_inverse(&mut y, &mut scratch);
        prop_assert_eq!(y, x);
    }
}

#[test]
fn integer_lifting_rounds_the_linear_scheme_symmetric_level() {
    for m in 3..=65usize {
        let x = lcg_ints(m as u64, m, 1000);
        let mut lifted = x.clone();
        let mut scratch = vec![0i64; m];
        linear::lift_forward(&mut lifted, &mut scratch);
        let t = TwoScale::new(Scheme::Linear, Boundary::Symmetric, m);
        assert_eq!(t.coarse, m.div_ceil(2));
        let f: Vec<f64> = x.iter().map(|&v| v as f64).collect();
        let mut packed = vec![0.0; m];
        t.decompose(&f, 1, &mut packed);
        for i in 0..m {
            let d = (lifted[i] as f64 - packed[i]).abs();
            // details are rounded once (≤ ½), coarse samples twice (≤ ½ + ¼·(½ + ½))
            let bound = if i < t.coarse { 1.0 } else { 0.5 };
            assert!(
                d <= bound,
                "m={m} i={i}: lifted {} vs {}",
                lifted[i],
                packed[i]
            );
        }
    }
}
