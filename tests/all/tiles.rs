//! Files of more than one tile (formats/MRA.md §14): every rate mode round-trips tiled,
//! the bytes do not depend on the thread count, `--level` and `--region` decode what a
//! one-piece decode would (cut to the region), only the tiles a region meets are read,
//! and the container names a missing, repeated or misplaced tile.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::{DataKind, Raster, SampleType, Samples};
use mra::scheme::{Boundary, Scheme};
use mra::ErrorKind;
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;

fn field(dims: &[usize], channels: usize, ty: SampleType, kind: DataKind) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let w = *dims.last().unwrap();
    let h = if dims.len() >= 2 {
        dims[dims.len() - 2]
    } else {
        1
    };
    let v: Vec<f64> = (0..n)
        .map(|i| {
            let p = i / channels;
            let (x, y, z) = ((p % w) as f64, ((p / w) % h) as f64, (p / w / h) as f64);
            120.0
                + 80.0 * (x * 0.13 + (i % channels) as f64).sin() * (y * 0.09 + z * 0.2).cos()
                + ((i * 7919) % 17) as f64
        })
        .collect();
    Raster::new(dims.to_vec(), channels, Samples::from_f64(&v, ty), kind).unwrap()
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

fn dec(
    bytes: &[u8],
    level: usize,
    region: Option<Vec<Range<usize>>>,
) -> mra::Result<codec::Decoded> {
    codec::decode(
        bytes,
        &DecodeOptions {
            level,
            allow_truncated: false,
            region,
        },
    )
}

fn psnr(a: &Raster, b: &Raster) -> f64 {
    let (x, y) = (a.to_f64(), b.to_f64());
    let mse = x
        .iter()
        .zip(&y)
        .map(|(p, q)| (p - q) * (p - q))
        .sum::<f64>()
        / x.len() as f64;
    10.0 * (255.0f64 * 255.0 / mse).log10()
}

/// The chunks of a file: (type, start, end) with `end` past the CRC.
fn chunks(bytes: &[u8]) -> Vec<([u8; 4], usize, usize)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 12 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let kind: [u8; 4] = bytes[at + 4..at + 8].try_into().unwrap();
        out.push((kind, at, at + 12 + len));
        at += 12 + len;
    }
    out
}

fn crc(kind: &[u8], payload: &[u8]) -> [u8; 4] {
    let mut c = mra::format::crc::Crc32c::new();
    c.update(kind);
    c.update(payload);
    c.finish().to_le_bytes()
}

/// A chunk rebuilt with a new payload (its CRC recomputed).
fn chunk(kind: &[u8; 4], payload: &[u8]) -> Vec<u8> {
    let mut v = (payload.len() as u32).to_le_bytes().to_vec();
    v.extend_from_slice(kind);
    v.extend_from_slice(payload);
    v.extend_from_slice(&crc(kind, payload));
    v
}

#[test]
fn lossless_tiles_decode_bit_exact_for_every_type_and_odd_grid() {
    let cases = [
        field(&[37, 53], 1, SampleType::U16, DataKind::Image),
        field(&[29, 31], 3, SampleType::U8, DataKind::Image),
        field(&[9, 13, 11], 1, SampleType::I16, DataKind::Volume),
        field(&[21, 19], 1, SampleType::F32, DataKind::Heightmap),
    ];
    for r in &cases {
        let tile: Vec<usize> = r.dims.iter().map(|&d| (d / 3).max(2)).collect();
        let bytes = codec::encode_tiled(r, &opts(Rate::Lossless), &tile).unwrap();
        assert_eq!((bytes[16], bytes[17]), (2, 1), "a tiled file is format 2.1");
        let d = dec(&bytes, 0, None).unwrap();
        assert!(d.complete);
        assert_eq!(d.raster.dims, r.dims);
        assert_eq!(d.raster.samples, r.samples, "{}", r.summary());
        // read in order (no seeking) to the same samples
        let s = codec::decode_stream(&bytes[..], bytes.len() as u64, &DecodeOptions::default())
            .unwrap();
        assert_eq!(s.raster.samples, r.samples);
    }
}

#[test]
fn one_tile_is_the_format_2_0_file_of_before() {
    let r = field(&[40, 60], 3, SampleType::U8, DataKind::Image);
    let o = EncodeOptions {
        format: codec::Format::Bands,
        ..opts(Rate::Quality(50.0))
    };
    let a = codec::encode(&r, &o).unwrap();
    let b = codec::encode_tiled(&r, &o, &[40, 60]).unwrap();
    assert_eq!(a, b);
    assert_eq!((a[16], a[17]), (2, 0));
    assert_eq!(codec::default_tile(&[512, 768], 3), vec![512, 768]);
    assert_eq!(codec::default_tile(&[16384, 16384], 1), vec![1024, 1024]);
    assert_eq!(
        codec::default_tile(&[1024, 1024, 1024], 1),
        vec![128, 128, 128]
    );
    // up to 2^26 samples in one piece: the seams' sizes of issue 52
    assert_eq!(codec::default_tile(&[6000, 6000], 1), vec![6000, 6000]);
    assert_eq!(
        codec::default_tile(&[256, 512, 512], 1),
        vec![256, 512, 512]
    );
    assert_eq!(codec::default_tile(&[6000, 6000], 3), vec![1024, 1024]);
    assert_eq!(codec::default_tile(&[4096, 4096], 4), vec![4096, 4096]);
}

#[test]
fn every_lossy_rate_mode_works_tiled_at_one_quality() {
    let r = field(&[128, 192], 3, SampleType::U8, DataKind::Image);
    let tile = [64, 64];
    for rate in [
        Rate::Quality(45.0),
        Rate::Keep(10.0),
        Rate::Threshold(4.0),
        Rate::Psnr(38.0),
        Rate::Bpp(1.5),
    ] {
        let one = codec::encode(&r, &opts(rate)).unwrap();
        let tiled = codec::encode_tiled(&r, &opts(rate), &tile).unwrap();
        let (a, b) = (
            dec(&one, 0, None).unwrap().raster,
            dec(&tiled, 0, None).unwrap().raster,
        );
        assert_eq!(b.dims, r.dims);
        let (pa, pb) = (psnr(&r, &a), psnr(&r, &b));
        let bpp = tiled.len() as f64 * 8.0 / r.positions() as f64;
        match rate {
            Rate::Psnr(db) => assert!(pb >= db - 0.05, "{rate:?}: {pb} dB"),
            Rate::Bpp(t) => assert!(bpp <= t && bpp > 0.9 * t, "{rate:?}: {bpp} bpp"),
            // the same step: the same quality within the seams' cost
            _ => assert!(
                (pa - pb).abs() < 1.5,
                "{rate:?}: one piece {pa} dB, tiles {pb} dB"
            ),
        }
    }
}

#[test]
fn max_error_bound_holds_in_every_tile() {
    for (ty, e) in [(SampleType::U16, 3.0), (SampleType::F32, 0.25)] {
        let r = field(&[45, 50], 1, ty, DataKind::Heightmap);
        let bytes = codec::encode_tiled(&r, &opts(Rate::MaxError(e)), &[16, 20]).unwrap();
        let d = dec(&bytes, 0, None).unwrap().raster;
        let worst = r
            .to_f64()
            .iter()
            .zip(d.to_f64())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst <= e, "{ty:?}: {worst} > {e}");
        assert!(worst > 0.0);
    }
}

#[test]
fn the_bytes_do_not_depend_on_the_thread_count() {
    let r = field(&[70, 90], 3, SampleType::U8, DataKind::Image);
    for rate in [
        Rate::Quality(50.0),
        Rate::Bpp(1.0),
        Rate::Lossless,
        Rate::MaxError(2.0),
    ] {
        let many = codec::encode_tiled(&r, &opts(rate), &[32, 32]).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let one = pool
            .install(|| codec::encode_tiled(&r, &opts(rate), &[32, 32]))
            .unwrap();
        assert_eq!(many, one, "{rate:?}");
        let a = pool.install(|| dec(&many, 0, None)).unwrap().raster;
        let b = dec(&many, 0, None).unwrap().raster;
        assert_eq!(a.samples, b.samples);
    }
}

#[test]
fn levels_decode_tiled_to_the_one_piece_extents() {
    // the last tile of each axis long enough for 3 levels of CDF 9/7 (16 samples)
    let r = field(&[112, 80], 1, SampleType::U16, DataKind::Image);
    for rate in [Rate::Quality(60.0), Rate::Lossless] {
        let one = codec::encode(&r, &opts(rate)).unwrap();
        let tiled = codec::encode_tiled(&r, &opts(rate), &[32, 32]).unwrap();
        for k in 1..=3 {
            let a = dec(&one, k, None).unwrap().raster;
            let b = dec(&tiled, k, None).unwrap().raster;
            assert_eq!(a.dims, b.dims, "{rate:?} level {k}");
            // a reduced tile is its own coarse block: close to the one-piece one
            let p = psnr(&a, &b);
            assert!(p > 25.0, "{rate:?} level {k}: {p} dB apart");
        }
    }
}

#[test]
fn a_region_decodes_to_the_cut_of_the_whole() {
    let r = field(&[50, 70], 1, SampleType::U16, DataKind::Image);
    let regions = [
        vec![12..20, 5..37],
        vec![49..50, 0..70],
        vec![0..50, 33..34],
    ];
    for tile in [vec![50, 70], vec![16, 16]] {
        for rate in [Rate::Quality(55.0), Rate::Lossless] {
            let bytes = codec::encode_tiled(&r, &opts(rate), &tile).unwrap();
            for k in [0, 1, 2] {
                let whole = dec(&bytes, k, None).unwrap().raster;
                for reg in &regions {
                    let part = dec(&bytes, k, Some(reg.clone())).unwrap().raster;
                    // the level's samples whose cells meet the box (slowest axis first in
                    // the option, as `dims`)
                    let (y, x) = (&reg[0], &reg[1]);
                    let (h, w) = (whole.dims[0], whole.dims[1]);
                    let ys = y.start * h / 50..(y.end * h).div_ceil(50);
                    let xs = x.start * w / 70..(x.end * w).div_ceil(70);
                    assert_eq!(part.dims, vec![ys.len(), xs.len()], "{tile:?} {k} {reg:?}");
                    let wv = whole.to_f64();
                    let pv = part.to_f64();
                    for (j, yy) in ys.clone().enumerate() {
                        for (i, xx) in xs.clone().enumerate() {
                            assert_eq!(
                                pv[j * xs.len() + i],
                                wv[yy * w + xx],
                                "{tile:?} {k} {reg:?}"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// A reader counting the bytes it hands out.
struct Counting<R> {
    inner: R,
    read: u64,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        Ok(n)
    }
}

impl<R: Seek> Seek for Counting<R> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(pos)
    }
}

#[test]
fn a_region_reads_only_the_tiles_it_meets() {
    let r = field(&[32, 64, 64], 1, SampleType::I16, DataKind::Volume);
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(50.0)), &[16, 16, 16]).unwrap();
    let whole = dec(&bytes, 0, None).unwrap().raster;
    let mut src = Counting {
        inner: std::io::Cursor::new(&bytes),
        read: 0,
    };
    // one tile of the 32 (z, y, x)
    let reg = vec![16..32, 0..16, 16..32];
    let d = codec::decode_seek(
        &mut src,
        bytes.len() as u64,
        &DecodeOptions {
            region: Some(reg.clone()),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(d.raster.dims, vec![16, 16, 16]);
    let want = {
        let v = whole.to_f64();
        let mut out = Vec::new();
        for z in 16..32 {
            for y in 0..16 {
                for x in 16..32 {
                    out.push(v[(z * 64 + y) * 64 + x]);
                }
            }
        }
        out
    };
    assert_eq!(d.raster.to_f64(), want);
    let tile_bytes = bytes.len() as f64 / 32.0;
    assert!(
        (src.read as f64) < 2.0 * tile_bytes + 1024.0,
        "{} bytes read of {} ({} tiles)",
        src.read,
        bytes.len(),
        32
    );
}

#[test]
fn metadata_survives_tiles_levels_and_regions() {
    let mut r = field(&[40, 48], 1, SampleType::U16, DataKind::Heightmap);
    r.meta.spacing = Some(vec![2.0, 3.0]);
    r.meta.origin = Some(vec![100.0, 200.0]);
    r.meta.units = Some("m".into());
    r.meta.nodata = Some(0.0);
    let bytes = codec::encode_tiled(&r, &opts(Rate::Lossless), &[16, 16]).unwrap();
    let d = dec(&bytes, 0, None).unwrap().raster;
    assert_eq!(d.meta, r.meta);
    // rows 4..8, columns 10..20 (slowest axis first); the origin is x, y
    let part = dec(&bytes, 0, Some(vec![4..8, 10..20])).unwrap().raster;
    assert_eq!(part.meta.spacing, r.meta.spacing);
    assert_eq!(
        part.meta.origin,
        Some(vec![100.0 + 10.0 * 3.0, 200.0 + 4.0 * 2.0])
    );
    assert_eq!(part.meta.units.as_deref(), Some("m"));
    let one = codec::encode(&r, &opts(Rate::Lossless)).unwrap();
    let (a, b) = (
        dec(&one, 1, None).unwrap().raster,
        dec(&bytes, 1, None).unwrap().raster,
    );
    assert_eq!(a.meta, b.meta);
}

#[test]
fn voids_come_back_in_a_tiled_file() {
    let mut r = field(&[30, 40], 1, SampleType::F32, DataKind::Heightmap);
    let mut v = r.to_f64();
    for i in [0usize, 17, 455, 456, 1199] {
        v[i] = f64::NAN;
    }
    r.samples = Samples::from_f64(&v, SampleType::F32);
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(60.0)), &[16, 16]).unwrap();
    let d = dec(&bytes, 0, None).unwrap().raster.to_f64();
    for (i, x) in d.iter().enumerate() {
        assert_eq!(x.is_nan(), v[i].is_nan(), "sample {i}");
    }
}

#[test]
fn info_shows_the_grid_and_bytes_per_level() {
    let r = field(&[40, 70], 1, SampleType::U8, DataKind::Image);
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(50.0)), &[16, 32]).unwrap();
    let i = codec::info(&bytes).unwrap();
    // lossy tiles are compact (2.2): one TRAT chunk for the grid's four tile classes
    assert_eq!(i.version, "2.2");
    assert_eq!((i.tile.clone(), i.tiles), (vec![16, 32], 9));
    assert!(i.complete);
    assert_eq!(i.chunks.iter().filter(|c| c.kind == "TILE").count(), 9);
    assert_eq!(i.chunks.iter().filter(|c| c.kind == "TRAT").count(), 1);
    let coded: u64 = i.levels_bytes.iter().map(|l| l.1).sum();
    assert!(coded > 0 && coded < bytes.len() as u64);
    // lossless tiles stay 2.1
    let lossless = codec::encode_tiled(&r, &opts(Rate::Lossless), &[16, 32]).unwrap();
    assert_eq!(codec::info(&lossless).unwrap().version, "2.1");
}

#[test]
fn a_missing_repeated_or_misplaced_tile_is_named() {
    let r = field(&[40, 40], 1, SampleType::U8, DataKind::Image);
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(50.0)), &[20, 20]).unwrap();
    let cs = chunks(&bytes);
    let tiles: Vec<_> = cs.iter().filter(|c| &c.0 == b"TILE").cloned().collect();
    assert_eq!(tiles.len(), 4);
    let in_order = |b: &[u8], t: bool| {
        codec::decode_stream(
            b,
            b.len() as u64,
            &DecodeOptions {
                allow_truncated: t,
                ..Default::default()
            },
        )
    };
    let seek = |b: &[u8], t: bool| {
        codec::decode(
            b,
            &DecodeOptions {
                allow_truncated: t,
                ..Default::default()
            },
        )
    };
    // tile 2 left out
    let missing = [&bytes[..tiles[2].1], &bytes[tiles[2].2..]].concat();
    let e = in_order(&missing, false).err().unwrap();
    assert!(
        matches!(e.kind(), ErrorKind::Format) && e.to_string().contains("tile 2"),
        "{e}"
    );
    let e = seek(&missing, false).err().unwrap();
    assert!(e.to_string().contains("tile"), "{e}");
    let d = in_order(&missing, true).unwrap();
    assert!(!d.complete);
    // tile 1 twice
    let twice = [
        &bytes[..tiles[2].2],
        &bytes[tiles[1].1..tiles[1].2],
        &bytes[tiles[2].2..],
    ]
    .concat();
    let e = in_order(&twice, false).err().unwrap();
    assert!(
        e.to_string().contains("second TILE chunk for tile 1"),
        "{e}"
    );
    // a tile index out of the grid
    let (_, s, en) = tiles[3];
    let mut p = bytes[s + 8..en - 4].to_vec();
    p[..4].copy_from_slice(&7u32.to_le_bytes());
    let bad = [&bytes[..s], &chunk(b"TILE", &p), &bytes[en..]].concat();
    let e = in_order(&bad, false).err().unwrap();
    assert!(e.to_string().contains("tile 7"), "{e}");
    let e = seek(&bad, false).err().unwrap();
    assert!(e.to_string().contains("tile 7"), "{e}");
    // an index entry pointing at the wrong tile
    let (_, s, en) = cs.iter().find(|c| &c.0 == b"TIDX").cloned().unwrap();
    let mut idx = bytes[s + 8..en - 4].to_vec();
    let e0: Vec<u8> = idx[..16].to_vec();
    idx.copy_within(16..32, 0);
    idx[16..32].copy_from_slice(&e0);
    let swapped = [&bytes[..s], &chunk(b"TIDX", &idx), &bytes[en..]].concat();
    let e = seek(&swapped, false).err().unwrap();
    assert!(e.to_string().contains("TIDX entry of tile 0"), "{e}");
    // an index entry past the file's end
    let mut idx = bytes[s + 8..en - 4].to_vec();
    idx[48..56].copy_from_slice(&(u64::MAX - 8).to_le_bytes());
    let far = [&bytes[..s], &chunk(b"TIDX", &idx), &bytes[en..]].concat();
    let e = seek(&far, false).err().unwrap();
    assert!(e.to_string().contains("tile 3"), "{e}");
    // truncated anywhere: an error, or with the flag a decode that is never complete
    for cut in [tiles[1].1 + 20, tiles[3].2, bytes.len() - 1] {
        let part = &bytes[..cut];
        assert!(seek(part, false).is_err(), "cut at {cut}");
        assert!(in_order(part, false).is_err(), "cut at {cut}");
        let d = seek(part, true).unwrap();
        assert!(!d.complete && d.raster.dims == r.dims, "cut at {cut}");
        assert!(!in_order(part, true).unwrap().complete, "cut at {cut}");
    }
}

#[test]
fn bad_tile_extents_and_regions_are_parameter_errors() {
    let r = field(&[20, 20], 1, SampleType::U8, DataKind::Image);
    for tile in [vec![0, 5], vec![21, 5], vec![5]] {
        let e = codec::encode_tiled(&r, &opts(Rate::Quality(50.0)), &tile)
            .err()
            .unwrap();
        assert!(matches!(e.kind(), ErrorKind::Parameter), "{tile:?}: {e}");
    }
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(50.0)), &[8, 8]).unwrap();
    #[allow(clippy::single_range_in_vec_init)] // one range for a 2-D raster: the error
    for reg in [vec![0..5], vec![0..5, 3..3], vec![0..21, 0..5]] {
        let e = dec(&bytes, 0, Some(reg.clone())).err().unwrap();
        assert!(matches!(e.kind(), ErrorKind::Parameter), "{reg:?}: {e}");
    }
}

fn vector(name: &str) -> Vec<u8> {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("formats/vectors");
    std::fs::read(dir.join(name)).unwrap()
}

/// Format 2.2 stores a lossy tile as its range and its streams (the rest from `HEAD`
/// and `TRAT`): the 2.1 and 2.2 files of one raster decode to the same samples at
/// every level and region, and each of the 9 tiles saves at least its `HEAD` chunk
/// (80 bytes) and its `MEND` (12).
#[test]
fn compact_tiles_decode_as_the_chunks_they_stand_for_and_save_the_headers() {
    let old = vector("tiled_gray16_q40.mra");
    let new = vector("tiled22_gray16_q40.mra");
    // HEAD's payload starts at byte 16: major, minor
    assert_eq!((old[17], new[17]), (1, 2), "minor versions");
    let tiles = chunks(&new).iter().filter(|c| &c.0 == b"TILE").count();
    assert_eq!(tiles, 9);
    assert!(
        new.len() + 92 * tiles <= old.len(),
        "{} bytes against {}",
        new.len(),
        old.len()
    );
    for level in [0, 1, 2] {
        for region in [None, Some(vec![9..10, 3..11])] {
            let a = dec(&old, level, region.clone()).unwrap().raster;
            let b = dec(&new, level, region.clone()).unwrap().raster;
            assert_eq!(a.samples, b.samples, "level {level} {region:?}");
            assert_eq!(a.meta, b.meta, "level {level} {region:?}");
        }
    }
    // the encoder writes lossy tiles compact, and what it writes decodes in order too
    let r = field(&[18, 21], 1, SampleType::U16, DataKind::Image);
    let bytes = codec::encode_tiled(&r, &opts(Rate::Quality(45.0)), &[8, 8]).unwrap();
    let seek = codec::decode(&bytes, &DecodeOptions::default()).unwrap();
    let in_order =
        codec::decode_stream(&bytes[..], bytes.len() as u64, &DecodeOptions::default()).unwrap();
    assert_eq!(bytes[17], 2);
    assert_eq!(seek.raster.samples, in_order.raster.samples);
    assert!(psnr(&r, &seek.raster) > 30.0);
}

/// What a 2.2 reader must reject (formats/MRA.md §14.1): another form, a stream
/// length past the payload, bytes after the last stream, a missing `TRAT`, a `TRAT` of
/// the wrong length or with a ratio that is not positive, and a `TRAT` in a 2.1 file.
#[test]
fn a_bad_compact_tile_or_trat_chunk_is_named() {
    let good = vector("tiled22_gray16_q40.mra");
    let cs = chunks(&good);
    let (_, ts, te) = cs.iter().find(|c| &c.0 == b"TILE").cloned().unwrap();
    let (_, rs, re) = cs.iter().find(|c| &c.0 == b"TRAT").cloned().unwrap();
    let tile = good[ts + 8..te - 4].to_vec();
    let with_tile = |p: &[u8]| [&good[..ts], &chunk(b"TILE", p), &good[te..]].concat();
    let with_trat = |p: &[u8]| [&good[..rs], &chunk(b"TRAT", p), &good[re..]].concat();
    let both = |b: &[u8]| {
        let o = DecodeOptions::default();
        [
            codec::decode(b, &o).err().map(|e| e.to_string()),
            codec::decode_stream(b, b.len() as u64, &o)
                .err()
                .map(|e| e.to_string()),
        ]
    };
    // payload: index (4), form (1), min and max (16), then the first stream's length
    let mut p = tile.clone();
    p[4] = 7;
    for e in both(&with_tile(&p)) {
        assert!(e.as_deref().unwrap_or("").contains("form 7"), "{e:?}");
    }
    let mut p = tile.clone();
    p[21] = 0x7F;
    for e in both(&with_tile(&p)) {
        assert!(e.as_deref().unwrap_or("").contains("left"), "{e:?}");
    }
    let mut p = tile.clone();
    p.push(0);
    let e = both(&with_tile(&p))[1].clone().unwrap_or_default();
    assert!(e.contains("after its last stream"), "{e}");
    let trat = good[rs + 8..re - 4].to_vec();
    let e = both(&with_trat(&trat[4..]))[1].clone().unwrap_or_default();
    assert!(e.contains("TRAT"), "{e}");
    let mut zero = trat.clone();
    zero[..4].copy_from_slice(&0f32.to_le_bytes());
    for e in both(&with_trat(&zero)) {
        assert!(e.as_deref().unwrap_or("").contains("ratio"), "{e:?}");
    }
    let without = [&good[..rs], &good[re..]].concat();
    let e = both(&without)[1].clone().unwrap_or_default();
    assert!(e.contains("TRAT"), "{e}");
    // a 2.1 file does not have one
    let old = vector("tiled_gray16_q40.mra");
    let (_, is, _) = chunks(&old)
        .iter()
        .find(|c| &c.0 == b"TIDX")
        .cloned()
        .unwrap();
    let old_with = [&old[..is], &chunk(b"TRAT", &trat), &old[is..]].concat();
    for e in both(&old_with) {
        assert!(e.as_deref().unwrap_or("").contains("TRAT"), "{e:?}");
    }
}
