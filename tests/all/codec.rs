//! The codec end to end: every mode on every sample type and odd shapes, lossless
//! bit-exactness, the max-error guarantee, progressive and truncated decoding, damaged
//! files, the test vectors in formats/vectors/, and a few corpus files.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::format::sha256::{hex, sha256};
use mra::io::{DataKind, Raster, SampleType, Samples};
use mra::scheme::{Boundary, Scheme};
use mra::ErrorKind;
use proptest::prelude::*;

use super::common;

const TYPES: [SampleType; 9] = SampleType::ALL;

/// Smooth field plus a little texture, scaled into the type's useful range.
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let w = *dims.last().unwrap();
    let h = if dims.len() > 1 {
        dims[dims.len() - 2]
    } else {
        1
    };
    let (lo, hi) = match ty {
        SampleType::U8 => (0.0, 255.0),
        SampleType::I8 => (-128.0, 127.0),
        SampleType::U16 => (0.0, 4000.0),
        SampleType::I16 => (-1000.0, 1500.0),
        SampleType::U32 | SampleType::I32 => (0.0, 1.0e5),
        _ => (-3.0, 8.0),
    };
    let mut x = seed.wrapping_mul(0x9E3779B97F4A7C15) | 1;
    let v: Vec<f64> = (0..n)
        .map(|i| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let p = i / channels;
            let (px, py, pz) = ((p % w) as f64, ((p / w) % h) as f64, (p / (w * h)) as f64);
            let s = 0.5
                + 0.35 * (px * 0.21 + (i % channels) as f64).sin() * (py * 0.17 + pz * 0.3).cos();
            let t = s + 0.05 * ((x >> 40) as f64 / (1u64 << 24) as f64 - 0.5);
            lo + (hi - lo) * t.clamp(0.0, 1.0)
        })
        .collect();
    let kind = if dims.len() == 3 {
        DataKind::Volume
    } else {
        DataKind::Image
    };
    Raster::new(dims.to_vec(), channels, Samples::from_f64(&v, ty), kind).unwrap()
}

fn opts(rate: Rate) -> EncodeOptions {
    EncodeOptions {
        rate,
        ..Default::default()
    }
}

fn max_err(a: &Raster, b: &Raster) -> f64 {
    (0..a.samples.len())
        .map(|i| (a.samples.get_f64(i) - b.samples.get_f64(i)).abs())
        .fold(0.0, f64::max)
}

/// A raster of the shape and type of `r` with every sample at `r`'s mean.
fn constant_like(r: &Raster) -> Raster {
    let n = r.samples.len();
    let mean = (0..n).map(|i| r.samples.get_f64(i)).sum::<f64>() / n as f64;
    let v = vec![mean; n];
    Raster::new(
        r.dims.clone(),
        r.channels,
        Samples::from_f64(&v, r.sample_type()),
        r.kind,
    )
    .unwrap()
}

/// Root-mean-square difference of two rasters of the same shape.
fn rms_err(a: &Raster, b: &Raster) -> f64 {
    let n = a.samples.len();
    assert_eq!(n, b.samples.len());
    let s: f64 = (0..n)
        .map(|i| (a.samples.get_f64(i) - b.samples.get_f64(i)).powi(2))
        .sum();
    (s / n.max(1) as f64).sqrt()
}

fn round_trip(r: &Raster, o: &EncodeOptions) -> Raster {
    let bytes = codec::encode(r, o).unwrap();
    codec::decode(&bytes, &DecodeOptions::default())
        .unwrap()
        .raster
}

const SHAPES: [(&[usize], usize); 6] = [
    (&[1, 1], 1),
    (&[1, 17], 1),
    (&[13, 1], 2),
    (&[9, 14], 3),
    (&[5, 6, 7], 1),
    (&[23], 4),
];

#[test]
fn every_lossy_mode_round_trips_every_type_and_shape() {
    for (k, &ty) in TYPES.iter().enumerate() {
        for (s, &(dims, ch)) in SHAPES.iter().enumerate() {
            let r = field(dims, ch, ty, (k * 10 + s) as u64);
            let (lo, hi) = r.samples.min_max().unwrap();
            let range = (hi - lo).max(1e-9);
            // the rms error of the best constant picture (the source's mean)
            let spread = rms_err(&r, &constant_like(&r));
            // rounding to the stored type
            let slack = match ty {
                SampleType::F16 => 0.01,
                SampleType::F32 | SampleType::F64 => 1e-6,
                _ => 0.5,
            };
            for rate in [
                Rate::Keep(20.0),
                Rate::Threshold(range * 0.01),
                Rate::Quality(60.0),
            ] {
                for scheme in Scheme::ALL {
                    let o = EncodeOptions {
                        scheme,
                        boundary: Boundary::Symmetric,
                        levels: 4,
                        rate,
                        format: Default::default(),
                        effort: mra::codec::DEFAULT_EFFORT,
                    };
                    let d = round_trip(&r, &o);
                    assert_eq!(d.dims, r.dims);
                    assert_eq!(d.channels, r.channels);
                    assert_eq!(d.sample_type(), ty);
                    assert_eq!(d.kind, r.kind);
                    let (e, rms) = (max_err(&r, &d), rms_err(&r, &d));
                    let what = format!(
                        "{ty} {dims:?}x{ch} {rate:?} {scheme}: max error {e}, rms error {rms}, \
                         range {range}, deviation from the mean {spread}"
                    );
                    match rate {
                        // a fifth of the details (on lanes of a few samples, a handful):
                        // closer to the picture than its mean is
                        Rate::Keep(_) => assert!(rms <= 0.8 * spread + slack, "{what}"),
                        _ => assert!(
                            rms <= 0.02 * range + slack && e <= 0.06 * range + slack,
                            "{what}"
                        ),
                    }
                }
            }
        }
    }
}

#[test]
fn quality_trades_size_for_error() {
    let r = field(&[40, 56], 3, SampleType::U8, 3);
    let mut last = (0usize, f64::INFINITY);
    for q in [20.0, 50.0, 80.0] {
        let bytes = codec::encode(&r, &opts(Rate::Quality(q))).unwrap();
        let d = codec::decode(&bytes, &DecodeOptions::default())
            .unwrap()
            .raster;
        let c = mra::metrics::compare(&r, &d, &Default::default()).unwrap();
        let mse = c.mse;
        assert!(
            bytes.len() > last.0 && mse < last.1,
            "q {q}: {} bytes, mse {mse}",
            bytes.len()
        );
        last = (bytes.len(), mse);
    }
}

#[test]
fn lossless_is_bit_exact_for_every_type_and_shape_including_nan() {
    for (k, &ty) in TYPES.iter().enumerate() {
        for (s, &(dims, ch)) in SHAPES.iter().enumerate() {
            let mut r = field(dims, ch, ty, (k * 7 + s) as u64);
            if let Samples::F32(v) = &mut r.samples {
                v[0] = f32::NAN;
                if v.len() > 2 {
                    v[1] = f32::NEG_INFINITY;
                    v[2] = -0.0;
                }
            }
            let d = round_trip(&r, &opts(Rate::Lossless));
            let a = mra::io::bytes::encode(&r.samples, false);
            let b = mra::io::bytes::encode(&d.samples, false);
            assert_eq!(a, b, "{ty} {dims:?}x{ch}");
        }
    }
}

/// One-piece files are format 3.0 by default; with `Format::Bands` lossless files are
/// format 2.3 (each band chooses its magnitude classes) and lossy ones 2.0; 16-bit samples over the whole range with sharp steps (details in the
/// thousands, where bands take the wide classes) come back bit-exact, and decode at
/// reduced levels to the halved extents.
#[test]
fn files_are_format_3_0_or_2_x_and_exact_on_wide_16_bit_data() {
    let (h, w) = (37usize, 53usize);
    let v: Vec<f64> = (0..h * w)
        .map(|i| {
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            let step = if (i % w) % 7 < 3 { 30000.0 } else { 0.0 };
            (20000.0
                + 12000.0 * (x * 0.8).sin() * (y * 0.6).cos()
                + step
                + 97.0 * ((i * 7919) % 17) as f64)
                .min(65535.0)
        })
        .collect();
    let r = Raster::new(
        vec![h, w],
        1,
        Samples::from_f64(&v, SampleType::U16),
        DataKind::Image,
    )
    .unwrap();
    let bytes = codec::encode(&r, &opts(Rate::Lossless)).unwrap();
    assert_eq!(codec::info(&bytes).unwrap().version, "3.2");
    let bands = EncodeOptions {
        format: codec::Format::Bands,
        ..opts(Rate::Lossless)
    };
    let two = codec::encode(&r, &bands).unwrap();
    assert_eq!(codec::info(&two).unwrap().version, "2.3");
    assert!(
        codec::decode(&two, &DecodeOptions::default())
            .unwrap()
            .raster
            .samples
            == r.samples
    );
    let d = codec::decode(&bytes, &DecodeOptions::default()).unwrap();
    assert!(d.complete);
    assert!(d.raster.samples == r.samples, "not bit-exact");
    for level in 1..=2 {
        let d = codec::decode(
            &bytes,
            &DecodeOptions {
                level,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(
            d.raster.dims,
            vec![h.div_ceil(1 << level), w.div_ceil(1 << level)]
        );
    }
    let lossy = codec::encode(&r, &opts(Rate::Quality(50.0))).unwrap();
    assert_eq!(codec::info(&lossy).unwrap().version, "3.2");
    let bands = EncodeOptions {
        format: codec::Format::Bands,
        ..opts(Rate::Quality(50.0))
    };
    assert_eq!(
        codec::info(&codec::encode(&r, &bands).unwrap())
            .unwrap()
            .version,
        "2.0"
    );
}

/// Bands and channels are coded in parallel, each into its own stream: the file, and
/// what the decoder makes of it, are the same with 1, 2 or 3 threads, in every rate mode.
#[test]
fn the_file_is_the_same_whatever_the_thread_count() {
    let r = mra::generate::images::noise(70, 90, 3, 4)
        .to_raster(SampleType::U8)
        .unwrap();
    let rates = [
        Rate::Bpp(1.5),
        Rate::Quality(60.0),
        Rate::Psnr(35.0),
        Rate::MaxError(2.0),
        Rate::Lossless,
    ];
    for rate in rates {
        let opts = EncodeOptions {
            rate,
            ..Default::default()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let bytes = codec::encode(&r, &opts).unwrap();
                let back = codec::decode(&bytes, &Default::default()).unwrap();
                (bytes, back.raster.samples)
            })
        };
        let one = run(1);
        for t in [2, 3] {
            let other = run(t);
            assert!(one.0 == other.0, "{rate:?}: file differs with {t} threads");
            assert!(
                one.1 == other.1,
                "{rate:?}: decode differs with {t} threads"
            );
        }
    }
}

#[test]
fn lossless_codes_floats_on_a_power_of_two_grid_as_integers() {
    // heights in whole metres and in quarter metres stored as floats: mode 3, exact and
    // far smaller than the bit patterns; one −0 or a value off the grid falls back to mode 1, exact
    let base = field(&[61, 47], 1, SampleType::I16, 3);
    let ints: Vec<f64> = (0..base.samples.len())
        .map(|i| base.samples.get_f64(i))
        .collect();
    for (ty, scale) in [
        (SampleType::F32, 1.0),
        (SampleType::F64, 0.25),
        (SampleType::F16, 0.5),
    ] {
        // + 0.0: no −0 from rounding small negatives
        let mut v: Vec<f64> = ints
            .iter()
            .map(|x| (x / 64.0).round() * scale + 0.0)
            .collect();
        let r = Raster::new(
            vec![61, 47],
            1,
            Samples::from_f64(&v, ty),
            DataKind::Heightmap,
        )
        .unwrap();
        let bytes = codec::encode(&r, &opts(Rate::Lossless)).unwrap();
        let d = codec::decode(&bytes, &DecodeOptions::default()).unwrap();
        assert_eq!(d.raster.samples, r.samples, "{ty} × {scale}");
        assert_eq!(d.header.delta, scale, "{ty}: the quantum");
        let (start, _) = head_of(&bytes);
        assert_eq!(bytes[start + 8 + 4 * 2], 3, "{ty}: mode byte 3 (two axes)");
        // f16 holds only multiples of 2^−24 under 2^16: −0 alone breaks its grid
        let odds: &[f64] = match ty {
            SampleType::F32 => &[-0.0, 1e-30],
            SampleType::F64 => &[-0.0, 0.1],
            _ => &[-0.0],
        };
        for &odd in odds {
            v[5] = odd;
            let r2 = Raster::new(
                vec![61, 47],
                1,
                Samples::from_f64(&v, ty),
                DataKind::Heightmap,
            )
            .unwrap();
            let b2 = codec::encode(&r2, &opts(Rate::Lossless)).unwrap();
            let d2 = codec::decode(&b2, &DecodeOptions::default()).unwrap();
            assert_eq!(d2.header.delta, 0.0, "{ty} with {odd}: bit patterns");
            let a = mra::io::bytes::encode(&r2.samples, false);
            assert_eq!(
                a,
                mra::io::bytes::encode(&d2.raster.samples, false),
                "{ty} with {odd}"
            );
            assert!(
                bytes.len() < b2.len(),
                "{ty}: {} ≥ {}",
                bytes.len(),
                b2.len()
            );
            v[5] = (ints[5] / 64.0).round() * scale + 0.0;
        }
    }
}

#[test]
fn extreme_integer_values_survive_lossless() {
    let v: Vec<i32> = vec![
        i32::MIN,
        i32::MAX,
        0,
        -1,
        1,
        i32::MAX,
        i32::MIN,
        7,
        9,
        -3,
        5,
        6,
    ];
    let r = Raster::new(vec![3, 4], 1, Samples::I32(v.clone()), DataKind::Image).unwrap();
    let d = round_trip(&r, &opts(Rate::Lossless));
    assert_eq!(d.samples, Samples::I32(v));
    let f: Vec<f64> = vec![f64::MAX, f64::MIN, f64::MIN_POSITIVE, 0.0, -0.0, 1e300];
    let r = Raster::new(vec![6], 1, Samples::F64(f.clone()), DataKind::Image).unwrap();
    let d = round_trip(&r, &opts(Rate::Lossless));
    assert_eq!(d.samples, Samples::F64(f));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn max_error_is_never_exceeded(
        h in 1usize..20, w in 1usize..20, ch in 1usize..4, t in 0usize..9,
        e in prop_oneof![Just(0.5f64), Just(1.0), Just(3.0), Just(10.0), Just(0.01)],
        seed in 0u64..1000, scheme in 0usize..3,
    ) {
        let ty = TYPES[t];
        let r = field(&[h, w], ch, ty, seed);
        let o = EncodeOptions { scheme: Scheme::ALL[scheme], boundary: Boundary::Symmetric, levels: 4, rate: Rate::MaxError(e), format: Default::default(), effort: mra::codec::DEFAULT_EFFORT };
        let d = round_trip(&r, &o);
        let m = max_err(&r, &d);
        prop_assert!(m <= e, "{ty} {h}x{w}x{ch} e {e}: {m}");
    }
}

#[test]
fn max_error_holds_on_a_3d_volume() {
    let r = field(&[9, 11, 13], 1, SampleType::I16, 5);
    for e in [1.0, 4.0, 25.0] {
        let d = round_trip(&r, &opts(Rate::MaxError(e)));
        assert!(max_err(&r, &d) <= e);
    }
}

#[test]
fn psnr_and_bpp_targets_are_met() {
    let r = field(&[64, 96], 3, SampleType::U8, 11);
    for target in [30.0, 38.0] {
        let bytes = codec::encode(&r, &opts(Rate::Psnr(target))).unwrap();
        let d = codec::decode(&bytes, &DecodeOptions::default())
            .unwrap()
            .raster;
        let p = mra::metrics::compare(&r, &d, &Default::default())
            .unwrap()
            .psnr
            .unwrap();
        assert!(p >= target && p < target + 0.5, "target {target}: {p}");
    }
    let r = field(&[128, 160], 3, SampleType::U8, 12);
    for b in [1.0, 3.0] {
        let bytes = codec::encode(&r, &opts(Rate::Bpp(b))).unwrap();
        let got = bytes.len() as f64 * 8.0 / (128.0 * 160.0);
        assert!(got <= b && got > b * 0.9, "target {b}: {got}");
    }
}

#[test]
fn progressive_levels_halve_the_size_and_approximate_the_picture() {
    let r = field(&[33, 50], 1, SampleType::U8, 2);
    for rate in [Rate::Quality(70.0), Rate::Lossless] {
        // Haar, whose coarse samples are cell means like the block means below
        let o = EncodeOptions {
            scheme: Scheme::Haar,
            ..opts(rate)
        };
        let bytes = codec::encode(&r, &o).unwrap();
        for k in 1..4 {
            let d = codec::decode(
                &bytes,
                &DecodeOptions {
                    level: k,
                    allow_truncated: false,
                    ..Default::default()
                },
            )
            .unwrap()
            .raster;
            let mut want = vec![33usize, 50];
            for _ in 0..k {
                want = want.iter().map(|n| n.div_ceil(2)).collect();
            }
            assert_eq!(d.dims, want, "{rate:?} level {k}");
            // the coarse picture is a local mean of the source
            let (lo, hi) = r.samples.min_max().unwrap();
            let (a, b) = d.samples.min_max().unwrap();
            // the 5/3 low-pass (−⅛, ¼, ¾, ¼, −⅛) may overshoot the range a little
            let slack = if rate == Rate::Lossless {
                0.25 * (hi - lo)
            } else {
                1.0
            };
            assert!(
                a >= lo - slack && b <= hi + slack,
                "{rate:?} level {k}: {a}..{b}"
            );
            // Haar's coarse samples are cell means; the 5/3 lifting's are the linear
            // scheme's (CDF 5/3) coarse samples, up to the lifting's roundings
            let m = if rate == Rate::Lossless {
                let fine = EncodeOptions {
                    scheme: Scheme::Linear,
                    ..opts(Rate::Quality(100.0))
                };
                let bytes = codec::encode(&r, &fine).unwrap();
                let opts = DecodeOptions {
                    level: k,
                    allow_truncated: false,
                    ..Default::default()
                };
                codec::decode(&bytes, &opts)
                    .unwrap()
                    .raster
                    .samples
                    .to_f64()
            } else {
                block_means(&r, 1 << k)
            };
            let got = d.samples.to_f64();
            let rms = (got
                .iter()
                .zip(&m)
                .map(|(g, w)| (g - w).powi(2))
                .sum::<f64>()
                / m.len() as f64)
                .sqrt();
            // (the integer lifting floors at every step: within 4% of the float
            // scheme's coarse block at level 3)
            let tol = if rate == Rate::Lossless { 0.04 } else { 0.03 };
            assert!(
                rms <= tol * (hi - lo),
                "{rate:?} level {k}: rms {rms} from the {0}x{0} block means (range {1})",
                1 << k,
                hi - lo
            );
        }
    }
}

/// Means of the `b`×`b` blocks of a one-channel image (blocks cut short at the far edges).
fn block_means(r: &Raster, b: usize) -> Vec<f64> {
    assert_eq!((r.dims.len(), r.channels), (2, 1));
    let (h, w) = (r.dims[0], r.dims[1]);
    let v = r.samples.to_f64();
    let mut out = Vec::new();
    for by in (0..h).step_by(b) {
        for bx in (0..w).step_by(b) {
            let (y1, x1) = ((by + b).min(h), (bx + b).min(w));
            let s: f64 = (by..y1)
                .flat_map(|y| (bx..x1).map(move |x| (y, x)))
                .map(|(y, x)| v[y * w + x])
                .sum();
            out.push(s / ((y1 - by) * (x1 - bx)) as f64);
        }
    }
    out
}

fn sample_file() -> (Raster, Vec<u8>) {
    let r = field(&[21, 30], 3, SampleType::U8, 8);
    let bytes = codec::encode(&r, &opts(Rate::Quality(60.0))).unwrap();
    (r, bytes)
}

#[test]
fn truncated_files_fail_without_the_flag_and_decode_with_it() {
    let (r, bytes) = sample_file();
    let info = codec::info(&bytes).unwrap();
    for cut in 0..bytes.len() {
        let part = &bytes[..cut];
        let e = codec::decode(part, &DecodeOptions::default()).unwrap_err();
        assert!(matches!(e.kind(), ErrorKind::Format), "cut {cut}: {e}");
        let ok = codec::decode(
            part,
            &DecodeOptions {
                level: 0,
                allow_truncated: true,
                ..Default::default()
            },
        );
        // with the flag every cut after the HEAD chunk decodes to the full shape
        let head_end = info.chunks[0].offset + info.chunks[0].bytes;
        if cut as u64 >= head_end {
            let d = ok.unwrap();
            assert_eq!(d.raster.dims, r.dims);
            assert!(!d.complete);
        }
    }
    // quality grows with the chunks kept
    let ends: Vec<u64> = info.chunks.iter().map(|c| c.offset + c.bytes).collect();
    let errs: Vec<f64> = ends[1..ends.len() - 1]
        .iter()
        .map(|&e| {
            let d = codec::decode(
                &bytes[..e as usize],
                &DecodeOptions {
                    level: 0,
                    allow_truncated: true,
                    ..Default::default()
                },
            )
            .unwrap();
            mra::metrics::compare(&r, &d.raster, &Default::default())
                .unwrap()
                .mse
        })
        .collect();
    assert!(errs.len() >= 3 && errs.first() > errs.last(), "{errs:?}");
}

#[test]
fn flipped_bits_are_reported_with_the_chunk_name() {
    let (_, bytes) = sample_file();
    let info = codec::info(&bytes).unwrap();
    for c in &info.chunks {
        let mut b = bytes.clone();
        let at = (c.offset + 8) as usize; // first payload byte (or CRC for empty MEND)
        b[at] ^= 0x10;
        let e = codec::decode(&b, &DecodeOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(&c.kind) && e.contains("CRC"), "{e}");
    }
}

fn head_of(bytes: &[u8]) -> (usize, usize) {
    let n = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
    (16, 16 + n)
}

fn recrc(bytes: &mut [u8]) {
    let (s, e) = head_of(bytes);
    let crc = mra::format::crc::crc32c(&bytes[12..e]);
    bytes[e..e + 4].copy_from_slice(&crc.to_le_bytes());
    let _ = s;
}

/// HEAD of a 2-D file: 5 bytes, 2 extents, channels, 5 codes, 5 f64, then the tile.
fn set_tile(b: &mut [u8], h: u32, w: u32) {
    let t = 16 + 5 + 8 + 2 + 5 + 40;
    b[t..t + 4].copy_from_slice(&h.to_le_bytes());
    b[t + 4..t + 8].copy_from_slice(&w.to_le_bytes());
}

#[test]
fn absurd_dimensions_wrong_magic_and_version_are_rejected() {
    // a format 2 file: its HEAD is rewritten below as a 2.x one
    let (r, _) = sample_file();
    let two = EncodeOptions {
        format: codec::Format::Bands,
        ..opts(Rate::Quality(60.0))
    };
    let bytes = codec::encode(&r, &two).unwrap();
    // dims: byte 5 of HEAD = ndims, then u32 extents
    let mut b = bytes.clone();
    b[16 + 5..16 + 9].copy_from_slice(&u32::MAX.to_le_bytes());
    b[16 + 9..16 + 13].copy_from_slice(&u32::MAX.to_le_bytes());
    set_tile(&mut b, u32::MAX, u32::MAX);
    recrc(&mut b);
    let e = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::LimitsExceeded, "{e}");
    // modest dims, but far more than the file could code
    let mut b = bytes.clone();
    b[16 + 5..16 + 9].copy_from_slice(&60000u32.to_le_bytes());
    b[16 + 9..16 + 13].copy_from_slice(&60000u32.to_le_bytes());
    set_tile(&mut b, 60000, 60000);
    recrc(&mut b);
    let e = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::LimitsExceeded, "{e}");
    let mut b = bytes.clone();
    b[1] = b'X';
    let e = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
    assert!(e.to_string().contains("signature"), "{e}");
    let mut b = bytes.clone();
    b[16] = mra::format::Version::LATEST.major + 1;
    recrc(&mut b);
    let e = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Unsupported, "{e}");
    assert!(e.to_string().contains("version"));
    // a minor version above the reader's is refused, naming the version (a band of a
    // newer coding would decode to other samples)
    let mut b = bytes.clone();
    assert_ne!(b[17], 9, "the sample file is already of minor version 9");
    b[17] = 9;
    recrc(&mut b);
    let e = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Unsupported, "{e}");
    assert!(e.to_string().contains("2.9"), "{e}");
    // the latest minor this reader implements is accepted (from 2.4 with the flags byte
    // that ends HEAD)
    let (s, e) = head_of(&bytes);
    let mut head = bytes[s..e].to_vec();
    head[1] = mra::format::Version::LATEST_2.minor;
    if mra::format::Version::LATEST_2.has_head_flags() {
        head.push(0);
    }
    let mut b = bytes[..s - 8].to_vec();
    mra::format::put_chunk(&mut b, b"HEAD", &head);
    b.extend_from_slice(&bytes[e + 4..]);
    codec::info(&b).unwrap_or_else(|e| panic!("minor version {}: {e}", b[17]));
}

#[test]
fn unknown_ancillary_chunks_are_skipped_and_critical_ones_rejected() {
    let (r, bytes) = sample_file();
    let (_, e) = head_of(&bytes);
    let at = e + 4;
    for (kind, ok) in [(b"zzZZ", true), (b"ZZZZ", false)] {
        let mut b = bytes[..at].to_vec();
        mra::format::put_chunk(&mut b, kind, b"future");
        b.extend_from_slice(&bytes[at..]);
        let d = codec::decode(&b, &DecodeOptions::default());
        if ok {
            assert_eq!(d.unwrap().raster.dims, r.dims);
        } else {
            assert_eq!(d.unwrap_err().kind(), ErrorKind::Unsupported);
        }
    }
}

#[test]
fn random_damage_never_panics() {
    let (_, bytes) = sample_file();
    let mut x = 0x1234_5678_9abc_def0u64;
    for _ in 0..300 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let mut b = bytes.clone();
        for k in 0..(1 + x % 4) {
            let i = ((x >> (8 * k)) as usize) % b.len();
            b[i] = (x >> 32) as u8;
        }
        // re-seal every chunk's CRC so that the damage reaches the decoders
        let mut pos = 8;
        while pos + 12 <= b.len() {
            let n = u32::from_le_bytes(b[pos..pos + 4].try_into().unwrap()) as usize;
            if pos + 12 + n > b.len() {
                break;
            }
            let crc = mra::format::crc::crc32c(&b[pos + 4..pos + 8 + n]);
            b[pos + 8 + n..pos + 12 + n].copy_from_slice(&crc.to_le_bytes());
            pos += 12 + n;
        }
        let _ = codec::decode(
            &b,
            &DecodeOptions {
                level: (x % 3) as usize,
                allow_truncated: x.is_multiple_of(2),
                ..Default::default()
            },
        );
        let _ = codec::info(&b);
    }
}

#[test]
fn metadata_survives() {
    let mut r = field(&[6, 7, 8], 1, SampleType::I16, 1);
    r.meta.spacing = Some(vec![3.0, 1.5, 1.5]);
    r.meta.origin = Some(vec![-1.0, 2.0, 3.5]);
    r.meta.units = Some("mm".into());
    r.meta.space = Some("left-posterior-superior".into());
    r.meta.extra.insert("dicom.Modality".into(), "CT".into());
    let d = round_trip(&r, &opts(Rate::Lossless));
    assert_eq!(d.meta, r.meta);
}

#[test]
fn test_vectors_decode_to_their_digests() {
    // formats/vectors: the current format; formats/vectors/v1: format 1 files, which
    // readers still decode to the same samples
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("formats/vectors");
    for (dir, major) in [(root.clone(), 2), (root.join("v1"), 1)] {
        let manifest: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap())
                .unwrap();
        let list = manifest.as_array().unwrap();
        assert!(list.len() >= 5);
        for v in list {
            let bytes = std::fs::read(dir.join(v["file"].as_str().unwrap())).unwrap();
            // format 3 vectors (code-blocks) sit beside the format 2 ones
            let name = v["name"].as_str().unwrap();
            let three = ["blocks30_", "blocks31_", "blocks32"]
                .iter()
                .position(|p| name.starts_with(p));
            let want = if three.is_some() { 3 } else { major };
            assert_eq!(bytes[16], want, "{name} is not a format {want} file");
            // 3.1 vectors (the HT block coder) and 3.2 ones (per-level code-blocks, and
            // block coder 2 in blocks32a) say so in their minor
            if let Some(minor) = three {
                assert_eq!(bytes[17] as usize, minor, "{name} is not a 3.{minor} file");
            }
            let level = v["level"].as_u64().unwrap() as usize;
            let d = codec::decode(
                &bytes,
                &DecodeOptions {
                    level,
                    allow_truncated: false,
                    ..Default::default()
                },
            )
            .unwrap()
            .raster;
            let dims: Vec<usize> = v["dims"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_u64().unwrap() as usize)
                .collect();
            assert_eq!(d.dims, dims);
            assert_eq!(d.sample_type().name(), v["sample_type"].as_str().unwrap());
            let raw = mra::io::bytes::encode(&d.samples, false);
            assert_eq!(
                hex(&sha256(&raw)),
                v["sha256"].as_str().unwrap(),
                "{}",
                v["name"]
            );
        }
    }
}

#[test]
fn corpus_lossless_is_bit_exact_on_images_volumes_and_heightmaps() {
    if common::corpus("").is_none() {
        return;
    }
    for f in [
        "images/kodak/kodim01.png",
        "images/highbit/artificial_gray16.png",
        "volumes/ct_pancreas_256.nrrd",
        "terrain/N44W072.hgt",
        "terrain/mt_st_helens_30m_f32.tif",
    ] {
        let Some(path) = common::corpus(f) else {
            continue;
        };
        let r = mra::io::read(&path).unwrap();
        let bytes = codec::encode(&r, &opts(Rate::Lossless)).unwrap();
        let d = codec::decode(&bytes, &DecodeOptions::default())
            .unwrap()
            .raster;
        assert!(d.samples == r.samples, "{f} not bit-exact");
        let raw = r.samples.len() * r.sample_type().size();
        eprintln!(
            "{f}: lossless {} bytes = {:.3} of raw",
            bytes.len(),
            bytes.len() as f64 / raw as f64
        );
    }
}

#[test]
fn corpus_max_error_and_psnr_targets() {
    if common::corpus("").is_none() {
        return;
    }
    if let Some(path) = common::corpus("terrain/N44W072.hgt") {
        let r = mra::io::read(&path).unwrap();
        for e in [1.0, 5.0] {
            let d = round_trip(&r, &opts(Rate::MaxError(e)));
            assert!(max_err(&r, &d) <= e);
        }
    }
    if let Some(path) = common::corpus("images/kodak/kodim23.png") {
        let r = mra::io::read(&path).unwrap();
        for target in [32.0, 40.0] {
            let bytes = codec::encode(&r, &opts(Rate::Psnr(target))).unwrap();
            let d = codec::decode(&bytes, &DecodeOptions::default())
                .unwrap()
                .raster;
            let p = mra::metrics::compare(&r, &d, &Default::default())
                .unwrap()
                .psnr
                .unwrap();
            assert!(p >= target && p <= target + 0.1, "target {target}: {p}");
        }
        let b = 1.0;
        let bytes = codec::encode(&r, &opts(Rate::Bpp(b))).unwrap();
        let got = bytes.len() as f64 * 8.0 / r.positions() as f64;
        assert!(got <= b && got >= b * 0.97, "bpp {got}");
    }
}

#[test]
fn cli_encode_decode_info_and_one_line_errors() {
    let exe = env!("CARGO_BIN_EXE_mra");
    let dir = std::env::temp_dir().join(format!("mra_codec_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("a.pgm");
    mra::io::write(&src, &field(&[37, 45], 1, SampleType::U8, 4)).unwrap();
    let mra_file = dir.join("a.mra");
    let run =
        |args: &[&std::ffi::OsStr]| std::process::Command::new(exe).args(args).output().unwrap();
    let o = run(&[
        "encode".as_ref(),
        src.as_os_str(),
        "-o".as_ref(),
        mra_file.as_os_str(),
        "--max-error".as_ref(),
        "2".as_ref(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.join("b.pgm");
    let o = run(&[
        "decode".as_ref(),
        mra_file.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(o.status.success());
    let a = mra::io::read(&src).unwrap();
    let b = mra::io::read(&out).unwrap();
    assert!(max_err(&a, &b) <= 2.0);
    let small = dir.join("c.pgm");
    let o = run(&[
        "decode".as_ref(),
        mra_file.as_os_str(),
        "-o".as_ref(),
        small.as_os_str(),
        "--level".as_ref(),
        "2".as_ref(),
    ]);
    assert!(o.status.success());
    assert_eq!(mra::io::read(&small).unwrap().dims, vec![10, 12]);
    let o = run(&["info".as_ref(), mra_file.as_os_str(), "--json".as_ref()]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["mode"], "maxerror");
    // damaged and truncated inputs: one line on stderr, exit 2, no output file
    let bytes = std::fs::read(&mra_file).unwrap();
    let bad = dir.join("bad.mra");
    std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
    let never = dir.join("never.pgm");
    // `info` reads any file, so its bad input is a damaged .mra: the signature, then junk
    let junk = dir.join("junk.mra");
    let mut j = vec![0x8B, b'M', b'R', b'A', 0x0D, 0x0A, 0x1A, 0x0A];
    j.extend_from_slice(b"not a header at all");
    std::fs::write(&junk, j).unwrap();
    for args in [
        vec![
            "decode".as_ref(),
            bad.as_os_str(),
            "-o".as_ref(),
            never.as_os_str(),
        ],
        vec![
            "decode".as_ref(),
            src.as_os_str(),
            "-o".as_ref(),
            never.as_os_str(),
        ],
        vec!["info".as_ref(), junk.as_os_str()],
    ] {
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!never.exists());
    }
    let o = run(&[
        "decode".as_ref(),
        bad.as_os_str(),
        "-o".as_ref(),
        never.as_os_str(),
        "--allow-truncated".as_ref(),
    ]);
    assert!(o.status.success());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn sequences_code_along_time_and_decode_a_frame_range() {
    let mut r = field(&[8, 12, 10], 3, SampleType::U8, 6);
    r.kind = DataKind::Sequence;
    let d = round_trip(&r, &opts(Rate::Lossless));
    assert_eq!(d.samples, r.samples);
    assert_eq!(d.kind, DataKind::Sequence);
    let part = codec::frames(d, 2, 5).unwrap();
    assert_eq!(part.dims, vec![3, 12, 10]);
    let per = 12 * 10 * 3;
    assert_eq!(
        mra::io::bytes::encode(&part.samples, false),
        mra::io::bytes::encode(&r.samples, false)[2 * per..5 * per].to_vec()
    );
    assert!(codec::frames(r, 5, 9).is_err());
}
