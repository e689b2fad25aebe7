//! Format 3.0 code-blocks (formats/MRA.md §15): a one-piece format 2 file cut into
//! code-blocks decodes to the same samples at every level, 2-D and 3-D, lossy and
//! lossless, odd sizes; the bytes do not depend on the thread count; a damaged block
//! index is a one-line error, exit 2, no output.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::format::{put_chunk, put_varint, ChunkReader, Cursor, Header};
use mra::io::{Raster, SampleType};
use std::process::Command;

/// A smooth field with texture (xorshift), `channels` channels of type `ty`.
/// The codec tests' wave ([`common::wave_field`]).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.13,
        fy: 0.07,
        noise: 0.08,
    };
    common::wave_field(dims, channels, ty, seed, hi, wave)
}

/// The one-piece format 2 file of `r` (what `to_blocks` cuts).
fn encode(r: &Raster, rate: Rate, levels: usize) -> Vec<u8> {
    let o = EncodeOptions {
        rate,
        levels,
        format: codec::Format::Bands,
        ..Default::default()
    };
    codec::encode_tiled(r, &o, &r.dims).unwrap()
}

fn header(bytes: &[u8]) -> Header {
    let mut rd = ChunkReader::new(bytes, bytes.len() as u64).unwrap();
    let head = rd.next_chunk().unwrap().unwrap();
    Header::parse(&head.payload).unwrap()
}

/// The samples of a decode at `level` (whole raster, or `region`).
fn decoded(bytes: &[u8], level: usize, region: Option<Vec<std::ops::Range<usize>>>) -> Raster {
    let o = DecodeOptions {
        level,
        region,
        ..Default::default()
    };
    codec::decode(bytes, &o).unwrap().raster
}

/// Cut into code-blocks, 2-D RGB and gray, a 3-D volume, lossy and lossless, odd sizes
/// and bands both smaller and larger than a block: version 3.0, and every level (and a
/// region) decodes to the samples of the format 2 file.
#[test]
fn code_blocks_decode_as_the_format_2_file() {
    let cases: Vec<(Raster, Rate, usize)> = vec![
        (
            field(&[149, 203], 3, SampleType::U8, 3, 255.0),
            Rate::Bpp(1.0),
            4,
        ),
        (
            field(&[130, 67], 1, SampleType::U16, 5, 60000.0),
            Rate::Lossless,
            3,
        ),
        (
            field(&[37, 41, 35], 1, SampleType::I16, 7, 3000.0),
            Rate::Quality(60.0),
            3,
        ),
        (
            field(&[21, 9, 70], 1, SampleType::U8, 9, 255.0),
            Rate::MaxError(2.0),
            2,
        ),
        (
            field(&[517, 389], 1, SampleType::U8, 15, 255.0),
            Rate::Bpp(0.8),
            5,
        ),
        (
            field(&[45, 99, 131], 1, SampleType::U16, 17, 4000.0),
            Rate::Bpp(0.5),
            3,
        ),
    ];
    for (r, rate, levels) in cases {
        let two = encode(&r, rate, levels);
        let three = codec::to_blocks(&two).unwrap();
        assert_eq!(header(&two).version.major, 2);
        assert_eq!(header(&three).version, mra::format::Version::LEVEL_BLOCKS);
        assert_eq!(
            codec::to_blocks(&three).unwrap(),
            three,
            "3.0 stays as it is"
        );
        for level in 0..=levels {
            let a = decoded(&two, level, None);
            let b = decoded(&three, level, None);
            assert_eq!(a.dims, b.dims, "{:?} level {level}", r.dims);
            assert_eq!(a.samples, b.samples, "{:?} {rate:?} level {level}", r.dims);
        }
        // a 3.0 region decodes only the blocks its support meets: the samples of the
        // whole decode cut to the region (the 2.x decode of a region is that)
        let wins: Vec<Vec<std::ops::Range<usize>>> = vec![
            r.dims.iter().map(|&d| d / 3..d / 3 + d / 4 + 1).collect(),
            r.dims.iter().map(|&d| 0..d / 5 + 1).collect(),
            r.dims.iter().map(|&d| d - d / 6 - 1..d).collect(),
        ];
        for win in wins {
            for level in 0..=levels.min(2) {
                let a = decoded(&two, level, Some(win.clone()));
                let b = decoded(&three, level, Some(win.clone()));
                assert_eq!(a.dims, b.dims);
                assert_eq!(a.samples, b.samples, "{:?} {win:?} level {level}", r.dims);
            }
        }
        if rate == Rate::Lossless {
            assert_eq!(decoded(&three, 0, None).samples, r.samples);
        }
    }
}

/// A 3.0 region of a lossy file is decoded from the code-blocks its support meets and
/// synthesized over that support alone: its samples are those of the same window cut
/// from a whole decode, for every scheme and boundary, 2-D and 3-D, odd sizes over
/// several blocks, levels 0 to 2, windows inside and at the edges.
#[test]
fn regions_of_code_blocks_are_windows_of_the_whole_decode() {
    use mra::scheme::{Boundary, Scheme};
    let cases: Vec<(Raster, usize)> = vec![
        (field(&[611, 529], 1, SampleType::U8, 21, 255.0), 4),
        (field(&[70, 139, 133], 1, SampleType::U16, 23, 4000.0), 3),
    ];
    for (r, levels) in cases {
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                if r.dims.len() == 3 && !matches!(scheme, Scheme::Cdf97 | Scheme::Haar) {
                    continue;
                }
                let o = EncodeOptions {
                    rate: Rate::Bpp(1.0),
                    levels,
                    scheme,
                    boundary,
                    format: codec::Format::Bands,
                    effort: mra::codec::DEFAULT_EFFORT,
                };
                let two = codec::encode_tiled(&r, &o, &r.dims).unwrap();
                let three = codec::to_blocks(&two).unwrap();
                let wins: Vec<Vec<std::ops::Range<usize>>> = vec![
                    r.dims.iter().map(|&d| d / 2..d / 2 + d / 7 + 1).collect(),
                    r.dims.iter().map(|&d| 0..d / 9 + 1).collect(),
                    r.dims.iter().map(|&d| d - d / 8 - 1..d).collect(),
                    r.dims.iter().map(|&d| d - 1..d).collect(),
                ];
                for win in wins {
                    for level in 0..=2 {
                        let a = decoded(&two, level, Some(win.clone()));
                        let b = decoded(&three, level, Some(win.clone()));
                        assert_eq!(a.dims, b.dims);
                        assert!(
                            a.samples == b.samples,
                            "{:?} {scheme:?} {boundary:?} {win:?} level {level}",
                            r.dims
                        );
                    }
                }
            }
        }
    }
}

/// The bytes of a 3.0 file are the same on one thread and on two.
#[test]
fn code_blocks_do_not_depend_on_the_thread_count() {
    let r = field(&[600, 530], 3, SampleType::U8, 11, 255.0);
    let two = encode(&r, Rate::Bpp(1.5), 5);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| codec::to_blocks(&two).unwrap())
    };
    let one = on(1);
    assert_eq!(one, on(2));
    assert_eq!(
        decoded(&one, 0, None).samples,
        decoded(&two, 0, None).samples
    );
}

/// A change to a block count and its lengths.
type Edit = dyn Fn(&mut u64, &mut Vec<u64>);

/// The file with the first band entry of its first `LEVL` chunk (a gray image: the
/// coarse block) rebuilt with its block count and lengths changed by `edit`.
fn forge(bytes: &[u8], edit: impl Fn(&mut u64, &mut Vec<u64>)) -> Vec<u8> {
    let mut rd = ChunkReader::new(bytes, bytes.len() as u64).unwrap();
    let mut out = mra::format::SIGNATURE.to_vec();
    let mut done = false;
    while let Ok(ch) = rd.next_chunk().unwrap() {
        if &ch.kind != b"LEVL" || done {
            put_chunk(&mut out, &ch.kind, &ch.payload);
            continue;
        }
        done = true;
        let mut cur = Cursor::new(&ch.payload, "LEVL");
        let level = cur.u16().unwrap();
        let ratio = cur.f32().unwrap();
        let len = cur.varint().unwrap() as usize;
        let entry = cur.take(len).unwrap();
        let rest = cur.take(ch.payload.len() - cur.pos).unwrap();
        let mut e = Cursor::new(entry, "entry");
        let mut n = e.varint().unwrap();
        let mut lens: Vec<u64> = (0..n).map(|_| e.varint().unwrap()).collect();
        let blocks = e.take(entry.len() - e.pos).unwrap().to_vec();
        edit(&mut n, &mut lens);
        let mut ne = Vec::new();
        put_varint(&mut ne, n);
        for &l in &lens {
            put_varint(&mut ne, l);
        }
        ne.extend_from_slice(&blocks);
        let mut p = level.to_le_bytes().to_vec();
        p.extend_from_slice(&ratio.to_le_bytes());
        put_varint(&mut p, ne.len() as u64);
        p.extend_from_slice(&ne);
        p.extend_from_slice(rest);
        put_chunk(&mut out, &ch.kind, &p);
    }
    out
}

/// A block index pointing outside its entry, blocks overlapping or missing, a block
/// count that is not the band's: `mra decode` exits 2 with one line naming the file,
/// and writes nothing.
#[test]
fn damaged_block_indices_are_one_line_errors() {
    // a coarse block of 9×8 in one code-block (3 levels of 300×290 … 5 levels)
    let r = field(&[300, 290], 1, SampleType::U8, 13, 255.0);
    let three = codec::to_blocks(&encode(&r, Rate::Bpp(2.0), 5)).unwrap();
    let dir = std::env::temp_dir().join(format!("mra-codeblocks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases: Vec<(&str, Box<Edit>)> = vec![
        ("outside", Box::new(|_, l| l[0] += 100_000)),
        ("overlap", Box::new(|_, l| l[0] += 1)),
        ("missing", Box::new(|_, l| l[0] -= 1)),
        (
            "count",
            Box::new(|n, l| {
                *n += 1;
                l.push(0)
            }),
        ),
    ];
    for (name, edit) in cases {
        let bad = forge(&three, edit);
        assert!(
            codec::decode(&bad, &DecodeOptions::default()).is_err(),
            "{name}"
        );
        let input = dir.join(format!("{name}.mra"));
        std::fs::write(&input, &bad).unwrap();
        // whole, and a region read by position (to an image, and streamed to NRRD)
        for (extra, ext) in [
            (vec![], "png"),
            (vec!["--region", "10:200,20:100"], "png"),
            (vec!["--region", "10:200,20:100", "--level", "1"], "nrrd"),
        ] {
            let output = dir.join(format!("{name}.{ext}"));
            let mut args = vec![
                "decode",
                input.to_str().unwrap(),
                "-o",
                output.to_str().unwrap(),
            ];
            args.extend(extra.iter().copied());
            let o = Command::new(env!("CARGO_BIN_EXE_mra"))
                .args(&args)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{name} {extra:?}: {err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
            assert!(err.contains(&format!("{name}.mra")), "{name}: {err}");
            assert!(!output.exists(), "{name} {extra:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--blocks` writes one-piece files: with a tile grid it stops before reading the input,
/// with one line naming both options (exit 2, no output); without `--tile` it writes a
/// 3.0 file of one piece.
#[test]
fn blocks_refuse_a_tile_grid_and_write_one_piece() {
    let dir = std::env::temp_dir().join(format!("mra-codeblocks-tile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("in.pgm");
    let r = field(&[70, 90], 1, SampleType::U8, 3, 255.0);
    mra::io::write(&input, &r).unwrap();
    let run = |extra: &[&str], out: &std::path::Path| {
        let mut args = vec![
            "encode",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--bpp",
            "2",
            "--blocks",
        ];
        args.extend_from_slice(extra);
        Command::new(env!("CARGO_BIN_EXE_mra"))
            .args(&args)
            .output()
            .unwrap()
    };
    let tiled = dir.join("tiled.mra");
    let o = run(&["--tile", "32"], &tiled);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("--blocks") && err.contains("--tile"), "{err}");
    assert!(!tiled.exists());
    let one = dir.join("one.mra");
    let o = run(&[], &one);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let h = header(&std::fs::read(&one).unwrap());
    assert!(h.version.has_blocks(), "{:?}", h.version);
    assert_eq!(h.tile, h.dims);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A region of a one-piece 3.0 file read from disk reads the heads, the code-block
/// indices and the blocks it needs, not the file: `mra decode --region --json` reports
/// the bytes it read (under half of this small file, whose finest bands are 3×3
/// blocks), and the samples are the same window of the whole decode.
#[test]
fn a_region_reads_only_its_code_blocks() {
    let r = field(&[1100, 1300], 1, SampleType::U8, 31, 255.0);
    let three = codec::to_blocks(&encode(&r, Rate::Bpp(2.0), 5)).unwrap();
    let dir = std::env::temp_dir().join(format!("mra-codeblocks-read-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("a.mra");
    std::fs::write(&input, &three).unwrap();
    let output = dir.join("a.nrrd");
    let o = Command::new(env!("CARGO_BIN_EXE_mra"))
        .args([
            "decode",
            input.to_str().unwrap(),
            "-o",
            output.to_str().unwrap(),
            "--region",
            "700:800,600:700",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let read = v["bytes_read"].as_u64().unwrap();
    assert!(
        read * 2 < three.len() as u64,
        "{read} bytes read of {}",
        three.len()
    );
    let win = vec![600..700, 700..800];
    let whole = codec::decode_file(&input, &DecodeOptions::default())
        .unwrap()
        .raster;
    let part = codec::decode_file(
        &input,
        &DecodeOptions {
            region: Some(win.clone()),
            ..Default::default()
        },
    )
    .unwrap()
    .raster;
    assert_eq!(part.dims, vec![100, 100]);
    let w = whole.dims[1];
    for y in 0..100 {
        for x in 0..100 {
            let i = (600 + y) * w + 700 + x;
            assert_eq!(
                part.samples.get_f64(y * 100 + x),
                whole.samples.get_f64(i),
                "{y} {x}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
