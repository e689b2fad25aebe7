//! Tiled files encoded and decoded in slabs (docs/tiles.md): a raw volume or a raw
//! NRRD read a tile-row at a time gives the bytes of the in-memory encode in every rate
//! mode, the metadata survives a streamed encode and decode, a decode in slabs (whole,
//! a region, a level) writes what the in-memory decode writes, and the CLI streams
//! without leaving a partial output behind.

use super::common;

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::slab::{self, Shape, SlabSink, SlabSource};
use mra::io::stream;
use mra::io::{self, DataKind, Raster, RawSpec, ReadOptions, SampleType, Samples};
use mra::scheme::{Boundary, Scheme};
use std::ops::Range;
use std::path::Path;
use std::process::Command;

fn field(dims: &[usize], ty: SampleType) -> Raster {
    let n: usize = dims.iter().product();
    let w = *dims.last().unwrap();
    let h = dims[dims.len() - 2];
    let v: Vec<f64> = (0..n)
        .map(|p| {
            let (x, y, z) = ((p % w) as f64, ((p / w) % h) as f64, (p / w / h) as f64);
            3000.0
                + 900.0 * (x * 0.13).sin() * (y * 0.09 + z * 0.2).cos()
                + ((p * 7919) % 37) as f64
        })
        .collect();
    let kind = if dims.len() == 2 {
        DataKind::Image
    } else {
        DataKind::Volume
    };
    Raster::new(dims.to_vec(), 1, Samples::from_f64(&v, ty), kind).unwrap()
}

fn opts(rate: Rate) -> EncodeOptions {
    EncodeOptions {
        scheme: Scheme::Cdf97,
        boundary: Boundary::Symmetric,
        levels: 4,
        rate,
        format: Default::default(),
        effort: mra::codec::DEFAULT_EFFORT,
    }
}

fn streamed(src: &mut dyn SlabSource, o: &EncodeOptions, tile: &[usize]) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    let n = codec::encode_stream(src, o, tile, &mut out).unwrap();
    let bytes = out.into_inner();
    assert_eq!(n as usize, bytes.len());
    bytes
}

/// A sink keeping what it is given, counting the slabs.
#[derive(Default)]
struct Keep {
    shape: Option<Shape>,
    samples: Vec<f64>,
    slabs: usize,
    ended: bool,
}

impl SlabSink for Keep {
    fn begin(&mut self, shape: &Shape) -> mra::Result<()> {
        self.shape = Some(shape.clone());
        Ok(())
    }
    fn rows(&mut self, s: &Samples) -> mra::Result<()> {
        self.samples.extend(s.to_f64());
        self.slabs += 1;
        Ok(())
    }
    fn end(&mut self) -> mra::Result<()> {
        self.ended = true;
        Ok(())
    }
}

#[test]
fn a_raw_file_streamed_gives_the_bytes_of_the_in_memory_encode_in_every_rate_mode() {
    let dir = common::scratch_dir("tiles_stream");
    // odd edges on both axes: 3 × 4 tiles of 16 × 12, the last ones shorter
    let r = field(&[37, 45], SampleType::U16);
    let p = dir.join("f.raw");
    std::fs::write(&p, io::bytes::encode(&r.samples, false)).unwrap();
    let ro = ReadOptions {
        raw: Some(RawSpec {
            dims: vec![37, 45],
            sample_type: SampleType::U16,
            big_endian: false,
        }),
        ..Default::default()
    };
    let tile = [16, 12];
    for rate in [
        Rate::Quality(60.0),
        Rate::Keep(10.0),
        Rate::Threshold(20.0),
        Rate::Psnr(45.0),
        Rate::Bpp(1.0),
        Rate::MaxError(3.0),
        Rate::Lossless,
    ] {
        let o = opts(rate);
        let mut src = stream::open(&p, &ro).unwrap().expect("a raw file streams");
        let s = streamed(&mut src, &o, &tile);
        let m = codec::encode_tiled(&r, &o, &tile).unwrap();
        assert!(s == m, "{rate:?}: streamed and in-memory bytes differ");
        let d = codec::decode(&s, &DecodeOptions::default()).unwrap();
        assert_eq!(d.raster.dims, r.dims, "{rate:?}");
        assert_eq!(
            Some((d.header.min, d.header.max)),
            r.samples.min_max(),
            "{rate:?}"
        );
    }
    // a big-endian 3-D raw file, slabs of 5 slices
    let v = field(&[11, 9, 14], SampleType::I16);
    let p3 = dir.join("v.raw");
    std::fs::write(&p3, io::bytes::encode(&v.samples, true)).unwrap();
    let ro3 = ReadOptions {
        raw: Some(RawSpec {
            dims: vec![11, 9, 14],
            sample_type: SampleType::I16,
            big_endian: true,
        }),
        ..Default::default()
    };
    let mut src = stream::open(&p3, &ro3).unwrap().unwrap();
    let o = opts(Rate::Quality(70.0));
    assert!(streamed(&mut src, &o, &[5, 4, 6]) == codec::encode_tiled(&v, &o, &[5, 4, 6]).unwrap());
}

#[test]
fn the_range_in_head_is_the_whole_rasters_in_one_pass_modes_too() {
    let r = field(&[30, 40], SampleType::F32);
    let (lo, hi) = r.samples.min_max().unwrap();
    for rate in [Rate::Lossless, Rate::MaxError(0.5), Rate::Quality(50.0)] {
        let mut src = slab::MemorySlabs::new(&r);
        let b = streamed(&mut src, &opts(rate), &[8, 16]);
        let h = codec::decode(&b, &DecodeOptions::default()).unwrap().header;
        assert_eq!((h.min, h.max), (lo, hi), "{rate:?}");
    }
}

#[test]
fn one_piece_read_in_slabs_gives_the_bytes_of_the_in_memory_encode() {
    // over 2^20 positions, so that the planes are filled from several slabs: a volume
    // (slabs of 4 planes) and an RGB image (colour transform per slab)
    let v = field(&[5, 300, 700], SampleType::U16);
    let mut rgb = Raster::new(
        vec![1030, 1024],
        3,
        Samples::U8(
            (0..1030 * 1024 * 3)
                .map(|i| ((i * 7 + (i / 3072) * 3) % 251) as u8)
                .collect(),
        ),
        DataKind::Image,
    )
    .unwrap();
    rgb.meta.description = Some("gradient".into());
    for r in [&v, &rgb] {
        let whole = r.dims.clone();
        for rate in [
            Rate::Quality(55.0),
            Rate::Keep(5.0),
            Rate::Threshold(40.0),
            Rate::Bpp(0.5),
            // near the lossless cost: the lossless file, read again whole
            Rate::Bpp(14.0),
            Rate::Psnr(40.0),
        ] {
            let o = opts(rate);
            let s = streamed(&mut slab::MemorySlabs::new(r), &o, &whole);
            let m = codec::encode(r, &o).unwrap();
            assert!(
                s == m,
                "{:?} {rate:?}: streamed and in-memory bytes differ",
                r.dims
            );
            let d = codec::decode(&s, &DecodeOptions::default()).unwrap();
            assert_eq!(d.raster.dims, r.dims);
            assert_eq!(d.raster.meta.description, r.meta.description);
        }
    }
}

/// `--lossless` and `--max-error` of a 16-bit volume read in slabs (the `i32` planes
/// and the residual coded a row at a time): the bytes of the in-memory encode, bit-exact
/// or within the bound on every sample, at full size and a level down.
#[test]
fn a_16_bit_volume_read_in_slabs_round_trips_exact_or_within_the_bound() {
    // over 2^20 positions: the planes filled from several slabs
    for ty in [SampleType::U16, SampleType::I16] {
        let mut v = field(&[18, 250, 240], ty);
        // the type's extremes, where the transform's values are largest
        let (lo, hi) = ty.range();
        if let Samples::U16(s) = &mut v.samples {
            s.iter_mut().step_by(101).for_each(|x| *x = hi as u16);
            s.iter_mut()
                .skip(50)
                .step_by(101)
                .for_each(|x| *x = lo as u16);
        }
        if let Samples::I16(s) = &mut v.samples {
            s.iter_mut().step_by(101).for_each(|x| *x = hi as i16);
            s.iter_mut()
                .skip(50)
                .step_by(101)
                .for_each(|x| *x = lo as i16);
        }
        let whole = v.dims.clone();
        for (rate, bound) in [
            (Rate::Lossless, 0.0),
            (Rate::MaxError(0.5), 0.0),
            (Rate::MaxError(1.0), 1.0),
            (Rate::MaxError(6.5), 6.5),
        ] {
            let o = opts(rate);
            let s = streamed(&mut slab::MemorySlabs::new(&v), &o, &whole);
            assert!(
                s == codec::encode(&v, &o).unwrap(),
                "{ty} {rate:?}: bytes differ"
            );
            let d = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
            assert_eq!(d.samples.sample_type(), ty);
            let worst = (0..v.samples.len())
                .map(|i| (v.samples.get_f64(i) - d.samples.get_f64(i)).abs())
                .fold(0.0, f64::max);
            assert!(worst <= bound, "{ty} {rate:?}: error {worst}");
            if rate == Rate::Lossless {
                assert_eq!(d.samples, v.samples);
                let l1 = DecodeOptions {
                    level: 1,
                    ..Default::default()
                };
                let half = codec::decode(&s, &l1).unwrap().raster;
                assert_eq!(half.dims, vec![9, 125, 120]);
            }
        }
    }
}

#[test]
fn metadata_survives_a_one_piece_encode_read_in_slabs() {
    let dir = common::scratch_dir("tiles_stream");
    let mut r = field(&[6, 10, 12], SampleType::I16);
    r.meta.space = Some("left-posterior-superior".into());
    r.meta.spacing = Some(vec![2.5, 0.7, 0.6]);
    r.meta.origin = Some(vec![-10.0, 20.5, 3.0]);
    r.meta.description = Some("phantom".into());
    let p = dir.join("one.nrrd");
    io::write(&p, &r).unwrap();
    let r = io::read(&p).unwrap();
    let mut src = stream::open(&p, &ReadOptions::default()).unwrap().unwrap();
    let o = opts(Rate::Quality(60.0));
    let bytes = streamed(&mut src, &o, &r.dims.clone());
    assert!(bytes == codec::encode(&r, &o).unwrap());
    let d = codec::decode(&bytes, &DecodeOptions::default())
        .unwrap()
        .raster;
    assert_eq!(d.meta.spacing, r.meta.spacing);
    assert_eq!(d.meta.origin, r.meta.origin);
    assert_eq!(d.meta.space, r.meta.space);
    assert_eq!(d.meta.description, r.meta.description);
}

fn nrrd_volume(dir: &Path) -> (std::path::PathBuf, Raster) {
    let mut r = field(&[13, 10, 12], SampleType::I16);
    r.meta.space = Some("left-posterior-superior".into());
    r.meta.spacing = Some(vec![2.5, 0.7, 0.6]);
    r.meta.directions = Some(vec![
        vec![0.6, 0.0, 0.0],
        vec![0.0, 0.7, 0.0],
        vec![0.0, 0.0, 2.5],
    ]);
    r.meta.origin = Some(vec![-10.0, 20.5, 3.0]);
    r.meta.nodata = Some(-1000.0);
    r.meta.description = Some("phantom".into());
    if let Samples::I16(v) = &mut r.samples {
        v[5] = -1000;
        v[777] = -1000;
    }
    let p = dir.join("v.nrrd");
    io::write(&p, &r).unwrap();
    let back = io::read(&p).unwrap();
    (p, back)
}

#[test]
fn metadata_survives_a_streamed_encode_and_decode() {
    let dir = common::scratch_dir("tiles_stream");
    let (p, r) = nrrd_volume(&dir);
    let mut src = stream::open(&p, &ReadOptions::default())
        .unwrap()
        .expect("a raw NRRD streams");
    assert_eq!(src.shape(), &Shape::of(&r));
    let o = opts(Rate::MaxError(2.0));
    let tile = [5, 4, 5];
    let bytes = streamed(&mut src, &o, &tile);
    assert!(bytes == codec::encode_tiled(&r, &o, &tile).unwrap());
    let f = dir.join("v.mra");
    std::fs::write(&f, &bytes).unwrap();
    // decoded in slabs into a NRRD, read back
    let out = dir.join("back.nrrd");
    let mut w = std::fs::File::create(&out).unwrap();
    let mut sink = stream::sink_for(&out, &mut w).unwrap();
    let d = codec::decode_file_slabs(&f, &DecodeOptions::default(), &mut sink).unwrap();
    drop(w);
    let (shape, complete) = (d.shape, d.complete);
    assert!(complete);
    assert_eq!(d.bytes_read, bytes.len() as u64);
    let back = io::read(&out).unwrap();
    let whole = codec::decode_file(&f, &DecodeOptions::default())
        .unwrap()
        .raster;
    assert_eq!(shape, Shape::of(&whole));
    assert_eq!(back.samples, whole.samples);
    for m in [&back.meta, &whole.meta] {
        assert_eq!(m.spacing, r.meta.spacing);
        assert_eq!(m.origin, r.meta.origin);
        assert_eq!(m.directions, r.meta.directions);
        assert_eq!(m.space, r.meta.space);
        assert_eq!(m.nodata, r.meta.nodata);
        assert_eq!(m.description, r.meta.description);
    }
    // voids marked again, every other sample within the bound
    let (a, b) = (r.to_f64(), back.to_f64());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        if *x == -1000.0 {
            assert_eq!(*y, -1000.0, "void {i}");
        } else {
            assert!((x - y).abs() <= 2.0, "sample {i}: {x} → {y}");
        }
    }
}

#[test]
fn a_decode_in_slabs_equals_the_decode_whole_for_regions_and_levels() {
    let dir = common::scratch_dir("tiles_stream");
    let r = field(&[40, 50, 36], SampleType::U16);
    let tile = [16, 16, 16];
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(55.0)), &tile).unwrap();
    let f = dir.join("v.mra");
    std::fs::write(&f, &bytes).unwrap();
    // (level, region, slabs handed over)
    type Case = (usize, Option<Vec<Range<usize>>>, usize);
    let cases: [Case; 6] = [
        (0, None, 3),
        (1, None, 3),
        (2, None, 3),
        (0, Some(vec![10..33, 17..18, 3..20]), 3),
        (2, Some(vec![20..30, 17..18, 3..20]), 1),
        (1, Some(vec![33..40, 0..50, 0..36]), 1),
    ];
    for (level, region, slabs) in cases {
        let o = DecodeOptions {
            level,
            allow_truncated: false,
            region: region.clone(),
        };
        let mut k = Keep::default();
        let d = codec::decode_file_slabs(&f, &o, &mut k).unwrap();
        let (shape, complete) = (d.shape, d.complete);
        let whole = codec::decode_file(&f, &o).unwrap().raster;
        assert!(complete && k.ended);
        if region.is_some() {
            // a third of the tiles at most, read by seeking
            assert!(
                d.bytes_read < bytes.len() as u64 / 2,
                "{} of {} bytes read for {region:?}",
                d.bytes_read,
                bytes.len()
            );
        }
        assert_eq!(k.slabs, slabs, "level {level} region {region:?}");
        assert_eq!(shape, Shape::of(&whole), "level {level} region {region:?}");
        assert_eq!(k.samples, whole.to_f64(), "level {level} region {region:?}");
    }
}

#[test]
fn a_raw_file_of_the_wrong_size_and_an_unstreamable_nrrd_are_told_apart() {
    let dir = common::scratch_dir("tiles_stream");
    let p = dir.join("short.raw");
    std::fs::write(&p, vec![0u8; 99]).unwrap();
    let ro = ReadOptions {
        raw: Some(RawSpec {
            dims: vec![10, 5],
            sample_type: SampleType::U16,
            big_endian: false,
        }),
        ..Default::default()
    };
    let e = stream::open(&p, &ro).err().expect("a size mismatch");
    assert_eq!(e.kind(), mra::ErrorKind::Format, "{e}");
    assert!(e.to_string().contains("99"), "{e}");
    // a gzip NRRD is read whole
    let r = field(&[6, 7], SampleType::U8);
    let g = dir.join("g.nrrd");
    io::write_with(&g, &r, &io::WriteOptions { compress: true }).unwrap();
    assert!(stream::open(&g, &ReadOptions::default()).unwrap().is_none());
    // a NRRD whose header declares more data than the file holds
    let bad = dir.join("bad.nrrd");
    std::fs::write(
        &bad,
        b"NRRD0004\ntype: uint16\ndimension: 2\nsizes: 4000 4000\nencoding: raw\nendian: little\n\n\x01\x02",
    )
    .unwrap();
    let e = stream::open(&bad, &ReadOptions::default())
        .err()
        .expect("too short");
    assert_eq!(e.kind(), mra::ErrorKind::Format, "{e}");
}

fn mra(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn the_cli_streams_raw_in_and_out_and_leaves_nothing_on_error() {
    let dir = common::scratch_dir("tiles_stream");
    let r = field(&[70, 90], SampleType::U16);
    let raw = dir.join("in.raw");
    std::fs::write(&raw, io::bytes::encode(&r.samples, false)).unwrap();
    let f = dir.join("f.mra");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let o = mra(&[
        "encode",
        &s(&raw),
        "--dims",
        "90x70",
        "--dtype",
        "u16",
        "-o",
        &s(&f),
        "--tile",
        "32",
        "--lossless",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["dims"], serde_json::json!([90, 70]));
    assert_eq!(
        j["bytes"].as_u64().unwrap(),
        std::fs::metadata(&f).unwrap().len()
    );
    let back = dir.join("back.raw");
    let o = mra(&["decode", &s(&f), "-o", &s(&back), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read(&back).unwrap(), std::fs::read(&raw).unwrap());
    // a region to NRRD
    let reg = dir.join("reg.nrrd");
    let o = mra(&["decode", &s(&f), "-o", &s(&reg), "--region", "30:70,10:40"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let g = io::read(&reg).unwrap();
    assert_eq!(g.dims, vec![30, 40]);
    assert_eq!(g.samples.get_f64(0), r.samples.get_f64(10 * 90 + 30));
    // a truncated file: exit 2, one line naming the file, no output left behind
    let cut = dir.join("cut.mra");
    let b = std::fs::read(&f).unwrap();
    std::fs::write(&cut, &b[..b.len() - 300]).unwrap();
    let out = dir.join("cut.raw");
    let o = mra(&["decode", &s(&cut), "-o", &s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("cut.mra") && err.lines().count() == 1, "{err}");
    assert!(!out.exists());
    assert!(mra::fsutil::leftover_temps(&out).is_empty());
}

/// A little-endian u16 gray TIFF of `w`×`h` in tiles of 16×16 (padding 0xFFFF), sample
/// (x, y) = y·w + x + 7: the tiled layout mra's own writer does not make.
fn tiled_tiff(w: usize, h: usize) -> Vec<u8> {
    let (across, down) = (w.div_ceil(16), h.div_ceil(16));
    let n = across * down;
    let mut f = b"II*\0".to_vec();
    let data_at = 8u32;
    let ifd_at = data_at + (n * 512) as u32;
    f.extend_from_slice(&ifd_at.to_le_bytes());
    for t in 0..n {
        let (tx, ty) = (t % across, t / across);
        for y in 0..16 {
            for x in 0..16 {
                let (gx, gy) = (tx * 16 + x, ty * 16 + y);
                let v = if gx < w && gy < h {
                    (gy * w + gx + 7) as u16
                } else {
                    0xFFFF
                };
                f.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    let tags: [(u16, u16, u32, u32); 12] = [
        (256, 3, 1, w as u32),
        (257, 3, 1, h as u32),
        (258, 3, 1, 16),
        (259, 3, 1, 1),
        (262, 3, 1, 1),
        (277, 3, 1, 1),
        (284, 3, 1, 1),
        (322, 3, 1, 16),
        (323, 3, 1, 16),
        (324, 4, n as u32, 0),
        (325, 4, n as u32, 0),
        (339, 3, 1, 1),
    ];
    let arrays_at = ifd_at + 2 + 12 * tags.len() as u32 + 4;
    f.extend_from_slice(&(tags.len() as u16).to_le_bytes());
    for (i, &(tag, ty, count, value)) in tags.iter().enumerate() {
        f.extend_from_slice(&tag.to_le_bytes());
        f.extend_from_slice(&ty.to_le_bytes());
        f.extend_from_slice(&count.to_le_bytes());
        let v = match tag {
            324 => arrays_at,
            325 => arrays_at + 4 * n as u32,
            _ => value,
        };
        let _ = i;
        f.extend_from_slice(&v.to_le_bytes());
    }
    f.extend_from_slice(&0u32.to_le_bytes());
    for t in 0..n {
        f.extend_from_slice(&(data_at + 512 * t as u32).to_le_bytes());
    }
    for _ in 0..n {
        f.extend_from_slice(&512u32.to_le_bytes());
    }
    f
}

/// The rows of `src` read in slabs of uneven heights, joined.
fn all_rows(src: &mut dyn SlabSource, cuts: &[usize]) -> Vec<f64> {
    let d0 = src.shape().dims[0];
    let mut at = 0;
    let mut v = Vec::new();
    for &c in cuts.iter().chain(std::iter::once(&d0)) {
        if c > at {
            v.extend(src.read_rows(at..c).unwrap().to_f64());
            at = c;
        }
    }
    v
}

#[test]
fn a_tiff_read_in_slabs_gives_the_raster_of_the_whole_reader() {
    let dir = common::scratch_dir("tiles_stream");
    // tiles with odd edges, slabs cutting through tile rows
    let t = dir.join("tiled.tif");
    std::fs::write(&t, tiled_tiff(40, 35)).unwrap();
    let whole = io::read(&t).unwrap();
    assert_eq!(whole.dims, vec![35, 40]);
    assert_eq!(
        whole.samples.get_f64(34 * 40 + 39),
        (34 * 40 + 39 + 7) as f64
    );
    let mut src = stream::open(&t, &ReadOptions::default()).unwrap().unwrap();
    assert_eq!(src.shape(), &Shape::of(&whole));
    assert_eq!(all_rows(&mut src, &[5, 16, 17, 33]), whole.to_f64());
    // a page stack with metadata
    let mut v = field(&[7, 9, 11], SampleType::F32);
    v.meta.spacing = Some(vec![2.0, 0.5, 0.25]);
    v.meta.nodata = Some(-5.0);
    v.meta.description = Some("stack".into());
    let p = dir.join("stack.tif");
    io::write_with(&p, &v, &io::WriteOptions { compress: true }).unwrap();
    let whole = io::read(&p).unwrap();
    let mut src = stream::open(&p, &ReadOptions::default()).unwrap().unwrap();
    assert_eq!(src.shape(), &Shape::of(&whole));
    assert_eq!(all_rows(&mut src, &[2, 3, 6]), whole.to_f64());
    // strips: Deflate with the floating-point predictor, GeoTIFF tags
    if let Some(g) = common::corpus("terrain/mt_st_helens_30m_f32.tif") {
        let whole = io::read(&g).unwrap();
        let mut src = stream::open(&g, &ReadOptions::default()).unwrap().unwrap();
        assert_eq!(src.shape(), &Shape::of(&whole));
        assert!(!src.shape().meta.geotiff.is_empty());
        assert_eq!(all_rows(&mut src, &[1, 205, 206, 207, 413]), whole.to_f64());
        // streamed encode: the bytes of the in-memory encode
        let o = opts(Rate::MaxError(0.5));
        let mut src = stream::open(&g, &ReadOptions::default()).unwrap().unwrap();
        assert!(
            streamed(&mut src, &o, &[128, 100])
                == codec::encode_tiled(&whole, &o, &[128, 100]).unwrap()
        );
    }
}

#[test]
fn a_tiff_written_in_slabs_reads_back_with_its_samples_and_tags() {
    use mra::io::{GeoTag, GeoValue};
    let dir = common::scratch_dir("tiles_stream");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let mut r = field(&[45, 37], SampleType::U16);
    r.meta.geotiff = vec![
        GeoTag {
            tag: 33550,
            value: GeoValue::Doubles(vec![30.0, 30.0, 0.0]),
        },
        GeoTag {
            tag: 33922,
            value: GeoValue::Doubles(vec![0.0, 0.0, 0.0, 500000.0, 5000000.0, 0.0]),
        },
    ];
    r.meta.description = Some("relief".into());
    let f = dir.join("r.mra");
    std::fs::write(
        &f,
        codec::encode_tiled(&r, &opts(Rate::Lossless), &[16, 16]).unwrap(),
    )
    .unwrap();
    let out = dir.join("r.tif");
    let o = mra(&["decode", &s(&f), "-o", &s(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let back = io::read(&out).unwrap();
    assert_eq!(back.samples, r.samples);
    assert_eq!(back.meta.geotiff, r.meta.geotiff);
    assert_eq!(back.meta.description, r.meta.description);
    // a region, at a level
    let reg = dir.join("reg.tif");
    let o = mra(&[
        "decode",
        &s(&f),
        "-o",
        &s(&reg),
        "--region",
        "3:30,10:40",
        "--level",
        "1",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole = codec::decode_file(
        &f,
        &DecodeOptions {
            level: 1,
            allow_truncated: false,
            // `--region` is x first, the library slowest first
            region: Some(vec![10..40, 3..30]),
        },
    )
    .unwrap()
    .raster;
    let back = io::read(&reg).unwrap();
    assert_eq!(
        (back.dims.clone(), back.samples),
        (whole.dims, whole.samples)
    );
    // a volume: one page per slice
    let v = field(&[9, 20, 18], SampleType::I16);
    let fv = dir.join("v.mra");
    std::fs::write(
        &fv,
        codec::encode_tiled(&v, &opts(Rate::Lossless), &[4, 8, 8]).unwrap(),
    )
    .unwrap();
    let ov = dir.join("v.tif");
    let o = mra(&["decode", &s(&fv), "-o", &s(&ov)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let back = io::read(&ov).unwrap();
    assert_eq!((back.dims, back.samples), (v.dims, v.samples));
}

#[test]
fn the_tiled_test_vectors_decode_in_slabs_to_their_digests() {
    use mra::format::sha256::{hex, sha256};
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("formats/vectors");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    let mut dims_seen = Vec::new();
    for v in manifest.as_array().unwrap() {
        let file = dir.join(v["file"].as_str().unwrap());
        if !codec::header_of_file(&file).unwrap().is_tiled() {
            continue;
        }
        let o = DecodeOptions {
            level: v["level"].as_u64().unwrap() as usize,
            ..Default::default()
        };
        let mut k = Keep::default();
        let d = codec::decode_file_slabs(&file, &o, &mut k).unwrap();
        assert!(d.complete && k.slabs >= 2, "{}", v["name"]);
        let s = Samples::from_f64(&k.samples, d.shape.sample_type);
        assert_eq!(
            hex(&sha256(&io::bytes::encode(&s, false))),
            v["sha256"].as_str().unwrap(),
            "{}",
            v["name"]
        );
        dims_seen.push(d.shape.dims.len());
    }
    // a tiled image (twice: two levels) and a tiled volume
    assert!(
        dims_seen.contains(&2) && dims_seen.contains(&3),
        "{dims_seen:?}"
    );
}

/// The streamed paths read the next slab (encode) or decode the next tile-row (decode)
/// while the current one is coded or written when there is more than one thread, and go
/// one slab at a time with one thread: the file's bytes and the decoded slabs are the
/// same with 1, 2 and 3 threads, in a one-pass and a two-pass rate mode, and a
/// truncated file is still named in slabs.
#[test]
fn the_pipelined_slabs_give_the_same_bytes_and_samples_with_any_thread_count() {
    let dir = common::scratch_dir("tiles_stream");
    let r = field(&[21, 40, 30], SampleType::U16);
    let p = dir.join("pipe.raw");
    std::fs::write(&p, io::bytes::encode(&r.samples, false)).unwrap();
    let ro = ReadOptions {
        raw: Some(RawSpec {
            dims: vec![21, 40, 30],
            sample_type: SampleType::U16,
            big_endian: false,
        }),
        ..Default::default()
    };
    let tile = [4, 16, 16];
    for rate in [Rate::Quality(60.0), Rate::Bpp(2.0), Rate::MaxError(4.0)] {
        let o = opts(rate);
        let mut files = Vec::new();
        let mut decoded = Vec::new();
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let bytes = pool.install(|| {
                let mut src = stream::open(&p, &ro).unwrap().unwrap();
                streamed(&mut src, &o, &tile)
            });
            let f = dir.join(format!("pipe{threads}.mra"));
            std::fs::write(&f, &bytes).unwrap();
            let k = pool.install(|| {
                let mut k = Keep::default();
                let d = codec::decode_file_slabs(&f, &DecodeOptions::default(), &mut k).unwrap();
                assert!(d.complete && k.ended);
                k
            });
            // one slab per grid row: ⌈21 / 4⌉
            assert_eq!(k.slabs, 6, "{rate:?} {threads} threads");
            files.push(bytes);
            decoded.push(k.samples);
        }
        let whole = codec::decode(&files[0], &DecodeOptions::default()).unwrap();
        assert_eq!(decoded[0], whole.raster.to_f64(), "{rate:?}");
        assert!(
            files.iter().all(|f| *f == files[0]),
            "{rate:?}: bytes differ"
        );
        assert!(
            decoded.iter().all(|d| *d == decoded[0]),
            "{rate:?}: samples differ"
        );
        // cut inside the fourth row of tiles: the slabs before it come, then the error
        let cut = dir.join("pipe_cut.mra");
        std::fs::write(&cut, &files[0][..files[0].len() * 2 / 3]).unwrap();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let err = pool
                .install(|| {
                    codec::decode_file_slabs(&cut, &DecodeOptions::default(), &mut Keep::default())
                })
                .unwrap_err();
            assert!(err.to_string().contains("truncated"), "{threads}: {err}");
        }
    }
}

/// A chunk rebuilt with a new payload (its CRC recomputed).
fn chunk(kind: &[u8; 4], payload: &[u8]) -> Vec<u8> {
    let mut c = mra::format::crc::Crc32c::new();
    c.update(kind);
    c.update(payload);
    let mut v = (payload.len() as u32).to_le_bytes().to_vec();
    v.extend_from_slice(kind);
    v.extend_from_slice(payload);
    v.extend_from_slice(&c.finish().to_le_bytes());
    v
}

/// The pipelined decode runs the tiles of a row as pool jobs, a few at a time, and
/// queues the next row's behind them: a tile whose chunk is sound but whose contents
/// are not (its body overwritten, its CRC recomputed) stops the decode with an error
/// naming that tile, after the rows before it, with any thread count and whether the
/// caller is a thread of the pool or not; the same file unbroken decodes in slabs to
/// the samples of the whole decode.
#[test]
fn a_bad_tile_in_a_pipelined_row_is_named_after_the_rows_before_it() {
    let dir = common::scratch_dir("tiles_stream");
    let r = field(&[20, 24, 24], SampleType::U16);
    let tile = [4, 8, 8];
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(60.0)), &tile).unwrap();
    // the TILE chunks, in tile order: (start, end past the CRC)
    let mut tiles = Vec::new();
    let mut at = 8;
    while at + 12 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        if &bytes[at + 4..at + 8] == b"TILE" {
            tiles.push((at, at + 12 + len));
        }
        at += 12 + len;
    }
    // 5 rows of 3 × 3 tiles; tile 31 is in the fourth row (27..36)
    assert_eq!(tiles.len(), 45);
    let (s, e) = tiles[31];
    let mut p = bytes[s + 8..e - 4].to_vec();
    for b in &mut p[4..] {
        *b = 0xA5;
    }
    let bad = [&bytes[..s], &chunk(b"TILE", &p), &bytes[e..]].concat();
    assert_eq!(bad.len(), bytes.len());
    let (good_f, bad_f) = (dir.join("good.mra"), dir.join("bad.mra"));
    std::fs::write(&good_f, &bytes).unwrap();
    std::fs::write(&bad_f, &bad).unwrap();
    let whole = codec::decode(&bytes, &DecodeOptions::default()).unwrap();
    let check = |threads: &str| {
        let mut k = Keep::default();
        let d = codec::decode_file_slabs(&good_f, &DecodeOptions::default(), &mut k).unwrap();
        assert!(d.complete && k.ended && k.slabs == 5, "{threads}");
        assert_eq!(k.samples, whole.raster.to_f64(), "{threads}");
        let mut k = Keep::default();
        let err = codec::decode_file_slabs(&bad_f, &DecodeOptions::default(), &mut k).unwrap_err();
        assert!(err.to_string().contains("tile 31"), "{threads}: {err}");
        assert_eq!(k.slabs, 3, "{threads}: the rows before the bad one");
        assert!(!k.ended, "{threads}");
    };
    // the caller outside the pool (the global pool's threads)
    check("global pool");
    // the caller a thread of the pool
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| check(&format!("{threads} threads")));
    }
}
