//! 2-D test images with values in [0, 1].

use super::rng::SplitMix64;
use super::Field;
use crate::io::DataKind;

fn field(h: usize, w: usize, channels: usize, data: Vec<f64>) -> Field {
    Field::new(&[h, w], channels, data, DataKind::Image)
}

/// Circular zone plate `½ (1 + cos(π r² / s))`, r measured from the centre in samples,
/// `s = max(H, W)`: the local frequency `r / s` cycles per sample reaches the Nyquist
/// limit ½ at `r = s / 2` (the middle of each edge), so every frequency appears once.
pub fn zone_plate(h: usize, w: usize) -> Field {
    let s = h.max(w) as f64;
    let (cy, cx) = ((h as f64 - 1.0) / 2.0, (w as f64 - 1.0) / 2.0);
    let mut d = Vec::with_capacity(h * w);
    for y in 0..h {
        for x in 0..w {
            let r2 = (y as f64 - cy).powi(2) + (x as f64 - cx).powi(2);
            d.push(0.5 * (1.0 + (std::f64::consts::PI * r2 / s).cos()));
        }
    }
    field(h, w, 1, d)
}

/// Linear ramps: channel 0 left→right, channel 1 top→bottom, channel 2 along the
/// diagonal, further channels the mean of the first two reversed.
pub fn gradient(h: usize, w: usize, channels: usize) -> Field {
    let mut d = Vec::with_capacity(h * w * channels);
    let fx = |x: usize| x as f64 / (w - 1).max(1) as f64;
    let fy = |y: usize| y as f64 / (h - 1).max(1) as f64;
    for y in 0..h {
        for x in 0..w {
            for c in 0..channels {
                d.push(match c {
                    0 => fx(x),
                    1 => fy(y),
                    2 => (fx(x) + fy(y)) / 2.0,
                    _ => 1.0 - (fx(x) + fy(y)) / 2.0,
                });
            }
        }
    }
    field(h, w, channels, d)
}

/// Hard edges: a dark background, a bright rectangle, a mid-grey disk overlapping it,
/// a thin vertical bar and a checkerboard quadrant (period 8 samples).
pub fn edges(h: usize, w: usize) -> Field {
    let (hf, wf) = (h as f64, w as f64);
    let mut d = Vec::with_capacity(h * w);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f64 / wf, y as f64 / hf);
            let mut val = 0.1;
            if (0.1..0.55).contains(&u) && (0.15..0.5).contains(&v) {
                val = 0.9;
            }
            if (u - 0.55).powi(2) + (v - 0.55).powi(2) < 0.2f64.powi(2) {
                val = 0.5;
            }
            if (0.8..0.83).contains(&u) {
                val = 1.0;
            }
            if u >= 0.6 && v < 0.3 && ((x / 8) + (y / 8)) % 2 == 0 {
                val = 0.7;
            }
            d.push(val);
        }
    }
    field(h, w, 1, d)
}

/// Distance from point p to segment a–b.
fn segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p.0 - a.0 - t * dx).powi(2) + (p.1 - a.1 - t * dy).powi(2)).sqrt()
}

/// Text-like strokes: dark "glyphs" on a light page, laid out in lines; each glyph is
/// 2–4 random strokes inside its cell, drawn with a one-sample anti-aliased edge.
pub fn strokes(h: usize, w: usize, seed: u64) -> Field {
    let mut rng = SplitMix64::new(seed);
    let cell = (h.min(w) as f64 / 10.0).max(6.0);
    let pen = (cell / 22.0).max(0.6);
    let mut segs: Vec<((f64, f64), (f64, f64))> = Vec::new();
    let mut y0 = cell * 0.5;
    while y0 + cell <= h as f64 {
        let mut x0 = cell * 0.5;
        while x0 + cell * 0.7 <= w as f64 {
            if rng.next_f64() < 0.85 {
                let n = 2 + (rng.next_u64() % 3) as usize;
                let mut p = (
                    x0 + rng.next_f64() * cell * 0.6,
                    y0 + rng.next_f64() * cell * 0.8,
                );
                for _ in 0..n {
                    let q = (
                        x0 + rng.next_f64() * cell * 0.6,
                        y0 + rng.next_f64() * cell * 0.8,
                    );
                    segs.push((p, q));
                    p = q;
                }
            }
            x0 += cell * 0.75;
        }
        y0 += cell * 1.3;
    }
    let mut d: Vec<f64> = vec![0.95; h * w];
    for &(a, b) in &segs {
        let (xmin, xmax) = (a.0.min(b.0) - pen - 1.0, a.0.max(b.0) + pen + 1.0);
        let (ymin, ymax) = (a.1.min(b.1) - pen - 1.0, a.1.max(b.1) + pen + 1.0);
        for y in (ymin.max(0.0) as usize)..(ymax.min(h as f64 - 1.0) as usize + 1) {
            for x in (xmin.max(0.0) as usize)..(xmax.min(w as f64 - 1.0) as usize + 1) {
                let dist = segment_distance((x as f64, y as f64), a, b);
                let cover = (pen + 0.5 - dist).clamp(0.0, 1.0);
                let v = &mut d[y * w + x];
                *v = (*v).min(0.95 - 0.9 * cover);
            }
        }
    }
    field(h, w, 1, d)
}

/// Uniform white noise in [0, 1), independent per sample and channel.
pub fn noise(h: usize, w: usize, channels: usize, seed: u64) -> Field {
    let mut rng = SplitMix64::new(seed);
    let d = (0..h * w * channels).map(|_| rng.next_f64()).collect();
    field(h, w, channels, d)
}
