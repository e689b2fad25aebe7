//! The tensor engine: pyramids over 2D and 3D arrays reconstruct exactly in both
//! orders, for every scheme × boundary and random sizes; subbands tile the array.

use mra::scheme::{Boundary, Scheme};
use mra::tensor::{
    analyze, analyze_with, synthesize, synthesize_with, Array, Engine, Order, Pyramid, PyramidSpec,
};
use proptest::prelude::*;

fn noise(seed: u64, n: usize) -> Vec<f64> {
    let mut x = seed ^ 0x9E3779B97F4A7C15;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 20001) as f64 / 100.0 - 100.0
        })
        .collect()
}

fn round_trip(
    shape: &[usize],
    axes: Vec<usize>,
    s: usize,
    b: usize,
    order: Order,
    levels: usize,
    seed: u64,
) {
    let data = noise(seed, shape.iter().product());
    let mut a = Array::from_shape_vec(shape, data.clone()).unwrap();
    let spec = PyramidSpec {
        scheme: Scheme::ALL[s],
        boundary: Boundary::ALL[b],
        levels,
        order,
        axes,
    };
    let pyr = analyze(&mut a, &spec).unwrap();
    synthesize(&mut a, &pyr).unwrap();
    for (i, (x, y)) in data.iter().zip(a.data()).enumerate() {
        assert!(
            (x - y).abs() <= 1e-12 * 100.0,
            "{spec:?} shape {shape:?}: sample {i}: {x} vs {y}"
        );
    }
}

/// Every engine gives the bits of the axis-by-axis engine, forward and back (f64 and
/// f32), including shapes where some levels cannot fuse: the cascade (default, and
/// forced into 1–4 parts with volumes included), and the fused levels.
fn engines_agree(shape: &[usize], axes: Vec<usize>, s: usize, b: usize, levels: usize, seed: u64) {
    let engines = [
        Engine::Fused,
        Engine::FusedLevels,
        Engine::CascadeParts(1 + (seed % 4) as usize),
    ];
    for engine in engines {
        engine_agrees(engine, shape, axes.clone(), s, b, levels, seed);
    }
}

fn engine_agrees(
    engine: Engine,
    shape: &[usize],
    axes: Vec<usize>,
    s: usize,
    b: usize,
    levels: usize,
    seed: u64,
) {
    let data = noise(seed, shape.iter().product());
    let spec = PyramidSpec {
        scheme: Scheme::ALL[s],
        boundary: Boundary::ALL[b],
        levels,
        order: Order::NonStandard,
        axes,
    };
    let same = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(x, y)| x.to_bits() == y.to_bits());
    let mut fused = Array::from_shape_vec(shape, data.clone()).unwrap();
    let mut axis = fused.clone();
    let p1 = analyze_with(&mut fused, &spec, engine).unwrap();
    let p2 = analyze_with(&mut axis, &spec, Engine::AxisByAxis).unwrap();
    assert_eq!(p1, p2);
    assert!(
        same(fused.data(), axis.data()),
        "{engine:?} analysis {spec:?} {shape:?}"
    );
    // synthesize the same coefficients both ways
    let mut back = fused.clone();
    synthesize_with(&mut fused, &p1, engine).unwrap();
    synthesize_with(&mut back, &p1, Engine::AxisByAxis).unwrap();
    assert!(
        same(fused.data(), back.data()),
        "{engine:?} synthesis {spec:?} {shape:?}"
    );
    // and in f32
    let d32: Vec<f32> = data.iter().map(|&v| v as f32).collect();
    let same32 = |x: &[f32], y: &[f32]| x.iter().zip(y).all(|(x, y)| x.to_bits() == y.to_bits());
    let mut f = Array::from_shape_vec(shape, d32.clone()).unwrap();
    let mut a = Array::from_shape_vec(shape, d32).unwrap();
    let p = analyze_with(&mut f, &spec, engine).unwrap();
    analyze_with(&mut a, &spec, Engine::AxisByAxis).unwrap();
    assert!(
        same32(f.data(), a.data()),
        "{engine:?} f32 analysis {spec:?} {shape:?}"
    );
    synthesize_with(&mut f, &p, engine).unwrap();
    synthesize_with(&mut a, &p, Engine::AxisByAxis).unwrap();
    assert!(
        same32(f.data(), a.data()),
        "{engine:?} f32 synthesis {spec:?} {shape:?}"
    );
}

#[test]
fn engines_agree_on_large_images_and_volumes() {
    // big enough for the parallel path and long regular runs
    for s in 0..3 {
        for b in 0..3 {
            engines_agree(&[300, 257], vec![0, 1], s, b, 4, 7);
            engines_agree(&[64, 96, 3], vec![0, 1], s, b, 3, 8);
            engines_agree(&[40, 33, 70], vec![0, 1, 2], s, b, 3, 9);
        }
    }
    // large enough (> 16 MiB) for levels that stream their output past the caches
    engines_agree(&[1500, 1501], vec![0, 1], 2, 2, 2, 10);
    // a volume whose lanes go through the transposed plane path, streaming
    engines_agree(&[66, 130, 260], vec![0, 1, 2], 1, 0, 2, 11);
    // images tall enough for the cascade to split into parts by itself (with two or more
    // threads; its rings stay below 1/16 of the image), odd sizes
    for s in 0..3 {
        for b in 0..3 {
            engine_agrees(Engine::Fused, &[2001, 301], vec![0, 1], s, b, 5, 12);
            engine_agrees(Engine::Fused, &[1803, 151, 3], vec![0, 1], s, b, 4, 13);
        }
    }
    // periodic images of even sizes: the cascade's ghost rows (the rows near the ends
    // that the rows reaching across the lane read), split into parts by itself
    for s in 0..3 {
        engine_agrees(Engine::Fused, &[1024, 160], vec![0, 1], s, 1, 5, 14);
        engine_agrees(Engine::Fused, &[512, 96, 3], vec![0, 1], s, 1, 4, 15);
    }
}

/// The cascade writes every sample of the output whatever the number of parts (a sample
/// no part writes keeps what the scratch array held before, and differs), with parts of
/// a few rows each and halos crossing several parts.
#[test]
fn cascade_parts_cover_every_row() {
    for parts in 1..=7 {
        for s in 0..3 {
            for b in 0..3 {
                engine_agrees(
                    Engine::CascadeParts(parts),
                    &[45, 38],
                    vec![0, 1],
                    s,
                    b,
                    4,
                    20 + parts as u64,
                );
                engine_agrees(
                    Engine::CascadeParts(parts),
                    &[21, 14, 19],
                    vec![0, 1, 2],
                    s,
                    b,
                    3,
                    30 + parts as u64,
                );
                engine_agrees(
                    Engine::CascadeParts(parts),
                    &[33, 20, 3],
                    vec![0, 1],
                    s,
                    b,
                    3,
                    40 + parts as u64,
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(120))]
    #[test]
    fn fused_and_axis_engines_give_the_same_bits(d in 1usize..20, h in 1usize..50, w in 1usize..70, c in 1usize..4, s in 0usize..3, b in 0usize..3, levels in 0usize..6, kind in 0usize..4, seed in any::<u64>()) {
        match kind {
            0 => engines_agree(&[h, w], vec![0, 1], s, b, levels, seed),
            1 => engines_agree(&[h, w, c], vec![0, 1], s, b, levels, seed),
            2 => engines_agree(&[d, h, w], vec![0, 1, 2], s, b, levels, seed),
            _ => engines_agree(&[h, w], vec![1, 0], s, b, levels, seed),
        }
    }
    #[test]
    fn every_2d_array_reconstructs(h in 1usize..80, w in 1usize..80, s in 0usize..3, b in 0usize..3, std in any::<bool>(), levels in 0usize..7, seed in any::<u64>()) {
        let order = if std { Order::Standard } else { Order::NonStandard };
        round_trip(&[h, w], vec![0, 1], s, b, order, levels, seed);
    }
    #[test]
    fn every_3d_array_reconstructs(d in 1usize..24, h in 1usize..24, w in 1usize..40, s in 0usize..3, b in 0usize..3, std in any::<bool>(), levels in 0usize..5, seed in any::<u64>()) {
        let order = if std { Order::Standard } else { Order::NonStandard };
        round_trip(&[d, h, w], vec![0, 1, 2], s, b, order, levels, seed);
    }
    #[test]
    fn images_with_channels_reconstruct(h in 1usize..50, w in 1usize..50, c in 1usize..5, s in 0usize..3, b in 0usize..3, levels in 0usize..5, seed in any::<u64>()) {
        round_trip(&[h, w, c], vec![0, 1], s, b, Order::NonStandard, levels, seed);
    }
}

#[test]
fn large_rows_take_the_row_path_and_reconstruct() {
    // wide enough for strips (row mode) and many lanes (threads)
    for s in 0..3 {
        for b in 0..3 {
            round_trip(&[67, 1500], vec![0, 1], s, b, Order::NonStandard, 4, 7);
            round_trip(&[9, 33, 70], vec![0, 1, 2], s, b, Order::Standard, 3, 8);
        }
    }
}

#[test]
fn f32_arrays_reconstruct_to_f32_precision() {
    let shape = [129usize, 257];
    let data: Vec<f32> = noise(3, shape[0] * shape[1])
        .iter()
        .map(|&x| x as f32)
        .collect();
    for scheme in Scheme::ALL {
        for boundary in Boundary::ALL {
            let mut a = Array::from_shape_vec(&shape, data.clone()).unwrap();
            let spec = PyramidSpec {
                scheme,
                boundary,
                levels: 5,
                order: Order::NonStandard,
                axes: vec![0, 1],
            };
            let pyr = analyze(&mut a, &spec).unwrap();
            synthesize(&mut a, &pyr).unwrap();
            let err = data
                .iter()
                .zip(a.data())
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max);
            assert!(
                err < 2e-3,
                "{scheme} {boundary}: max error {err} on values up to 100"
            );
        }
    }
}

#[test]
fn subbands_tile_the_array_exactly_once() {
    for (shape, axes) in [
        (vec![37usize, 64], vec![0usize, 1]),
        (vec![10, 17, 33], vec![0, 1, 2]),
        (vec![20, 30, 3], vec![0, 1]),
    ] {
        let spec = PyramidSpec {
            scheme: Scheme::Chaikin,
            boundary: Boundary::Interpolating,
            levels: 3,
            order: Order::NonStandard,
            axes,
        };
        let pyr = Pyramid::plan(&shape, &spec).unwrap();
        let mut count = vec![0u8; shape.iter().product()];
        for band in pyr.subbands() {
            let mut idx = vec![0usize; shape.len()];
            // iterate the box
            let total: usize = band.ranges.iter().map(|r| r.len()).product();
            for mut t in 0..total {
                for k in (0..shape.len()).rev() {
                    idx[k] = band.ranges[k].start + t % band.ranges[k].len();
                    t /= band.ranges[k].len();
                }
                let lin = idx.iter().zip(&shape).fold(0, |acc, (&i, &n)| acc * n + i);
                count[lin] += 1;
            }
        }
        assert!(count.iter().all(|&c| c == 1), "{shape:?}");
    }
}

#[test]
fn constant_image_has_zero_detail_bands() {
    let shape = [64usize, 96];
    for scheme in Scheme::ALL {
        for boundary in Boundary::ALL {
            let mut a = Array::from_shape_vec(&shape, vec![42.0f64; 64 * 96]).unwrap();
            let spec = PyramidSpec {
                scheme,
                boundary,
                levels: 3,
                order: Order::NonStandard,
                axes: vec![0, 1],
            };
            let pyr = analyze(&mut a, &spec).unwrap();
            for band in pyr.subbands().iter().skip(1) {
                for i in band.ranges[0].clone() {
                    for j in band.ranges[1].clone() {
                        let v = a.data()[i * shape[1] + j];
                        assert!(
                            v.abs() < 1e-10,
                            "{scheme} {boundary} band {:?}: {v}",
                            band.high
                        );
                    }
                }
            }
        }
    }
}
