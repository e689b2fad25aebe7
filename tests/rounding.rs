//! How every path sums a row's taps (`kernel::pair_taps` and `kernel::sum_terms`): the
//! rule itself, checked against sums written out by hand, then every kernel that takes
//! rows with equal weights (the regular rows of the schemes) against it, in every build
//! the CPU has, bit for bit.

use mra::scheme::kernel::{
    combine_lane_taps, combine_pair_has_build, combine_pair_merged, combine_pair_with,
    combine_with, pair_taps, row_sum, SECOND,
};
use mra::scheme::sparse::Simd;
use mra::scheme::Sample;

fn lcg(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 20.0 - 10.0
        })
        .collect()
}

fn same<T: Sample + Into<f64>>(a: T, b: T) -> bool {
    let (a, b): (f64, f64) = (a.into(), b.into());
    a.to_bits() == b.to_bits()
}

/// The pairs: a tap pairs with the next tap of its weight not yet paired.
#[test]
fn taps_of_equal_weight_pair_in_column_order() {
    let s = SECOND;
    let mut p = [0usize; 8];
    // cubic's synthesis row: 1/8 at 0, 2, 3, 6; 3/8 at 4, 5
    let w = [0.125, 0.75, 0.125, 0.125, 0.375, 0.375, 0.125];
    assert!(pair_taps(&w, &mut p));
    assert_eq!(&p[..7], &[2, 1, s, 6, 5, s, s]);
    // cubic's analysis row: the symmetric taps around its centre
    let a = [0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125];
    assert!(pair_taps(&a, &mut p));
    assert_eq!(&p[..7], &[6, 5, 4, 3, s, s, s]);
    // three equal weights: a pair and a single tap
    assert!(pair_taps(&[0.5, 0.5, 0.5], &mut p));
    assert_eq!(&p[..3], &[1, s, 2]);
    // distinct weights: no pairs, every tap alone
    assert!(!pair_taps(&[0.25, -0.75, 0.75, -0.25f32], &mut p));
    assert_eq!(&p[..4], &[0, 1, 2, 3]);
}

/// The sums, written out: cubic's `a` is `⅛(x₀ + x₆)`, then `fma(x₁ + x₅, −½, ·)`,
/// `fma(x₂ + x₄, ⅜, ·)`, then `+ 1·x₃`; a row without equal weights is the plain sum.
#[test]
fn row_sums_are_the_documented_formulas() {
    let a = [0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125];
    for seed in 0..200 {
        let x = lcg(seed, 7);
        let mut acc = 0.125 * (x[0] + x[6]);
        acc = (x[1] + x[5]).mul_add(-0.5, acc);
        acc = (x[2] + x[4]).mul_add(0.375, acc);
        acc += 1.0 * x[3];
        assert_eq!(row_sum(&a, |k| x[k]).to_bits(), acc.to_bits());
        let x32: Vec<f32> = x.iter().map(|&v| v as f32).collect();
        let a32: Vec<f32> = a.iter().map(|&v| v as f32).collect();
        let mut acc = 0.125f32 * (x32[0] + x32[6]);
        acc = (x32[1] + x32[5]).mul_add(-0.5, acc);
        acc = (x32[2] + x32[4]).mul_add(0.375, acc);
        acc += x32[3];
        assert_eq!(row_sum(&a32, |k| x32[k]).to_bits(), acc.to_bits());
        // a boundary row of distinct weights
        let b = [0.5, -0.875, 0.5625, -0.125];
        let plain = ((0.5 * x[0] + -0.875 * x[1]) + 0.5625 * x[2]) + -0.125 * x[3];
        assert_eq!(row_sum(&b, |k| x[k]).to_bits(), plain.to_bits());
        // a pair that comes after single taps
        let c = [0.25, 0.75, -0.5, 0.75];
        let mut acc = 0.25 * x[0];
        acc = (x[1] + x[3]).mul_add(0.75, acc);
        acc += -0.5 * x[2];
        assert_eq!(row_sum(&c, |k| x[k]).to_bits(), acc.to_bits());
    }
}

/// Rows with equal weights, of every shape: the schemes' regular rows, and rows drawn
/// from a few weights (many pairs, longer than one pass of the kernels).
fn paired_rows() -> Vec<Vec<f64>> {
    let mut rows = vec![
        vec![0.5, 0.5],
        vec![1.0, 1.0],
        vec![-0.25, 0.75, 0.75, -0.25],
        vec![0.75, 0.25, 0.75, -0.25],
        vec![0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125],
        vec![-0.125, 0.5, -0.75, 0.5, -0.125],
        vec![0.125, 0.75, 0.125, 0.125, 0.375, 0.375, 0.125],
        vec![0.5, 0.5, 0.5, -1.0, 0.5],
    ];
    for n in [3usize, 9, 12, 17, 33, 40] {
        let r = lcg(n as u64 + 100, n);
        rows.push(
            r.iter()
                .map(|v| [0.25, -0.5, 1.0][(v.abs() as usize) % 3])
                .collect(),
        );
    }
    rows
}

/// `combine` of rows with pairs in every build gives the bits of `row_sum`.
#[test]
fn combine_with_pairs_gives_the_bits_of_the_rule() {
    fn check<T: Sample + Into<f64>>(x: &[T], w: &[T], len: usize) {
        let n = w.len();
        let src: Vec<&[T]> = (0..n).map(|k| &x[k..k + len]).collect();
        for simd in Simd::available() {
            let mut out = vec![T::from_f64(7.0); len];
            combine_with(simd, &mut out, &src, w);
            for i in 0..len {
                let want = row_sum(w, |k| src[k][i]);
                assert!(same(out[i], want), "{simd:?} {n} taps len {len} at {i}");
            }
        }
    }
    for row in paired_rows() {
        for len in [0usize, 1, 5, 8, 15, 16, 17, 31, 40, 100] {
            let x = lcg(len as u64 + row.len() as u64, len + row.len());
            let x32: Vec<f32> = x.iter().map(|&v| v as f32).collect();
            let w32: Vec<f32> = row.iter().map(|&v| v as f32).collect();
            check(&x, &row, len);
            check(&x32, &w32, len);
        }
    }
}

/// The regular rows of the three schemes, as `polyphase` pairs them for the pair
/// kernels: `(inputs, m1, w1, m2, w2)`.
fn scheme_pairs() -> Vec<(u32, Vec<f64>, u32, Vec<f64>)> {
    vec![
        (0b11, vec![0.5, 0.5], 0b11, vec![0.5, -0.5]),
        (0b11, vec![1.0, 1.0], 0b11, vec![1.0, -1.0]),
        (
            0b1111,
            vec![-0.25, 0.75, 0.75, -0.25],
            0b1111,
            vec![0.25, -0.75, 0.75, -0.25],
        ),
        (
            0b1111,
            vec![0.25, -0.75, 0.75, -0.25, 0.0, 0.0],
            0b111100,
            vec![0.0, 0.0, -0.25, 0.75, 0.75, -0.25],
        ),
        (
            0b1111,
            vec![0.75, 0.25, 0.75, -0.25],
            0b1111,
            vec![0.25, 0.75, 0.25, -0.75],
        ),
        (
            0b1111111,
            vec![0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125],
            0b11111,
            vec![-0.125, 0.5, -0.75, 0.5, -0.125, 0.0, 0.0],
        ),
        (
            0b1111111,
            vec![0.125, -0.5, 0.375, 1.0, 0.375, -0.5, 0.125],
            0b1111100,
            vec![0.0, 0.0, -0.125, 0.5, -0.75, 0.5, -0.125],
        ),
        (
            0b1111111,
            vec![0.125, 0.75, 0.125, 0.125, 0.375, 0.375, 0.125],
            0b1110110,
            vec![0.0, 0.5, 0.5, 0.0, 0.5, -1.0, 0.5],
        ),
        (
            0b111011,
            vec![0.5, 0.5, 0.0, 0.5, -1.0, 0.5, 0.0],
            0b1111111,
            vec![0.125, 0.75, 0.125, 0.125, 0.375, 0.375, 0.125],
        ),
    ]
}

/// The pair kernels on the schemes' regular rows (each has a vector build: tested) give
/// the bits of one `combine` per output, in every build, as two outputs and merged.
#[test]
fn pair_kernels_on_the_schemes_rows_give_the_bits_of_the_rule() {
    fn check<T: Sample + Into<f64>>(x: &[T], m1: u32, w1: &[T], m2: u32, w2: &[T], len: usize) {
        let u = w1.len();
        let src: Vec<&[T]> = (0..u).map(|k| &x[k..k + len]).collect();
        let want = |m: u32, w: &[T]| {
            let ks: Vec<usize> = (0..u).filter(|&k| m >> k & 1 == 1).collect();
            let wk: Vec<T> = ks.iter().map(|&k| w[k]).collect();
            (0..len)
                .map(|i| row_sum(&wk, |j| src[ks[j]][i]))
                .collect::<Vec<T>>()
        };
        let (e1, e2) = (want(m1, w1), want(m2, w2));
        for simd in Simd::available() {
            let (mut a, mut b) = (vec![T::default(); len], vec![T::default(); len]);
            combine_pair_with(simd, &mut a, &mut b, &src, w1, m1, w2, m2);
            for i in 0..len {
                assert!(
                    same(a[i], e1[i]) && same(b[i], e2[i]),
                    "{simd:?} u {u} len {len} at {i}"
                );
            }
        }
        let mut merged = vec![T::default(); 2 * len];
        if combine_pair_merged(&mut merged, &src, w1, m1, w2, m2) {
            for i in 0..len {
                assert!(same(merged[2 * i], e1[i]) && same(merged[2 * i + 1], e2[i]));
            }
        }
    }
    for (m1, w1, m2, w2) in scheme_pairs() {
        let w1_32: Vec<f32> = w1.iter().map(|&v| v as f32).collect();
        let w2_32: Vec<f32> = w2.iter().map(|&v| v as f32).collect();
        assert!(combine_pair_has_build(&w1, m1, &w2, m2), "{w1:?} {w2:?}");
        assert!(
            combine_pair_has_build(&w1_32, m1, &w2_32, m2),
            "{w1:?} {w2:?}"
        );
        for len in [0usize, 1, 7, 8, 9, 16, 17, 33, 64, 100] {
            let x = lcg(len as u64 * 3 + m2 as u64, len + w1.len());
            let x32: Vec<f32> = x.iter().map(|&v| v as f32).collect();
            check(&x, m1, &w1, m2, &w2, len);
            check(&x32, m1, &w1_32, m2, &w2_32, len);
        }
    }
}

/// The rows near the ends of a volume's lanes (`combine_lane_taps`, 8 lanes at a time
/// in registers) with pairs give the bits of the rule.
#[test]
fn lane_taps_with_pairs_give_the_bits_of_the_rule() {
    for (w, h) in [(16usize, 8usize), (20, 13), (40, 17), (9, 3)] {
        let x: Vec<f32> = lcg(w as u64 * 7 + h as u64, w * h)
            .iter()
            .map(|&v| v as f32)
            .collect();
        // rows 0.. near the start, with the regular rows' weights at a few offsets
        let mut rows: Vec<(usize, Vec<(usize, f32)>)> = Vec::new();
        for (r, row) in paired_rows()
            .into_iter()
            .filter(|r| r.len() <= 7)
            .enumerate()
        {
            let first = r % (w - row.len() + 1);
            rows.push((
                r,
                row.iter()
                    .enumerate()
                    .map(|(k, &v)| (first + k, v as f32))
                    .collect(),
            ));
        }
        let ys = rows.len() + 2;
        let mut y = vec![0f32; h * ys];
        combine_lane_taps(&x, w, h, &rows, &mut y, ys);
        for t in 0..h {
            for (r, taps) in &rows {
                let ws: Vec<f32> = taps.iter().map(|p| p.1).collect();
                let want = row_sum(&ws, |k| x[t * w + taps[k].0]);
                assert!(same(y[t * ys + r], want), "w {w} h {h} lane {t} row {r}");
            }
        }
    }
}

/// The operators' own rows (`Csr::apply`, the reference of the engines' tests) follow
/// the rule: every row of every scheme and boundary, at a few lengths.
#[test]
fn operators_apply_their_rows_by_the_rule() {
    use mra::scheme::{Boundary, Scheme, TwoScale};
    for scheme in [Scheme::Haar, Scheme::Chaikin, Scheme::Cubic] {
        for boundary in [
            Boundary::Interpolating,
            Boundary::Periodic,
            Boundary::Symmetric,
        ] {
            for m in [9usize, 16, 33] {
                let t = TwoScale::new(scheme, boundary, m);
                for op in [&t.analysis, &t.synthesis] {
                    let x = lcg(m as u64, op.cols());
                    let mut y = vec![0.0; op.rows()];
                    op.apply(&x, 1, &mut y, 1, 1);
                    for (r, &got) in y.iter().enumerate() {
                        let (cols, ws) = op.row_slices(r);
                        let want = row_sum(ws, |k| x[cols[k] as usize]);
                        assert!(!cols.is_empty());
                        assert_eq!(
                            got.to_bits(),
                            want.to_bits(),
                            "{scheme:?} {boundary:?} {m} row {r}"
                        );
                    }
                }
            }
        }
    }
}
