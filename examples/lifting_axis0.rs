//! Would lifting steps make the engine's row combines along axis 0 cheaper? One output
//! pair (a coarse and a detail row of cubic analysis) on rows held in the caches, two ways:
//!
//! - **direct**, as the engine does it: `C_j = ⅛F_{2j−3} − ½F_{2j−2} + ⅜F_{2j−1} + F_{2j}
//!   + ⅜F_{2j+1} − ½F_{2j+2} + ⅛F_{2j+3}` and `D_j = −⅛F_{2j−1} + ½F_{2j} − ¾F_{2j+1}
//!   + ½F_{2j+2} − ⅛F_{2j+3}`: 7 rows read, 2 written, 12 multiplies and 10 adds per pair;
//! - **lifting**, the same operator factored into three steps on the even rows `e_j = F_{2j}`
//!   and the odd rows `o_j = F_{2j+1}`:
//!   `e¹_j = e_j − ¼(o_{j−1} + o_j)`, `o¹_j = o_j − (e¹_j + e¹_{j+1})`,
//!   `C_j = 2e¹_j + ½(o¹_{j−1} + o¹_j)`, `D_j = −½o¹_j` (synthesis runs them backwards),
//!   streamed row pair by row pair: 5 rows read (two new, the odd row before, `e¹_{j−1}`,
//!   `o¹_{j−2}`), 4 written (`e¹_j`, `o¹_{j−1}` kept for the next pair, `C`, `D`), 4
//!   multiplies and 6 adds per pair.
//!
//! The example first checks that both give the same rows (to f32 rounding), then times
//! them in interleaved rounds, in ns per output sample:
//! `cargo run --release --example lifting_axis0 -- [width 4096]`.
use std::time::Instant;

/// The direct pair over the seven rows `F_{2j−3..=2j+3}`.
#[inline(always)]
fn direct_body(r: [&[f32]; 7], c: &mut [f32], d: &mut [f32]) {
    let w = c.len();
    let [r0, r1, r2, r3, r4, r5, r6] = r.map(|x| &x[..w]);
    let d = &mut d[..w];
    for i in 0..w {
        c[i] = 0.125 * r0[i] - 0.5 * r1[i] + 0.375 * r2[i] + r3[i] + 0.375 * r4[i] - 0.5 * r5[i]
            + 0.125 * r6[i];
        d[i] = -0.125 * r2[i] + 0.5 * r3[i] - 0.75 * r4[i] + 0.5 * r5[i] - 0.125 * r6[i];
    }
}

/// One lifting pair: from `e_k`, `o_k`, `o_{k−1}`, `e¹_{k−1}` and `o¹_{k−2}`, the rows
/// `e¹_k`, `o¹_{k−1}`, `C_{k−1}` and `D_{k−2}`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lifting_body(
    ek: &[f32],
    ok: &[f32],
    oprev: &[f32],
    e1prev: &[f32],
    o1pp: &[f32],
    e1k: &mut [f32],
    o1prev: &mut [f32],
    c: &mut [f32],
    d: &mut [f32],
) {
    let w = ek.len();
    let (ok, oprev, e1prev, o1pp) = (&ok[..w], &oprev[..w], &e1prev[..w], &o1pp[..w]);
    let (e1k, o1prev, c, d) = (&mut e1k[..w], &mut o1prev[..w], &mut c[..w], &mut d[..w]);
    for i in 0..w {
        let e1 = ek[i] - 0.25 * (oprev[i] + ok[i]);
        e1k[i] = e1;
        let o1 = oprev[i] - (e1prev[i] + e1);
        o1prev[i] = o1;
        c[i] = 2.0 * e1prev[i] + 0.5 * (o1pp[i] + o1);
        d[i] = -0.5 * o1pp[i];
    }
}

/// Both kernels built for AVX-512 when the machine has it (as the engine's are), else
/// for the baseline.
macro_rules! built {
    ($name:ident, $avx512:ident, $body:ident, ($($a:ident: $t:ty),*)) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx2,fma")]
        #[inline(never)]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $avx512($($a: $t),*) {
            $body($($a),*)
        }
        #[allow(clippy::too_many_arguments)]
        fn $name($($a: $t),*) {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the machine has the features the build asks for.
                return unsafe { $avx512($($a),*) };
            }
            $body($($a),*)
        }
    };
}
built!(direct, direct_avx512, direct_body, (r: [&[f32]; 7], c: &mut [f32], d: &mut [f32]));
built!(lifting, lifting_avx512, lifting_body, (ek: &[f32], ok: &[f32], oprev: &[f32],
    e1prev: &[f32], o1pp: &[f32], e1k: &mut [f32], o1prev: &mut [f32], c: &mut [f32],
    d: &mut [f32]));

fn main() {
    let w: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4096);
    let n = 16; // input rows F_0..F_15, in the caches
    let rows: Vec<Vec<f32>> = (0..n)
        .map(|r| {
            (0..w)
                .map(|i| ((i * 2654435761 + r * 40503) % 1000) as f32 * 0.01)
                .collect()
        })
        .collect();
    let row = |r: usize| &rows[r][..];
    let zero = vec![0f32; w];
    let (mut e1prev, mut e1k) = (zero.clone(), zero.clone());
    let (mut o1pp, mut o1prev) = (zero.clone(), zero.clone());
    let (mut c, mut d) = (zero.clone(), zero.clone());
    // largest difference of `ours` from the direct coarse (or detail) row over F_first…
    let (mut cd, mut dd) = (zero.clone(), zero.clone());
    let mut against_direct = |first: usize, ours: &[f32], detail: bool| -> f32 {
        direct(std::array::from_fn(|t| row(first + t)), &mut cd, &mut dd);
        let theirs = if detail { &dd } else { &cd };
        ours.iter()
            .zip(theirs)
            .fold(0f32, |m, (a, b)| m.max((a - b).abs()))
    };

    // the same rows both ways (pairs whose seven inputs exist)
    let mut worst = 0f32;
    for k in 1..n / 2 {
        lifting(
            row(2 * k),
            row(2 * k + 1),
            row(2 * k - 1),
            &e1prev,
            &o1pp,
            &mut e1k,
            &mut o1prev,
            &mut c,
            &mut d,
        );
        // e¹_0 comes from k = 0, which reads o_{−1}: the first checked coarse row is C_2
        let j = k - 1;
        if j >= 2 && 2 * j + 3 < n {
            worst = worst.max(against_direct(2 * j - 3, &c, false));
            if j >= 3 {
                worst = worst.max(against_direct(2 * j - 5, &d, true));
            }
        }
        std::mem::swap(&mut e1prev, &mut e1k);
        std::mem::swap(&mut o1pp, &mut o1prev);
    }
    assert!(worst < 1e-4, "lifting and direct rows differ by {worst}");
    println!("lifting and direct rows agree to {worst:e} (values up to 10)");

    let pairs = 20_000;
    for round in 0..5 {
        let t = Instant::now();
        for k in 0..pairs {
            let b = (2 * k) % (n - 7);
            direct(std::array::from_fn(|t| row(b + t)), &mut c, &mut d);
        }
        let direct_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        for k in 0..pairs {
            let b = 1 + (2 * k) % (n - 3);
            lifting(
                row(b + 1),
                row(b + 2),
                row(b),
                &e1prev,
                &o1pp,
                &mut e1k,
                &mut o1prev,
                &mut c,
                &mut d,
            );
            std::mem::swap(&mut e1prev, &mut e1k);
            std::mem::swap(&mut o1pp, &mut o1prev);
        }
        let lifting_s = t.elapsed().as_secs_f64();
        let ns = |s: f64| s / (pairs * 2 * w) as f64 * 1e9;
        println!(
            "round {round}: direct {:.3} ns per output sample, lifting {:.3}",
            ns(direct_s),
            ns(lifting_s)
        );
    }
    std::hint::black_box((&c, &d));
}
