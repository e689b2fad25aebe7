//! Curve and surface evaluation throughput (issue 8), one core.
//!
//! `cargo bench --bench curve` prints one line per case:
//! `RESULT <case> <points> <seconds> <Mpoints/s>` (best of several runs), which
//! `benches/peers/curve_peers.py` reads to compare with SciPy, tinyspline and geomdl in the
//! same run.

use mra::curve::{BSpline, Nurbs};
use mra::surface::TensorPatch;
use std::hint::black_box;
use std::time::Instant;

fn best_of<F: FnMut()>(runs: usize, mut f: F) -> f64 {
    let mut best = f64::MAX;
    for _ in 0..runs {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    best
}

fn report(case: &str, points: usize, secs: f64) {
    println!(
        "RESULT {case} {points} {secs:.6} {:.1}",
        points as f64 / secs / 1e6
    );
}

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 53) as f64
}

fn main() {
    let n = 1_000_000;
    let mut seed = 7u64;
    // cubic B-spline, 20 control points in 3D, open knots, 10^6 sorted parameters
    let pts: Vec<f64> = (0..20 * 3).map(|_| lcg(&mut seed) * 10.0 - 5.0).collect();
    let c = BSpline::open(pts, 3, 4).unwrap();
    let params: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let mut out = vec![0.0; n * 3];
    let s = best_of(15, || c.eval_many(black_box(&params), &mut out).unwrap());
    black_box(&out);
    report("bspline_cubic_20", n, s);
    // the same through the basis functions of §3.9 (no power form), for reference
    let s = best_of(5, || {
        c.eval_many_de_boor(black_box(&params), &mut out).unwrap()
    });
    black_box(&out);
    report("bspline_cubic_20_basis_path", n, s);

    // the exact NURBS circle (§4.1), 10^6 points
    let circle = Nurbs::circle([0.0, 0.0], 1.0).unwrap();
    let mut out2 = vec![0.0; n * 2];
    let s = best_of(15, || {
        circle.eval_many(black_box(&params), &mut out2).unwrap()
    });
    black_box(&out2);
    report("nurbs_circle", n, s);

    // 1000 × 1000 grid of a bicubic 10 × 10 B-spline patch in 3D
    let m = 1000;
    let net: Vec<f64> = (0..10 * 10 * 3)
        .map(|_| lcg(&mut seed) * 10.0 - 5.0)
        .collect();
    let tu = mra::curve::KnotVector::open(10, 4)
        .unwrap()
        .as_slice()
        .to_vec();
    let p = TensorPatch::bspline(net, 3, (10, 10), (4, 4), tu.clone(), tu).unwrap();
    let g: Vec<f64> = (0..m).map(|i| i as f64 / (m - 1) as f64).collect();
    let mut grid = vec![0.0; m * m * 3];
    let s = best_of(15, || {
        p.eval_grid(black_box(&g), black_box(&g), &mut grid)
            .unwrap()
    });
    black_box(&grid);
    report("patch_bicubic_10x10_grid_1000", m * m, s);
}
