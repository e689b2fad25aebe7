//! Float samples through the one-transform file (`codec::encode_streamed`) and the one
//! layout rule: `codec::encode` (in memory, Python's entry) writes what `mra encode`
//! writes from a file (`codec::encode_stream` at `codec::default_layout`), streamed or
//! tiled, floats and voids included.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::slab::{MemorySlabs, Shape};
use mra::io::{GeoTag, GeoValue, Raster, SampleType, Samples};

/// A smooth field with texture over `[−hi/2, hi/2]` of `ty` (floats keep the fractions).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.07,
        fy: 0.04,
        noise: 0.05,
    };
    let mut r = common::wave_field(dims, channels, SampleType::F64, seed, hi, wave);
    let v: Vec<f64> = r.samples.to_f64().iter().map(|x| x - hi / 2.0).collect();
    r.samples = Samples::from_f64(&v, ty);
    r
}

use common::{stream_encode as streamed, stream_opts as opts};

/// What `mra encode` writes of `r` read from a file: `encode_stream` at the default
/// layout.
fn cli_path(r: &Raster, o: &EncodeOptions) -> Vec<u8> {
    let tile = codec::default_layout(&Shape::of(r), o);
    let mut out = std::io::Cursor::new(Vec::new());
    codec::encode_stream(&mut MemorySlabs::new(r), o, &tile, &mut out).unwrap();
    out.into_inner()
}

/// At a fixed step (`--threshold`) the streamed file of float samples is the
/// whole-array encoder's byte for byte (the same finite range in the header, the same
/// planes, the same indices), f32 and f64, images, colour and volumes; an infinite
/// sample is coded as the whole-array encoder codes it.
#[test]
fn streamed_float_files_are_the_whole_encoders_bytes() {
    let mut inf = field(&[300, 77], 1, SampleType::F32, 3, 2.0);
    if let Samples::F32(v) = &mut inf.samples {
        v[1000] = f32::INFINITY;
        v[2000] = f32::NEG_INFINITY;
    }
    let cases = [
        (field(&[300, 77], 1, SampleType::F32, 1, 2.0), 5, 0.002),
        (field(&[131, 97], 3, SampleType::F32, 2, 1000.0), 4, 1.5),
        (field(&[40, 33, 29], 1, SampleType::F64, 4, 7.5e4), 3, 30.0),
        (inf, 5, 0.002),
    ];
    for (r, levels, t) in &cases {
        let o = opts(Rate::Threshold(*t), *levels);
        let whole = codec::encode(r, &o).unwrap();
        let s = streamed(r, &o);
        assert!(
            s == whole,
            "{}: {} vs {} bytes",
            r.summary(),
            s.len(),
            whole.len()
        );
    }
}

/// The streamed decode of a float file gives the samples of the whole-array decode,
/// and the file (with its spacing, origin and GeoTIFF tags) does not depend on the
/// thread count; `--bpp` lands within 1% under its budget.
#[test]
fn streamed_float_files_decode_as_whole_and_keep_their_metadata() {
    let dir = common::scratch_dir("streamed_float");
    let mut img = field(&[520, 130], 1, SampleType::F32, 5, 300.0);
    img.meta.spacing = Some(vec![30.0, 30.0]);
    img.meta.origin = Some(vec![500000.0, 4100000.0]);
    img.meta.geotiff = vec![
        GeoTag {
            tag: 33550,
            value: GeoValue::Doubles(vec![30.0, 30.0, 0.0]),
        },
        GeoTag {
            tag: 34735,
            value: GeoValue::Shorts(vec![1, 1, 0, 1, 1024, 0, 1, 1]),
        },
    ];
    img.meta.units = Some("m".into());
    let vol = field(&[48, 40, 36], 1, SampleType::F64, 6, 1.0);
    for (r, rate) in [
        (&img, Rate::Bpp(1.0)),
        (&img, Rate::Quality(60.0)),
        (&vol, Rate::Keep(4.0)),
        (&vol, Rate::Bpp(0.5)),
        (&img, Rate::Psnr(60.0)),
    ] {
        let o = opts(rate, 4);
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| streamed(r, &o))
        };
        let s = on(1);
        assert!(s == on(2), "{} {rate:?}", r.summary());
        if let Rate::Bpp(b) = rate {
            let got = s.len() as f64 * 8.0 / r.positions() as f64;
            assert!(got <= b && got >= 0.99 * b, "{rate:?}: {got} bpp");
        }
        let whole = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
        assert_eq!(whole.sample_type(), r.sample_type());
        assert_eq!(whole.meta, r.meta, "{} {rate:?}", r.summary());
        let path = dir.join("f.mra");
        std::fs::write(&path, &s).unwrap();
        let mut d = codec::StreamedDecoder::open(&path).unwrap();
        let mut got: Vec<f64> = Vec::new();
        while let Some(slab) = d.next_slab().unwrap() {
            got.extend(slab.to_f64());
        }
        assert_eq!(got, whole.samples.to_f64(), "{} {rate:?}", r.summary());
    }
}

/// One rule for every caller, over the real one-piece limit (a 4736² RGB u8 image:
/// 2^24 positions and 2^26 samples exceeded): `codec::encode` writes the bytes of the
/// CLI's path, one transform streamed.
#[test]
fn in_memory_and_cli_encodes_are_one_file_over_the_limit() {
    let n = 4736;
    let r = common::wave_field(
        &[n, n],
        3,
        SampleType::U8,
        7,
        255.0,
        common::Wave {
            fx: 0.02,
            fy: 0.01,
            noise: 0.04,
        },
    );
    let o = opts(Rate::Quality(40.0), 5);
    assert!(codec::streams(&Shape::of(&r), &o));
    let mem = codec::encode(&r, &o).unwrap();
    assert!(mem == cli_path(&r, &o));
    assert!(!codec::header_of(&mem).unwrap().is_tiled());
}

/// Under the limit too `codec::encode` is the CLI's path (one piece, the whole-array
/// encoder), a float raster with NaN voids included (filled, listed, marked again);
/// the stream fills them too, and its file marks them again where they were.
#[test]
fn in_memory_and_cli_encodes_agree_with_voids() {
    let mut f = field(&[300, 210], 1, SampleType::F32, 8, 100.0);
    let holes = [5usize, 300 * 100 + 17, 300 * 210 - 3];
    if let Samples::F32(v) = &mut f.samples {
        for &i in &holes {
            v[i] = f32::NAN;
        }
    }
    for rate in [Rate::Quality(40.0), Rate::Bpp(1.0)] {
        let o = opts(rate, 4);
        let mem = codec::encode(&f, &o).unwrap();
        assert!(mem == cli_path(&f, &o), "{rate:?}");
        let d = codec::decode(&mem, &DecodeOptions::default())
            .unwrap()
            .raster;
        let v = d.samples.to_f64();
        assert!(holes.iter().all(|&i| v[i].is_nan()));
        assert_eq!(v.iter().filter(|x| x.is_nan()).count(), holes.len());
        let d = codec::decode(&streamed(&f, &o), &DecodeOptions::default())
            .unwrap()
            .raster;
        let v = d.samples.to_f64();
        assert!(holes.iter().all(|&i| v[i].is_nan()));
        assert_eq!(v.iter().filter(|x| x.is_nan()).count(), holes.len());
    }
}

/// `--psnr` of a one-transform file lands within 0.1 dB over its target (the step from
/// the sampled tiles, then passes over the stream each decoded and compared), for
/// integer and float images, colour and volumes, with the PSNR of `mra compare`.
#[test]
fn streamed_psnr_lands_just_over_its_target() {
    let cases = [
        (field(&[700, 300], 1, SampleType::U16, 21, 60000.0), 50.0),
        (field(&[260, 190], 3, SampleType::U8, 22, 255.0), 38.0),
        (field(&[400, 300], 1, SampleType::F32, 23, 2.0), 45.0),
        (field(&[60, 48, 40], 1, SampleType::F32, 24, 900.0), 55.0),
    ];
    for (r, db) in &cases {
        let s = streamed(r, &opts(Rate::Psnr(*db), 5));
        let d = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
        let got = mra::metrics::psnr(r, &d, &Default::default())
            .unwrap()
            .unwrap();
        eprintln!("{} --psnr {db}: {got:.3} dB, {} B", r.summary(), s.len());
        assert!(
            got >= *db && got < db + 0.1,
            "{} at --psnr {db}: {got} dB",
            r.summary()
        );
    }
}
