//! Time forward+inverse pyramids of an image (5 levels) or a volume (3 levels):
//! `cargo run --release --example pyramid_timing -- 4096 cubic symmetric [reps] [dims 2|3] [levels]`.
//! For CPU time on a busy machine: `perf stat -e task-clock` with reps 1 and 11, difference / 10.
//! `SHAPE=256x256x264` in the environment times that shape instead of `n` along every axis.
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
    let reps: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(3);
    let dims: usize = args.get(5).and_then(|s| s.parse().ok()).unwrap_or(2);
    let levels: usize = args
        .get(6)
        .and_then(|s| s.parse().ok())
        .unwrap_or(if dims == 3 { 3 } else { 5 });
    let shape: Vec<usize> = match std::env::var("SHAPE") {
        Ok(v) => v
            .split('x')
            .map(|t| t.parse().expect("SHAPE: sizes joined by x"))
            .collect(),
        Err(_) => vec![n; dims],
    };
    let len: usize = shape.iter().product();
    let data: Vec<f32> = (0..len).map(|i| (i % 251) as f32).collect();
    let mut a = Array::from_shape_vec(&shape, data.clone()).unwrap();
    let spec = PyramidSpec {
        scheme,
        boundary,
        levels,
        order: Order::NonStandard,
        axes: (0..dims).collect(),
    };
    for _ in 0..reps {
        let t = Instant::now();
        let pyr = analyze(&mut a, &spec).unwrap();
        let t1 = t.elapsed().as_secs_f64();
        synthesize(&mut a, &pyr).unwrap();
        let t2 = t.elapsed().as_secs_f64();
        println!(
            "forward {:.2} ms, inverse {:.2} ms, {:.0} MB/s",
            t1 * 1e3,
            (t2 - t1) * 1e3,
            (len * 4) as f64 / t2 / 1e6
        );
    }
    let err = a
        .data()
        .iter()
        .zip(&data)
        .map(|(x, y)| (x - y).abs())
        .fold(0f32, f32::max);
    println!("max reconstruction error {err:e}");
}
