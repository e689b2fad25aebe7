//! Time forward+inverse pyramids: `cargo run --release --example pyramid_timing -- 4096 cubic symmetric [reps]`.
//! For CPU time on a busy machine: `perf stat -e task-clock` with reps 1 and 11, difference / 10.
use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(2048);
    let scheme = args
        .get(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(mra::scheme::Scheme::Cubic);
    let boundary = args
        .get(3)
        .map(|s| s.parse().unwrap())
        .unwrap_or(mra::scheme::Boundary::Symmetric);
    let data: Vec<f32> = (0..n * n).map(|i| (i % 251) as f32).collect();
    let mut a = Array::from_shape_vec(&[n, n], data).unwrap();
    let spec = PyramidSpec {
        scheme,
        boundary,
        levels: 5,
        order: Order::NonStandard,
        axes: vec![0, 1],
    };
    let reps: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(3);
    for _ in 0..reps {
        let t = Instant::now();
        let pyr = analyze(&mut a, &spec).unwrap();
        let t1 = t.elapsed().as_secs_f64();
        synthesize(&mut a, &pyr).unwrap();
        let t2 = t.elapsed().as_secs_f64();
        println!(
            "forward {:.1} ms, inverse {:.1} ms, {:.0} MB/s",
            t1 * 1e3,
            (t2 - t1) * 1e3,
            (n * n * 4) as f64 / t2 / 1e6
        );
    }
}
