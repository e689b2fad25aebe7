//! A file parsed once serves many regions ([`codec::Opened`]): every region and level
//! decodes to what a fresh [`codec::decode`] of the same region gives, for one-piece
//! 3.0 files (lossy and lossless, 2-D and 3-D) and for the files read again on each call
//! (format 2, tiled, `--max-error`); one value serves two threads at once; a damaged
//! file fails at open with a one-line error.

use mra::codec::{self, DecodeOptions, EncodeOptions, Opened, Rate};
use mra::io::{DataKind, Raster, SampleType, Samples};
use std::ops::Range;

/// A smooth field with texture (xorshift), `channels` channels of type `ty`.
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let w = *dims.last().unwrap();
    let mut x = seed | 1;
    let v: Vec<f64> = (0..n)
        .map(|i| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let p = i / channels;
            let (px, py) = ((p % w) as f64, (p / w) as f64);
            let s = 0.5 + 0.35 * (px * 0.11 + (i % channels) as f64).sin() * (py * 0.05).cos();
            hi * (s + 0.08 * ((x >> 40) as f64 / (1u64 << 24) as f64 - 0.5)).clamp(0.0, 1.0)
        })
        .collect();
    let kind = if dims.len() == 3 {
        DataKind::Volume
    } else {
        DataKind::Image
    };
    Raster::new(dims.to_vec(), channels, Samples::from_f64(&v, ty), kind).unwrap()
}

fn fresh(bytes: &[u8], level: usize, region: Option<Vec<Range<usize>>>) -> Raster {
    let o = DecodeOptions {
        level,
        region,
        ..Default::default()
    };
    codec::decode(bytes, &o).unwrap().raster
}

/// Windows inside, at a corner, at the far corner and one sample wide.
fn windows(dims: &[usize]) -> Vec<Vec<Range<usize>>> {
    vec![
        dims.iter().map(|&d| d / 3..d / 3 + d / 4 + 1).collect(),
        dims.iter().map(|&d| 0..d / 5 + 1).collect(),
        dims.iter().map(|&d| d - d / 6 - 1..d).collect(),
        dims.iter().map(|&d| d / 2..d / 2 + 1).collect(),
    ]
}

fn assert_send_sync<T: Send + Sync>() {}

/// Every region and level of one opened file decodes as a fresh decode of it does,
/// whatever the file's layout.
#[test]
fn opened_regions_are_fresh_decodes() {
    assert_send_sync::<Opened>();
    let blocks = EncodeOptions::default();
    let bands = EncodeOptions {
        format: codec::Format::Bands,
        ..Default::default()
    };
    let cases: Vec<(Raster, EncodeOptions, usize, Option<Vec<usize>>)> = vec![
        (
            field(&[301, 419], 3, SampleType::U8, 3, 255.0),
            EncodeOptions {
                rate: Rate::Bpp(1.0),
                levels: 4,
                ..blocks.clone()
            },
            4,
            None,
        ),
        (
            field(&[150, 97], 1, SampleType::U16, 5, 60000.0),
            EncodeOptions {
                rate: Rate::Lossless,
                levels: 3,
                ..blocks.clone()
            },
            3,
            None,
        ),
        (
            field(&[37, 81, 75], 1, SampleType::I16, 7, 3000.0),
            EncodeOptions {
                rate: Rate::Quality(60.0),
                levels: 3,
                ..blocks.clone()
            },
            3,
            None,
        ),
        (
            field(&[61, 90], 1, SampleType::U8, 9, 255.0),
            EncodeOptions {
                rate: Rate::MaxError(2.0),
                levels: 2,
                ..blocks.clone()
            },
            2,
            None,
        ),
        (
            field(&[120, 130], 1, SampleType::U8, 11, 255.0),
            EncodeOptions {
                rate: Rate::Bpp(1.0),
                levels: 3,
                ..bands.clone()
            },
            3,
            None,
        ),
        (
            field(&[120, 130], 1, SampleType::U8, 13, 255.0),
            EncodeOptions {
                rate: Rate::Bpp(1.0),
                levels: 3,
                ..bands.clone()
            },
            3,
            Some(vec![64, 64]),
        ),
    ];
    for (r, o, levels, tile) in cases {
        let bytes = match &tile {
            Some(t) => codec::encode_tiled(&r, &o, t).unwrap(),
            None => codec::encode_tiled(&r, &o, &r.dims).unwrap(),
        };
        let opened = Opened::from_bytes(bytes.clone()).unwrap();
        assert_eq!(opened.header().dims, r.dims);
        for level in 0..=levels.min(2) {
            let whole = opened.region(level, None).unwrap().raster;
            assert_eq!(whole.samples, fresh(&bytes, level, None).samples);
            for win in windows(&r.dims) {
                let a = opened.region(level, Some(&win)).unwrap().raster;
                let b = fresh(&bytes, level, Some(win.clone()));
                assert_eq!(a.dims, b.dims, "{:?} {win:?} level {level}", r.dims);
                assert!(
                    a.samples == b.samples,
                    "{:?} {:?} {win:?} level {level}",
                    r.dims,
                    o.rate
                );
                assert_eq!(a.meta, b.meta);
            }
        }
        assert!(opened.region(levels + 1, None).is_err());
        let bad: Vec<Range<usize>> = r.dims.iter().map(|&d| d..d + 1).collect();
        assert!(opened.region(0, Some(&bad)).is_err());
    }
}

/// An opened file on disk serves regions from two threads at once, each what a fresh
/// decode of the file gives; a truncated file fails at open.
#[test]
fn an_opened_file_serves_two_threads() {
    let r = field(&[700, 650], 1, SampleType::U8, 17, 255.0);
    let o = EncodeOptions {
        rate: Rate::Bpp(1.5),
        levels: 5,
        ..Default::default()
    };
    let bytes = codec::encode_tiled(&r, &o, &r.dims).unwrap();
    let dir = std::env::temp_dir().join(format!("mra-region-opened-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.mra");
    std::fs::write(&path, &bytes).unwrap();
    let opened = Opened::open(&path).unwrap();
    let wins: Vec<Vec<Range<usize>>> = (0..8)
        .map(|i| vec![i * 80..i * 80 + 64, 600 - i * 70..650 - i * 70])
        .collect();
    std::thread::scope(|s| {
        for half in wins.chunks(4) {
            let (opened, bytes) = (&opened, &bytes);
            s.spawn(move || {
                for w in half {
                    for level in 0..2 {
                        let a = opened.region(level, Some(w)).unwrap().raster;
                        let b = fresh(bytes, level, Some(w.clone()));
                        assert!(a.samples == b.samples, "{w:?} level {level}");
                    }
                }
            });
        }
    });
    let cut = dir.join("cut.mra");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let e = Opened::open(&cut).err().expect("a truncated file fails at open");
    assert!(!e.to_string().contains('\n'), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

