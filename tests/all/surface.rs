//! Surfaces: tensor-product patches, exact NURBS primitives, curve-based surfaces, tessellation
//! and mesh output (issue 8).

use mra::curve::{BSpline, Bezier, Curve, Nurbs};
use mra::mesh::io::{obj, ply};
use mra::mesh::render::{encode_png, render, Options, BACKGROUND};
use mra::mesh::Mesh;
use mra::surface::sweep::transport;
use mra::surface::{
    tessellate, Coons, CrossBlend, FaceKind, Loft, Revolution, RotationalBlend, Surface, Sweep,
    TensorPatch,
};
use mra::ErrorKind;
use std::f64::consts::{PI, TAU};

use super::common;

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
}

/// The per-vertex normals `tessellate` stores in the mesh.
fn normals(m: &Mesh) -> &[[f64; 3]] {
    m.attributes.vertex_normals.as_deref().unwrap()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}
fn v3(p: &[f64]) -> [f64; 3] {
    [p[0], p[1], if p.len() > 2 { p[2] } else { 0.0 }]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    match v {
        serde_json::Value::Array(a) => a.iter().flat_map(floats).collect(),
        serde_json::Value::Number(x) => vec![x.as_f64().unwrap()],
        _ => vec![],
    }
}

#[test]
fn geomdl_reference_surfaces_agree_to_1e_12() {
    let path = format!(
        "{}/tests/reference/geomdl_surfaces.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let f: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let mut checked = 0;
    for s in f["surfaces"].as_array().unwrap() {
        let g = |k: &str| s[k].as_u64().unwrap() as usize;
        let (ku, kv, nu, nv) = (g("order_u"), g("order_v"), g("nu"), g("nv"));
        let net = floats(&s["net"]);
        let (tu, tv) = (floats(&s["knots_u"]), floats(&s["knots_v"]));
        let p = if s["rational"].as_bool().unwrap() {
            TensorPatch::nurbs(&net, &floats(&s["weights"]), 3, (nu, nv), (ku, kv), tu, tv).unwrap()
        } else {
            TensorPatch::bspline(net, 3, (nu, nv), (ku, kv), tu, tv).unwrap()
        };
        for (uv, want) in s["params"]
            .as_array()
            .unwrap()
            .iter()
            .zip(s["values"].as_array().unwrap())
        {
            let uv = floats(uv);
            let want = floats(want);
            let got = p.eval(uv[0], uv[1]).unwrap();
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() <= 1e-12 * (1.0 + want[c].abs()),
                    "{} ({ku},{kv}) at {uv:?}: {got:?} vs {want:?}",
                    s["kind"]
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 500, "{checked}");
}

#[test]
fn bezier_patch_u_curves_are_bezier_curves_of_the_column_points() {
    // §5.3.1: Q(u, v) = Σ_i P_i^v B_{i,d}(u) with P_i^v = Σ_j P_{ij} B_{j,d'}(v)
    let mut g = Lcg(1);
    let (nu, nv) = (4, 3);
    let net: Vec<f64> = (0..nu * nv * 3).map(|_| g.range(-3.0, 3.0)).collect();
    let p = TensorPatch::bezier(net.clone(), 3, (nu, nv)).unwrap();
    for _ in 0..50 {
        let (u, v) = (g.next(), g.next());
        let mut col = Vec::new();
        for i in 0..nu {
            let row = Bezier::new(net[i * nv * 3..(i + 1) * nv * 3].to_vec(), 3).unwrap();
            col.extend(row.eval(v).unwrap());
        }
        let want = Bezier::new(col, 3).unwrap().eval(u).unwrap();
        assert!(dist(v3(&p.eval(u, v).unwrap()), v3(&want)) < 1e-13);
    }
    // first degree: the bilinear patch
    let corners = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 2.0, 1.0, 1.0, 0.0];
    let b = TensorPatch::bezier(corners, 3, (2, 2)).unwrap();
    let q = b.eval(0.25, 0.5).unwrap();
    let want = [
        0.25,
        0.5,
        0.75 * 0.5 * 1.0 + 0.25 * 0.5 * 2.0 + 0.25 * 0.5 * 0.0,
    ];
    assert!(dist(v3(&q), want) < 1e-15, "{q:?}");
}

#[test]
fn partial_derivatives_match_finite_differences_for_rational_and_polynomial_patches() {
    let mut g = Lcg(2);
    let (nu, nv) = (6, 5);
    let net: Vec<f64> = (0..nu * nv * 3).map(|_| g.range(-3.0, 3.0)).collect();
    let w: Vec<f64> = (0..nu * nv).map(|_| g.range(0.3, 3.0)).collect();
    let tu = mra::curve::KnotVector::open(nu, 4)
        .unwrap()
        .as_slice()
        .to_vec();
    let tv = mra::curve::KnotVector::open(nv, 3)
        .unwrap()
        .as_slice()
        .to_vec();
    let patches = [
        TensorPatch::bspline(net.clone(), 3, (nu, nv), (4, 3), tu.clone(), tv.clone()).unwrap(),
        TensorPatch::nurbs(&net, &w, 3, (nu, nv), (4, 3), tu, tv).unwrap(),
    ];
    let h = 1e-6;
    for p in &patches {
        for _ in 0..30 {
            let (u, v) = (g.range(0.01, 0.99), g.range(0.01, 0.99));
            let [q, qu, qv] = p.eval_partials(u, v).unwrap();
            assert!(dist(v3(&q), v3(&p.eval(u, v).unwrap())) < 1e-13);
            let fu: Vec<f64> = (0..3)
                .map(|c| (p.eval(u + h, v).unwrap()[c] - p.eval(u - h, v).unwrap()[c]) / (2.0 * h))
                .collect();
            let fv: Vec<f64> = (0..3)
                .map(|c| (p.eval(u, v + h).unwrap()[c] - p.eval(u, v - h).unwrap()[c]) / (2.0 * h))
                .collect();
            let scale = 1.0 + fu.iter().chain(&fv).fold(0.0f64, |m, x| m.max(x.abs()));
            assert!(dist(v3(&qu), v3(&fu)) < 1e-6 * scale, "{qu:?} vs {fu:?}");
            assert!(dist(v3(&qv), v3(&fv)) < 1e-6 * scale, "{qv:?} vs {fv:?}");
        }
    }
}

#[test]
fn grid_evaluation_equals_pointwise_evaluation() {
    let mut g = Lcg(3);
    for (ku, kv, rational) in [(4, 4, false), (3, 5, false), (4, 4, true), (2, 3, true)] {
        let (nu, nv) = (ku + 4, kv + 3);
        let net: Vec<f64> = (0..nu * nv * 3).map(|_| g.range(-3.0, 3.0)).collect();
        let w: Vec<f64> = (0..nu * nv).map(|_| g.range(0.3, 3.0)).collect();
        let tu = mra::curve::KnotVector::uniform(nu, ku).as_slice().to_vec();
        let tv = mra::curve::KnotVector::open(nv, kv)
            .unwrap()
            .as_slice()
            .to_vec();
        let p = if rational {
            TensorPatch::nurbs(&net, &w, 3, (nu, nv), (ku, kv), tu, tv).unwrap()
        } else {
            TensorPatch::bspline(net, 3, (nu, nv), (ku, kv), tu, tv).unwrap()
        };
        let ((u0, u1), (v0, v1)) = p.ranges();
        let us: Vec<f64> = (0..17).map(|i| u0 + (u1 - u0) * i as f64 / 16.0).collect();
        let vs: Vec<f64> = (0..23).map(|i| v0 + (v1 - v0) * i as f64 / 22.0).collect();
        let mut out = vec![0.0; us.len() * vs.len() * 3];
        p.eval_grid(&us, &vs, &mut out).unwrap();
        for (i, &u) in us.iter().enumerate() {
            for (j, &v) in vs.iter().enumerate() {
                let k = (i * vs.len() + j) * 3;
                assert!(dist(v3(&out[k..k + 3]), v3(&p.eval(u, v).unwrap())) < 1e-12);
            }
        }
    }
}

#[test]
fn exact_nurbs_sphere_torus_and_cylinder_lie_on_their_surfaces() {
    let n = 101;
    let grid = |p: &TensorPatch, f: &dyn Fn([f64; 3]) -> f64| {
        let ((u0, u1), (v0, v1)) = p.ranges();
        let mut worst: f64 = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = u0 + (u1 - u0) * i as f64 / (n - 1) as f64;
                let v = v0 + (v1 - v0) * j as f64 / (n - 1) as f64;
                worst = worst.max(f(v3(&p.eval(u, v).unwrap())).abs());
            }
        }
        worst
    };
    let s = TensorPatch::sphere(2.0).unwrap();
    assert!(s.is_rational());
    assert!(grid(&s, &|p| dot(p, p).sqrt() - 2.0) < 1e-12);
    let t = TensorPatch::torus(3.0, 1.0).unwrap();
    assert!(
        grid(&t, &|p| ((p[0].hypot(p[1]) - 3.0).powi(2) + p[2] * p[2])
            .sqrt()
            - 1.0)
            < 1e-12
    );
    let c = TensorPatch::cylinder(1.5, 4.0).unwrap();
    assert!(grid(&c, &|p| p[0].hypot(p[1]) - 1.5) < 1e-12);
    assert!(
        grid(&c, &|p| if (-1e-12..=4.0 + 1e-12).contains(&p[2]) {
            0.0
        } else {
            1.0
        }) == 0.0
    );
    assert_eq!(
        TensorPatch::torus(1.0, 2.0).unwrap_err().kind(),
        ErrorKind::Parameter
    );
}

fn bez(pts: &[[f64; 3]]) -> Box<dyn Curve> {
    Box::new(Bezier::new(pts.iter().flatten().copied().collect(), 3).unwrap())
}

fn coons_curves() -> [Vec<[f64; 3]>; 4] {
    let (p00, p10, p01, p11) = (
        [0.0, 0.0, 0.0],
        [3.0, 0.0, 0.0],
        [0.0, 3.0, 0.0],
        [3.0, 3.0, 0.5],
    );
    [
        vec![p00, [1.0, 0.0, 1.0], [2.0, 0.0, -0.5], p10],
        vec![p01, [1.0, 3.0, -0.5], [2.0, 3.0, 1.0], p11],
        vec![p00, [0.0, 1.0, 0.8], [0.0, 2.0, 0.8], p01],
        vec![p10, [3.0, 1.0, -0.8], [3.0, 2.0, 1.2], p11],
    ]
}

#[test]
fn coons_patch_interpolates_its_four_boundary_curves() {
    let c = coons_curves();
    let s = Coons::new(bez(&c[0]), bez(&c[1]), bez(&c[2]), bez(&c[3])).unwrap();
    let b: Vec<Box<dyn Curve>> = c.iter().map(|p| bez(p)).collect();
    for i in 0..=50 {
        let t = i as f64 / 50.0;
        let pt = |k: usize| v3(&b[k].point(t).unwrap());
        assert!(dist(s.point(t, 0.0).unwrap(), pt(0)) < 1e-14);
        assert!(dist(s.point(t, 1.0).unwrap(), pt(1)) < 1e-14);
        assert!(dist(s.point(0.0, t).unwrap(), pt(2)) < 1e-14);
        assert!(dist(s.point(1.0, t).unwrap(), pt(3)) < 1e-14);
    }
    // exact partials agree with differences
    let [_, qu, qv] = s.partials(0.3, 0.6).unwrap();
    let h = 1e-6;
    let fu = (0..3).map(|k| {
        (s.point(0.3 + h, 0.6).unwrap()[k] - s.point(0.3 - h, 0.6).unwrap()[k]) / (2.0 * h)
    });
    let fv = (0..3).map(|k| {
        (s.point(0.3, 0.6 + h).unwrap()[k] - s.point(0.3, 0.6 - h).unwrap()[k]) / (2.0 * h)
    });
    assert!(qu.iter().zip(fu).all(|(a, b)| (a - b).abs() < 1e-7));
    assert!(qv.iter().zip(fv).all(|(a, b)| (a - b).abs() < 1e-7));
    // curves that do not meet at a corner are refused
    let mut bad = coons_curves();
    bad[3][3] = [3.0, 3.0, 0.6];
    let e = Coons::new(bez(&bad[0]), bez(&bad[1]), bez(&bad[2]), bez(&bad[3]))
        .err()
        .unwrap();
    assert_eq!(e.kind(), ErrorKind::Parameter);
    assert!(e.to_string().contains("corner"), "{e}");
}

fn circle3(z: f64) -> Box<dyn Curve> {
    // the NURBS circle lifted to height z
    let c = Nurbs::circle([0.0, 0.0], 1.0).unwrap();
    let pts: Vec<f64> = c.points().chunks(2).flat_map(|p| [p[0], p[1], z]).collect();
    Box::new(Nurbs::new(&pts, &c.weights(), 3, 3, c.knots().to_vec()).unwrap())
}

#[test]
fn loft_between_two_circles_is_a_cylinder_and_interpolates_both() {
    let s = Loft {
        p0: circle3(0.0),
        p1: circle3(2.0),
    };
    for i in 0..=20 {
        for j in 0..=20 {
            let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
            let p = s.point(u, v).unwrap();
            assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-12 && (p[2] - 2.0 * v).abs() < 1e-14);
        }
    }
    let m = tessellate(&s, 33, 9, FaceKind::Quads).unwrap();
    // the normal Q_u × Q_v of a counter-clockwise circle lofted upward points outward
    for (p, n) in m.positions.iter().zip(normals(&m)) {
        assert!(
            (n[0] * p[0] + n[1] * p[1] - 1.0).abs() < 1e-9 && n[2].abs() < 1e-9,
            "{n:?} at {p:?}"
        );
    }
}

#[test]
fn revolution_by_trigonometry_and_exact_nurbs_revolve_trace_the_profile() {
    let prof = vec![0.5, 0.0, 1.0, 0.5, 0.7, 1.0, 0.9, 1.5];
    let b = BSpline::open(prof.clone(), 2, 3).unwrap();
    let trig = Revolution {
        profile: Box::new(b.clone()),
        angle: TAU,
    };
    let n = Nurbs::new(&prof, &[1.0; 4], 2, 3, b.knots().to_vec()).unwrap();
    let exact = TensorPatch::revolve(&n, TAU).unwrap();
    for i in 0..=16 {
        for j in 0..=16 {
            let (t, v) = (i as f64 / 16.0, j as f64 / 16.0);
            let c = b.eval(v).unwrap();
            let p = trig.point(t * TAU, v).unwrap();
            assert!((p[0].hypot(p[1]) - c[0]).abs() < 1e-13 && (p[2] - c[1]).abs() < 1e-14);
            assert!((p[0] - c[0] * (t * TAU).cos()).abs() < 1e-13);
            let q = exact.eval(t, v).unwrap();
            assert!((q[0].hypot(q[1]) - c[0]).abs() < 1e-12 && (q[2] - c[1]).abs() < 1e-12);
        }
    }
    // example 5.5: a torus from a circle profile
    let tor = Revolution {
        profile: Box::new(Nurbs::circle([2.0, 0.0], 0.5).unwrap()),
        angle: TAU,
    };
    let p = tor.point(1.0, 0.3).unwrap();
    assert!(((p[0].hypot(p[1]) - 2.0).powi(2) + p[2] * p[2] - 0.25).abs() < 1e-12);
}

fn helix(turns: f64, pts: usize) -> Box<dyn Curve> {
    // an interpolating-ish helix: dense control points on the helix, cubic open B-spline
    let mut p = Vec::new();
    for i in 0..pts {
        let t = turns * TAU * i as f64 / (pts - 1) as f64;
        p.extend_from_slice(&[t.cos(), t.sin(), 0.2 * t]);
    }
    Box::new(BSpline::open(p, 3, 4).unwrap())
}

fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    dot(a, b).clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn sweep_along_a_helix_has_no_frame_flips() {
    let profile: Box<dyn Curve> = Box::new(Nurbs::circle([0.0, 0.0], 0.1).unwrap());
    let s = Sweep::new(profile, helix(3.0, 60), 600, None).unwrap();
    let frames = s.sampled_frames();
    for w in frames.windows(2) {
        let ([t0, n0, b0], [t1, n1, _]) = (w[0], w[1]);
        assert!(angle(n0, n1) < 10.0, "normal turned {}°", angle(n0, n1));
        assert!(
            dot(n0, t0).abs() < 1e-12
                && dot(b0, t0).abs() < 1e-12
                && (dot(n0, n0) - 1.0).abs() < 1e-12
        );
        // rotation-minimising: N does not spin about T (its change is along T only, to first order)
        let dn = [n1[0] - n0[0], n1[1] - n0[1], n1[2] - n0[2]];
        assert!(dot(dn, b0).abs() < 1e-3, "twist {}", dot(dn, b0));
        let _ = t1;
    }
    // surface points sit at the profile radius from the path, in the normal plane
    for i in 0..=20 {
        let u = i as f64 / 20.0;
        let [t, _, _] = s.frame(u).unwrap();
        let c = v3(&helix(3.0, 60).point(u).unwrap());
        for j in 0..8 {
            let p = s.point(u, j as f64 / 8.0).unwrap();
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            assert!((dist(p, c) - 0.1).abs() < 1e-12 && dot(d, t).abs() < 1e-12);
        }
    }
}

#[test]
fn parallel_transport_keeps_the_normal_through_an_inflection_where_frenet_flips() {
    // planar S-curve: y = x³ has an inflection at 0
    let pts: Vec<f64> = (0..9)
        .flat_map(|i| {
            let x = -1.0 + i as f64 / 4.0;
            [x, x * x * x, 0.0]
        })
        .collect();
    let path: Box<dyn Curve> = Box::new(BSpline::open(pts, 3, 4).unwrap());
    let s = Sweep::new(
        Box::new(Nurbs::circle([0.0, 0.0], 0.05).unwrap()),
        path,
        400,
        Some([0.0, 1.0, 0.0]),
    )
    .unwrap();
    let f = s.sampled_frames();
    for w in f.windows(2) {
        assert!(angle(w[0][1], w[1][1]) < 10.0);
    }
    // the Frenet normal (T × (Q' × Q'')) × … flips sign across the inflection
    let c = mra::curve::BSpline::open(
        (0..9)
            .flat_map(|i| {
                let x = -1.0 + i as f64 / 4.0;
                [x, x * x * x, 0.0]
            })
            .collect(),
        3,
        4,
    )
    .unwrap();
    let frenet_b = |u: f64| {
        cross(
            v3(&c.derivative(u, 1).unwrap()),
            v3(&c.derivative(u, 2).unwrap()),
        )
    };
    assert!(
        frenet_b(0.3)[2] * frenet_b(0.7)[2] < 0.0,
        "binormal flips at the inflection"
    );
    assert!(
        dot(f[120][1], f[280][1]) > 0.9,
        "parallel transport does not flip"
    );
    // a transported vector stays unit and orthogonal
    let n = transport([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.6, 0.8, 0.0]);
    assert!((dot(n, n) - 1.0).abs() < 1e-15 && dot(n, [0.6, 0.8, 0.0]).abs() < 1e-15);
}

fn stroke(pts: &[[f64; 2]]) -> Box<dyn Curve> {
    Box::new(BSpline::open(pts.iter().flatten().copied().collect(), 2, 4).unwrap())
}

fn pear() -> (Box<dyn Curve>, Box<dyn Curve>) {
    let l = [
        [0.0, 0.0],
        [-0.8, 0.3],
        [-1.2, 1.2],
        [-0.5, 2.2],
        [-0.4, 3.0],
        [-0.05, 3.4],
    ];
    let r: Vec<[f64; 2]> = l.iter().map(|p| [-p[0], p[1]]).collect();
    (stroke(&l), stroke(&r))
}

#[test]
fn rotational_blend_passes_through_both_strokes_on_circles() {
    let (l, r) = pear();
    let s = RotationalBlend::new(l, r).unwrap();
    let (l, r) = pear();
    for i in 0..=20 {
        let u = i as f64 / 20.0;
        let (a, b) = (v3(&l.point(u).unwrap()), v3(&r.point(u).unwrap()));
        assert!(dist(s.point(u, 0.0).unwrap(), a) < 1e-14);
        assert!(dist(s.point(u, PI).unwrap(), b) < 1e-12);
        let c = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, 0.0];
        for j in 0..12 {
            let p = s.point(u, j as f64 * TAU / 12.0).unwrap();
            assert!((dist(p, c) - dist(a, b) / 2.0).abs() < 1e-12);
        }
    }
}

#[test]
fn cross_blend_with_a_half_circle_section_is_the_rotational_blend() {
    let (l, r) = pear();
    let rot = RotationalBlend::new(l, r).unwrap();
    let (l, r) = pear();
    let half = Nurbs::arc([0.5, 0.0], 0.5, 0.0, PI).unwrap(); // from (1,0) to (0,0) above the chord
                                                              // draw it from the left end (0,0) to the right end (1,0): mirror x
    let pts: Vec<f64> = half
        .points()
        .chunks(2)
        .flat_map(|p| [1.0 - p[0], p[1]])
        .collect();
    let sec = Nurbs::new(&pts, &half.weights(), 2, 3, half.knots().to_vec()).unwrap();
    let cross_s = CrossBlend::new(l, r, Box::new(sec), true).unwrap();
    for i in 0..=10 {
        let u = i as f64 / 10.0;
        for v in [0.0, 0.25, 0.5, 0.75, 1.0] {
            // the arc's rational parameter is not the angle: compare positions on the same circle
            let p = cross_s.point(u, v).unwrap();
            let on_circle =
                (0..=2000).any(|k| dist(rot.point(u, PI * k as f64 / 2000.0).unwrap(), p) < 2e-3);
            assert!(on_circle, "u={u} v={v}");
        }
        assert!(
            dist(
                cross_s.point(u, 0.5).unwrap(),
                rot.point(u, PI / 2.0).unwrap()
            ) < 1e-12
        );
        assert!(
            dist(
                cross_s.point(u, 1.5).unwrap(),
                rot.point(u, 1.5 * PI).unwrap()
            ) < 1e-12
        );
    }
}

#[test]
fn tessellation_counts_and_outward_unit_normals_on_the_sphere_including_poles() {
    let s = TensorPatch::sphere(1.0).unwrap();
    let m = tessellate(&s, 17, 13, FaceKind::Triangles).unwrap();
    assert_eq!(m.positions.len(), 17 * 13);
    assert_eq!(m.face_count(), 2 * 16 * 12);
    for (p, n) in m.positions.iter().zip(normals(&m)) {
        assert!((dot(*n, *n) - 1.0).abs() < 1e-12);
        assert!(dot(*n, *p) > 0.9, "normal {n:?} at {p:?}");
    }
    let q = tessellate(&s, 5, 4, FaceKind::Quads).unwrap();
    assert!(q.faces().all(|f| f.len() == 4) && q.face_count() == 4 * 3);
    assert_eq!(
        tessellate(&s, 1, 4, FaceKind::Quads).unwrap_err().kind(),
        ErrorKind::Parameter
    );
}

#[test]
fn obj_round_trip_and_ply_header() {
    let m = tessellate(
        &TensorPatch::torus(2.0, 0.5).unwrap(),
        9,
        7,
        FaceKind::Triangles,
    )
    .unwrap();
    let back = obj::parse(&obj::to_bytes(&m).unwrap()).unwrap();
    assert_eq!(back.positions, m.positions);
    assert_eq!((&back.offsets, &back.indices), (&m.offsets, &m.indices));
    // the analytic normals go out as `vn` lines, one per vertex
    assert_eq!(back.attributes.normals, normals(&m));
    let ply = String::from_utf8(ply::to_bytes(&m, ply::Encoding::Ascii).unwrap()).unwrap();
    assert!(ply.starts_with("ply\nformat ascii 1.0\n"));
    assert!(ply.contains(&format!("element vertex {}\n", m.positions.len())));
    assert!(ply.contains(&format!("element face {}\n", m.face_count())));
    assert!(["nx", "ny", "nz"]
        .iter()
        .all(|c| ply.contains(&format!("property double {c}\n"))));
    let header = ply.lines().position(|l| l == "end_header").unwrap() + 1;
    assert_eq!(
        ply.lines().count(),
        header + m.positions.len() + m.face_count()
    );
    assert!(obj::parse(b"v 0 0 0\nf 1 2 3\n").is_err());
}

#[test]
fn render_draws_the_model_in_the_middle_of_the_picture() {
    let m = tessellate(
        &TensorPatch::sphere(1.0).unwrap(),
        24,
        24,
        FaceKind::Triangles,
    )
    .unwrap();
    let img = render(
        &m,
        &Options {
            width: 64,
            height: 48,
            azimuth: 35.0,
            elevation: 25.0,
            z_up: true,
            back_color: Some([225, 170, 110]),
            supersample: 2,
            ..Options::default()
        },
    )
    .unwrap();
    assert_eq!((img.width, img.height), (64, 48));
    let px = |x: usize, y: usize| &img.rgb[(y * 64 + x) * 3..(y * 64 + x) * 3 + 3];
    assert_ne!(px(32, 24), &BACKGROUND);
    assert_eq!(px(0, 0), &BACKGROUND);
    let png = encode_png(&img).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

fn mra_cmd(args: &[&str]) -> (i32, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mra-surface-tests-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn cli_surface_commands_write_meshes_and_refuse_bad_input() {
    let o = scratch("coons.obj");
    let os = o.to_str().unwrap();
    let (code, err) = mra_cmd(&[
        "surface",
        "coons",
        "--kind",
        "bezier",
        "--p0",
        "corpus/curves/coons_p0.csv",
        "--p1",
        "corpus/curves/coons_p1.csv",
        "--q0",
        "corpus/curves/coons_q0.csv",
        "--q1",
        "corpus/curves/coons_q1.csv",
        "--resolution",
        "9,7",
        "-o",
        os,
    ]);
    assert_eq!(code, 0, "{err}");
    let m = mra::mesh::io::read(&o).unwrap();
    assert_eq!((m.positions.len(), m.face_count()), (63, 96));
    assert!(
        dist(m.positions[0], [0.0, 0.0, 0.0]) < 1e-15
            && dist(m.positions[62], [3.0, 3.0, 0.5]) < 1e-15
    );
    let png = scratch("coons.png");
    assert_eq!(
        mra_cmd(&[
            "surface",
            "render",
            os,
            "-o",
            png.to_str().unwrap(),
            "--size",
            "80x60"
        ])
        .0,
        0
    );
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
    // every documented example command of the surface group runs
    for args in [
        vec![
            "surface",
            "patch",
            "--kind",
            "bezier",
            "corpus/curves/patch44.csv",
        ],
        vec!["surface", "primitive", "--shape", "sphere"],
        vec![
            "surface",
            "loft",
            "--kind",
            "bezier",
            "corpus/curves/coons_p0.csv",
            "corpus/curves/coons_p1.csv",
        ],
        vec![
            "surface",
            "revolve",
            "--order",
            "3",
            "--exact",
            "--angle",
            "270",
            "corpus/curves/profile.csv",
        ],
        vec![
            "surface",
            "sweep",
            "--order",
            "3",
            "--profile",
            "corpus/curves/section.csv",
            "--path",
            "corpus/curves/helix.csv",
        ],
        vec![
            "surface",
            "rotational-blend",
            "--left",
            "corpus/curves/left.csv",
            "--right",
            "corpus/curves/right.csv",
        ],
        vec![
            "surface",
            "cross-blend",
            "--left",
            "corpus/curves/left.csv",
            "--right",
            "corpus/curves/right.csv",
            "--section",
            "corpus/curves/section_leaf.csv",
            "--mirror",
        ],
    ] {
        // a fresh file per command: a command that writes nothing cannot pass on the
        // output of the one before
        let out = common::scratch_file("example.ply");
        let mut a = args.clone();
        a.extend(["--resolution", "12,10", "-o", out.to_str().unwrap()]);
        let (code, err) = mra_cmd(&a);
        assert_eq!(code, 0, "{a:?}: {err}");
        let text = std::fs::read_to_string(&out).unwrap_or_else(|e| panic!("{a:?}: {e}"));
        assert!(text.contains("element vertex 120"), "{a:?}");
        let m = mra::mesh::io::read(&out).unwrap_or_else(|e| panic!("{a:?}: {e}"));
        assert_eq!(m.positions.len(), 120, "{a:?}");
        assert!(m.face_count() > 0, "{a:?}");
        assert!(m.positions.iter().flatten().all(|v| v.is_finite()), "{a:?}");
    }
    // corners that do not meet, unknown formats, bad resolution: exit 2, one line, no file
    // (each case its own output path, checked to be absent after the run)
    let bad_dir = common::scratch_dir("bad_surfaces");
    let bad_obj = bad_dir.join("bad.obj");
    let bad_stl = bad_dir.join("bad.stl");
    let (bad, stl) = (bad_obj.to_str().unwrap(), bad_stl.to_str().unwrap());
    for args in [
        vec![
            "surface",
            "coons",
            "--kind",
            "bezier",
            "--p0",
            "corpus/curves/coons_p0.csv",
            "--p1",
            "corpus/curves/coons_p0.csv",
            "--q0",
            "corpus/curves/coons_q0.csv",
            "--q1",
            "corpus/curves/coons_q1.csv",
            "-o",
            bad,
        ],
        vec![
            "surface",
            "primitive",
            "--shape",
            "torus",
            "--radius",
            "1",
            "--minor",
            "2",
            "-o",
            bad,
        ],
        vec![
            "surface",
            "primitive",
            "--shape",
            "sphere",
            "--resolution",
            "1,5",
            "-o",
            bad,
        ],
        vec!["surface", "primitive", "--shape", "sphere", "-o", stl],
    ] {
        let (code, err) = mra_cmd(&args);
        assert_eq!(code, 2, "{args:?}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.starts_with("mra: "), "{err}");
        let left: Vec<_> = std::fs::read_dir(&bad_dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert!(left.is_empty(), "{args:?} left {left:?}");
    }
}
