//! Engine throughput: forward + inverse pyramid, in MB/s of input, next to a plain copy
//! (`copy_from_slice`, one thread) of the same buffer timed in the same run: each
//! repetition times the copy and then the pyramid, so both see the same moment of a
//! shared machine (its memory bandwidth moves by a third from one minute to the next).
//! Each figure is given for the best and the median of the repetitions (the median also
//! measures the other jobs; the best is the least disturbed run). The JSON also gives the
//! best of the same copy split over all threads (context only: the target is against the
//! plain copy; on the 2-core machine the split copy runs at up to twice its speed).
//!
//! `cargo bench --bench engine` (set `MRA_BENCH_QUICK=1` for smaller sizes). Prints one
//! JSON object per line plus a table; `benches/peers/pywavelets_peer.py` runs this and
//! PyWavelets side by side.

use mra::scheme::{Boundary, Scheme};
use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use rayon::prelude::*;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[v.len() / 2]
}

/// (best, median) seconds of `reps` runs of each of `fs`, in turn, after one warm-up run
/// of each.
fn time_each<const N: usize>(reps: usize, mut fs: [&mut dyn FnMut(); N]) -> [(f64, f64); N] {
    for f in fs.iter_mut() {
        f(); // warm up
    }
    let mut times: [Vec<f64>; N] = std::array::from_fn(|_| Vec::new());
    for _ in 0..reps {
        for (f, v) in fs.iter_mut().zip(times.iter_mut()) {
            let t = Instant::now();
            f();
            v.push(t.elapsed().as_secs_f64());
        }
    }
    times.map(|v| (v.iter().cloned().fold(f64::INFINITY, f64::min), median(v)))
}

fn main() {
    let quick = std::env::var("MRA_BENCH_QUICK").is_ok();
    let reps = if quick { 3 } else { 9 };
    let threads = rayon::current_num_threads();
    let cases: Vec<(Vec<usize>, usize)> = if quick {
        vec![(vec![1024, 1024], 5), (vec![64, 64, 64], 3)]
    } else {
        vec![(vec![4096, 4096], 5), (vec![256, 256, 256], 3)]
    };
    println!("# threads: {threads}");
    println!(
        "{:<14} {:<8} {:<14} {:>17} {:>17} {:>15}",
        "shape", "scheme", "boundary", "MB/s best/median", "copy best/median", "% copy b/m"
    );
    for (shape, levels) in cases {
        let n: usize = shape.iter().product();
        let data: Vec<f32> = (0..n)
            .map(|i| ((i * 2654435761) % 1000) as f32 * 0.25)
            .collect();
        let bytes = (n * 4) as f64;
        let mut dst = vec![0f32; n];
        let mut dst2 = vec![0f32; n];
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                let spec = PyramidSpec {
                    scheme,
                    boundary,
                    levels,
                    order: Order::NonStandard,
                    axes: (0..shape.len()).collect(),
                };
                let mut a = Array::from_shape_vec(&shape, data.clone()).unwrap();
                let part = n.div_ceil(threads);
                let [copy, t, copy_par] = time_each(
                    reps,
                    [
                        &mut || {
                            dst.copy_from_slice(&data);
                            std::hint::black_box(&mut dst);
                        },
                        &mut || {
                            let pyr = analyze(&mut a, &spec).unwrap();
                            synthesize(&mut a, &pyr).unwrap();
                        },
                        // the same copy on every thread (context: the engine uses them all)
                        &mut || {
                            dst2.par_chunks_mut(part)
                                .zip(data.par_chunks(part))
                                .for_each(|(d, s)| d.copy_from_slice(s));
                            std::hint::black_box(&mut dst2);
                        },
                    ],
                );
                let (copy_best, copy_med) = (bytes / copy.0 / 1e6, bytes / copy.1 / 1e6);
                let copy_par_best = bytes / copy_par.0 / 1e6;
                let (best, med) = (bytes / t.0 / 1e6, bytes / t.1 / 1e6);
                let shape_s = shape
                    .iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join("x");
                println!(
                    "{:<14} {:<8} {:<14} {:>8.0}/{:<8.0} {:>8.0}/{:<8.0} {:>6.1}%/{:.1}%",
                    shape_s,
                    scheme.name(),
                    boundary.name(),
                    best,
                    med,
                    copy_best,
                    copy_med,
                    100.0 * best / copy_best,
                    100.0 * med / copy_med
                );
                println!(
                    "{{\"bench\":\"engine\",\"shape\":\"{shape_s}\",\"levels\":{levels},\"scheme\":\"{}\",\"boundary\":\"{}\",\"seconds\":{},\"seconds_best\":{},\"mb_per_s\":{med},\"mb_per_s_best\":{best},\"copy_mb_per_s\":{copy_med},\"copy_mb_per_s_best\":{copy_best},\"copy_all_threads_mb_per_s_best\":{copy_par_best},\"threads\":{threads}}}",
                    scheme.name(), boundary.name(), t.1, t.0
                );
            }
        }
    }
}
