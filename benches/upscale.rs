//! Upscaler throughput (cubic rule, and the default method): ×2 of an RGB u8 image (Kodak
//! size) and of a 256³ f32 volume in every mode, in output MB/s, next to a plain copy of
//! the output buffer.
//!
//! `cargo bench --bench upscale` (`MRA_BENCH_QUICK=1` for a 128³ volume).
//! `benches/peers/upscale_peers.py` compares against OpenImageIO, scikit-image, SciPy
//! and Pillow on real data.

use mra::io::{DataKind, Raster, SampleType};
use mra::progress::Progress;
use mra::scheme::subdivide::Refinement;
use mra::upscale::{upscale_raster, AxisPlan, Clamp, Edge, Geometry, Method, Mode};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[v.len() / 2]
}

fn plans(dims: &[usize], f: usize) -> Vec<AxisPlan> {
    (0..dims.len())
        .map(|a| AxisPlan {
            axis: a,
            len: dims[a] * f,
            geometry: Geometry::Centre,
        })
        .collect()
}

fn main() {
    let quick = std::env::var("MRA_BENCH_QUICK").is_ok();
    let reps = if quick { 3 } else { 5 };
    let n = if quick { 128 } else { 256 };
    println!("# threads: {}", rayon::current_num_threads());
    println!("| data | mode | seconds | output MB/s | copy MB/s |");
    println!("|---|---|---|---|---|");
    let image: Vec<f32> = (0..384 * 256 * 3)
        .map(|i| ((i * 7919) % 256) as f32)
        .collect();
    let volume: Vec<f32> = (0..n * n * n).map(|i| ((i * 31) % 1000) as f32).collect();
    let cases: Vec<(String, Raster)> = vec![
        (
            "384x256 RGB u8 -> 768x512".into(),
            Raster::from_f32(vec![256, 384], 3, &image, SampleType::U8, DataKind::Image).unwrap(),
        ),
        (
            format!("{n}^3 f32 -> {}^3", 2 * n),
            Raster::from_f32(vec![n, n, n], 1, &volume, SampleType::F32, DataKind::Volume).unwrap(),
        ),
    ];
    for (name, r) in &cases {
        let out_bytes = (r.samples.len() * (1 << r.dims.len())) as f64
            * match r.sample_type() {
                SampleType::U8 => 1.0,
                _ => 4.0,
            };
        let copy = {
            let buf = vec![1u8; out_bytes as usize];
            median(
                (0..reps)
                    .map(|_| {
                        let t = Instant::now();
                        let c = buf.clone();
                        std::hint::black_box(&c);
                        t.elapsed().as_secs_f64()
                    })
                    .collect(),
            )
        };
        let cubic = |mode| Method {
            rule: Refinement::Cubic,
            mode,
            edge: Edge::Linear,
            order: None,
            clamp: Clamp::Off,
        };
        for (label, m) in [
            ("Area".to_string(), cubic(Mode::Area)),
            ("Interpolate".into(), cubic(Mode::Interpolate)),
            ("Control".into(), cubic(Mode::Control)),
            (
                "default: Chaikin area, clamp auto".into(),
                Method::default(),
            ),
        ] {
            let p = plans(&r.dims, 2);
            let secs = median(
                (0..reps)
                    .map(|_| {
                        let input = r.clone();
                        let t = Instant::now();
                        let o = upscale_raster(input, &m, &p, &Progress::hidden()).unwrap();
                        let s = t.elapsed().as_secs_f64();
                        std::hint::black_box(o);
                        s
                    })
                    .collect(),
            );
            println!(
                "| {name} | {label} | {secs:.4} | {:.0} | {:.0} |",
                out_bytes / secs / 1e6,
                out_bytes / copy / 1e6
            );
        }
    }
}
