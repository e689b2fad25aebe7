//! `--lossless` as one transform streamed a slab at a time (`codec::encode_streamed`,
//! what `mra encode --lossless` writes above the one-piece limit): the bytes of the
//! whole-array lossless encode, whatever the thread count and block coder; decoded
//! slab by slab (`StreamedDecoder`) to the very samples; a truncated file is a
//! one-line error.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Format, Rate};
use mra::io::slab::MemorySlabs;
use mra::io::{Raster, SampleType};
use mra::scheme::{Boundary, Scheme};

/// A smooth field with texture over `[0, hi]` (the codec tests' wave).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.09,
        fy: 0.04,
        noise: 0.08,
    };
    common::wave_field(dims, channels, ty, seed, hi, wave)
}

fn opts(rate: Rate, levels: usize, effort: u8) -> EncodeOptions {
    EncodeOptions {
        rate,
        levels,
        // a lossless file is the 5/3 lifting whatever the scheme asked
        boundary: Boundary::Periodic,
        scheme: Scheme::Cdf97,
        format: Format::Blocks,
        effort,
    }
}

fn streamed(r: &Raster, o: &EncodeOptions) -> Vec<u8> {
    let mut out = Vec::new();
    let n = codec::encode_streamed(&mut MemorySlabs::new(r), o, &mut out).unwrap();
    assert_eq!(n as usize, out.len());
    out
}

/// Rasters of every shape the stream takes: 1 and 3 channels, 8 and 16 bits, signed,
/// odd sizes, bands of several stripes of code-blocks, lanes of 2, volumes.
fn cases() -> Vec<(Raster, usize)> {
    vec![
        (field(&[131, 97], 3, SampleType::U8, 1, 255.0), 4),
        (field(&[1100, 75], 1, SampleType::U16, 2, 60000.0), 5),
        (field(&[517, 301], 3, SampleType::U16, 3, 65535.0), 6),
        (field(&[2, 9], 1, SampleType::I8, 4, 100.0), 3),
        (field(&[301, 67], 2, SampleType::I16, 5, 30000.0), 7),
        (field(&[70, 41, 33], 1, SampleType::U16, 6, 4000.0), 3),
        (field(&[45, 20, 17], 3, SampleType::U8, 7, 255.0), 4),
        (field(&[5, 64, 3], 1, SampleType::U16, 8, 9000.0), 5),
    ]
}

/// The streamed lossless file is the whole-array encoder's file byte for byte (the same
/// header, integer transform, indices and code-block streams) for every case, at the
/// efforts of each block coder, and an exact `--max-error` writes it too.
#[test]
fn streamed_lossless_files_are_the_whole_encoders_bytes() {
    for (r, levels) in cases() {
        for effort in [1u8, 4, 7] {
            let o = opts(Rate::Lossless, levels, effort);
            let whole = codec::encode(&r, &o).unwrap();
            let s = streamed(&r, &o);
            assert!(
                s == whole,
                "{} effort {effort}: {} vs {} bytes",
                r.summary(),
                s.len(),
                whole.len()
            );
        }
        let exact = opts(Rate::MaxError(0.5), levels, codec::DEFAULT_EFFORT);
        assert!(streamed(&r, &exact) == codec::encode(&r, &exact).unwrap());
    }
}

/// The streamed lossless file does not depend on the thread count.
#[test]
fn streamed_lossless_files_do_not_depend_on_the_thread_count() {
    for (r, levels) in cases().into_iter().step_by(2) {
        let o = opts(Rate::Lossless, levels, codec::DEFAULT_EFFORT);
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| streamed(&r, &o))
        };
        assert!(on(1) == on(2), "{}", r.summary());
    }
}

/// A lossless file decoded slab by slab through the integer synthesis
/// (`StreamedDecoder`, what `mra decode` does over the one-piece limit) gives the
/// samples back exactly, on 1 and 2 threads, and the whole decode agrees.
#[test]
fn the_streamed_lossless_decode_gives_the_samples_back() {
    let dir = common::scratch_dir("streamed_lossless_decode");
    for (r, levels) in cases() {
        for effort in [1u8, 7] {
            let file = streamed(&r, &opts(Rate::Lossless, levels, effort));
            let path = dir.join("s.mra");
            std::fs::write(&path, &file).unwrap();
            let whole = codec::decode(&file, &DecodeOptions::default()).unwrap();
            assert!(whole.raster.samples == r.samples, "{}", r.summary());
            for threads in [1, 2] {
                let got = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| {
                        let mut d = codec::StreamedDecoder::open(&path).unwrap();
                        assert_eq!(d.shape().dims, r.dims);
                        let mut got: Vec<f64> = Vec::new();
                        while let Some(slab) = d.next_slab().unwrap() {
                            assert_eq!(slab.sample_type(), r.sample_type());
                            got.extend(slab.to_f64());
                        }
                        got
                    });
                assert!(
                    got == r.samples.to_f64(),
                    "{} effort {effort} on {threads} threads",
                    r.summary()
                );
            }
        }
    }
}

/// A truncated streamed lossless file is an error: the library's (no panic), and the
/// CLI's (one line naming the file, exit code 2, no output).
#[test]
fn a_truncated_streamed_lossless_file_is_a_one_line_error() {
    let r = field(&[300, 80], 3, SampleType::U16, 10, 9000.0);
    let s = streamed(&r, &opts(Rate::Lossless, 4, codec::DEFAULT_EFFORT));
    let cut = &s[..s.len() * 2 / 3];
    assert!(codec::decode(cut, &DecodeOptions::default()).is_err());
    let dir = common::scratch_dir("streamed_lossless_truncated");
    std::fs::write(dir.join("cut.mra"), cut).unwrap();
    assert!(codec::StreamedDecoder::open(&dir.join("cut.mra")).is_err());
    let o = common::mra_with_stdin(Some(&dir), &["decode", "cut.mra", "-o", "out.nrrd"], &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("cut.mra"), "{err}");
    assert!(!dir.join("out.nrrd").exists());
}
