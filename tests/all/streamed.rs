//! The one-transform file of a raster streamed a slab at a time
//! (`codec::encode_streamed`, what `mra encode` writes above the one-piece limit): the
//! bytes of the whole-array 3.0 encode at the same step, whatever the thread count; a
//! region of it is the whole decode cropped; a truncated one is a one-line error.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Format, Rate};
use mra::io::slab::{MemorySlabs, Shape};
use mra::io::{Raster, SampleType};
use mra::scheme::{Boundary, Scheme};

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

fn opts(rate: Rate, levels: usize, boundary: Boundary) -> EncodeOptions {
    EncodeOptions {
        rate,
        levels,
        boundary,
        scheme: Scheme::Cdf97,
        format: Format::Blocks,
        effort: 7, // the context coder: the whole-array file is coder 0 too
    }
}

fn streamed(r: &Raster, o: &EncodeOptions) -> Vec<u8> {
    let mut out = Vec::new();
    let n = codec::encode_streamed(&mut MemorySlabs::new(r), o, &mut out).unwrap();
    assert_eq!(n as usize, out.len());
    out
}

/// At a fixed step (`--threshold`: the dead-zone quantizer on both paths) the streamed
/// file is the whole-array encoder's file byte for byte: the same transform, indices and
/// code-block streams of the same block coder (efforts 1, 4 and 7: HT, adaptive,
/// context), for RGB, 16-bit, volumes and 4-D, odd sizes, bands of several stripes of
/// code-blocks (rows 256 tall in images, planes 32 deep in volumes), and periodic ends
/// (whose first rows come last).
#[test]
fn streamed_files_are_the_whole_encoders_bytes() {
    let cases: [(Raster, usize, f64); 5] = [
        (field(&[131, 97], 3, SampleType::U8, 1, 255.0), 4, 3.0),
        (field(&[1100, 75], 1, SampleType::U16, 2, 60000.0), 5, 400.0),
        (field(&[70, 41, 33], 1, SampleType::U16, 3, 4000.0), 3, 20.0),
        (
            field(&[150, 23, 19], 2, SampleType::I16, 4, 3000.0),
            4,
            10.0,
        ),
        (field(&[5, 6, 7, 9], 1, SampleType::U8, 5, 255.0), 2, 2.0),
    ];
    for (r, levels, t) in &cases {
        for (boundary, effort) in [
            (Boundary::Symmetric, 7),
            (Boundary::Periodic, 7),
            (Boundary::Symmetric, 4),
            (Boundary::Periodic, 1),
        ] {
            let o = EncodeOptions {
                effort,
                ..opts(Rate::Threshold(*t), *levels, boundary)
            };
            let whole = codec::encode(r, &o).unwrap();
            assert_eq!(codec::info(&whole).unwrap().version, "3.2");
            let s = streamed(r, &o);
            assert!(
                s == whole,
                "{} {boundary:?} effort {effort}: {} vs {} bytes",
                r.summary(),
                s.len(),
                whole.len()
            );
        }
    }
}

/// The streamed file does not depend on the thread count (rate modes that take a first
/// pass included), and `--bpp` lands near its budget.
#[test]
fn streamed_files_do_not_depend_on_the_thread_count() {
    let r = field(&[600, 210], 1, SampleType::U16, 7, 50000.0);
    let v = field(&[66, 40, 37], 3, SampleType::U8, 8, 255.0);
    for (r, rate) in [
        (&r, Rate::Bpp(1.0)),
        (&r, Rate::Quality(60.0)),
        (&v, Rate::Keep(4.0)),
        (&v, Rate::Bpp(0.5)),
    ] {
        let o = opts(rate, 4, Boundary::Symmetric);
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| streamed(r, &o))
        };
        let one = on(1);
        assert!(one == on(2), "{} {rate:?}", r.summary());
        if let Rate::Bpp(b) = rate {
            let got = one.len() as f64 * 8.0 / r.positions() as f64;
            assert!(got <= b && got >= b * 0.99, "{rate:?}: {got} bpp");
        }
    }
}

/// The streamed encoder codes the blocks with the coder of the effort (HT at 1, coder 2
/// at the default 4, the context coder at 7), its header says so, and at the rate modes
/// that optimise the indices (`--quality`, `--bpp`: coder 2 by its own costs) the file
/// is within 2% of the whole-array encoder's in bytes and in squared error (a parent
/// band's indices are chosen without its own parent: module doc).
#[test]
fn a_streamed_file_says_the_coder_of_its_effort() {
    let r = field(&[300, 290], 1, SampleType::U16, 12, 30000.0);
    let sq = |f: &[u8]| -> f64 {
        let d = codec::decode(f, &DecodeOptions::default()).unwrap().raster;
        let (a, b) = (r.samples.to_f64(), d.samples.to_f64());
        a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum()
    };
    for (effort, coder) in [(1u8, 1u8), (codec::DEFAULT_EFFORT, 2), (7, 0)] {
        for rate in [Rate::Quality(60.0), Rate::Threshold(40.0)] {
            let o = EncodeOptions {
                effort,
                ..opts(rate, 4, Boundary::Symmetric)
            };
            let s = streamed(&r, &o);
            assert_eq!(codec::header_of(&s).unwrap().coder, coder, "{effort}");
            let whole = codec::encode(&r, &o).unwrap();
            let (ls, lw) = (s.len() as f64, whole.len() as f64);
            let (es, ew) = (sq(&s), sq(&whole));
            let what = format!("effort {effort} {rate:?}: {ls} vs {lw} bytes, {es} vs {ew}");
            assert!((ls / lw - 1.0).abs() <= 0.02, "{what}");
            assert!((es / ew - 1.0).abs() <= 0.02, "{what}");
        }
    }
}

/// A region of a streamed file decodes to the whole decode cut to the region.
#[test]
fn a_region_of_a_streamed_file_is_the_whole_decode_cropped() {
    let r = field(&[700, 90], 3, SampleType::U8, 9, 255.0);
    let s = streamed(&r, &opts(Rate::Bpp(1.5), 5, Boundary::Symmetric));
    let whole = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
    let (ys, xs) = (300..420, 17..61);
    let part = codec::decode(
        &s,
        &DecodeOptions {
            region: Some(vec![ys.clone(), xs.clone()]),
            ..Default::default()
        },
    )
    .unwrap()
    .raster;
    assert_eq!(part.dims, vec![ys.len(), xs.len()]);
    let (w, c) = (r.dims[1], r.channels);
    let all = whole.samples.to_f64();
    let want: Vec<f64> = ys
        .flat_map(|y| {
            let xs = xs.clone();
            let all = &all;
            xs.flat_map(move |x| (0..c).map(move |k| all[(y * w + x) * c + k]))
        })
        .collect();
    assert_eq!(part.samples.to_f64(), want);
}

/// A truncated streamed file is an error (the library's and the CLI's: one line, exit
/// code 2, no output).
#[test]
fn a_truncated_streamed_file_is_a_one_line_error() {
    let r = field(&[300, 80], 1, SampleType::U16, 10, 9000.0);
    let s = streamed(&r, &opts(Rate::Quality(50.0), 4, Boundary::Symmetric));
    let cut = &s[..s.len() * 2 / 3];
    assert!(codec::decode(cut, &DecodeOptions::default()).is_err());
    let dir = common::scratch_dir("streamed_truncated");
    std::fs::write(dir.join("cut.mra"), cut).unwrap();
    let o = common::mra_with_stdin(Some(&dir), &["decode", "cut.mra", "-o", "out.nrrd"], &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("cut.mra"), "{err}");
    assert!(!dir.join("out.nrrd").exists());
}

/// Over the one-piece limit a one-tile encode (the default layout there, or `--tile
/// whole`) streams for the lossy modes of one step and `--psnr`, integer or float
/// samples, for `--lossless` (and exact `--max-error`) of 8- and 16-bit integer samples,
/// and for `--max-error` above the lossless range (a base and its residual), with a nodata
/// value or not; format 2 and small rasters do not. The default layout streams them all,
/// the lossless ones too (their streamed decode reads the code-blocks from the file a
/// batch at a time).
#[test]
fn a_whole_tile_streams_over_the_one_piece_limit() {
    let small = field(&[4, 4], 1, SampleType::U16, 1, 100.0);
    let mut big = Shape::of(&small);
    big.dims = vec![16384, 8192];
    let o = |rate| opts(rate, 6, Boundary::Symmetric);
    assert!(codec::streams(&big, &o(Rate::Bpp(1.0))));
    assert!(codec::streams(&big, &o(Rate::Quality(50.0))));
    assert!(codec::streams(&big, &o(Rate::Lossless)));
    assert!(codec::streams(&big, &o(Rate::MaxError(0.5))));
    assert!(codec::streams(&big, &o(Rate::MaxError(2.0))));
    assert!(codec::streams(&big, &o(Rate::Psnr(40.0))));
    assert!(!codec::streams(&Shape::of(&small), &o(Rate::Bpp(1.0))));
    let mut float = big.clone();
    float.sample_type = SampleType::F32;
    assert!(codec::streams(&float, &o(Rate::Bpp(1.0))));
    let mut nodata = big.clone();
    nodata.meta.nodata = Some(0.0);
    assert!(codec::streams(&nodata, &o(Rate::Bpp(1.0))));
    // the default layout: one transform where the stream covers, else the tiles
    assert_eq!(codec::default_layout(&big, &o(Rate::Bpp(1.0))), big.dims);
    assert_eq!(codec::default_layout(&big, &o(Rate::Keep(5.0))), big.dims);
    let tiles = codec::default_tile(&big.dims, 1);
    assert_ne!(tiles, big.dims);
    assert_eq!(codec::default_layout(&big, &o(Rate::Lossless)), big.dims);
    assert_eq!(
        codec::default_layout(&big, &o(Rate::MaxError(0.5))),
        big.dims
    );
    assert_eq!(
        codec::default_layout(&big, &o(Rate::MaxError(2.0))),
        big.dims
    );
    assert_eq!(
        codec::default_layout(&float, &o(Rate::Bpp(1.0))),
        float.dims
    );
    assert_eq!(codec::default_layout(&nodata, &o(Rate::Bpp(1.0))), big.dims);
    let mut two = o(Rate::Bpp(1.0));
    two.format = Format::Bands;
    assert_eq!(codec::default_layout(&big, &two), tiles);
    // volumes are one transform by default too; 4 axes (not decoded streamed) and the
    // modes the stream does not cover stay tiled
    let mut vol = big.clone();
    vol.dims = vec![1024, 1024, 1024];
    assert!(codec::streams(&vol, &o(Rate::Bpp(1.0))));
    assert_eq!(codec::default_layout(&vol, &o(Rate::Bpp(1.0))), vol.dims);
    assert!(codec::streams(&vol, &o(Rate::Lossless)));
    assert_eq!(codec::default_layout(&vol, &o(Rate::Lossless)), vol.dims);
    let mut wide = vol.clone();
    wide.sample_type = SampleType::U32;
    assert_eq!(
        codec::default_layout(&wide, &o(Rate::Lossless)),
        codec::default_tile(&vol.dims, 1)
    );
    let mut four = big.clone();
    four.dims = vec![16, 256, 256, 256];
    assert!(codec::streams(&four, &o(Rate::Bpp(1.0))));
    assert_eq!(
        codec::default_layout(&four, &o(Rate::Bpp(1.0))),
        codec::default_tile(&four.dims, 1)
    );
    let small = Shape::of(&small);
    assert_eq!(
        codec::default_layout(&small, &o(Rate::Lossless)),
        small.dims
    );
}

/// A whole decode through the streamed synthesis (what `mra decode` to raw, NRRD or
/// TIFF does with a file over the one-piece limit) gives the samples of the whole-array
/// decode, slab by slab, for images and volumes, colour and periodic ends.
#[test]
fn the_streamed_decode_gives_the_whole_decodes_samples() {
    let cases: [(Raster, usize, Boundary); 4] = [
        (
            field(&[1100, 75], 1, SampleType::U16, 2, 60000.0),
            5,
            Boundary::Symmetric,
        ),
        (
            field(&[301, 67], 3, SampleType::U8, 6, 255.0),
            4,
            Boundary::Periodic,
        ),
        (
            field(&[70, 41, 33], 1, SampleType::U16, 3, 4000.0),
            3,
            Boundary::Symmetric,
        ),
        (
            field(&[45, 20, 17], 2, SampleType::I16, 4, 3000.0),
            3,
            Boundary::Periodic,
        ),
    ];
    let dir = common::scratch_dir("streamed_decode");
    for (r, levels, boundary) in &cases {
        let s = streamed(r, &opts(Rate::Bpp(1.0), *levels, *boundary));
        let path = dir.join("s.mra");
        std::fs::write(&path, &s).unwrap();
        let whole = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
        let mut d = codec::StreamedDecoder::open(&path).unwrap();
        assert_eq!(d.shape().dims, r.dims);
        let mut got: Vec<f64> = Vec::new();
        while let Some(slab) = d.next_slab().unwrap() {
            got.extend(slab.to_f64());
        }
        assert_eq!(got, whole.samples.to_f64(), "{} {boundary:?}", r.summary());
    }
}

/// A streamed decode of many stripes of code-blocks per band (each batch decoded ahead,
/// beside the synthesis of the rows before it, and dropped after its last row is read;
/// a parent band's batches held while its children's decode reads them) gives the
/// samples of the whole-array decode: long volumes and images, one and two channels,
/// symmetric and periodic ends (whose first rows are read again at the end), planes
/// large enough to be summed in pieces on the pool.
#[test]
fn a_long_streamed_decode_gives_the_whole_decodes_samples() {
    let cases: [(Raster, usize, Boundary); 5] = [
        (
            field(&[160, 96, 128], 1, SampleType::U16, 7, 4000.0),
            3,
            Boundary::Symmetric,
        ),
        // planes of over 2^17 samples: their sums along axis 0 cut into pieces on the pool
        (
            field(&[24, 384, 352], 1, SampleType::U16, 11, 9000.0),
            3,
            Boundary::Symmetric,
        ),
        (
            field(&[136, 64, 80], 2, SampleType::I16, 8, 3000.0),
            4,
            Boundary::Periodic,
        ),
        (
            field(&[2300, 512], 1, SampleType::U16, 9, 60000.0),
            5,
            Boundary::Periodic,
        ),
        (
            field(&[1700, 700], 3, SampleType::U8, 10, 255.0),
            3,
            Boundary::Symmetric,
        ),
    ];
    let dir = common::scratch_dir("streamed_long");
    for (r, levels, boundary) in &cases {
        let s = streamed(r, &opts(Rate::Bpp(2.0), *levels, *boundary));
        let path = dir.join("s.mra");
        std::fs::write(&path, &s).unwrap();
        let whole = codec::decode(&s, &DecodeOptions::default()).unwrap().raster;
        let mut d = codec::StreamedDecoder::open(&path).unwrap();
        let (mut got, mut slabs) = (Vec::new(), 0);
        while let Some(slab) = d.next_slab().unwrap() {
            got.extend(slab.to_f64());
            slabs += 1;
        }
        assert!(slabs > 8, "{}: {slabs} slabs", r.summary());
        assert_eq!(got, whole.samples.to_f64(), "{} {boundary:?}", r.summary());
    }
}

/// `--bpp` codes the whole stream until it lands within 1% under the budget (the sampled
/// tiles alone, each its own small pyramid, miss it by a few percent), for images,
/// colour and volumes at several budgets.
#[test]
fn streamed_bpp_lands_within_one_percent_under_the_budget() {
    let cases = [
        (field(&[700, 300], 1, SampleType::U16, 21, 60000.0), 0.5),
        (field(&[700, 300], 1, SampleType::U16, 21, 60000.0), 2.0),
        (field(&[260, 190], 3, SampleType::U8, 22, 255.0), 1.0),
        (field(&[60, 48, 40], 1, SampleType::U16, 23, 9000.0), 1.0),
    ];
    for (r, b) in &cases {
        let s = streamed(r, &opts(Rate::Bpp(*b), 5, Boundary::Symmetric));
        let got = s.len() as f64 * 8.0 / r.positions() as f64;
        assert!(
            got <= *b && got >= 0.99 * b,
            "{} at --bpp {b}: {got} bits per position",
            r.summary()
        );
    }
}

/// Mean squared error of the decode of `f` against `r`.
fn mse(r: &Raster, f: &[u8]) -> f64 {
    let d = codec::decode(f, &DecodeOptions::default()).unwrap().raster;
    let (a, b) = (r.samples.to_f64(), d.samples.to_f64());
    a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64
}

/// At `--quality` (one step, optimised indices on both paths) the streamed file, whose
/// coarser detail bands choose their indices before their parent is known, is the
/// whole-array encoder's within 0.5% in bytes and in mean squared error.
#[test]
fn streamed_optimised_files_are_near_the_whole_encoders() {
    let cases = [
        (field(&[700, 300], 1, SampleType::U16, 31, 60000.0), 5),
        (field(&[60, 48, 40], 1, SampleType::U16, 33, 9000.0), 3),
    ];
    for (r, levels) in &cases {
        let o = opts(Rate::Quality(70.0), *levels, Boundary::Symmetric);
        let whole = codec::encode(r, &o).unwrap();
        let s = streamed(r, &o);
        let (bw, bs) = (whole.len() as f64, s.len() as f64);
        let (dw, ds) = (mse(r, &whole), mse(r, &s));
        eprintln!(
            "{}: whole {bw} B, mse {dw}; streamed {bs} B, mse {ds}",
            r.summary()
        );
        assert!(
            (bs / bw - 1.0).abs() < 0.005,
            "{}: {bs} vs {bw} bytes",
            r.summary()
        );
        assert!(
            (ds / dw - 1.0).abs() < 0.005,
            "{}: mse {ds} vs {dw}",
            r.summary()
        );
    }
}

/// A volume is one transform by default over the one-piece limit because the stream is
/// not below the tiles: at `--bpp` both land within the budget and the streamed file's
/// error is below the tiled file's (tiles of 16³, each its own pyramid, seams at their
/// faces), on a smooth field and on one whose content changes every 8 planes away from
/// the tiles' faces (the kind of change tiles would leave uncoded on a face).
#[test]
fn a_streamed_volume_is_not_below_its_tiles() {
    let smooth = field(&[48, 40, 36], 1, SampleType::U16, 41, 20000.0);
    // planes 0..4, 4..12, 12..20, …: each group a plane of a different field
    let planes = field(&[7, 40, 36], 1, SampleType::U16, 42, 20000.0);
    let (pl, n) = (40 * 36, 48);
    let src = planes.samples.to_f64();
    let stepped: Vec<u16> = (0..n)
        .flat_map(|z| {
            let k = (z + 4) / 8;
            src[k * pl..(k + 1) * pl].iter().map(|&v| v as u16)
        })
        .collect();
    let stepped = Raster::new(
        vec![n, 40, 36],
        1,
        mra::io::Samples::U16(stepped),
        smooth.kind,
    )
    .unwrap();
    for r in [&smooth, &stepped] {
        let o = opts(Rate::Bpp(1.0), 3, Boundary::Symmetric);
        let s = streamed(r, &o);
        let t = codec::encode_tiled(r, &o, &[16, 16, 16]).unwrap();
        let bits = |f: &[u8]| f.len() as f64 * 8.0 / r.positions() as f64;
        assert!(bits(&s) <= 1.0 && bits(&t) <= 1.0, "{}", r.summary());
        let (ms, mt) = (mse(r, &s), mse(r, &t));
        eprintln!(
            "{}: streamed {} bpp mse {ms}, tiles {} bpp mse {mt}",
            r.summary(),
            bits(&s),
            bits(&t)
        );
        assert!(ms < mt, "{}: mse {ms} streamed vs {mt} tiled", r.summary());
    }
}

/// A one-piece file of every block coder (efforts 1, 4 and 7: HT, adaptive, context),
/// per-level code-blocks included, decoded whole slab by slab by `StreamedDecoder` (what
/// `mra decode` to PPM, raw, NRRD or TIFF does over the one-piece limit: the bands
/// decoded a batch of stripes of code-blocks at a time and synthesized a few rows at a
/// time) gives the samples of the whole-array decode, for colour, 16-bit gray, periodic
/// ends and a volume; `mra decode` to PPM writes the bytes of the whole raster's PPM.
#[test]
fn a_one_piece_file_decodes_in_stripes_to_the_whole_decodes_samples() {
    let cases: [(Raster, usize, Boundary); 4] = [
        (
            field(&[389, 301], 3, SampleType::U8, 31, 255.0),
            5,
            Boundary::Symmetric,
        ),
        (
            field(&[517, 70], 1, SampleType::U16, 32, 60000.0),
            4,
            Boundary::Periodic,
        ),
        (
            field(&[133, 250], 3, SampleType::U8, 33, 255.0),
            3,
            Boundary::Periodic,
        ),
        (
            field(&[40, 37, 45], 1, SampleType::U16, 34, 4000.0),
            3,
            Boundary::Symmetric,
        ),
    ];
    let dir = common::scratch_dir("stripes_decode");
    for (r, levels, boundary) in &cases {
        for effort in [1u8, 4, 7] {
            let o = EncodeOptions {
                effort,
                ..opts(Rate::Bpp(1.5), *levels, *boundary)
            };
            let file = codec::encode(r, &o).unwrap();
            let path = dir.join("s.mra");
            std::fs::write(&path, &file).unwrap();
            let whole = codec::decode(&file, &DecodeOptions::default())
                .unwrap()
                .raster;
            let mut d = codec::StreamedDecoder::open(&path).unwrap();
            assert_eq!(d.shape().dims, r.dims);
            let (mut got, mut slabs) = (Vec::new(), 0);
            while let Some(slab) = d.next_slab().unwrap() {
                got.extend(slab.to_f64());
                slabs += 1;
            }
            let what = format!("{} effort {effort} {boundary:?}", r.summary());
            assert_eq!(got, whole.samples.to_f64(), "{what}");
            if r.positions() > 1 << 16 {
                assert!(slabs > 1, "{what}: {slabs} slab");
            }
            if r.dims.len() == 2 && r.channels == 3 && effort == 7 {
                let ppm = dir.join("s.ppm");
                let out = common::mra_with_stdin(
                    None,
                    &[
                        "decode",
                        path.to_str().unwrap(),
                        "-o",
                        ppm.to_str().unwrap(),
                    ],
                    b"",
                );
                assert!(
                    out.status.success(),
                    "{}",
                    String::from_utf8_lossy(&out.stderr)
                );
                let mut want = Vec::new();
                mra::io::pnm::write(&mut want, &whole).unwrap();
                assert_eq!(std::fs::read(&ppm).unwrap(), want, "{what}");
            }
        }
    }
}
