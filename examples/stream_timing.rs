//! Time the streamed pyramid (`tensor::stream`) against the whole-array transform:
//! `cargo run --release --example stream_timing -- SHAPE stream|whole [scheme] [levels]`,
//! e.g. `16384x16384 stream cdf97 5` or `512x512x512 stream cdf97 3`. The array's rows
//! come from a generator, the band rows go to a sink that only sums them (stream); the
//! whole-array path fills an array and runs `analyze`/`synthesize` on it. Prints MB/s of
//! each direction; run under `/usr/bin/time -v` for the peak RSS.
use mra::tensor::stream::StreamPlan;
use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use std::time::Instant;

fn sample(i: usize) -> f32 {
    ((i.wrapping_mul(2654435761) >> 7) % 251) as f32
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape: Vec<usize> = args
        .get(1)
        .map_or("4096x4096", String::as_str)
        .split('x')
        .map(|t| t.parse().expect("SHAPE: sizes joined by x"))
        .collect();
    let mode = args.get(2).map_or("stream", String::as_str);
    let scheme = args
        .get(3)
        .map(|s| s.parse().expect("scheme"))
        .unwrap_or(mra::scheme::Scheme::Cdf97);
    let levels: usize = args
        .get(4)
        .and_then(|s| s.parse().ok())
        .unwrap_or(if shape.len() == 3 { 3 } else { 5 });
    let spec = PyramidSpec {
        scheme,
        boundary: mra::scheme::Boundary::Symmetric,
        levels,
        order: Order::NonStandard,
        axes: (0..shape.len()).collect(),
    };
    let len: usize = shape.iter().product();
    let mb = (len * 4) as f64 / 1e6;
    match mode {
        "stream" => {
            let plan = StreamPlan::new(&shape, &spec).expect("plan");
            let rl = plan.row_len();
            let mut sum = 0f64;
            let t = Instant::now();
            plan.analyze(
                |r, row: &mut [f32]| {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v = sample(r * rl + j);
                    }
                },
                |br| sum += br.data.iter().map(|&v| v as f64).sum::<f64>(),
            )
            .expect("analysis");
            let ta = t.elapsed().as_secs_f64();
            let mut back = 0f64;
            let t = Instant::now();
            plan.synthesize(
                |band, row, out: &mut [f32]| {
                    for (j, v) in out.iter_mut().enumerate() {
                        *v = sample(band * 7919 + row * 131 + j);
                    }
                },
                |_, row| back += row.iter().map(|&v| v as f64).sum::<f64>(),
            )
            .expect("synthesis");
            let ts = t.elapsed().as_secs_f64();
            println!(
                "stream {shape:?}: analysis {:.2} s {:.0} MB/s, synthesis {:.2} s {:.0} MB/s (sums {sum:e} {back:e})",
                ta,
                mb / ta,
                ts,
                mb / ts
            );
        }
        _ => {
            let data: Vec<f32> = (0..len).map(sample).collect();
            let mut a = Array::from_shape_vec(&shape, data).unwrap();
            let t = Instant::now();
            let pyr = analyze(&mut a, &spec).unwrap();
            let ta = t.elapsed().as_secs_f64();
            let sum: f64 = a.data().iter().map(|&v| v as f64).sum();
            let t = Instant::now();
            synthesize(&mut a, &pyr).unwrap();
            let ts = t.elapsed().as_secs_f64();
            println!(
                "whole {shape:?}: analysis {:.2} s {:.0} MB/s, synthesis {:.2} s {:.0} MB/s (sum {sum:e})",
                ta,
                mb / ta,
                ts,
                mb / ts
            );
        }
    }
}
