//! The kernel table a plan runs: a planner given any CPU level this machine runs gives,
//! with every engine, the bits of a planner given the plain loops, forward and back, for
//! images and volumes, f32 and f64.

use mra::scheme::{Boundary, Scheme};
use mra::tensor::{analyze_in, synthesize_in, Array, Engine, Order, Planner, PyramidSpec};
use mra::tuning::CpuLevel;

fn noise(seed: u64, n: usize) -> Vec<f64> {
    let mut x = seed ^ 0x9E37_79B9_7F4A_7C15;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 20001) as f64 / 100.0 - 100.0
        })
        .collect()
}

/// Forward then back with `planner`: the pyramid's samples, then the reconstruction.
fn run<T: mra::scheme::Sample>(
    planner: &Planner,
    data: &[T],
    shape: &[usize],
    spec: &PyramidSpec,
    engine: Engine,
) -> (Vec<T>, Vec<T>) {
    let mut a = Array::from_shape_vec(shape, data.to_vec()).unwrap();
    let pyr = analyze_in(planner, &mut a, spec, engine).unwrap();
    let forward = a.data().to_vec();
    synthesize_in(planner, &mut a, &pyr, engine).unwrap();
    (forward, a.data().to_vec())
}

fn bits<T: mra::scheme::Sample>(v: &[T]) -> Vec<u64> {
    v.iter().map(|x| x.to_f64().to_bits()).collect()
}

fn check<T: mra::scheme::Sample>(data: &[T], shape: &[usize], spec: &PyramidSpec, what: &str) {
    let engines = [
        Engine::Fused,
        Engine::FusedLevels,
        Engine::AxisByAxis,
        Engine::CascadeParts(2),
    ];
    let scalar = Planner::with_cpu(CpuLevel::Scalar);
    assert_eq!(scalar.kernels().level(), CpuLevel::Scalar);
    for engine in engines {
        let (want_f, want_b) = run(&scalar, data, shape, spec, engine);
        for level in CpuLevel::available() {
            let planner = Planner::with_cpu(level);
            assert_eq!(planner.kernels().level(), level);
            let (f, b) = run(&planner, data, shape, spec, engine);
            assert!(
                bits(&f) == bits(&want_f),
                "{what} {engine:?} {level:?}: forward differs from the scalar table"
            );
            assert!(
                bits(&b) == bits(&want_b),
                "{what} {engine:?} {level:?}: inverse differs from the scalar table"
            );
        }
    }
}

#[test]
fn every_cpu_levels_table_gives_the_bits_of_the_scalar_table() {
    for scheme in Scheme::ALL {
        for boundary in Boundary::ALL {
            for (shape, levels) in [(vec![67usize, 130], 3), (vec![20, 24, 28], 2)] {
                let n: usize = shape.iter().product();
                let spec = PyramidSpec {
                    scheme,
                    boundary,
                    levels,
                    order: Order::NonStandard,
                    axes: (0..shape.len()).collect(),
                };
                let what = format!("{scheme} {boundary} {shape:?}");
                let x = noise(n as u64 + levels as u64, n);
                check(&x, &shape, &spec, &what);
                let x32: Vec<f32> = x.iter().map(|&v| v as f32).collect();
                check(&x32, &shape, &spec, &what);
            }
        }
    }
}

/// A table never holds a build the CPU does not run: asking for the widest level gives
/// at most what this machine has.
#[test]
fn a_table_is_capped_at_what_the_cpu_runs() {
    let k = mra::tensor::Kernels::new(CpuLevel::Avx512);
    assert!(k.level() <= CpuLevel::widest());
    assert_eq!(
        mra::tensor::Kernels::new(CpuLevel::Scalar).level(),
        CpuLevel::Scalar
    );
}
