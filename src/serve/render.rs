//! An image request rendered: the coarsest level that still holds the output's detail
//! is read, mapped to display values, resampled, given its quality, mirrored, turned
//! and encoded.
//!
//! ```text
//! level     the largest k with w·R_k/W ≥ out_w and h·R'_k/H ≥ out_h   (R_k: level extent)
//! window    x·R_k/W .. (x+w)·R_k/W on columns (rows alike): fractional, read as its
//!           whole samples ⌊·⌋ .. ⌈·⌉
//! display   8-bit images as they are; other types v ↦ 255·(v − lo)/(hi − lo), clamped,
//!           with lo, hi the header's min and max or the request's ?window=lo,hi;
//!           heightmaps hillshaded (Horn, sun 315°/45°, the cell that makes the relief
//!           span a quarter of the image, scaled by the level's step), gray
//! resample  each output sample the area mean of the window's samples under it
//!           (a window of exactly out_w × out_h whole samples is copied)
//! quality   gray = 0.299 R + 0.587 G + 0.114 B; bitonal = gray ≥ 128; color repeats gray
//! ```

use super::cache::LevelCache;
use super::iiif::{Format, ImageRequest, Quality, Resolved};
use super::source::{Plane, Source, Via};
use super::ServeError;
use crate::io::{DataKind, SampleType};
use crate::limits::Limits;
use crate::terrain::{hillshade, Grid, Shading};

/// JPEG quality of the tiles.
pub const JPEG_QUALITY: u8 = 90;

/// The level a request reads: the coarsest whose window is at least the output's size.
pub fn choose_level(src: &Source, r: &Resolved) -> usize {
    let (fw, fh) = src.size();
    let mut k = 0;
    for l in 1..=src.depth() {
        let (lw, lh) = src.level_size(l);
        let ww = r.w as f64 * lw as f64 / fw as f64;
        let wh = r.h as f64 * lh as f64 / fh as f64;
        if ww + 1e-9 >= r.out_w as f64 && wh + 1e-9 >= r.out_h as f64 {
            k = l;
        } else {
            break;
        }
    }
    k
}

/// A fractional interval `[a, b)` of one axis of a level, snapped to whole samples
/// within 1e-9.
fn span(start: u64, len: u64, level: usize, full: u64) -> (f64, f64) {
    let snap = |v: f64| {
        if (v - v.round()).abs() < 1e-9 {
            v.round()
        } else {
            v
        }
    };
    let s = level as f64 / full as f64;
    (snap(start as f64 * s), snap((start + len) as f64 * s))
}

/// What a render did and where its time went (the `Server-Timing` header of an answer).
#[derive(Clone, Copy, Debug, Default)]
pub struct Trace {
    /// The level read.
    pub level: usize,
    /// Where its window came from.
    pub via: Via,
    /// Whether the window was resampled (its size is not the output's).
    pub resampled: bool,
    /// Getting the window's display values (decodes included).
    pub window: std::time::Duration,
    /// Resampling, quality and orientation.
    pub resample: std::time::Duration,
    /// Encoding.
    pub encode: std::time::Duration,
}

/// Render a resolved request to encoded bytes.
pub fn render(
    src: &Source,
    cache: &LevelCache,
    limits: &Limits,
    req: &ImageRequest,
    r: &Resolved,
    window: Option<(f64, f64)>,
    trace: &mut Trace,
) -> Result<Vec<u8>, ServeError> {
    use std::time::Instant;
    let t0 = Instant::now();
    limits.check_elems(
        "the output of a request",
        r.out_w.saturating_mul(r.out_h),
        3 * 8,
    )?;
    let k = choose_level(src, r);
    let (fw, fh) = src.size();
    let (lw, lh) = src.level_size(k);
    let (x0, x1) = span(r.x, r.w, lw, fw);
    let (y0, y1) = span(r.y, r.h, lh, fh);
    let cols = (x0.floor() as usize)..(x1.ceil() as usize).min(lw).max(x0.floor() as usize + 1);
    let rows = (y0.floor() as usize)..(y1.ceil() as usize).min(lh).max(y0.floor() as usize + 1);
    trace.level = k;
    let shown = if src.header.kind == DataKind::Heightmap {
        shaded(
            src,
            cache,
            limits,
            k,
            rows.clone(),
            cols.clone(),
            &mut trace.via,
        )?
    } else {
        display(
            src,
            src.window(cache, limits, k, rows.clone(), cols.clone(), &mut trace.via)?,
            window,
        )
    };
    let (ow, oh) = (r.out_w as usize, r.out_h as usize);
    let t1 = Instant::now();
    trace.window = t1 - t0;
    trace.resampled =
        !(shown.w == ow && shown.h == oh && x0 == cols.start as f64 && y0 == rows.start as f64);
    let out = resample(
        shown,
        (x0 - cols.start as f64, x1 - cols.start as f64),
        (y0 - rows.start as f64, y1 - rows.start as f64),
        ow,
        oh,
    );
    let out = apply_quality(out, req.quality);
    let out = orient(out, req.rotation.mirror, req.rotation.quarters);
    let t2 = Instant::now();
    trace.resample = t2 - t1;
    let bytes = encode(&out, req.format);
    trace.encode = t2.elapsed();
    bytes
}

/// Display values (0..255, 1 or 3 channels) of a window of samples.
fn display(src: &Source, p: Plane, window: Option<(f64, f64)>) -> Plane {
    let h = &src.header;
    let (lo, hi) = match (window, h.sample_type) {
        (Some(w), _) => w,
        (None, SampleType::U8) => (0.0, 255.0),
        (None, _) => (h.min, h.max),
    };
    let scale = if hi > lo { 255.0 / (hi - lo) } else { 0.0 };
    let keep = if p.c >= 3 { 3 } else { 1 };
    let identity = window.is_none() && h.sample_type == SampleType::U8;
    if identity && keep == p.c {
        return p;
    }
    let mut data = Vec::with_capacity(p.h * p.w * keep);
    for px in p.data.chunks_exact(p.c) {
        for &v in &px[..keep] {
            data.push(if identity {
                v
            } else {
                ((v as f64 - lo) * scale).clamp(0.0, 255.0) as f32
            });
        }
    }
    Plane {
        h: p.h,
        w: p.w,
        c: keep,
        data,
    }
}

/// The hillshade of a heightmap's window, computed with a one-sample margin so that
/// neighbouring tiles meet without a seam.
fn shaded(
    src: &Source,
    cache: &LevelCache,
    limits: &Limits,
    k: usize,
    rows: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
    via: &mut Via,
) -> Result<Plane, ServeError> {
    let (lw, lh) = src.level_size(k);
    let mr = rows.start.saturating_sub(1)..(rows.end + 1).min(lh);
    let mc = cols.start.saturating_sub(1)..(cols.end + 1).min(lw);
    let p = src.window(cache, limits, k, mr.clone(), mc.clone(), via)?;
    let heights: Vec<f64> = p.data.chunks_exact(p.c).map(|s| s[0] as f64).collect();
    let g = Grid::new(p.h, p.w, 1, heights)?;
    let (fw, fh) = src.size();
    let span = (src.header.max - src.header.min).max(f64::MIN_POSITIVE);
    let base = span / (0.25 * fw.max(fh) as f64);
    let s = Shading {
        cell: (base * fh as f64 / lh as f64, base * fw as f64 / lw as f64),
        ..Shading::default()
    };
    let px = hillshade(&g, &s);
    let (oy, ox) = (rows.start - mr.start, cols.start - mc.start);
    let mut data = Vec::with_capacity(rows.len() * cols.len());
    for y in 0..rows.len() {
        let at = (oy + y) * p.w + ox;
        data.extend(px[at..at + cols.len()].iter().map(|&v| v as f32));
    }
    Ok(Plane {
        h: rows.len(),
        w: cols.len(),
        c: 1,
        data,
    })
}

/// For each of `n` outputs, the input samples under it and their weights (the overlap
/// of `[a + i·s, a + (i+1)·s)` with each sample, divided by `s`), `s = (b − a)/n ≥ 1`.
fn weights(a: f64, b: f64, n: usize, len: usize) -> Vec<Vec<(usize, f32)>> {
    let s = (b - a) / n as f64;
    (0..n)
        .map(|i| {
            let (l, r) = (a + i as f64 * s, a + (i + 1) as f64 * s);
            let mut w = Vec::new();
            let first = (l.floor().max(0.0) as usize).min(len - 1);
            let last = ((r.ceil() as usize).max(first + 1)).min(len);
            for j in first..last {
                let o = (r.min(j as f64 + 1.0) - l.max(j as f64)).max(0.0);
                if o > 1e-12 {
                    w.push((j, (o / (r - l)) as f32));
                }
            }
            if w.is_empty() {
                w.push((first, 1.0));
            }
            w
        })
        .collect()
}

/// The area-mean resampling of the fractional window `xs × ys` of `p` to `ow × oh`.
fn resample(p: Plane, xs: (f64, f64), ys: (f64, f64), ow: usize, oh: usize) -> Plane {
    if (p.w, p.h) == (ow, oh) && xs == (0.0, ow as f64) && ys == (0.0, oh as f64) {
        // the window is the output: every weight is 1
        return p;
    }
    let c = p.c;
    let wx = weights(xs.0, xs.1, ow, p.w);
    let wy = weights(ys.0, ys.1, oh, p.h);
    // columns first: p.h × ow
    let mut tmp = vec![0f32; p.h * ow * c];
    for y in 0..p.h {
        let row = &p.data[y * p.w * c..(y + 1) * p.w * c];
        for (x, ws) in wx.iter().enumerate() {
            let out = &mut tmp[(y * ow + x) * c..(y * ow + x + 1) * c];
            for &(j, w) in ws {
                for (o, &v) in out.iter_mut().zip(&row[j * c..(j + 1) * c]) {
                    *o += w * v;
                }
            }
        }
    }
    let mut data = vec![0f32; oh * ow * c];
    for (y, ws) in wy.iter().enumerate() {
        let out = &mut data[y * ow * c..(y + 1) * ow * c];
        for &(j, w) in ws {
            for (o, &v) in out.iter_mut().zip(&tmp[j * ow * c..(j + 1) * ow * c]) {
                *o += w * v;
            }
        }
    }
    Plane {
        h: oh,
        w: ow,
        c,
        data,
    }
}

fn apply_quality(p: Plane, q: Quality) -> Plane {
    let gray = |p: &Plane| -> Vec<f32> {
        if p.c == 1 {
            return p.data.clone();
        }
        p.data
            .chunks_exact(3)
            .map(|v| 0.299 * v[0] + 0.587 * v[1] + 0.114 * v[2])
            .collect()
    };
    let (c, data) = match q {
        Quality::Default => return p,
        Quality::Color if p.c == 3 => return p,
        Quality::Color => (3, p.data.iter().flat_map(|&v| [v, v, v]).collect()),
        Quality::Gray => (1, gray(&p)),
        Quality::Bitonal => (
            1,
            gray(&p)
                .into_iter()
                .map(|v| if v.round() >= 128.0 { 255.0 } else { 0.0 })
                .collect(),
        ),
    };
    Plane {
        h: p.h,
        w: p.w,
        c,
        data,
    }
}

/// Mirror (left–right) and then turn clockwise by `quarters` quarter turns.
fn orient(p: Plane, mirror: bool, quarters: u8) -> Plane {
    if !mirror && quarters == 0 {
        return p;
    }
    let (h, w, c) = (p.h, p.w, p.c);
    let (nh, nw) = if quarters % 2 == 1 { (w, h) } else { (h, w) };
    let mut data = vec![0f32; p.data.len()];
    for y in 0..h {
        for x in 0..w {
            let mx = if mirror { w - 1 - x } else { x };
            // where (y, mx) lands after the turn
            let (ty, tx) = match quarters % 4 {
                0 => (y, mx),
                1 => (mx, h - 1 - y),
                2 => (h - 1 - y, w - 1 - mx),
                _ => (w - 1 - mx, y),
            };
            let (s, d) = ((y * w + x) * c, (ty * nw + tx) * c);
            data[d..d + c].copy_from_slice(&p.data[s..s + c]);
        }
    }
    Plane {
        h: nh,
        w: nw,
        c,
        data,
    }
}

/// 8-bit samples (rounded, clamped) encoded as PNG (fast compression) or JPEG
/// (quality [`JPEG_QUALITY`], chroma 4:2:0, at most 65535 pixels a side as the format
/// allows).
fn encode(p: &Plane, f: Format) -> Result<Vec<u8>, ServeError> {
    use image::ImageEncoder;
    let px: Vec<u8> = p
        .data
        .iter()
        // round(clamp(v)): for v ≥ 0, ⌊v + ½⌋ is the cast's truncation (NaN gives 0)
        .map(|&v| (v.clamp(0.0, 255.0) + 0.5) as u8)
        .collect();
    let failed = |e: String| {
        ServeError::from(crate::Error::format(
            format!("encoding a {}x{} tile: {e}", p.w, p.h),
            "an encodable tile",
        ))
    };
    let mut out = Vec::new();
    match f {
        Format::Png => {
            let ct = if p.c == 3 {
                image::ExtendedColorType::Rgb8
            } else {
                image::ExtendedColorType::L8
            };
            image::codecs::png::PngEncoder::new_with_quality(
                &mut out,
                image::codecs::png::CompressionType::Fast,
                image::codecs::png::FilterType::Adaptive,
            )
            .write_image(&px, p.w as u32, p.h as u32, ct)
            .map_err(|e| failed(e.to_string()))?;
        }
        Format::Jpg => {
            let (Ok(w), Ok(h)) = (u16::try_from(p.w), u16::try_from(p.h)) else {
                return Err(ServeError::bad(
                    "size",
                    &format!("{}x{}", p.w, p.h),
                    "at most 65535 pixels a side in JPEG",
                ));
            };
            let ct = if p.c == 3 {
                jpeg_encoder::ColorType::Rgb
            } else {
                jpeg_encoder::ColorType::Luma
            };
            let mut enc = jpeg_encoder::Encoder::new(&mut out, JPEG_QUALITY);
            // chroma at half resolution both ways (4:2:0), as libjpeg's default and
            // iipsrv's tiles
            enc.set_sampling_factor(jpeg_encoder::SamplingFactor::F_2_2);
            enc.encode(&px, w, h, ct)
                .map_err(|e| failed(e.to_string()))?;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(h: usize, w: usize, c: usize) -> Plane {
        Plane {
            h,
            w,
            c,
            data: (0..h * w * c).map(|i| i as f32).collect(),
        }
    }

    #[test]
    fn a_window_of_the_output_size_is_copied() {
        let p = plane(4, 5, 3);
        assert_eq!(resample(p.clone(), (0.0, 5.0), (0.0, 4.0), 5, 4), p);
        // the same through the weights: a window one sample wider, its first column
        // left out
        let q = plane(4, 6, 3);
        let r = resample(q.clone(), (1.0, 6.0), (0.0, 4.0), 5, 4);
        for y in 0..4 {
            assert_eq!(
                r.data[y * 15..(y + 1) * 15],
                q.data[y * 18 + 3..(y + 1) * 18]
            );
        }
    }

    #[test]
    fn halving_takes_the_mean_of_two_by_two() {
        let p = Plane {
            h: 2,
            w: 2,
            c: 1,
            data: vec![0.0, 4.0, 8.0, 12.0],
        };
        assert_eq!(resample(p, (0.0, 2.0), (0.0, 2.0), 1, 1).data, vec![6.0]);
        // a fractional window: the mean of 1½ samples weighs them 2:1
        let q = Plane {
            h: 1,
            w: 2,
            c: 1,
            data: vec![3.0, 6.0],
        };
        let r = resample(q, (0.0, 1.5), (0.0, 1.0), 1, 1);
        assert!((r.data[0] - 4.0).abs() < 1e-5, "{:?}", r.data);
    }

    #[test]
    fn turns_and_mirrors_move_the_corners() {
        // 2 × 3: [[0 1 2] [3 4 5]]
        let p = plane(2, 3, 1);
        let r = orient(p.clone(), false, 1);
        assert_eq!((r.h, r.w), (3, 2));
        assert_eq!(r.data, vec![3.0, 0.0, 4.0, 1.0, 5.0, 2.0]);
        assert_eq!(
            orient(p.clone(), false, 2).data,
            vec![5.0, 4.0, 3.0, 2.0, 1.0, 0.0]
        );
        assert_eq!(
            orient(p.clone(), false, 3).data,
            vec![2.0, 5.0, 1.0, 4.0, 0.0, 3.0]
        );
        assert_eq!(orient(p, true, 0).data, vec![2.0, 1.0, 0.0, 5.0, 4.0, 3.0]);
    }

    #[test]
    fn gray_and_bitonal_reduce_to_one_channel() {
        let p = Plane {
            h: 1,
            w: 2,
            c: 3,
            data: vec![255.0, 255.0, 255.0, 10.0, 20.0, 30.0],
        };
        let g = apply_quality(p.clone(), Quality::Gray);
        assert_eq!(g.c, 1);
        assert!((g.data[0] - 255.0).abs() < 1e-3);
        assert_eq!(apply_quality(p, Quality::Bitonal).data, vec![255.0, 0.0]);
    }
}
