//! Subdivision rules: worked examples, affine invariance, interpolation, and the
//! eigenvalues 1, ½, ¼, ¼ of the local subdivision matrices of §7.5.1 and §7.6.1.

use mra::scheme::subdivide::{matrix, refine, refine_steps, Ends, Refinement};

const SQUARE: [f64; 8] = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];

#[test]
fn chaikin_cuts_the_corners_of_a_square() {
    let f = refine(&SQUARE, 2, Refinement::Chaikin, Ends::Closed).unwrap();
    let want = [
        0.25, 0.0, 0.75, 0.0, 1.0, 0.25, 1.0, 0.75, 0.75, 1.0, 0.25, 1.0, 0.0, 0.75, 0.0, 0.25,
    ];
    assert_eq!(f, want);
}

#[test]
fn cubic_subdivision_of_a_square_by_hand() {
    // F_{2j} = ⅛C_{j−1} + ¾C_j + ⅛C_{j+1},  F_{2j+1} = ½(C_j + C_{j+1})
    let f = refine(&SQUARE, 2, Refinement::Cubic, Ends::Closed).unwrap();
    let want = [
        0.125, 0.125, 0.5, 0.0, 0.875, 0.125, 1.0, 0.5, 0.875, 0.875, 0.5, 1.0, 0.125, 0.875, 0.0,
        0.5,
    ];
    assert_eq!(f, want);
}

#[test]
fn open_cubic_rules_by_hand() {
    // F_0 = C_0, F_1 = ½(C_0+C_1), F_2 = ¾C_1 + ¼C_2, F_3 = 3/16 C_1 + 11/16 C_2 + ⅛C_3, F_4 = ½(C_2 + C_3)
    let c: Vec<f64> = vec![0.0, 16.0, 32.0, 48.0, 64.0, 0.0, 0.0, 0.0];
    let f = refine(&c, 1, Refinement::Cubic, Ends::Open).unwrap();
    assert_eq!(f.len(), 2 * 8 - 3);
    assert_eq!(
        &f[..5],
        &[0.0, 8.0, 0.75 * 16.0 + 0.25 * 32.0, 3.0 + 22.0 + 6.0, 40.0]
    );
    assert_eq!(*f.last().unwrap(), 0.0);
}

#[test]
fn every_rule_keeps_constants_and_open_rules_keep_end_points() {
    for rule in Refinement::ALL {
        for ends in [Ends::Open, Ends::Closed] {
            for n in rule.min_points(ends)..rule.min_points(ends) + 12 {
                let s = matrix(rule, ends, n).unwrap();
                for r in 0..s.rows() {
                    let sum: f64 = s.row(r).map(|x| x.1).sum();
                    assert!(
                        (sum - 1.0).abs() < 1e-15,
                        "{rule:?} {ends:?} n={n} row {r} sums to {sum}"
                    );
                }
                if ends == Ends::Open && rule != Refinement::Box {
                    let c: Vec<f64> = (0..n).map(|i| (i * i) as f64).collect();
                    let f = refine(&c, 1, rule, ends).unwrap();
                    assert_eq!(f[0], c[0], "{rule:?} n={n}");
                    assert_eq!(*f.last().unwrap(), c[n - 1], "{rule:?} n={n}");
                }
            }
        }
    }
}

#[test]
fn four_point_scheme_interpolates_its_control_points() {
    let pts: Vec<f64> = (0..9)
        .flat_map(|i| [(i as f64).sin(), (i as f64 * 0.7).cos()])
        .collect();
    for ends in [Ends::Open, Ends::Closed] {
        let f = refine_steps(&pts, 2, Refinement::FourPoint, ends, 3).unwrap();
        for j in 0..9 {
            assert_eq!(&f[16 * j..16 * j + 2], &pts[2 * j..2 * j + 2], "{ends:?}");
        }
    }
}

#[test]
fn too_few_points_is_a_parameter_error() {
    let e = refine(&[0.0, 1.0, 2.0], 1, Refinement::Cubic, Ends::Open).unwrap_err();
    assert_eq!(e.kind(), mra::ErrorKind::Parameter);
}

/// Characteristic polynomial coefficients (highest first) by Faddeev–LeVerrier.
fn char_poly(a: &[Vec<f64>]) -> Vec<f64> {
    let n = a.len();
    let mut coeffs = vec![1.0];
    let mut m = vec![vec![0.0; n]; n];
    let mut c = 1.0;
    for k in 1..=n {
        // M_k = A M_{k-1} + c_{k-1} I
        let mut next = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..n {
                next[i][j] =
                    (0..n).map(|l| a[i][l] * m[l][j]).sum::<f64>() + if i == j { c } else { 0.0 };
            }
        }
        m = next;
        let am: f64 = (0..n)
            .map(|i| (0..n).map(|l| a[i][l] * m[l][i]).sum::<f64>())
            .sum();
        c = -am / k as f64;
        coeffs.push(c);
    }
    coeffs
}

/// Divide a polynomial (highest first) by `(x − r)`, returning quotient and remainder.
fn deflate(p: &[f64], r: f64) -> (Vec<f64>, f64) {
    let mut q = Vec::with_capacity(p.len() - 1);
    let mut acc = 0.0;
    for &c in p {
        acc = acc * r + c;
        q.push(acc);
    }
    let rem = q.pop().unwrap();
    (q, rem)
}

/// The local subdivision matrix: fine rows `rows`, coarse columns `cols` of a closed
/// refinement matrix of 32 points.
fn local(
    rule: Refinement,
    rows: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
) -> Vec<Vec<f64>> {
    let s = matrix(rule, Ends::Closed, 32).unwrap().to_dense();
    rows.map(|r| cols.clone().map(|c| s[r][c]).collect())
        .collect()
}

#[test]
fn chaikin_and_dyn_levin_local_matrices_have_eigenvalues_1_half_quarter_quarter() {
    // Chaikin: fine F_{2j-1..2j+2} around coarse C_{j-1..j+2} (both centred between C_j and C_{j+1})
    let j = 10;
    let s = local(Refinement::Chaikin, 2 * j - 1..2 * j + 3, j - 1..j + 3);
    // Dyn–Levin: fine points at coarse positions j−1.5 … j+1.5 from C_{j−3 … j+3}
    let d = local(Refinement::FourPoint, 2 * j - 3..2 * j + 4, j - 3..j + 4);
    for (name, m, rest) in [
        ("chaikin", s, vec![1.0]),
        ("dyn-levin", d, vec![1.0, -0.125 + 0.0, 0.0, 0.0]),
    ] {
        let mut p = char_poly(&m);
        for root in [1.0, 0.5, 0.25, 0.25] {
            let (q, rem) = deflate(&p, root);
            assert!(
                rem.abs() < 1e-12,
                "{name}: {root} is not an eigenvalue (remainder {rem})"
            );
            p = q;
        }
        if name == "chaikin" {
            assert_eq!(p, rest);
        } else {
            // the remaining eigenvalues are 1/8, −1/16, −1/16: all below 1/4
            for root in [0.125, -0.0625, -0.0625] {
                let (q, rem) = deflate(&p, root);
                assert!(
                    rem.abs() < 1e-12,
                    "{name}: {root} is not an eigenvalue (remainder {rem})"
                );
                p = q;
            }
            assert_eq!(p.len(), 1);
        }
    }
}
