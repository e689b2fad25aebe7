//! Exactness of the 1D schemes: perfect reconstruction for every scheme × boundary ×
//! length, the filter rows as written in the notes, worked examples.

use mra::scheme::{
    analyze_lane, max_levels, synthesize_lane, Boundary, LevelKind, Scheme, TwoScale,
};
use proptest::prelude::*;

fn dense_product(t: &TwoScale) -> Vec<Vec<f64>> {
    let a = t.analysis.to_dense();
    let s = t.synthesis.to_dense();
    let m = t.fine;
    let mut out = vec![vec![0.0; m]; m];
    for i in 0..m {
        for k in 0..m {
            if a[i][k] == 0.0 {
                continue;
            }
            for j in 0..m {
                out[i][j] += a[i][k] * s[k][j];
            }
        }
    }
    out
}

#[test]
fn analysis_times_synthesis_is_identity_for_every_length_up_to_96() {
    for scheme in Scheme::ALL {
        for boundary in Boundary::ALL {
            for m in 1..=96 {
                let t = TwoScale::new(scheme, boundary, m);
                let prod = dense_product(&t);
                for i in 0..m {
                    for j in 0..m {
                        let want = if i == j { 1.0 } else { 0.0 };
                        assert!(
                            (prod[i][j] - want).abs() < 1e-12,
                            "{scheme} {boundary} m={m} ({:?}): [A;B][P|Q][{i}][{j}] = {}",
                            t.kind,
                            prod[i][j]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn native_levels_are_used_from_the_documented_lengths_on() {
    use Boundary::*;
    let cases = [
        (Scheme::Haar, Periodic, 2),
        (Scheme::Chaikin, Interpolating, 8),
        (Scheme::Chaikin, Periodic, 4),
        (Scheme::Chaikin, Symmetric, 3),
        (Scheme::Cubic, Interpolating, 13),
        (Scheme::Cubic, Periodic, 8),
        (Scheme::Cubic, Symmetric, 3),
    ];
    for (s, b, m) in cases {
        assert_eq!(
            TwoScale::new(s, b, m).kind,
            LevelKind::Native,
            "{s} {b} {m}"
        );
        assert_ne!(
            TwoScale::new(s, b, m - 1).kind,
            LevelKind::Native,
            "{s} {b} {}",
            m - 1
        );
    }
}

fn lcg(seed: u64, n: usize) -> Vec<f64> {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 11) as f64 / (1u64 << 53) as f64) * 200.0 - 100.0
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    #[test]
    fn every_lane_reconstructs(len in 1usize..=300, dim in 1usize..=3, s in 0usize..3, b in 0usize..3, seed in any::<u64>(), lv in 0usize..8) {
        let scheme = Scheme::ALL[s];
        let boundary = Boundary::ALL[b];
        let data = lcg(seed, len * dim);
        let levels = lv.min(max_levels(scheme, boundary, len));
        let (packed, plan) = analyze_lane(&data, dim, scheme, boundary, levels).unwrap();
        let back = synthesize_lane(&packed, dim, &plan).unwrap();
        let scale = data.iter().fold(1.0f64, |a, &x| a.max(x.abs()));
        for (x, y) in data.iter().zip(&back) {
            prop_assert!((x - y).abs() <= 1e-12 * scale, "{} {} len {} levels {}: {} vs {}", scheme, boundary, len, levels, x, y);
        }
    }
}
