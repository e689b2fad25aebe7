//! Time the entropy coder on one band of synthetic, sparse, spatially clustered
//! coefficients (about the statistics of a fine detail band at ~1 bit per sample):
//! `cargo run --release --example entropy_timing -- [side] [reps]`.
use mra::entropy::{decode_band, encode_band, BandKind, Parent};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(512);
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let (dims, pdims) = ([n / 8, n, n], [n / 16, n / 2, n / 2]);
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    let mut rnd = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let mut band = |d: &[usize; 3]| -> Vec<i64> {
        let len = d.iter().product::<usize>();
        (0..len)
            .map(|i| {
                // activity that varies smoothly over the band, times a random draw
                let (y, xx) = ((i / d[2]) % d[1], i % d[2]);
                let act = ((y as f64 * 0.05).sin() * (xx as f64 * 0.03).cos()).abs();
                let u = (rnd() >> 11) as f64 / (1u64 << 53) as f64;
                let v = (-(1.0 - u).ln() * act * 1.5) as i64;
                if rnd() & 1 == 0 {
                    v
                } else {
                    -v
                }
            })
            .collect()
    };
    let parent = band(&pdims);
    let q = band(&dims);
    let zeros = q.iter().filter(|&&v| v == 0).count() as f64 / q.len() as f64;
    let p = Some(Parent {
        data: &parent,
        dims: &pdims,
    });
    let mut bytes = Vec::new();
    for _ in 0..reps {
        let t = Instant::now();
        bytes = encode_band(&q, &dims, BandKind::Detail, p);
        let te = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let back = decode_band(&bytes, &dims, BandKind::Detail, p).unwrap();
        let td = t.elapsed().as_secs_f64();
        assert_eq!(back, q);
        println!(
            "{} coefficients ({:.0}% zero), {:.3} bits each: encode {:.1} ns, decode {:.1} ns per coefficient",
            q.len(),
            zeros * 100.0,
            bytes.len() as f64 * 8.0 / q.len() as f64,
            te * 1e9 / q.len() as f64,
            td * 1e9 / q.len() as f64
        );
    }
    let h = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    });
    println!("bytes {} hash {h:016x}", bytes.len());
}
