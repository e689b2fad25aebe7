//! Marching cubes throughput on 256³ fields (sphere and smooth noise), CSG volume and the
//! 20-primitive render. Peers: `python3 benches/peers/solid_peers.py` (same fields).
//!
//!     cargo bench --bench solid

use mra::solid::mc::{polygonize, Grid};
use mra::solid::{render, scene::Scene, tlist};
use std::time::Instant;

fn field(name: &str, n: usize) -> Vec<f32> {
    let c = (n - 1) as f64 / 2.0;
    let mut v = vec![0f32; n * n * n];
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let (x, y, z) = (i as f64, j as f64, k as f64);
                v[(k * n + j) * n + i] = if name == "sphere" {
                    (0.35 * (n - 1) as f64
                        - ((x - c).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt())
                        as f32
                } else {
                    ((0.11 * x).sin() * (0.13 * y).cos()
                        + (0.07 * z + 0.3 * (0.05 * x).sin()).sin()) as f32
                };
            }
        }
    }
    v
}

fn best_of<F: FnMut() -> usize>(reps: usize, mut f: F) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut out = 0;
    for _ in 0..reps {
        let t = Instant::now();
        out = f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out)
}

fn main() {
    let n = 256;
    println!("threads: {}", rayon::current_num_threads());
    for name in ["sphere", "noise"] {
        let v = field(name, n);
        let g = Grid {
            values: &v,
            dims: [n; 3],
            spacing: [1.0; 3],
            origin: [0.0; 3],
        };
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (s, faces) = pool
                .install(|| best_of(7, || polygonize(&g, 0.0, false).unwrap().mesh.face_count()));
            println!(
                "marching cubes {name} {n}^3, {threads} thread(s): {:.1} ms, {faces} triangles, {:.1} Mvoxel/s",
                s * 1e3,
                (n * n * n) as f64 / s / 1e6
            );
        }
    }
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/corpus/scenes");
    let sc = Scene::read(std::path::Path::new(&format!("{dir}/csg20.json"))).unwrap();
    let (s, _) = best_of(3, || render::render(&sc, 512, 512).unwrap().rgb.len());
    println!(
        "render 512^2 of {} primitives: {:.1} ms",
        sc.root.leaf_count(),
        s * 1e3
    );
    let sb = Scene::read(std::path::Path::new(&format!(
        "{dir}/box_minus_cylinder.json"
    )))
    .unwrap();
    let (s, _) = best_of(3, || {
        tlist::volume(&sb.root, tlist::DEFAULT_RAYS, tlist::DEFAULT_STEPS).unwrap() as usize
    });
    println!("CSG volume box-cylinder, 512^2 rays: {:.1} ms", s * 1e3);
}
