//! Time one level along each axis: `cargo run --release --example axis_timing -- 4096`.
use mra::scheme::{Boundary, Scheme, TwoScale};
use mra::tensor::transform_axis;
use std::time::Instant;
fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4096);
    let mut data: Vec<f32> = (0..n * n).map(|i| (i % 251) as f32).collect();
    let t = TwoScale::new(Scheme::Cubic, Boundary::Symmetric, n);
    for axis in [0, 1] {
        for op in [&t.analysis, &t.synthesis] {
            let s = Instant::now();
            transform_axis(&mut data, &[n, n], &[n, n], axis, op);
            let e = s.elapsed().as_secs_f64();
            println!(
                "axis {axis}: {:.1} ms = {:.0} MB/s",
                e * 1e3,
                (n * n * 4) as f64 / e / 1e6
            );
        }
    }
    let mut dst = vec![0f32; n * n];
    let s = Instant::now();
    dst.copy_from_slice(&data);
    println!("copy: {:.1} ms", s.elapsed().as_secs_f64() * 1e3);
}
