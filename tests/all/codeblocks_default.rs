//! Format 3.0 as what the encoder writes by default: every rate mode, sample type,
//! 1-D to 4-D raster and colour comes back as the mode promises from a 3.0 file coded
//! directly in code-blocks; `Format::Bands` (`mra encode --format 2`) writes 2.x; the
//! bytes do not depend on the thread count; a raster read in slabs writes the bytes of
//! the raster in memory; tiled files stay 2.x.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Format, Rate};
use mra::io::slab::MemorySlabs;
use mra::io::{Raster, SampleType};
use std::process::Command;

/// A smooth field with texture (xorshift) over `[0, hi]`, `channels` channels of `ty`.
/// The codec tests' wave ([`common::wave_field`]).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.11,
        fy: 0.05,
        noise: 0.06,
    };
    common::wave_field(dims, channels, ty, seed, hi, wave)
}

fn opts(rate: Rate, format: Format) -> EncodeOptions {
    EncodeOptions {
        rate,
        levels: 4,
        format,
        ..Default::default()
    }
}

fn version(bytes: &[u8]) -> String {
    codec::info(bytes).unwrap().version
}

fn decoded(bytes: &[u8]) -> Raster {
    codec::decode(bytes, &DecodeOptions::default())
        .unwrap()
        .raster
}

fn psnr(a: &Raster, b: &Raster) -> f64 {
    let (x, y) = (a.samples.to_f64(), b.samples.to_f64());
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    let mse = x.iter().zip(&y).map(|(p, q)| (p - q).powi(2)).sum::<f64>() / x.len() as f64;
    10.0 * ((hi - lo).max(1e-30).powi(2) / mse.max(1e-300)).log10()
}

/// The rasters of the tests: 1-D to 4-D, gray and colour, 8/16-bit, signed and float,
/// bands both smaller and larger than a code-block.
fn rasters() -> Vec<Raster> {
    vec![
        field(&[70_001], 1, SampleType::U16, 1, 60000.0),
        field(&[300, 277], 3, SampleType::U8, 2, 255.0),
        field(&[141, 95], 1, SampleType::F32, 3, 1.0),
        field(&[37, 70, 66], 1, SampleType::I16, 4, 3000.0),
        field(&[3, 9, 20, 17], 1, SampleType::U16, 5, 4000.0),
    ]
}

/// Every rate mode writes 3.0 by default, and the file keeps the mode's promise: exact
/// for `--lossless` (and `--max-error 0`), within the bound for `--max-error`, within
/// the budget for `--bpp`, at the target for `--psnr`; `--keep` and `--threshold` (no
/// index optimisation) decode to the samples of the format 2 file, `--quality` to
/// nearly its PSNR. With `Format::Bands` the same modes write 2.x.
#[test]
fn every_mode_writes_3_0_by_default_and_round_trips() {
    for r in rasters() {
        let ty = r.sample_type();
        let range = if ty.is_float() { 1.0 } else { 255.0 };
        let modes = [
            Rate::Lossless,
            Rate::MaxError(0.0),
            Rate::MaxError(range * 0.02),
            Rate::Bpp(1.0),
            Rate::Psnr(40.0),
            Rate::Quality(60.0),
            Rate::Keep(10.0),
            Rate::Threshold(range * 0.02),
        ];
        for rate in modes {
            let what = format!("{} {rate:?}", r.summary());
            let three = codec::encode(&r, &opts(rate, Format::Blocks)).unwrap();
            let two = codec::encode(&r, &opts(rate, Format::Bands)).unwrap();
            assert_eq!(version(&three), "3.2", "{what}");
            assert!(version(&two).starts_with("2."), "{what}");
            let d3 = decoded(&three);
            let d2 = decoded(&two);
            assert_eq!(d3.dims, r.dims, "{what}");
            assert_eq!(d3.sample_type(), ty, "{what}");
            let (a, b) = (r.samples.to_f64(), d3.samples.to_f64());
            let err = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            match rate {
                _ if rate == Rate::Lossless || rate == Rate::MaxError(0.0) => {
                    assert!(d3.samples == r.samples, "{what}: not exact")
                }
                Rate::MaxError(e) => assert!(err <= e * (1.0 + 1e-9) + 1e-12, "{what}: {err}"),
                Rate::Bpp(b) => {
                    let bpp = three.len() as f64 * 8.0 / r.positions() as f64;
                    assert!(bpp <= b, "{what}: {bpp} bpp");
                }
                Rate::Psnr(db) => {
                    let p = codec::decode(&three, &DecodeOptions::default()).unwrap();
                    let got = mra::metrics::psnr(&r, &p.raster, &Default::default())
                        .unwrap()
                        .unwrap_or(f64::INFINITY);
                    assert!(got >= db - 1e-9, "{what}: {got} dB");
                }
                Rate::Keep(_) | Rate::Threshold(_) => {
                    assert!(d3.samples == d2.samples, "{what}: not the 2.x samples")
                }
                _ => {
                    let (p3, p2) = (psnr(&r, &d3), psnr(&r, &d2));
                    assert!(p3 > p2 - 0.5, "{what}: {p3} dB against {p2}");
                }
            }
        }
    }
}

/// The bytes of a 3.0 file are the same on one thread and on three, in every mode.
#[test]
fn default_files_do_not_depend_on_the_thread_count() {
    let r = field(&[530, 300], 3, SampleType::U8, 11, 255.0);
    let v = field(&[40, 90, 70], 1, SampleType::U16, 12, 4000.0);
    for (r, rate) in [
        (&r, Rate::Bpp(1.0)),
        (&r, Rate::Quality(50.0)),
        (&r, Rate::Lossless),
        (&v, Rate::MaxError(3.0)),
        (&v, Rate::Psnr(45.0)),
        (&v, Rate::Keep(5.0)),
    ] {
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| codec::encode(r, &opts(rate, Format::Blocks)).unwrap())
        };
        let one = on(1);
        assert_eq!(version(&one), "3.2");
        assert!(one == on(3), "{} {rate:?}", r.summary());
    }
}

/// A raster handed out in slabs (what `mra encode` streams from a raw volume) writes
/// the bytes of the raster in memory, 3.0 by default and 2.x with `Format::Bands`.
#[test]
fn slabs_write_the_default_file_of_the_raster() {
    let v = field(&[50, 61, 47], 1, SampleType::U16, 21, 5000.0);
    for rate in [
        Rate::Lossless,
        Rate::MaxError(4.0),
        Rate::Bpp(0.7),
        Rate::Quality(55.0),
    ] {
        for format in [Format::Blocks, Format::Bands] {
            let o = opts(rate, format);
            let whole = codec::encode(&v, &o).unwrap();
            let mut out = std::io::Cursor::new(Vec::new());
            codec::encode_stream(&mut MemorySlabs::new(&v), &o, &v.dims, &mut out).unwrap();
            assert!(out.into_inner() == whole, "{rate:?} {format:?}");
            assert_eq!(version(&whole).starts_with('3'), format == Format::Blocks);
        }
    }
}

/// A tiled file stays 2.x whatever the format asked for (its tiles are format 2
/// one-tile files).
#[test]
fn tiled_files_stay_format_2() {
    let r = field(&[200, 170], 1, SampleType::U8, 31, 255.0);
    for rate in [Rate::Bpp(1.0), Rate::Lossless] {
        let t = codec::encode_tiled(&r, &opts(rate, Format::Blocks), &[64, 64]).unwrap();
        assert!(version(&t).starts_with("2."), "{rate:?}");
        let d = decoded(&t);
        assert_eq!(d.dims, r.dims);
    }
}

/// `mra encode` writes 3.0 by default and 2.x with `--format 2`; `--format 4` is a
/// one-line error, exit 2, no output.
#[test]
fn the_cli_writes_3_0_by_default_and_2_x_with_format_2() {
    let dir = std::env::temp_dir().join(format!("mra-default3-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("in.pgm");
    mra::io::write(&input, &field(&[70, 90], 1, SampleType::U8, 3, 255.0)).unwrap();
    let run = |extra: &[&str], out: &std::path::Path| {
        let mut args = vec![
            "encode",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        Command::new(env!("CARGO_BIN_EXE_mra"))
            .args(&args)
            .output()
            .unwrap()
    };
    for (extra, want) in [
        (&[][..], "3.2"),
        (&["--blocks"][..], "3.2"),
        (&["--format", "3", "--lossless"][..], "3.2"),
        (&["--format", "2"][..], "2.0"),
        (&["--format", "2", "--lossless"][..], "2.3"),
    ] {
        let out = dir.join("o.mra");
        let o = run(extra, &out);
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(version(&std::fs::read(&out).unwrap()), want, "{extra:?}");
    }
    let bad = dir.join("bad.mra");
    let o = run(&["--format", "4"], &bad);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!bad.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
