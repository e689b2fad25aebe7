//! Time whole decodes of `.mra` files in process (the library's `codec::decode`, as the
//! Python package calls it), for profiles without the Python boundary:
//! `cargo run --release --example decode_timing -- FILE.mra [reps]`; prints the best and
//! the median wall time of `reps` decodes (run under `perf record -g` for a profile).
use mra::codec::{decode, DecodeOptions};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("usage: decode_timing FILE.mra [reps]");
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(20);
    let bytes = std::fs::read(path).expect("read the file");
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        let d = decode(&bytes, &DecodeOptions::default()).expect("decode");
        times.push(t.elapsed().as_secs_f64());
        std::hint::black_box(d);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{path}: best {:.4} s, median {:.4} s over {reps} decodes",
        times[0],
        times[reps / 2]
    );
}
