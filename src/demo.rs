//! What the jobs of `mra demo` share: the table's row and the generated data they run
//! on. Each application adds its rows (`codec::demo`, `upscale::demo_rows`,
//! `terrain::demo_rows`, built with the `cli` feature only); the command line gathers
//! them with its own (`cli/demo.rs`).

use std::path::PathBuf;

/// One line of the demo's table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoRow {
    pub job: String,
    pub data: String,
    pub result: String,
    pub seconds: f64,
    pub output: Option<PathBuf>,
}

/// A zig-zag drawn around a circle: a "stroke" with fine detail on a smooth base.
pub fn zigzag_circle(n: usize) -> Vec<f64> {
    (0..n)
        .flat_map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            let r = 10.0 + if i % 2 == 0 { 0.6 } else { -0.6 };
            [r * t.cos(), r * t.sin()]
        })
        .collect()
}

/// The generated zone plate (`mra generate zone-plate`) on the 8-bit scale, as f32.
pub fn zone_plate(h: usize, w: usize) -> Vec<f32> {
    crate::generate::images::zone_plate(h, w)
        .data()
        .iter()
        .map(|&v| (v * 255.0) as f32)
        .collect()
}

/// The generated Shepp–Logan-style phantom (`mra generate phantom`) of `n³` voxels,
/// mapped to a CT-like range (−1000 … 1000) as f32.
pub fn blob_volume(n: usize) -> Vec<f32> {
    crate::generate::phantom::shepp_logan(n, n, n)
        .data()
        .iter()
        .map(|&v| (v * 2000.0 - 1000.0) as f32)
        .collect()
}

/// The largest `|a_i − b_i|`.
pub fn max_abs_diff<T: Copy + Into<f64>>(a: &[T], b: &[T]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (x.into() - y.into()).abs())
        .fold(0.0, f64::max)
}
