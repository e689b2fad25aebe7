use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let h: usize = args[1].parse().unwrap();
    let w: usize = args[2].parse().unwrap();
    let scheme = args[3].parse().unwrap();
    let levels: usize = args[4].parse().unwrap();
    let shape = vec![h, w];
    let len = h * w;
    let data: Vec<f32> = (0..len).map(|i| (i % 251) as f32).collect();
    let mut a = Array::from_shape_vec(&shape, data).unwrap();
    let spec = PyramidSpec {
        scheme,
        boundary: mra::scheme::Boundary::Symmetric,
        levels,
        order: Order::NonStandard,
        axes: vec![0, 1],
    };
    let mut best = (f64::MAX, f64::MAX);
    for _ in 0..8 {
        let t = Instant::now();
        let pyr = analyze(&mut a, &spec).unwrap();
        let t1 = t.elapsed().as_secs_f64();
        synthesize(&mut a, &pyr).unwrap();
        let t2 = t.elapsed().as_secs_f64() - t1;
        best = (best.0.min(t1), best.1.min(t2));
    }
    println!(
        "{h}x{w} L{levels}: fwd {:.1} inv {:.1} ms",
        best.0 * 1e3,
        best.1 * 1e3
    );
}
