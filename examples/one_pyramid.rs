//! One forward+inverse pyramid (for profilers): `one_pyramid N scheme boundary`.
use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1024);
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
    let pyr = analyze(&mut a, &spec).unwrap();
    synthesize(&mut a, &pyr).unwrap();
    println!("{}", a.data()[7]);
}
