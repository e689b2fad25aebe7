//! Voids (NaN samples, samples equal to `meta.nodata`) through the one-transform file:
//! filled block by block as the raster streams, their mask coded as the whole-array
//! encoder codes it, and marked again by the streamed decode.

use super::common;
use mra::codec::{self, DecodeOptions, Rate};
use mra::io::slab::{MemorySlabs, Shape};
use mra::io::{GeoTag, GeoValue, Raster, SampleType, Samples};

/// A smooth field with texture over `[−hi/2, hi/2]` of `ty`.
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.03,
        fy: 0.02,
        noise: 0.05,
    };
    let mut r = common::wave_field(dims, channels, SampleType::F64, seed, hi, wave);
    let v: Vec<f64> = r.samples.to_f64().iter().map(|x| x - hi / 2.0).collect();
    r.samples = Samples::from_f64(&v, ty);
    r
}

/// Positions (row-major over `dims`) of a few discs, a run along a row, scattered
/// samples and the box `whole` (rows × columns of a 2-D raster's first axes).
fn holes(dims: &[usize], whole: Option<[std::ops::Range<usize>; 2]>) -> Vec<usize> {
    let w = *dims.last().unwrap();
    let n: usize = dims.iter().product();
    let rows = n / w;
    let mut out = Vec::new();
    for p in 0..n {
        let (y, x) = ((p / w) as i64, (p % w) as i64);
        let disc = |cy: i64, cx: i64, r: i64| (y - cy).pow(2) + (x - cx).pow(2) <= r * r;
        let r = rows as i64;
        let inside = disc(r / 3, w as i64 / 2, 9)
            || disc(r / 2, 3, 5)
            || disc(r - 4, w as i64 - 2, 6)
            || (y == r / 5 && x > 4 && x < w as i64 / 2)
            || p % 9973 == 17
            || whole
                .as_ref()
                .is_some_and(|[a, b]| a.contains(&(y as usize)) && b.contains(&(x as usize)));
        if inside {
            out.push(p);
        }
    }
    out
}

/// `r` with the samples at `at` (positions, every channel) set to `v`.
fn with_voids(mut r: Raster, at: &[usize], v: f64) -> Raster {
    let c = r.channels;
    let mut s = r.samples.to_f64();
    for &p in at {
        for k in 0..c {
            s[p * c + k] = v;
        }
    }
    r.samples = Samples::from_f64(&s, r.sample_type());
    r
}

use common::{stream_encode as streamed, stream_opts as opts};

use common::on_threads as on;

/// The samples of the streamed decode of `file` (`codec::StreamedDecoder`, slab by slab).
fn stream_decode(file: &[u8], tag: &str) -> (Shape, Vec<f64>) {
    let path = common::scratch_dir("streamed_voids").join(format!("{tag}.mra"));
    std::fs::write(&path, file).unwrap();
    let mut d = codec::StreamedDecoder::open(&path).unwrap();
    let mut got = Vec::new();
    while let Some(slab) = d.next_slab().unwrap() {
        got.extend(slab.to_f64());
    }
    std::fs::remove_file(&path).unwrap();
    (d.shape().clone(), got)
}

/// Is `x` the void marker `nodata` (NaN without one)?
fn is_marker(x: f64, nodata: Option<f64>) -> bool {
    match nodata {
        Some(n) => x == n,
        None => x.is_nan(),
    }
}

/// Under the one-piece limit a block is the whole raster, so the stream fills its
/// voids by the whole-array encoder's pull-push: at a fixed step (`--threshold`) the
/// streamed file is the whole-array encoder's byte for byte (the mask coded as it codes
/// it, the same range, the same planes), for NaN voids among infinite samples, a
/// nodata value of 16-bit samples, colour and volumes; and the lossless stream of
/// 16-bit samples with a nodata value gives them back exactly.
#[test]
fn streamed_voids_under_the_limit_are_the_whole_encoders_bytes() {
    let dims = [260, 97];
    let mut nan = with_voids(
        field(&dims, 1, SampleType::F32, 1, 2.0),
        &holes(&dims, None),
        f64::NAN,
    );
    if let Samples::F32(v) = &mut nan.samples {
        v[4000] = f32::INFINITY;
        v[9000] = f32::NEG_INFINITY;
    }
    let mut srtm = with_voids(
        field(&dims, 1, SampleType::I16, 2, 3000.0),
        &holes(&dims, None),
        -32768.0,
    );
    srtm.meta.nodata = Some(-32768.0);
    let mut rgb = with_voids(
        field(&[131, 90], 3, SampleType::U8, 3, 200.0),
        &holes(&[131, 90], None),
        255.0,
    );
    rgb.meta.nodata = Some(255.0);
    let vdims = [30, 41, 37];
    let vol = with_voids(
        field(&vdims, 1, SampleType::F64, 4, 900.0),
        &holes(&vdims, None),
        f64::NAN,
    );
    for (r, t) in [(&nan, 0.002), (&srtm, 3.0), (&rgb, 1.0), (&vol, 1.0)] {
        let o = opts(Rate::Threshold(t), 4);
        let whole = codec::encode(r, &o).unwrap();
        assert!(codec::header_of(&whole).unwrap().voids, "{}", r.summary());
        let s = streamed(r, &o);
        assert!(
            s == whole,
            "{}: {} vs {} bytes",
            r.summary(),
            s.len(),
            whole.len()
        );
    }
    let o = opts(Rate::Lossless, 4);
    let s = streamed(&srtm, &o);
    assert!(s == codec::encode(&srtm, &o).unwrap());
    let d = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
    assert!(d.samples == srtm.samples);
    assert_eq!(d.meta, srtm.meta);
    let (shape, got) = stream_decode(&s, "lossless");
    assert_eq!(got, srtm.samples.to_f64());
    assert_eq!(shape.meta, srtm.meta);
}

/// Any raster: the streamed decode marks the voids where they were (the nodata value,
/// else NaN) and nowhere else, gives the whole decode's samples, and keeps the
/// metadata; `--psnr` lands over its target on the valid samples (`mra compare` leaves
/// voids out).
#[test]
fn streamed_voids_come_back_where_they_were() {
    let dims = [700, 300];
    let at = holes(&dims, Some([100..300, 0..120]));
    let mut dem = with_voids(field(&dims, 1, SampleType::I16, 5, 4000.0), &at, -9999.0);
    dem.meta.nodata = Some(-9999.0);
    dem.meta.spacing = Some(vec![30.0, 30.0]);
    dem.meta.origin = Some(vec![500000.0, 4100000.0]);
    dem.meta.units = Some("m".into());
    dem.meta.geotiff = vec![GeoTag {
        tag: 33550,
        value: GeoValue::Doubles(vec![30.0, 30.0, 0.0]),
    }];
    let nan = with_voids(field(&dims, 2, SampleType::F32, 6, 10.0), &at, f64::NAN);
    for r in [&dem, &nan] {
        for rate in [Rate::Quality(50.0), Rate::Bpp(1.0), Rate::Psnr(45.0)] {
            let s = streamed(r, &opts(rate, 5));
            let whole = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
            assert_eq!(whole.meta, r.meta, "{} {rate:?}", r.summary());
            let (shape, got) = stream_decode(&s, "any");
            assert_eq!(shape.meta, r.meta);
            let want = whole.samples.to_f64();
            assert!(
                got.iter()
                    .zip(&want)
                    .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())),
                "{} {rate:?}",
                r.summary()
            );
            let src = r.samples.to_f64();
            let nodata = r.meta.nodata;
            for (i, (&a, &g)) in src.iter().zip(&got).enumerate() {
                let void = mra::io::nodata::is_void(a, nodata);
                assert_eq!(
                    is_marker(g, nodata),
                    void,
                    "{} {rate:?} sample {i}",
                    r.summary()
                );
            }
            let db = mra::metrics::psnr(r, &whole, &Default::default())
                .unwrap()
                .unwrap();
            match rate {
                Rate::Psnr(t) => assert!(db >= t, "{rate:?}: {db} dB"),
                _ => assert!(db > 30.0, "{rate:?}: {db} dB"),
            }
        }
    }
}

/// Over the one-piece limit (16400 × 1025 positions of 4 channels: 2^24 positions and
/// 2^26 samples exceeded) a raster with voids is one transform by default, from
/// `codec::encode` (Python's entry) as from `mra encode`'s path: a nodata value of
/// 16-bit samples and NaN among floats, a window of the fill void throughout included;
/// the file does not depend on the thread count, the streamed decode marks the voids
/// exactly where they were and gives the whole decode's samples, and the valid samples
/// are within the rate's expectation.
#[test]
fn voids_over_the_limit_are_one_transform() {
    let dims = [16400, 1025];
    let at = holes(&dims, Some([2048..3072, 0..1024]));
    let mut dem = with_voids(field(&dims, 4, SampleType::I16, 7, 6000.0), &at, -32768.0);
    dem.meta.nodata = Some(-32768.0);
    dem.meta.spacing = Some(vec![1.0 / 3600.0, 1.0 / 3600.0]);
    dem.meta.origin = Some(vec![7.0, 46.0]);
    let mut nan = with_voids(field(&dims, 4, SampleType::F32, 8, 50.0), &at, f64::NAN);
    if let Samples::F32(v) = &mut nan.samples {
        v[5] = f32::INFINITY;
    }
    for (r, threads) in [(&dem, true), (&nan, false)] {
        let shape = Shape::of(r);
        let o = opts(Rate::Quality(50.0), 5);
        assert!(codec::streams(&shape, &o));
        assert_eq!(codec::default_layout(&shape, &o), shape.dims);
        let one = on(1, || codec::encode(r, &o).unwrap());
        if threads {
            let two = on(2, || {
                let mut out = std::io::Cursor::new(Vec::new());
                let tile = codec::default_layout(&shape, &o);
                codec::encode_stream(&mut MemorySlabs::new(r), &o, &tile, &mut out).unwrap();
                out.into_inner()
            });
            assert!(one == two, "{}", r.summary());
        }
        let h = codec::header_of(&one).unwrap();
        assert!(!h.is_tiled() && h.voids);
        assert!(codec::decodes_streamed(&h));
        let whole = codec::decode(&one, &DecodeOptions::default())
            .unwrap()
            .raster;
        assert_eq!(whole.meta, r.meta);
        let path = common::scratch_dir("streamed_voids").join("big.mra");
        std::fs::write(&path, &one).unwrap();
        let mut d = codec::StreamedDecoder::open(&path).unwrap();
        assert_eq!(d.shape().meta, r.meta);
        let nodata = r.meta.nodata;
        let (mut sse, mut n, mut at) = (0.0, 0usize, 0usize);
        while let Some(slab) = d.next_slab().unwrap() {
            for k in 0..slab.len() {
                let (a, g, w) = (
                    r.samples.get_f64(at + k),
                    slab.get_f64(k),
                    whole.samples.get_f64(at + k),
                );
                let void = mra::io::nodata::is_void(a, nodata);
                assert_eq!(
                    is_marker(g, nodata),
                    void,
                    "{} sample {}",
                    r.summary(),
                    at + k
                );
                assert!(g == w || (g.is_nan() && w.is_nan()), "sample {}", at + k);
                if !void && a.is_finite() {
                    sse += (a - g) * (a - g);
                    n += 1;
                }
            }
            at += slab.len();
        }
        assert_eq!(at, r.samples.len());
        std::fs::remove_file(&path).unwrap();
        // the quality's step: an error of a small fraction of the span
        let span = match r.sample_type() {
            SampleType::I16 => 6000.0,
            _ => 50.0,
        };
        let rmse = (sse / n as f64).sqrt();
        eprintln!("{}: {} B, rmse {rmse}", r.summary(), one.len());
        assert!(rmse < span * 0.01, "{}: rmse {rmse}", r.summary());
    }
}

/// `--max-error` of a raster with voids through the stream: the voids come back where
/// they were (the nodata value of 16-bit samples, NaN among floats), every valid sample
/// within the bound, and the streamed decode (the residual added, then the voids marked)
/// gives the whole decode's samples.
#[test]
fn streamed_max_error_keeps_voids_and_the_bound() {
    let dims = [300, 260];
    let at = holes(&dims, Some([40..90, 0..70]));
    let mut dem = with_voids(field(&dims, 1, SampleType::I16, 7, 4000.0), &at, -9999.0);
    dem.meta.nodata = Some(-9999.0);
    let nan = with_voids(field(&dims, 2, SampleType::F32, 8, 10.0), &at, f64::NAN);
    for (r, e) in [(&dem, 2.0), (&nan, 0.01)] {
        let s = streamed(r, &opts(Rate::MaxError(e), 4));
        let whole = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
        assert_eq!(whole.meta, r.meta, "{}", r.summary());
        let (shape, got) = stream_decode(&s, "max_error");
        assert_eq!(shape.meta, r.meta);
        let want = whole.samples.to_f64();
        assert!(
            got.iter()
                .zip(&want)
                .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())),
            "{}",
            r.summary()
        );
        let nodata = r.meta.nodata;
        for (i, (&a, &g)) in r.samples.to_f64().iter().zip(&got).enumerate() {
            let void = mra::io::nodata::is_void(a, nodata);
            assert_eq!(is_marker(g, nodata), void, "{} sample {i}", r.summary());
            if !void {
                assert!((a - g).abs() <= e, "{} sample {i}: {a} vs {g}", r.summary());
            }
        }
    }
}
