//! The streamed pyramid (`tensor::stream`): row by row along axis 0, the bits of the
//! whole-array `analyze`/`synthesize` for every scheme, boundary, level count, odd sizes
//! and 1-D to 4-D arrays; the synthesis pulls band rows in the order `pull_order` says;
//! without periodic ends every band's rows come out in increasing order.

use mra::scheme::{Boundary, Scheme};
use mra::tensor::stream::StreamPlan;
use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use proptest::prelude::*;

fn noise(seed: u64, n: usize) -> Vec<f32> {
    let mut x = seed ^ 0x9E3779B97F4A7C15;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            ((x % 20001) as f64 / 100.0 - 100.0) as f32
        })
        .collect()
}

/// Offsets in the array (row-major `shape`) of row `row` of the band with `ranges`,
/// in the band row's order.
fn band_row_offsets(shape: &[usize], ranges: &[std::ops::Range<usize>], row: usize) -> Vec<usize> {
    let mut offs = vec![ranges[0].start + row];
    for d in 1..shape.len() {
        offs = offs
            .iter()
            .flat_map(|&o| ranges[d].clone().map(move |i| o * shape[d] + i))
            .collect();
    }
    offs
}

fn spec(s: usize, b: usize, levels: usize, axes: Vec<usize>) -> PyramidSpec {
    PyramidSpec {
        scheme: Scheme::ALL[s],
        boundary: Boundary::ALL[b],
        levels,
        order: Order::NonStandard,
        axes,
    }
}

/// Stream analysis and synthesis of random data of `shape` against the whole-array
/// transform, bit for bit.
fn stream_agrees(shape: &[usize], spec: &PyramidSpec, seed: u64) {
    let data = noise(seed, shape.iter().product());
    let mut whole = Array::from_shape_vec(shape, data.clone()).unwrap();
    let pyr = analyze(&mut whole, spec).unwrap();
    let plan = StreamPlan::new(shape, spec).unwrap();
    assert_eq!(plan.pyramid(), &pyr);
    let bands = plan.bands().to_vec();
    let row_len = plan.row_len();
    // analysis: every band row into its place
    let mut out = vec![f32::NAN; data.len()];
    let mut seen = vec![0usize; data.len()];
    let mut last: Vec<Option<usize>> = vec![None; bands.len()];
    let mut in_order = true;
    plan.analyze(
        |r, row: &mut [f32]| row.copy_from_slice(&data[r * row_len..(r + 1) * row_len]),
        |br| {
            let b = &bands[br.band];
            assert_eq!((br.level, br.high), (b.level, &b.high[..]));
            let offs = band_row_offsets(shape, &b.ranges, br.row);
            assert_eq!(offs.len(), br.data.len());
            assert_eq!(br.shape.iter().product::<usize>(), br.data.len());
            for (&o, &v) in offs.iter().zip(br.data) {
                out[o] = v;
                seen[o] += 1;
            }
            in_order &= last[br.band].is_none_or(|l| l < br.row);
            last[br.band] = Some(br.row);
        },
    )
    .unwrap();
    assert!(
        seen.iter().all(|&n| n == 1),
        "{spec:?} {shape:?}: a sample not written once"
    );
    let same = |x: &[f32], y: &[f32]| x.iter().zip(y).all(|(x, y)| x.to_bits() == y.to_bits());
    assert!(same(&out, whole.data()), "analysis {spec:?} {shape:?}");
    if spec.boundary != Boundary::Periodic {
        assert!(in_order, "{spec:?} {shape:?}: band rows out of order");
    }
    // synthesis from the coefficients, band rows pulled in the order announced
    let coeffs = whole.data().to_vec();
    synthesize(&mut whole, &pyr).unwrap();
    let order = plan.pull_order();
    let mut pulls = Vec::new();
    let mut back = vec![f32::NAN; data.len()];
    let mut next = 0;
    plan.synthesize(
        |band, row, dst: &mut [f32]| {
            pulls.push((band, row));
            let offs = band_row_offsets(shape, &bands[band].ranges, row);
            assert_eq!(offs.len(), dst.len());
            for (d, &o) in dst.iter_mut().zip(&offs) {
                *d = coeffs[o];
            }
        },
        |r, row| {
            assert_eq!(r, next);
            next += 1;
            back[r * row_len..(r + 1) * row_len].copy_from_slice(row);
        },
    )
    .unwrap();
    assert_eq!(next, shape[0]);
    assert!(same(&back, whole.data()), "synthesis {spec:?} {shape:?}");
    assert_eq!(pulls, order, "{spec:?} {shape:?}: pull order");
    // every band row pulled exactly once
    let mut sorted = pulls.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(
        sorted.len(),
        pulls.len(),
        "{spec:?} {shape:?}: a band row pulled twice"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(160))]
    #[test]
    fn the_stream_gives_the_bits_of_the_whole_array(
        a in 1usize..40, b in 1usize..30, c in 1usize..12, d in 1usize..6,
        s in 0usize..8, bd in 0usize..3, levels in 0usize..6, kind in 0usize..6, seed in any::<u64>()
    ) {
        match kind {
            0 => stream_agrees(&[a * 7 + b], &spec(s, bd, levels, vec![0]), seed),
            1 => stream_agrees(&[a, b], &spec(s, bd, levels, vec![0, 1]), seed),
            2 => stream_agrees(&[a, b, d], &spec(s, bd, levels, vec![0, 1]), seed),
            3 => stream_agrees(&[a, b, c], &spec(s, bd, levels, vec![0, 1, 2]), seed),
            4 => stream_agrees(&[c, d, b, a % 7 + 1], &spec(s, bd, levels, vec![0, 1, 2, 3]), seed),
            _ => stream_agrees(&[a, b], &spec(s, bd, levels, vec![1, 0]), seed),
        }
    }
}

/// Larger arrays: the whole-array transform runs as the cascade (images) or fused levels
/// (volumes) there, every scheme and boundary.
#[test]
fn the_stream_agrees_on_larger_images_and_volumes() {
    for s in 0..Scheme::ALL.len() {
        for b in 0..3 {
            stream_agrees(&[301, 257], &spec(s, b, 5, vec![0, 1]), 7);
            stream_agrees(&[64, 45, 3], &spec(s, b, 4, vec![0, 1]), 8);
            stream_agrees(&[40, 33, 70], &spec(s, b, 3, vec![0, 1, 2]), 9);
        }
    }
}

/// An axis that stops before the others (a short axis 0, or a short axis 1) still
/// streams with the whole-array bits.
#[test]
fn the_stream_handles_axes_that_stop_early() {
    for s in [0, 2, 7] {
        for b in 0..3 {
            stream_agrees(&[3, 200], &spec(s, b, 6, vec![0, 1]), 1);
            stream_agrees(&[200, 2, 5], &spec(s, b, 6, vec![0, 1, 2]), 2);
        }
    }
}

/// The standard order, an axis 0 left out, rows of the wrong length or too many rows:
/// an error, no panic.
#[test]
fn the_stream_refuses_what_it_cannot_run() {
    let mut std = spec(0, 0, 2, vec![0, 1]);
    std.order = Order::Standard;
    assert!(StreamPlan::new(&[8, 8], &std).is_err());
    assert!(StreamPlan::new(&[8, 8], &spec(0, 0, 2, vec![1])).is_err());
    let plan = StreamPlan::new(&[4, 8], &spec(0, 0, 2, vec![0, 1])).unwrap();
    let mut a = plan.analysis(|_| {});
    assert!(a.push(&[0f32; 7]).is_err());
    for _ in 0..4 {
        a.push(&[1f32; 8]).unwrap();
    }
    assert!(a.push(&[1f32; 8]).is_err());
    assert!(a.finish().is_ok());
    let short = plan.analysis::<f32, _>(|_| {});
    assert!(short.finish().is_err());
}

/// The rows a stream holds do not grow with the array's length: within a few rows for
/// an image of 1200 rows and one of 4800 (the levels' lengths differ in parity), every
/// scheme and boundary (periodic ends hold the rows reaching across the lane until its
/// end), analysis and synthesis.
#[test]
fn the_stream_holds_a_few_rows_per_level_whatever_the_length() {
    let most = |rows: usize, s: usize, b: usize| {
        let shape = [rows, 8];
        let plan = StreamPlan::new(&shape, &spec(s, b, 5, vec![0, 1])).unwrap();
        let mut a = plan.analysis::<f32, _>(|_| {});
        let mut held = 0;
        for r in 0..rows {
            a.push(&[r as f32; 8]).unwrap();
            held = held.max(a.held_rows());
        }
        assert!(a.finish().is_ok());
        let mut syn = plan.synthesis(|_, _, d: &mut [f32]| d.fill(1.0));
        let mut row = [0f32; 8];
        let mut held_back = 0;
        for _ in 0..rows {
            syn.pull(&mut row).unwrap();
            held_back = held_back.max(syn.held_rows());
        }
        (held, held_back)
    };
    for s in 0..Scheme::ALL.len() {
        for b in 0..3 {
            let (short, long) = (most(1200, s, b), most(4800, s, b));
            let what = (Scheme::ALL[s], Boundary::ALL[b], short, long);
            assert!(long.0 <= short.0 + 8 && long.1 <= short.1 + 8, "{what:?}");
            assert!(long.0 <= 240 && long.1 <= 240, "{long:?} rows held");
        }
    }
}
