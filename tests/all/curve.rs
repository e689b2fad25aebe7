//! Curves: Bézier, B-spline, NURBS, knot insertion and scheme eigen-analysis (issue 8).

use mra::curve::analysis::{analyze, named_mask, parse_mask};
use mra::curve::basis::{basis_brute, basis_derivs, basis_funs, span, DerivWork, KnotVector};
use mra::curve::eigen::eigenvalues;
use mra::curve::geometry::curvature;
use mra::curve::knot::{
    insert, insert_midpoints, insert_midpoints_nurbs, insert_nurbs, refine_periodic,
};
use mra::curve::{BSpline, Bezier, Curve, Nurbs};
use mra::ErrorKind;

/// A small deterministic generator (no extra dependency).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
    fn int(&mut self, a: usize, b: usize) -> usize {
        a + (self.next() * (b - a + 1) as f64) as usize % (b - a + 1)
    }
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= tol * (1.0 + y.abs()))
}

fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert!(close(a, b, tol), "{what}: {a:?} vs {b:?}");
}

/// Random non-decreasing knots for n points of order k, with some repeated interior knots.
fn random_knots(g: &mut Lcg, n: usize, k: usize) -> Vec<f64> {
    let mut t: Vec<f64> = (0..n + k).map(|_| g.range(-2.0, 3.0)).collect();
    t.sort_by(|a, b| a.partial_cmp(b).unwrap());
    // repeat a few knots (multiplicity below k inside the range)
    for _ in 0..2 {
        if k > 2 {
            let i = g.int(1, n + k - 2);
            t[i] = t[i - 1];
        }
    }
    t.sort_by(|a, b| a.partial_cmp(b).unwrap());
    if t[k - 1] >= t[n] {
        t[n] = t[k - 1] + 1.0;
        for j in n + 1..n + k {
            t[j] = t[j].max(t[n]);
        }
    }
    t
}

#[test]
fn example_2_4_de_casteljau_gives_3_5_and_1_5_at_one_half() {
    let b = Bezier::new(vec![4.0, 0.0, 8.0, 2.0, 0.0, 2.0, 0.0, 0.0], 2).unwrap();
    assert_close(&b.eval(0.5).unwrap(), &[3.5, 1.5], 1e-15, "de Casteljau");
    assert_close(
        &b.eval_bernstein(0.5).unwrap(),
        &[3.5, 1.5],
        1e-15,
        "Bernstein",
    );
    // Example 2.1: Q(0) = P0, Q(1/2) = (4, 1), Q(1) = P2
    let q = Bezier::new(vec![0.0, 0.0, 4.0, 2.0, 8.0, 0.0], 2).unwrap();
    assert_close(&q.eval(0.0).unwrap(), &[0.0, 0.0], 0.0, "Q(0)");
    assert_close(&q.eval(0.5).unwrap(), &[4.0, 1.0], 0.0, "Q(1/2)");
    assert_close(&q.eval(1.0).unwrap(), &[8.0, 0.0], 0.0, "Q(1)");
    // Example 2.2 (general form §2.2): T(0) = d(P1 − P0), T(1) = d(Pd − Pd−1)
    assert_close(&q.derivative(0.0, 1).unwrap(), &[8.0, 4.0], 1e-15, "T(0)");
    assert_close(&q.derivative(1.0, 1).unwrap(), &[8.0, -4.0], 1e-15, "T(1)");
}

#[test]
fn de_casteljau_matches_bernstein_sum_in_any_dimension() {
    let mut g = Lcg(1);
    for dim in 1..=4 {
        for d in 0..8 {
            let pts: Vec<f64> = (0..(d + 1) * dim).map(|_| g.range(-5.0, 5.0)).collect();
            let b = Bezier::new(pts, dim).unwrap();
            for _ in 0..20 {
                let u = g.next();
                assert_close(
                    &b.eval(u).unwrap(),
                    &b.eval_bernstein(u).unwrap(),
                    1e-13,
                    "bezier",
                );
            }
        }
    }
}

#[test]
fn splitting_gives_two_curves_that_trace_the_original() {
    let mut g = Lcg(2);
    let pts: Vec<f64> = (0..6 * 3).map(|_| g.range(-5.0, 5.0)).collect();
    let b = Bezier::new(pts, 3).unwrap();
    let s = 0.3;
    let (l, r) = b.split(s).unwrap();
    assert_eq!(l.degree(), 5);
    for i in 0..=20 {
        let t = i as f64 / 20.0;
        assert_close(&l.eval(t).unwrap(), &b.eval(s * t).unwrap(), 1e-13, "left");
        assert_close(
            &r.eval(t).unwrap(),
            &b.eval(s + (1.0 - s) * t).unwrap(),
            1e-13,
            "right",
        );
    }
    assert_close(&l.points()[15..], &r.points()[..3], 0.0, "shared point");
}

#[test]
fn degree_elevation_keeps_the_curve() {
    let mut g = Lcg(3);
    let b = Bezier::new((0..4 * 2).map(|_| g.range(-5.0, 5.0)).collect(), 2).unwrap();
    let e = b.elevate().elevate();
    assert_eq!(e.degree(), 5);
    for i in 0..=50 {
        let u = i as f64 / 50.0;
        assert_close(&e.eval(u).unwrap(), &b.eval(u).unwrap(), 1e-13, "elevated");
    }
}

#[test]
fn bezier_derivatives_match_finite_differences_and_vanish_above_the_degree() {
    let mut g = Lcg(4);
    let b = Bezier::new((0..5 * 2).map(|_| g.range(-5.0, 5.0)).collect(), 2).unwrap();
    let h = 1e-5;
    for i in 1..10 {
        let u = i as f64 / 10.0;
        let d1 = b.derivative(u, 1).unwrap();
        let p = b.eval(u + h).unwrap();
        let m = b.eval(u - h).unwrap();
        let fd: Vec<f64> = p.iter().zip(&m).map(|(a, c)| (a - c) / (2.0 * h)).collect();
        assert_close(&d1, &fd, 1e-7, "first derivative");
        assert_close(
            &b.derivative(u, 5).unwrap(),
            &[0.0, 0.0],
            0.0,
            "fifth derivative",
        );
    }
}

#[test]
fn bezier_is_a_bspline_on_the_standard_knots_without_interior_knots() {
    let mut g = Lcg(5);
    for d in 0..6 {
        let b = Bezier::new((0..(d + 1) * 3).map(|_| g.range(-5.0, 5.0)).collect(), 3).unwrap();
        let s = b.to_bspline();
        for i in 0..=30 {
            let u = i as f64 / 30.0;
            assert_close(
                &s.eval(u).unwrap(),
                &b.eval(u).unwrap(),
                1e-13,
                "bezier as bspline",
            );
        }
    }
}

/// Closed forms of §3.4.3–3.4.6 for N_{0,k} on the integer knots.
fn n0(k: usize, u: f64) -> f64 {
    match k {
        1 => (0.0..1.0).contains(&u) as u8 as f64,
        2 => {
            if (0.0..1.0).contains(&u) {
                u
            } else if (1.0..2.0).contains(&u) {
                2.0 - u
            } else {
                0.0
            }
        }
        3 => {
            if (0.0..1.0).contains(&u) {
                u * u / 2.0
            } else if (1.0..2.0).contains(&u) {
                0.75 - (u - 1.5).powi(2)
            } else if (2.0..3.0).contains(&u) {
                (3.0 - u).powi(2) / 2.0
            } else {
                0.0
            }
        }
        4 => {
            if (0.0..1.0).contains(&u) {
                u.powi(3) / 6.0
            } else if (1.0..2.0).contains(&u) {
                (-3.0 * (u - 1.0).powi(3) + 3.0 * (u - 1.0).powi(2) + 3.0 * (u - 1.0) + 1.0) / 6.0
            } else if (2.0..3.0).contains(&u) {
                (3.0 * (u - 2.0).powi(3) - 6.0 * (u - 2.0).powi(2) + 4.0) / 6.0
            } else if (3.0..4.0).contains(&u) {
                (4.0 - u).powi(3) / 6.0
            } else {
                0.0
            }
        }
        _ => unreachable!(),
    }
}

#[test]
fn uniform_basis_functions_of_orders_one_to_four_match_section_3_4() {
    // (the notes print the second cubic piece as (−3(u−1)³ + 3(u−1)² + 3u − 2)/6, which equals
    // the form above: 3u − 2 = 3(u − 1) + 1)
    for k in 1..=4 {
        let n = 8;
        let t = KnotVector::uniform(n, k);
        for s in 0..=80 {
            let u = (k - 1) as f64 + s as f64 * (n - k + 1) as f64 / 80.0;
            for i in 0..n {
                let want = n0(k, u - i as f64);
                let got = basis_brute(t.as_slice(), n, i, k, u);
                // at the right end of the range the last span is closed
                if u == n as f64 {
                    continue;
                }
                assert!(
                    (got - want).abs() < 1e-14,
                    "N_{i},{k}({u}) = {got}, expected {want}"
                );
            }
        }
    }
}

#[test]
fn basis_sums_to_one_and_has_local_support_on_random_knot_vectors() {
    let mut g = Lcg(6);
    for _ in 0..200 {
        let k = g.int(1, 6);
        let n = g.int(k, k + 8);
        let t = random_knots(&mut g, n, k);
        let (a, b) = (t[k - 1], t[n]);
        for _ in 0..20 {
            let u = g.range(a, b);
            let mut sum = 0.0;
            for i in 0..n {
                let v = basis_brute(&t, n, i, k, u);
                assert!(v >= 0.0, "positivity");
                if !(t[i] <= u && u <= t[i + k]) {
                    assert_eq!(v, 0.0, "local support of N_{i},{k} at {u} on {t:?}");
                }
                sum += v;
            }
            assert!(
                (sum - 1.0).abs() < 1e-13,
                "partition of unity: {sum} at {u} on {t:?}"
            );
        }
    }
}

#[test]
fn triangular_basis_equals_the_recursion_at_and_near_knots() {
    let mut g = Lcg(7);
    for _ in 0..200 {
        let k = g.int(1, 6);
        let n = g.int(k, k + 8);
        let t = random_knots(&mut g, n, k);
        let (a, b) = (t[k - 1], t[n]);
        let mut params: Vec<f64> = (0..10).map(|_| g.range(a, b)).collect();
        for &x in &t[k - 1..=n] {
            for e in [0.0, 1e-9, -1e-9, 1e-12, -1e-12] {
                if x + e >= a && x + e <= b {
                    params.push(x + e);
                }
            }
        }
        let mut nb = vec![0.0; k];
        let (mut l, mut r) = (vec![0.0; k], vec![0.0; k]);
        for &u in &params {
            let d = span(&t, n, k, u);
            assert!(t[d] <= u && (u < t[d + 1] || u == b) && t[d] < t[d + 1]);
            basis_funs(&t, d, u, k, &mut nb, &mut l, &mut r);
            for i in 0..n {
                let want = basis_brute(&t, n, i, k, u);
                let got = if i + k > d && i <= d {
                    nb[i + k - 1 - d]
                } else {
                    0.0
                };
                assert!(
                    (got - want).abs() < 1e-13,
                    "N_{i},{k}({u}): {got} vs {want} on {t:?}"
                );
            }
        }
    }
}

#[test]
fn de_boor_equals_the_brute_force_sum_and_eval_many() {
    let mut g = Lcg(8);
    for _ in 0..100 {
        let k = g.int(1, 6);
        let n = g.int(k, k + 8);
        let dim = g.int(1, 4);
        let t = random_knots(&mut g, n, k);
        let pts: Vec<f64> = (0..n * dim).map(|_| g.range(-5.0, 5.0)).collect();
        let c = BSpline::new(pts, dim, k, t.clone()).unwrap();
        let (a, b) = c.range();
        let mut params: Vec<f64> = (0..20).map(|_| g.range(a, b)).collect();
        params.extend(
            t[k - 1..=n]
                .iter()
                .flat_map(|&x| [x, x + 1e-9, x - 1e-9])
                .filter(|&u| u >= a && u <= b),
        );
        params.sort_by(|x, y| x.partial_cmp(y).unwrap());
        let mut many = vec![0.0; params.len() * dim];
        c.eval_many(&params, &mut many).unwrap();
        for (j, &u) in params.iter().enumerate() {
            let brute = c.eval_brute(u).unwrap();
            assert_close(&c.eval(u).unwrap(), &brute, 1e-12, "de Boor");
            assert_close(&many[j * dim..(j + 1) * dim], &brute, 1e-12, "eval_many");
        }
    }
}

#[test]
fn parameters_outside_the_valid_range_and_bad_curves_are_parameter_errors() {
    let pts = vec![0.0, 0.0, 1.0, 1.0, 2.0, 0.0, 3.0, 1.0];
    let c = BSpline::uniform(pts.clone(), 2, 3).unwrap();
    assert_eq!(c.range(), (2.0, 4.0));
    for u in [1.999999, 4.000001, f64::NAN] {
        let e = c.eval(u).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parameter);
        assert!(e.to_string().contains("valid range"), "{e}");
    }
    // too few points for the order
    assert_eq!(
        BSpline::uniform(pts.clone(), 2, 5).unwrap_err().kind(),
        ErrorKind::Parameter
    );
    // decreasing knots
    let e = BSpline::new(pts.clone(), 2, 2, vec![0.0, 1.0, 3.0, 2.0, 4.0, 5.0]).unwrap_err();
    assert!(e.to_string().contains("non-decreasing"), "{e}");
    // wrong knot count
    let e = BSpline::new(pts.clone(), 2, 2, vec![0.0, 1.0, 2.0]).unwrap_err();
    assert!(e.to_string().contains("number of knots"), "{e}");
    // empty valid range
    let e = BSpline::new(pts.clone(), 2, 2, vec![0.0, 1.0, 1.0, 1.0, 1.0, 5.0]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parameter);
    // zero and negative weights
    let t = KnotVector::open(4, 3).unwrap().as_slice().to_vec();
    for w in [0.0, -1.0] {
        let e = Nurbs::new(&pts, &[1.0, w, 1.0, 1.0], 2, 3, t.clone()).unwrap_err();
        assert!(e.to_string().contains("weight"), "{e}");
    }
    // Bezier parameter outside [0, 1]
    assert_eq!(
        Bezier::new(pts, 2).unwrap().eval(1.5).unwrap_err().kind(),
        ErrorKind::Parameter
    );
}

#[test]
fn bspline_derivatives_agree_three_ways() {
    let mut g = Lcg(9);
    for _ in 0..50 {
        let k = g.int(2, 6);
        let n = g.int(k, k + 6);
        let t = random_knots(&mut g, n, k);
        let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
        let c = BSpline::new(pts, 2, k, t).unwrap();
        let dc = c.derivative_curve().unwrap();
        let (a, b) = c.range();
        for _ in 0..10 {
            let u = g.range(a, b);
            let d1 = c.derivative(u, 1).unwrap();
            assert_close(&d1, &dc.eval(u).unwrap(), 1e-10, "derivative curve");
            if k > 2 {
                let ddc = dc.derivative_curve().unwrap();
                assert_close(
                    &c.derivative(u, 2).unwrap(),
                    &ddc.eval(u).unwrap(),
                    1e-9,
                    "second",
                );
            }
            assert_close(
                &c.derivative(u, k).unwrap(),
                &[0.0, 0.0],
                0.0,
                "order k derivative",
            );
        }
    }
    // basis derivatives sum to zero (derivative of the partition of unity)
    let t = random_knots(&mut g, 9, 4);
    let mut w = DerivWork::new(4);
    let mut out = vec![0.0; 3 * 4];
    let u = 0.5 * (t[3] + t[9]);
    basis_derivs(&t, span(&t, 9, 4, u), u, 2, &mut w, &mut out);
    assert!(out[4..8].iter().sum::<f64>().abs() < 1e-10);
    assert!(out[8..12].iter().sum::<f64>().abs() < 1e-8);
}

fn fixture(name: &str) -> serde_json::Value {
    let path = format!("{}/tests/reference/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    match v {
        serde_json::Value::Array(a) => a.iter().flat_map(floats).collect(),
        serde_json::Value::Number(x) => vec![x.as_f64().unwrap()],
        _ => vec![],
    }
}

#[test]
fn geomdl_reference_curves_agree_to_1e_12() {
    let f = fixture("geomdl_curves.json");
    let curves = f["curves"].as_array().unwrap();
    assert!(curves.len() >= 32);
    let mut checked = 0;
    for c in curves {
        let k = c["order"].as_u64().unwrap() as usize;
        let dim = c["dim"].as_u64().unwrap() as usize;
        let pts = floats(&c["points"]);
        let knots = floats(&c["knots"]);
        let rational = c["rational"].as_bool().unwrap();
        let params = floats(&c["params"]);
        let values = c["values"].as_array().unwrap();
        let ders = c["derivatives"].as_array().unwrap();
        let curve: Box<dyn Curve> = if rational {
            Box::new(Nurbs::new(&pts, &floats(&c["weights"]), dim, k, knots).unwrap())
        } else {
            Box::new(BSpline::new(pts, dim, k, knots).unwrap())
        };
        for (j, &u) in params.iter().enumerate() {
            let want = floats(&values[j]);
            assert_close(
                &curve.point(u).unwrap(),
                &want,
                1e-12,
                &format!("{} k={k} u={u}", c["kind"]),
            );
            let d = ders[j].as_array().unwrap();
            for (o, dv) in d.iter().enumerate() {
                let want = floats(dv);
                let got = curve.derivative(u, o).unwrap();
                // derivatives scale with 1/knot spacing: relative tolerance
                let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                let ok = got
                    .iter()
                    .zip(&want)
                    .all(|(a, b)| (a - b).abs() <= 1e-12 * scale);
                assert!(
                    ok,
                    "derivative {o} of {} k={k} rational={rational} at {u}: {got:?} vs {want:?}",
                    c["kind"]
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 500);
}

#[test]
fn nurbs_circle_has_radius_error_below_1e_12_over_10000_samples() {
    let c = Nurbs::circle([1.5, -2.0], 3.0).unwrap();
    assert_eq!(
        c.knots(),
        &[0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0]
    );
    let w = c.weights();
    assert!((w[1] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15 && w[2] == 1.0);
    let params: Vec<f64> = (0..10_000).map(|i| i as f64 / 9_999.0).collect();
    let mut out = vec![0.0; 20_000];
    c.eval_many(&params, &mut out).unwrap();
    let mut worst: f64 = 0.0;
    for (i, p) in out.chunks(2).enumerate() {
        let r = (p[0] - 1.5).hypot(p[1] + 2.0);
        worst = worst.max((r - 3.0).abs());
        let q = c.eval(params[i]).unwrap();
        assert_close(&q, p, 1e-14, "eval vs eval_many");
    }
    assert!(worst <= 1e-12, "radius error {worst}");
    // curvature 1/r, and arcs of any sweep lie on the circle
    assert!((curvature(&c, 0.3).unwrap() - 1.0 / 3.0).abs() < 1e-12);
    for (a0, a1) in [(0.3, 1.0), (-1.0, 2.5), (0.0, 5.0)] {
        let a = Nurbs::arc([0.0, 0.0], 2.0, a0, a1).unwrap();
        let s = a.eval(0.0).unwrap();
        let e = a.eval(1.0).unwrap();
        assert_close(
            &s,
            &[2.0 * f64::cos(a0), 2.0 * f64::sin(a0)],
            1e-14,
            "arc start",
        );
        assert_close(
            &e,
            &[2.0 * f64::cos(a1), 2.0 * f64::sin(a1)],
            1e-14,
            "arc end",
        );
        for i in 0..=1000 {
            let p = a.eval(i as f64 / 1000.0).unwrap();
            assert!((p[0].hypot(p[1]) - 2.0).abs() < 1e-12);
        }
    }
}

#[test]
fn nurbs_with_equal_weights_is_the_bspline_and_rational_basis_oracle_agrees() {
    let mut g = Lcg(10);
    let pts: Vec<f64> = (0..7 * 3).map(|_| g.range(-5.0, 5.0)).collect();
    let t = random_knots(&mut g, 7, 4);
    let b = BSpline::new(pts.clone(), 3, 4, t.clone()).unwrap();
    let n = Nurbs::new(&pts, &[2.5; 7], 3, 4, t.clone()).unwrap();
    let ws: Vec<f64> = (0..7).map(|_| g.range(0.2, 4.0)).collect();
    let r = Nurbs::new(&pts, &ws, 3, 4, t).unwrap();
    let (a, bb) = b.range();
    for i in 0..=40 {
        let u = a + (bb - a) * i as f64 / 40.0;
        assert_close(
            &n.eval(u).unwrap(),
            &b.eval(u).unwrap(),
            1e-13,
            "equal weights",
        );
        assert_close(
            &r.eval(u).unwrap(),
            &r.eval_brute(u).unwrap(),
            1e-12,
            "rational oracle",
        );
    }
}

#[test]
fn boehm_insertion_keeps_the_curve_for_bsplines_and_nurbs() {
    let mut g = Lcg(11);
    for _ in 0..50 {
        let k = g.int(1, 6);
        let n = g.int(k, k + 6);
        let t = random_knots(&mut g, n, k);
        let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
        let ws: Vec<f64> = (0..n).map(|_| g.range(0.2, 4.0)).collect();
        let c = BSpline::new(pts.clone(), 2, k, t.clone()).unwrap();
        let r = Nurbs::new(&pts, &ws, 2, k, t).unwrap();
        let (a, b) = c.range();
        let ubar = g.range(a, b);
        let c1 = insert(&c, ubar).unwrap();
        let r1 = insert_nurbs(&r, ubar).unwrap();
        assert_eq!(c1.len(), n + 1);
        let cm = insert_midpoints(&c).unwrap();
        let rm = insert_midpoints_nurbs(&r).unwrap();
        for i in 0..=50 {
            let u = if i == 50 {
                b
            } else {
                a + (b - a) * i as f64 / 50.0
            };
            let want = c.eval(u).unwrap();
            assert_close(&c1.eval(u).unwrap(), &want, 1e-11, "Boehm");
            assert_close(&cm.eval(u).unwrap(), &want, 1e-11, "midpoints");
            let want = r.eval(u).unwrap();
            assert_close(&r1.eval(u).unwrap(), &want, 1e-11, "Boehm NURBS");
            assert_close(&rm.eval(u).unwrap(), &want, 1e-11, "midpoints NURBS");
        }
    }
    // multiplicity may not exceed the order
    let c = BSpline::open(vec![0.0, 1.0, 2.0, 3.0], 1, 2).unwrap();
    let c = insert(&insert(&c, 0.5).unwrap(), 0.5).unwrap();
    assert_eq!(insert(&c, 0.5).unwrap_err().kind(), ErrorKind::Parameter);
}

/// The uniform B-spline masks of Table 1 (§7.2.2), orders 1..5.
fn table1(k: usize) -> Vec<f64> {
    let row: Vec<f64> = (0..=k)
        .map(|i| mra::curve::bezier::binomial(k, i))
        .collect();
    let s = 2f64.powi(k as i32 - 1);
    row.iter().map(|x| x / s).collect()
}

#[test]
fn midpoint_insertion_on_uniform_knots_is_the_subdivision_mask_of_table_1() {
    let mut g = Lcg(12);
    for k in 1..=5 {
        let n = 9;
        let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
        let fine = refine_periodic(&pts, 2, k).unwrap();
        assert_eq!(fine.len(), 2 * n * 2);
        // F_i = Σ_j a_{i − 2j + s} C_j for one shift s (cyclic indices)
        let a = table1(k);
        let apply = |s: isize| -> Vec<f64> {
            let mut f = vec![0.0; 2 * n * 2];
            for i in 0..2 * n {
                for j in 0..n as isize {
                    for wrap in -2..=2isize {
                        let jj = j + wrap * n as isize;
                        let m = i as isize - 2 * jj + s;
                        if m >= 0 && (m as usize) < a.len() {
                            for c in 0..2 {
                                f[i * 2 + c] += a[m as usize] * pts[j as usize * 2 + c];
                            }
                        }
                    }
                }
            }
            f
        };
        let found = (-8..8).any(|s| close(&apply(s), &fine, 1e-13));
        assert!(found, "order {k}: refine_periodic is not the Table 1 mask");
        // and the closed curve is unchanged: C(u) = F(2u + shift) for one half-integer shift
        let coarse = BSpline::periodic(&pts, 2, k).unwrap();
        let finec = BSpline::periodic(&fine, 2, k).unwrap();
        let (a0, b0) = coarse.range();
        let (fa, fb) = finec.range();
        let period = 2.0 * n as f64;
        let ok = (0..4 * n as i64).any(|sh| {
            let shift = sh as f64 * 0.5;
            (0..40).all(|i| {
                let u = a0 + (b0 - a0) * (i as f64 + 0.37) / 40.0;
                let mut v = (2.0 * (u - a0) + shift).rem_euclid(period) + fa;
                if v > fb {
                    v = fb;
                }
                close(&finec.eval(v).unwrap(), &coarse.eval(u).unwrap(), 1e-11)
            })
        });
        assert!(ok, "order {k}: the refined closed curve differs");
    }
}

#[test]
fn midpoint_insertion_on_open_knots_gives_the_end_rules_of_section_7_4() {
    // quadratic: F0 = C0, F1 = (C0 + C1)/2, F2 = 3/4 C1 + 1/4 C2, …, symmetric at the end
    let c: Vec<f64> = vec![0.0, 1.0, 4.0, 9.0, 16.0, 25.0];
    let f = insert_midpoints(&BSpline::open(c.clone(), 1, 3).unwrap()).unwrap();
    let f = f.points();
    assert_eq!(f.len(), 2 * c.len() - 2);
    assert_close(
        &f[..3],
        &[c[0], 0.5 * (c[0] + c[1]), 0.75 * c[1] + 0.25 * c[2]],
        1e-15,
        "start",
    );
    let m = f.len();
    assert_close(
        &f[m - 3..],
        &[0.75 * c[4] + 0.25 * c[3], 0.5 * (c[4] + c[5]), c[5]],
        1e-15,
        "end",
    );
    // cubic: F3 = 3/16 C1 + 11/16 C2 + 1/8 C3, F4 = (C2 + C3)/2
    let c: Vec<f64> = vec![0.0, 1.0, 4.0, 9.0, 16.0, 25.0, 36.0, 49.0];
    let f = insert_midpoints(&BSpline::open(c.clone(), 1, 4).unwrap()).unwrap();
    let f = f.points();
    assert_eq!(f.len(), 2 * c.len() - 3);
    let want = [
        c[0],
        0.5 * (c[0] + c[1]),
        0.75 * c[1] + 0.25 * c[2],
        3.0 / 16.0 * c[1] + 11.0 / 16.0 * c[2] + 0.125 * c[3],
        0.5 * (c[2] + c[3]),
    ];
    assert_close(&f[..5], &want, 1e-14, "cubic start");
}

#[test]
fn eigenvalues_of_known_matrices() {
    // triangular: the diagonal
    let a = [2.0, 1.0, 5.0, 0.0, -3.0, 4.0, 0.0, 0.0, 0.5];
    let ev = eigenvalues(&a, 3).unwrap();
    let re: Vec<f64> = ev.iter().map(|e| e.re).collect();
    assert_close(&re, &[-3.0, 2.0, 0.5], 1e-13, "triangular");
    // companion matrix of (x − 1)(x − 2)(x² + 1): roots 2, 1, ±i
    // x⁴ − 3x³ + 3x² − 3x + 2
    let c = [
        3.0, -3.0, 3.0, -2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
    ];
    let ev = eigenvalues(&c, 4).unwrap();
    assert!((ev[0].re - 2.0).abs() < 1e-12 && ev[0].im.abs() < 1e-12);
    let mut unit: Vec<_> = ev[1..].to_vec();
    unit.sort_by(|a, b| a.im.partial_cmp(&b.im).unwrap());
    assert!(
        (unit[0].im + 1.0).abs() < 1e-12 && unit[0].re.abs() < 1e-12,
        "{ev:?}"
    );
    assert!(
        (unit[1].re - 1.0).abs() < 1e-12 && unit[1].im.abs() < 1e-12,
        "{ev:?}"
    );
    assert!((unit[2].im - 1.0).abs() < 1e-12, "{ev:?}");
    // random matrices: trace and trace of the square are kept
    let mut g = Lcg(13);
    for n in 1..=12 {
        let a: Vec<f64> = (0..n * n).map(|_| g.range(-1.0, 1.0)).collect();
        let ev = eigenvalues(&a, n).unwrap();
        let tr: f64 = (0..n).map(|i| a[i * n + i]).sum();
        let tr2: f64 = (0..n)
            .map(|i| (0..n).map(|j| a[i * n + j] * a[j * n + i]).sum::<f64>())
            .sum();
        let s: f64 = ev.iter().map(|e| e.re).sum();
        let s2: f64 = ev.iter().map(|e| e.re * e.re - e.im * e.im).sum();
        let si: f64 = ev.iter().map(|e| e.im).sum();
        assert!(
            (s - tr).abs() < 1e-10 && (s2 - tr2).abs() < 1e-10 && si.abs() < 1e-10,
            "n={n}"
        );
    }
}

fn spectrum(name: &str) -> (Vec<f64>, mra::curve::analysis::Analysis) {
    let a = analyze(&named_mask(name).unwrap(), None).unwrap();
    let re = a.eigenvalues.iter().map(|e| e.re).collect();
    (re, a)
}

#[test]
fn chaikin_spectrum_is_1_half_quarter_quarter_and_suggests_c1() {
    let (re, a) = spectrum("chaikin");
    assert_close(&re, &[1.0, 0.5, 0.25, 0.25], 1e-12, "Chaikin (Example 7.2)");
    assert!(a.affine_invariant);
    assert_eq!(a.smoothness, Some(1));
}

#[test]
fn bspline_and_four_point_spectra_match_the_notes() {
    let (re, a) = spectrum("cubic");
    assert_close(&re, &[1.0, 0.5, 0.25, 0.125, 0.125], 1e-12, "cubic");
    assert_eq!(a.smoothness, Some(2));
    let (re, a) = spectrum("quartic");
    assert_close(&re[..5], &[1.0, 0.5, 0.25, 0.125, 0.0625], 1e-12, "quartic");
    assert_eq!(a.smoothness, Some(3));
    // Dyn–Levin four-point (§7.6.1): leading 1, 1/2, 1/4, 1/4 as in the notes
    let (re, a) = spectrum("four-point");
    assert_close(&re[..4], &[1.0, 0.5, 0.25, 0.25], 1e-12, "four-point");
    assert!(a.affine_invariant);
    assert_eq!(a.smoothness, Some(1));
    // linear B-spline: C0; box: no continuous limit suggested
    assert_eq!(spectrum("linear").1.smoothness, Some(0));
    assert_eq!(spectrum("box").1.smoothness, None);
}

#[test]
fn user_masks_parse_as_fractions_and_non_affine_masks_are_flagged() {
    let m = parse_mask("-1/16, 0, 9/16, 1, 9/16, 0, -1/16").unwrap();
    assert_eq!(m, named_mask("four-point").unwrap());
    let a = analyze(&parse_mask("1/3 2/3 2/3 1/3").unwrap(), None).unwrap();
    assert!(a.affine_invariant);
    let a = analyze(&parse_mask("0.3,0.7,0.8,0.3").unwrap(), None).unwrap();
    assert!(!a.affine_invariant);
    assert!(parse_mask("1/0,2").is_err());
    assert!(parse_mask("abc").is_err());
}

// ---- command line ----

fn mra_cmd(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mra-curve-tests-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn cli_eval_prints_example_2_4_and_samples_with_parameters() {
    let (code, out, _) = mra_cmd(&[
        "curve",
        "eval",
        "--kind",
        "bezier",
        "--at",
        "0.5",
        "corpus/curves/example24.csv",
    ]);
    assert_eq!(code, 0);
    assert_eq!(out.trim(), "3.5,1.5");
    let (code, out, _) = mra_cmd(&[
        "curve",
        "eval",
        "--samples",
        "5",
        "--with-u",
        "corpus/curves/wave.csv",
    ]);
    assert_eq!(code, 0);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 5);
    assert_eq!(lines[0], "0,0,0"); // open knots interpolate the first point
    assert_eq!(lines[4], "1,7,1");
    // the NURBS circle file of the corpus stays on the unit circle
    let (code, out, _) = mra_cmd(&[
        "curve",
        "eval",
        "--kind",
        "nurbs",
        "--order",
        "3",
        "--knots",
        "corpus/curves/circle_knots.txt",
        "--samples",
        "33",
        "corpus/curves/circle.csv",
    ]);
    assert_eq!(code, 0);
    let pts: Vec<Vec<f64>> = out
        .lines()
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(pts.len(), 33, "{out}");
    for v in &pts {
        assert_eq!(v.len(), 2, "{v:?}");
        assert!((v[0].hypot(v[1]) - 1.0).abs() < 1e-12, "{v:?}");
    }
    // and goes round it: the samples cover every quadrant
    let quadrants: std::collections::BTreeSet<(bool, bool)> =
        pts.iter().map(|v| (v[0] >= 0.0, v[1] >= 0.0)).collect();
    assert_eq!(quadrants.len(), 4, "{pts:?}");
}

#[test]
fn cli_bad_input_gives_one_line_exit_2_and_no_output_file() {
    let knots = scratch("decreasing.txt");
    std::fs::write(&knots, "0,1,3,2,4,5,6,7,8,9,10,11").unwrap();
    let weights = scratch("zero_w.csv");
    std::fs::write(&weights, "x,y,w\n0,0,1\n1,1,0\n2,0,1\n").unwrap();
    let out = scratch("never.csv");
    let k = knots.to_str().unwrap();
    let w = weights.to_str().unwrap();
    let o = out.to_str().unwrap();
    let cases: Vec<Vec<&str>> = vec![
        vec![
            "curve",
            "eval",
            "--order",
            "9",
            "corpus/curves/wave.csv",
            "-o",
            o,
        ],
        vec![
            "curve",
            "eval",
            "--order",
            "4",
            "--knots",
            k,
            "corpus/curves/wave.csv",
            "-o",
            o,
        ],
        vec![
            "curve",
            "eval",
            "--order",
            "3",
            "--knots",
            "corpus/curves/circle_knots.txt",
            "corpus/curves/wave.csv",
            "-o",
            o,
        ],
        vec![
            "curve", "eval", "--kind", "nurbs", "--order", "2", w, "-o", o,
        ],
        vec![
            "curve",
            "eval",
            "--at",
            "1.5",
            "corpus/curves/wave.csv",
            "-o",
            o,
        ],
        vec!["curve", "plot", "corpus/curves/missing.csv", "-o", o],
        vec![
            "curve",
            "insert-knot",
            "--u",
            "7",
            "corpus/curves/wave.csv",
            "-o",
            o,
        ],
    ];
    for c in cases {
        let (code, stdout, stderr) = mra_cmd(&c);
        assert_eq!(code, 2, "{c:?}: {stderr}");
        assert!(stdout.is_empty());
        assert_eq!(stderr.trim_end().lines().count(), 1, "{c:?}: {stderr}");
        assert!(stderr.starts_with("mra: "), "{stderr}");
        assert!(!out.exists(), "{c:?} left an output file");
    }
}

#[test]
fn cli_insert_knot_midpoints_keeps_the_curve() {
    let fine = scratch("fine.csv");
    let knots = scratch("fine_knots.txt");
    let (code, _, err) = mra_cmd(&[
        "curve",
        "insert-knot",
        "--order",
        "3",
        "--midpoints",
        "--knots-out",
        knots.to_str().unwrap(),
        "corpus/curves/wave.csv",
        "-o",
        fine.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let (c1, a, _) = mra_cmd(&[
        "curve",
        "eval",
        "--order",
        "3",
        "--samples",
        "41",
        "corpus/curves/wave.csv",
    ]);
    let (c2, b, e2) = mra_cmd(&[
        "curve",
        "eval",
        "--order",
        "3",
        "--knots",
        knots.to_str().unwrap(),
        "--samples",
        "41",
        fine.to_str().unwrap(),
    ]);
    assert_eq!((c1, c2), (0, 0), "{e2}");
    // the refined control polygon has more points than the source's
    let count = |p: &std::path::Path| {
        mra::points::parse(&std::fs::read_to_string(p).unwrap())
            .unwrap()
            .len()
    };
    let wave = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/curves/wave.csv");
    assert!(
        count(&fine) > count(&wave),
        "{} vs {}",
        count(&fine),
        count(&wave)
    );
    assert_eq!((a.lines().count(), b.lines().count()), (41, 41), "{a}\n{b}");
    for (x, y) in a.lines().zip(b.lines()) {
        let x: Vec<f64> = x.split(',').map(|t| t.parse().unwrap()).collect();
        let y: Vec<f64> = y.split(',').map(|t| t.parse().unwrap()).collect();
        assert!(close(&x, &y, 1e-13), "{x:?} vs {y:?}");
    }
}

#[test]
fn cli_plot_writes_svg_and_png() {
    let svg = scratch("wave.svg");
    let png = scratch("wave.png");
    assert_eq!(
        mra_cmd(&[
            "curve",
            "plot",
            "corpus/curves/wave.csv",
            "-o",
            svg.to_str().unwrap()
        ])
        .0,
        0
    );
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(s.starts_with("<svg") && s.matches("<circle").count() >= 8 + 6);
    assert_eq!(
        mra_cmd(&[
            "curve",
            "plot",
            "corpus/curves/wave.csv",
            "-o",
            png.to_str().unwrap()
        ])
        .0,
        0
    );
    assert_eq!(&std::fs::read(&png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn cli_scheme_analyze_reports_the_chaikin_spectrum() {
    let (code, out, _) = mra_cmd(&["scheme", "analyze", "--mask", "1/4,3/4,3/4,1/4"]);
    assert_eq!(code, 0);
    let ev: Vec<f64> = out
        .lines()
        .skip_while(|l| !l.starts_with("eigenvalues"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .map(|l| l.trim().parse().unwrap())
        .collect();
    assert_close(&ev, &[1.0, 0.5, 0.25, 0.25], 1e-12, "cli Chaikin");
    assert!(out.contains("affine invariant: yes") && out.contains("C1"));
    let (code, _, err) = mra_cmd(&["scheme", "analyze", "--mask", "1/4,x"]);
    assert_eq!(code, 2);
    assert!(err.contains("mask coefficient"));
}

#[test]
fn power_form_evaluation_equals_the_brute_force_sum_at_and_near_knots() {
    use mra::curve::poly::PiecewisePoly;
    let mut g = Lcg(14);
    for _ in 0..200 {
        let k = g.int(1, 6);
        let n = g.int(k, k + 8);
        let dim = g.int(1, 4);
        let t = random_knots(&mut g, n, k);
        let pts: Vec<f64> = (0..n * dim).map(|_| g.range(-5.0, 5.0)).collect();
        let c = BSpline::new(pts, dim, k, t.clone()).unwrap();
        let (a, b) = c.range();
        let mut params: Vec<f64> = (0..30).map(|_| g.range(a, b)).collect();
        params.extend(
            t[k - 1..=n]
                .iter()
                .flat_map(|&x| [x, x + 1e-9, x - 1e-9, x + 1e-12])
                .filter(|&u| u >= a && u <= b),
        );
        let p = PiecewisePoly::from_bspline(&c);
        // unsorted and sorted orders both work
        for sorted in [false, true] {
            if sorted {
                params.sort_by(|x, y| x.partial_cmp(y).unwrap());
            }
            let mut out = vec![0.0; params.len() * dim];
            p.eval_many(&params, &mut out).unwrap();
            for (j, &u) in params.iter().enumerate() {
                let want = c.eval_brute(u).unwrap();
                assert_close(
                    &out[j * dim..(j + 1) * dim],
                    &want,
                    1e-11,
                    &format!("power form k={k} at {u}"),
                );
            }
        }
        assert_eq!(
            p.eval_many(&[b + 1e-9], &mut vec![0.0; dim])
                .unwrap_err()
                .kind(),
            ErrorKind::Parameter
        );
    }
}

#[test]
fn ellipse_normals_and_curvature_follow_sections_1_2_and_1_3() {
    use mra::curve::geometry::{normal_2d, unit_tangent};
    // an exact NURBS ellipse: the circle scaled by (a, b) (affine invariance, §4.4)
    let (a, b) = (3.0, 2.0);
    let c = Nurbs::circle([0.0, 0.0], 1.0).unwrap();
    let pts: Vec<f64> = c
        .points()
        .chunks(2)
        .flat_map(|p| [a * p[0], b * p[1]])
        .collect();
    let e = Nurbs::new(&pts, &c.weights(), 2, 3, c.knots().to_vec()).unwrap();
    for i in 0..=100 {
        let u = i as f64 / 100.0;
        let p = e.eval(u).unwrap();
        assert!(((p[0] / a).powi(2) + (p[1] / b).powi(2) - 1.0).abs() < 1e-12);
        let t = e.derivative(u, 1).unwrap();
        let n = normal_2d(&e, u).unwrap();
        assert!((n[0] * t[0] + n[1] * t[1]).abs() < 1e-12);
        // the normal of a counter-clockwise ellipse points inward: (−b cos θ, −a sin θ) ∥ N (Example 1.6)
        assert!(n[0] * p[0] / (a * a) + n[1] * p[1] / (b * b) < 0.0);
        let ut = unit_tangent(&e, u).unwrap();
        assert!((ut[0].hypot(ut[1]) - 1.0).abs() < 1e-14);
    }
    // curvature at the vertices: a/b² at (±a, 0), b/a² at (0, ±b)
    assert!((curvature(&e, 0.0).unwrap() - a / (b * b)).abs() < 1e-12);
    assert!((curvature(&e, 0.25).unwrap() - b / (a * a)).abs() < 1e-12);
    // a straight line (in 3D) has zero curvature
    let l = Bezier::new(vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0], 3).unwrap();
    assert!(curvature(&l, 0.4).unwrap().abs() < 1e-14);
}

#[test]
fn smaller_invariant_windows_keep_the_leading_eigenvalues() {
    // Chaikin on 3 points (a dual scheme: the fine window sits half a step aside): 1, 1/2, 1/4
    let a = analyze(&named_mask("chaikin").unwrap(), Some(3)).unwrap();
    let re: Vec<f64> = a.eigenvalues.iter().map(|e| e.re).collect();
    assert_close(&re, &[1.0, 0.5, 0.25], 1e-12, "Chaikin, 3 points");
    // cubic on 3 points: 1, 1/2, 1/4 (the classic vertex neighbourhood)
    let a = analyze(&named_mask("cubic").unwrap(), Some(3)).unwrap();
    let re: Vec<f64> = a.eigenvalues.iter().map(|e| e.re).collect();
    assert_close(&re, &[1.0, 0.5, 0.25], 1e-12, "cubic, 3 points");
    // a window too small to be invariant is refused
    assert_eq!(
        analyze(&named_mask("cubic").unwrap(), Some(2))
            .unwrap_err()
            .kind(),
        ErrorKind::Parameter
    );
}

#[test]
fn splitting_a_bspline_by_knot_insertion_keeps_both_halves() {
    use mra::curve::knot::{split, split_nurbs};
    let mut g = Lcg(15);
    for _ in 0..50 {
        let k = g.int(1, 5);
        let n = g.int(k, k + 6);
        let t = random_knots(&mut g, n, k);
        let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
        let ws: Vec<f64> = (0..n).map(|_| g.range(0.2, 4.0)).collect();
        let c = BSpline::new(pts.clone(), 2, k, t.clone()).unwrap();
        let r = Nurbs::new(&pts, &ws, 2, k, t.clone()).unwrap();
        let (a, b) = c.range();
        // split at a random parameter and at an existing interior knot
        let mut at = vec![g.range(a, b)];
        at.extend(t[k..n].iter().copied().filter(|&x| x > a && x < b).take(1));
        for s in at {
            let (l, rr) = split(&c, s).unwrap();
            let (nl, nr) = split_nurbs(&r, s).unwrap();
            assert_eq!(l.range(), (a, s));
            assert_eq!(rr.range(), (s, b));
            for i in 0..=20 {
                // the left half ends with the limit from the left: compare on [a, s) only
                // (order 1 and full-multiplicity knots are discontinuous)
                let u = a + (s - a) * i.min(19) as f64 / 20.0;
                assert_close(&l.eval(u).unwrap(), &c.eval(u).unwrap(), 1e-11, "left half");
                assert_close(
                    &nl.eval(u).unwrap(),
                    &r.eval(u).unwrap(),
                    1e-11,
                    "left NURBS half",
                );
                let v = if i == 20 {
                    b
                } else {
                    s + (b - s) * i as f64 / 20.0
                };
                assert_close(
                    &rr.eval(v).unwrap(),
                    &c.eval(v).unwrap(),
                    1e-11,
                    "right half",
                );
                assert_close(
                    &nr.eval(v).unwrap(),
                    &r.eval(v).unwrap(),
                    1e-11,
                    "right NURBS half",
                );
            }
        }
        assert_eq!(split(&c, a).unwrap_err().kind(), ErrorKind::Parameter);
    }
}

#[test]
fn delta_index_of_example_3_7_and_continuity_k_minus_1_minus_multiplicity() {
    // Example 3.7: u = {0,1,2,3,3,4,5,5,5,6}, k = 3, m = 6
    let t = [0.0, 1.0, 2.0, 3.0, 3.0, 4.0, 5.0, 5.0, 5.0, 6.0];
    assert_eq!(span(&t, 7, 3, 2.8), 2);
    assert_eq!(span(&t, 7, 3, 3.0), 4);
    assert_eq!(span(&t, 7, 3, 3.1), 4);
    // the notes give δ(5) = 8 by searching all knots; 5 is the right end of the valid range
    // [u_2, u_7] = [2, 5], where the last non-empty span of the range (δ = 5) is used
    assert_eq!(span(&t, 7, 3, 5.0), 5);
    // §3.8.2: a cubic (k = 4) is C^{k−1−µ} at a knot of multiplicity µ
    let mut g = Lcg(16);
    for mu in 1..=3 {
        let mut knots = vec![0.0, 1.0, 2.0, 3.0];
        knots.extend(std::iter::repeat_n(4.0, mu));
        knots.extend([5.0, 6.0, 7.0, 8.0]);
        let n = knots.len() - 4;
        let pts: Vec<f64> = (0..n).map(|_| g.range(-5.0, 5.0)).collect();
        let c = BSpline::new(pts, 1, 4, knots).unwrap();
        let h = 1e-7;
        for d in 0..3 {
            let jump =
                (c.derivative(4.0 + h, d).unwrap()[0] - c.derivative(4.0 - h, d).unwrap()[0]).abs();
            if d + mu < 4 {
                assert!(jump < 1e-4, "µ={mu}: derivative {d} jumps by {jump}");
            } else {
                assert!(jump > 1e-3, "µ={mu}: derivative {d} should jump ({jump})");
            }
        }
    }
}

#[test]
fn csv_point_tables_read_headers_weights_and_net_rows() {
    use mra::curve::csv::{parse, parse_numbers};
    let t = parse("# a comment\nx, y, w\n1,0,1\n1 1 0.5\n0;1;1  # trailing comment\n").unwrap();
    assert_eq!((t.dim, t.rows, t.cols), (2, 1, 3));
    assert_eq!(t.points, vec![1.0, 0.0, 1.0, 1.0, 0.0, 1.0]);
    assert_eq!(t.weights, Some(vec![1.0, 0.5, 1.0]));
    // a net: rows separated by blank lines (comment-only lines do not split rows)
    let n = parse("0,0,0\n0,1,0\n\n1,0,0\n# note\n1,1,1\n\n\n").unwrap();
    assert_eq!((n.dim, n.rows, n.cols), (3, 2, 2));
    assert!(n.weights.is_none());
    for bad in [
        "",
        "# only\n",
        "1,2\n3\n",
        "1,2\nx,y\n",
        "1,2\n\n3,4\n5,6\n",
        "1,nan\n",
        "w\n1\n",
    ] {
        let e = parse(bad).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Format, "{bad:?}");
    }
    assert_eq!(
        parse_numbers("0, 0 0\n0.5;1 # knots\n1", "knot").unwrap(),
        vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0]
    );
    assert!(parse_numbers("0,a", "knot").is_err());
}

// ---- knot insertion = the engine's subdivision (src/scheme/subdivide.rs) ----

use mra::scheme::subdivide::{refine, refine_steps, Ends, Refinement};

const BSPLINE_RULES: [(Refinement, usize); 5] = [
    (Refinement::Box, 1),
    (Refinement::Linear, 2),
    (Refinement::Chaikin, 3),
    (Refinement::Cubic, 4),
    (Refinement::Quartic, 5),
];

#[test]
fn closed_midpoint_insertion_equals_the_engine_refine_up_to_index_origin() {
    let mut g = Lcg(17);
    for (rule, k) in BSPLINE_RULES {
        for n in rule.min_points(Ends::Closed).max(k)..=13 {
            let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
            let theirs = refine(&pts, 2, rule, Ends::Closed).unwrap();
            let ours = refine_periodic(&pts, 2, k).unwrap();
            assert_eq!(theirs.len(), ours.len(), "{rule:?} n={n}");
            let m = 2 * n;
            let shift = (0..m).find(|&s| {
                (0..m).all(|i| {
                    let j = (i + s) % m;
                    close(&theirs[i * 2..i * 2 + 2], &ours[j * 2..j * 2 + 2], 1e-13)
                })
            });
            assert!(
                shift.is_some(),
                "{rule:?} n={n}: refine(Closed) is not midpoint knot insertion"
            );
            // the closed curve is unchanged: C(u) = F(2u + s) for a fixed half-integer s
            let coarse = BSpline::periodic(&pts, 2, k).unwrap();
            let fine = BSpline::periodic(&theirs, 2, k).unwrap();
            let (a0, b0) = coarse.range();
            let (fa, fb) = fine.range();
            let same = (0..4 * n).any(|sh| {
                (0..60).all(|i| {
                    let u = a0 + (b0 - a0) * (i as f64 + 0.31) / 60.0;
                    let v = ((2.0 * (u - a0) + sh as f64 * 0.5).rem_euclid(m as f64) + fa).min(fb);
                    close(&fine.eval(v).unwrap(), &coarse.eval(u).unwrap(), 1e-11)
                })
            });
            assert!(same, "{rule:?} n={n}: the refined closed curve differs");
        }
    }
}

#[test]
fn open_midpoint_insertion_on_clamped_knots_equals_the_engine_refine_row_by_row() {
    let mut g = Lcg(18);
    let mut differing = Vec::new();
    for (rule, k) in BSPLINE_RULES {
        for n in rule.min_points(Ends::Open).max(k)..=14 {
            let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
            let theirs = refine(&pts, 2, rule, Ends::Open).unwrap();
            let coarse = BSpline::open(pts.clone(), 2, k).unwrap();
            let ours = insert_midpoints(&coarse).unwrap();
            let ours = ours.points();
            assert_eq!(theirs.len(), ours.len(), "{rule:?} n={n}: lengths");
            for i in 0..theirs.len() / 2 {
                if !close(&theirs[i * 2..i * 2 + 2], &ours[i * 2..i * 2 + 2], 1e-13) {
                    differing.push(format!("{rule:?} n={n} row {i}"));
                }
            }
            // and the refined polygon, on the finer open knots, is the same curve
            let fine = BSpline::open(theirs.clone(), 2, k).unwrap();
            for i in 0..=100 {
                let u = i as f64 / 100.0;
                assert_close(
                    &fine.eval(u).unwrap(),
                    &coarse.eval(u).unwrap(),
                    1e-12,
                    &format!("{rule:?} n={n} u={u}"),
                );
            }
        }
    }
    assert!(
        differing.is_empty(),
        "rows where refine(Open) differs from Boehm insertion: {differing:?}"
    );
}

#[test]
fn engine_refine_steps_equal_repeated_midpoint_insertion_and_four_point_interpolates() {
    // three steps of the engine = three rounds of midpoint insertion on the open cubic
    let mut g = Lcg(19);
    let n = 10;
    let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
    let coarse = BSpline::open(pts.clone(), 2, 4).unwrap();
    let mut ours = coarse.clone();
    for steps in 1..=3 {
        ours = insert_midpoints(&ours).unwrap();
        let theirs = refine_steps(&pts, 2, Refinement::Cubic, Ends::Open, steps).unwrap();
        assert_close(&theirs, ours.points(), 1e-12, &format!("{steps} steps"));
    }
    // the 4-point scheme interpolates: every coarse point stays (§7.6.1)
    let f = refine(&pts, 2, Refinement::FourPoint, Ends::Closed).unwrap();
    for j in 0..n {
        assert!((0..2 * n).any(|i| close(&f[i * 2..i * 2 + 2], &pts[j * 2..j * 2 + 2], 0.0)));
    }
}

#[test]
fn rational_basis_is_non_negative_sums_to_one_and_reproduces_the_curve() {
    let mut g = Lcg(20);
    for _ in 0..50 {
        let k = g.int(1, 5);
        let n = g.int(k, k + 6);
        let t = KnotVector::open(n, k).unwrap().as_slice().to_vec();
        let pts: Vec<f64> = (0..n * 2).map(|_| g.range(-5.0, 5.0)).collect();
        let ws: Vec<f64> = (0..n).map(|_| g.range(0.2, 4.0)).collect();
        let c = Nurbs::new(&pts, &ws, 2, k, t.clone()).unwrap();
        for i in 0..=20 {
            let u = i as f64 / 20.0;
            let r = c.rational_basis(u).unwrap();
            assert!(r.iter().all(|&x| x >= 0.0));
            assert!((r.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            let p: Vec<f64> = (0..2)
                .map(|d| (0..n).map(|j| r[j] * pts[j * 2 + d]).sum())
                .collect();
            assert_close(&p, &c.eval(u).unwrap(), 1e-12, "Σ R_i P_i");
        }
        // R_{0,k}(0) = R_{m,k}(1) = 1 on the standard knots (§4.3)
        assert!((c.rational_basis(0.0).unwrap()[0] - 1.0).abs() < 1e-15);
        assert!((c.rational_basis(1.0).unwrap()[n - 1] - 1.0).abs() < 1e-15);
        // equal weights: R = N
        let e = Nurbs::new(&pts, &vec![3.0; n], 2, k, t.clone()).unwrap();
        let u = g.next();
        let r = e.rational_basis(u).unwrap();
        for (j, rj) in r.iter().enumerate() {
            assert!((rj - basis_brute(&t, n, j, k, u)).abs() < 1e-14);
        }
    }
}

#[test]
fn geomdl_knot_insertion_agrees_to_1e_12() {
    let f = fixture("geomdl_curves.json");
    let cases = f["insertions"].as_array().unwrap();
    assert!(cases.len() >= 16);
    for c in cases {
        let k = c["order"].as_u64().unwrap() as usize;
        let pts = floats(&c["points"]);
        let knots = floats(&c["knots"]);
        let u = c["u"].as_f64().unwrap();
        let times = c["times"].as_u64().unwrap();
        let want_knots = floats(&c["new_knots"]);
        let want_pts = floats(&c["new_points"]);
        if c["rational"].as_bool().unwrap() {
            let mut r = Nurbs::new(&pts, &floats(&c["weights"]), 2, k, knots).unwrap();
            for _ in 0..times {
                r = insert_nurbs(&r, u).unwrap();
            }
            assert_close(r.knots(), &want_knots, 1e-15, "knots");
            assert_close(&r.points(), &want_pts, 1e-12, "NURBS points");
            assert_close(&r.weights(), &floats(&c["new_weights"]), 1e-12, "weights");
        } else {
            let mut b = BSpline::new(pts, 2, k, knots).unwrap();
            for _ in 0..times {
                b = insert(&b, u).unwrap();
            }
            assert_close(b.knots(), &want_knots, 1e-15, "knots");
            assert_close(
                b.points(),
                &want_pts,
                1e-12,
                &format!("k={k} u={u} x{times}"),
            );
        }
    }
}
