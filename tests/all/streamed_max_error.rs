//! `--max-error E` as one transform (`codec::encode_streamed`, the default layout over
//! the one-piece limit): a streamed lossy base and its residual layer (`RESI`), every
//! decoded sample within E of the source through the whole-array decode and through the
//! streamed decode (`StreamedDecoder`, which adds the residual slab by slab), the same
//! bytes on 1 and 2 threads, the metadata kept.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::slab::Shape;
use mra::io::{Raster, SampleType, Samples};

/// A smooth field with texture over `[0, hi]` (floats keep the fractions).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.09,
        fy: 0.05,
        noise: 0.08,
    };
    let mut r = common::wave_field(dims, channels, SampleType::F64, seed, hi, wave);
    r.samples = Samples::from_f64(&r.samples.to_f64(), ty);
    r
}

fn opts(e: f64, levels: usize) -> EncodeOptions {
    common::stream_opts(Rate::MaxError(e), levels)
}

use common::stream_encode as streamed;

/// The streamed decode of the file at `path`: its shape and samples.
fn streamed_decode(path: &std::path::Path) -> (Shape, Vec<f64>) {
    let mut d = codec::StreamedDecoder::open(path).unwrap();
    let mut got = Vec::new();
    while let Some(slab) = d.next_slab().unwrap() {
        got.extend(slab.to_f64());
    }
    (d.shape().clone(), got)
}

/// Every sample of `got` within `e` of `r`'s (NaN for NaN, an infinity for itself).
fn assert_within(r: &Raster, got: &[f64], e: f64, what: &str) {
    let want = r.samples.to_f64();
    assert_eq!(got.len(), want.len(), "{what}");
    for (i, (&a, &b)) in want.iter().zip(got).enumerate() {
        let ok = (a - b).abs() <= e || a == b || (a.is_nan() && b.is_nan());
        assert!(ok, "{what}: sample {i}: {a} → {b} (E = {e})");
    }
}

/// Integers (E ≥ 1) and floats (any E > 0), images (gray, RGB) and volumes, odd
/// extents, bands of several stripes of code-blocks: the streamed file decodes within
/// E of the source through the whole-array decode and the streamed decode alike, and
/// is a mode 2 file (the residual layer present) no longer than the source's samples.
#[test]
fn every_sample_is_within_the_bound() {
    let cases: Vec<(Raster, f64, usize)> = vec![
        (field(&[611, 267], 1, SampleType::U16, 1, 60000.0), 5.0, 5),
        (field(&[611, 267], 1, SampleType::U16, 1, 60000.0), 1.0, 5),
        (field(&[203, 131], 3, SampleType::U8, 2, 255.0), 2.0, 4),
        (field(&[37, 41, 29], 1, SampleType::I16, 3, 4000.0), 3.0, 3),
        (field(&[70, 33, 45], 2, SampleType::U16, 4, 9000.0), 1.5, 3),
        (field(&[301, 97], 1, SampleType::F32, 5, 2.0), 0.01, 4),
        (field(&[45, 31, 23], 1, SampleType::F32, 6, 500.0), 0.5, 3),
        (field(&[129, 75], 3, SampleType::F64, 7, 1.0), 0.002, 4),
    ];
    let dir = common::scratch_dir("streamed_max_error");
    for (r, e, levels) in &cases {
        let what = format!("{} E = {e}", r.summary());
        let file = streamed(r, &opts(*e, *levels));
        let info = codec::header_of(&file).unwrap();
        assert_eq!(info.mode, mra::format::Mode::MaxError, "{what}");
        assert_eq!(info.max_error, *e, "{what}");
        let whole = codec::decode(&file, &DecodeOptions::default())
            .unwrap()
            .raster;
        assert_within(r, &whole.samples.to_f64(), *e, &what);
        let path = dir.join("m.mra");
        std::fs::write(&path, &file).unwrap();
        let (shape, got) = streamed_decode(&path);
        assert_eq!(shape.dims, r.dims, "{what}");
        assert_eq!(
            got,
            whole.samples.to_f64(),
            "{what}: streamed against whole decode"
        );
        let bytes = r.samples.to_f64().len() * r.sample_type().size();
        assert!(
            file.len() < bytes,
            "{what}: {} bytes of {bytes}",
            file.len()
        );
    }
}

/// Samples the residual cannot bring within the bound by itself (f32 values near 10⁷,
/// whose spacing is 1, at E = 0.3; infinities) are exceptions, written by both decodes.
#[test]
fn exceptions_are_written_by_the_streamed_decode() {
    let mut r = field(&[260, 70], 1, SampleType::F64, 8, 50.0);
    let v: Vec<f64> = r
        .samples
        .to_f64()
        .iter()
        .map(|x| 1.0e7 + x.round())
        .collect();
    let mut v32: Vec<f32> = v.iter().map(|&x| x as f32).collect();
    v32[77] = f32::INFINITY;
    v32[9000] = f32::NEG_INFINITY;
    r.samples = Samples::F32(v32);
    let e = 0.3;
    let file = streamed(&r, &opts(e, 4));
    let whole = codec::decode(&file, &DecodeOptions::default())
        .unwrap()
        .raster;
    assert_within(&r, &whole.samples.to_f64(), e, "whole");
    let dir = common::scratch_dir("streamed_max_error_exc");
    let path = dir.join("x.mra");
    std::fs::write(&path, &file).unwrap();
    let (_, got) = streamed_decode(&path);
    assert_eq!(got, whole.samples.to_f64());
    assert_eq!(got[77], f64::INFINITY);
    assert_eq!(got[9000], f64::NEG_INFINITY);
}

/// The file does not depend on the thread count.
#[test]
fn streamed_max_error_files_do_not_depend_on_the_thread_count() {
    let img = field(&[333, 150], 3, SampleType::U8, 9, 255.0);
    let vol = field(&[40, 36, 33], 1, SampleType::F32, 10, 100.0);
    for (r, e) in [(&img, 3.0), (&vol, 0.05)] {
        let o = opts(e, 4);
        let on = |threads: usize| common::on_threads(threads, || streamed(r, &o));
        assert!(on(1) == on(2), "{} E = {e}", r.summary());
    }
}

/// Spacing, origin and units go through the file to both decodes.
#[test]
fn streamed_max_error_keeps_the_metadata() {
    let mut r = field(&[150, 90], 1, SampleType::I16, 11, 3000.0);
    r.meta.spacing = Some(vec![0.5, 0.25]);
    r.meta.origin = Some(vec![-10.0, 20.0]);
    r.meta.units = Some("mm".into());
    let file = streamed(&r, &opts(2.0, 4));
    let whole = codec::decode(&file, &DecodeOptions::default())
        .unwrap()
        .raster;
    let dir = common::scratch_dir("streamed_max_error_meta");
    let path = dir.join("m.mra");
    std::fs::write(&path, &file).unwrap();
    let (shape, got) = streamed_decode(&path);
    for meta in [&whole.meta, &shape.meta] {
        assert_eq!(meta.spacing, r.meta.spacing);
        assert_eq!(meta.origin, r.meta.origin);
        assert_eq!(meta.units, r.meta.units);
    }
    assert_within(&r, &got, 2.0, "streamed");
}

/// Over the one-piece limit `--max-error` above the lossless range streams by default
/// (images and volumes, integers and floats), and a file of it decodes through the
/// stream, with a nodata value too; small rasters and 4 axes do not.
#[test]
fn max_error_is_one_transform_over_the_limit() {
    let small = Shape::of(&field(&[4, 4], 1, SampleType::U16, 1, 100.0));
    let mut big = small.clone();
    big.dims = vec![16384, 8192];
    let mut vol = small.clone();
    vol.dims = vec![1024, 1024, 1024];
    let mut float = big.clone();
    float.sample_type = SampleType::F32;
    for (s, e) in [
        (&big, 1.0),
        (&big, 5.0),
        (&vol, 2.0),
        (&float, 0.5),
        (&float, 1e-3),
    ] {
        assert!(codec::streams(s, &opts(e, 6)), "{:?} E = {e}", s.dims);
        assert_eq!(codec::default_layout(s, &opts(e, 6)), s.dims, "E = {e}");
    }
    assert_eq!(codec::default_layout(&small, &opts(2.0, 6)), small.dims);
    let mut nodata = big.clone();
    nodata.meta.nodata = Some(0.0);
    assert!(codec::streams(&nodata, &opts(2.0, 6)));
    let mut four = big.clone();
    four.dims = vec![16, 256, 256, 256];
    assert_eq!(
        codec::default_layout(&four, &opts(2.0, 6)),
        codec::default_tile(&four.dims, 1)
    );
    // the header of such a file is one the streamed decode takes
    let r = field(&[64, 64], 1, SampleType::U16, 12, 1000.0);
    let mut h = codec::header_of(&streamed(&r, &opts(2.0, 3))).unwrap();
    h.dims = vec![16384, 8192];
    h.tile = h.dims.clone();
    assert!(codec::decodes_streamed(&h));
}
