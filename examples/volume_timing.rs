//! Time forward+inverse pyramids of a volume: `cargo run --release --example volume_timing -- 256 cubic symmetric [reps]`.
use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(128);
    let scheme = args
        .get(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(mra::scheme::Scheme::Cubic);
    let boundary = args
        .get(3)
        .map(|s| s.parse().unwrap())
        .unwrap_or(mra::scheme::Boundary::Symmetric);
    let reps: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(3);
    let data: Vec<f32> = (0..n * n * n).map(|i| (i % 251) as f32).collect();
    let mut a = Array::from_shape_vec(&[n, n, n], data).unwrap();
    let spec = PyramidSpec {
        scheme,
        boundary,
        levels: 3,
        order: Order::NonStandard,
        axes: vec![0, 1, 2],
    };
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
            (n * n * n * 4) as f64 / t2 / 1e6
        );
    }
}
