//! Does the machine overlap a pass over memory with arithmetic in the caches?
//! `cargo run --release --example pass_overlap -- [k]` (2 threads: `RAYON_NUM_THREADS=2`).
//!
//! Each thread takes half of a 4096² f32 array, row by row, and times (best of 15):
//! - **memory pass**: the row copied from the array into an L1 buffer, then streamed
//!   (non-temporal stores, `kernel::stream_copy`) to a second array: the traffic of one
//!   direction of the image cascade, without its arithmetic;
//! - **compute**: `k` 7-tap row combines over rows held in the caches per row;
//! - **both**, one after the other per row, as the cascade does;
//! - **both in chunks**: the combines in pieces of 512 samples, each followed by a
//!   prefetch of that piece of the next array row and the streaming of that piece of the
//!   previous output row (the memory traffic spread through the arithmetic).
//!
//! If "both" is near the larger of the first two, the core hides the memory traffic behind
//! the arithmetic; if it is near their sum, it does not.
use mra::scheme::kernel::{combine, stream_copy};
use rayon::prelude::*;
use std::time::Instant;

const N: usize = 4096;
const CHUNK: usize = 512;
const W: [f32; 7] = [0.1, 0.2, 0.3, 0.4, 0.3, 0.2, 0.1];

fn best(mut f: impl FnMut()) -> f64 {
    f();
    let mut b = f64::INFINITY;
    for _ in 0..15 {
        let t = Instant::now();
        f();
        b = b.min(t.elapsed().as_secs_f64());
    }
    b * 1e3
}

/// The seven cached rows of a combine (16 samples apart, so that they do not share L1 sets).
fn taps(ring: &[f32], at: usize, len: usize) -> [&[f32]; 7] {
    std::array::from_fn(|j| &ring[j * (N + 16) + at..][..len])
}

/// One half of the array: `mem` the pass over memory, `k` combines per row.
fn rows(dst: &mut [f32], src: &[f32], mem: bool, k: usize) {
    let ring = vec![1f32; 7 * (N + 16)];
    let mut buf = vec![0f32; N];
    for (d, s) in dst.chunks_mut(N).zip(src.chunks(N)) {
        if mem {
            buf.copy_from_slice(s);
        }
        for _ in 0..k {
            combine(&mut buf, &taps(&ring, 0, N), &W);
        }
        if mem {
            stream_copy(&buf, d);
        }
    }
}

/// One half of the array with the memory traffic spread through the combines.
fn chunks(dst: &mut [f32], src: &[f32], k: usize) {
    let ring = vec![1f32; 7 * (N + 16)];
    let (mut buf, mut prev) = (vec![0f32; N], vec![0f32; N]);
    let n = src.len() / N;
    for r in 0..n {
        buf.copy_from_slice(&src[r * N..][..N]);
        for c in (0..N).step_by(CHUNK) {
            for _ in 0..k {
                combine(&mut buf[c..c + CHUNK], &taps(&ring, c, CHUNK), &W);
            }
            if r + 1 < n {
                let next = &src[(r + 1) * N + c..][..CHUNK];
                for l in (0..CHUNK).step_by(16) {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the address is inside `src`; a prefetch never faults.
                    unsafe {
                        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                        _mm_prefetch::<_MM_HINT_T0>(next[l..].as_ptr() as *const i8)
                    };
                }
            }
            if r > 0 {
                stream_copy(&prev[c..c + CHUNK], &mut dst[(r - 1) * N + c..][..CHUNK]);
            }
        }
        std::mem::swap(&mut prev, &mut buf);
    }
    stream_copy(&prev, &mut dst[(n - 1) * N..][..N]);
}

fn main() {
    let k: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2);
    let src: Vec<f32> = (0..N * N).map(|i| (i % 251) as f32).collect();
    let mut dst = vec![0f32; N * N];
    let half = N * N / 2;
    let mut run = |f: &(dyn Fn(&mut [f32], &[f32]) + Sync)| {
        best(|| {
            dst.par_chunks_mut(half)
                .zip(src.par_chunks(half))
                .for_each(|(d, s)| f(d, s))
        })
    };
    let m = run(&|d, s| rows(d, s, true, 0));
    let c = run(&|d, s| rows(d, s, false, k));
    let b = run(&|d, s| rows(d, s, true, k));
    let i = run(&|d, s| chunks(d, s, k));
    println!(
        "k {k}, {} threads: memory pass {m:.2} ms, compute {c:.2} ms, both {b:.2} ms \
         (sum {:.2}, larger {:.2}), both in chunks {i:.2} ms",
        rayon::current_num_threads(),
        m + c,
        m.max(c)
    );
}
