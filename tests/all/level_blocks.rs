//! Format 3.2 code-blocks per level (formats/MRA.md §15.3): the extents follow the
//! rule at every level, a region of a 3.2 file is the same window of the whole decode
//! (2-D and 3-D, lossy and lossless, odd sizes, every level), it reads a small share of
//! the file, and a file whose per-level grid does not match its indices is a one-line
//! error, exit 2, no output.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::format::{put_chunk, ChunkReader, Header, Version};
use mra::io::{DataKind, Raster, SampleType, Samples};
use std::ops::Range;
use std::process::Command;

/// A smooth field with texture (xorshift), one channel of type `ty`.
fn field(dims: &[usize], ty: SampleType, seed: u64, hi: f64) -> Raster {
    let n: usize = dims.iter().product();
    let w = *dims.last().unwrap();
    let mut x = seed | 1;
    let v: Vec<f64> = (0..n)
        .map(|i| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let (px, py) = ((i % w) as f64, (i / w) as f64);
            let s = 0.5 + 0.35 * (px * 0.13).sin() * (py * 0.07).cos();
            hi * (s + 0.08 * ((x >> 40) as f64 / (1u64 << 24) as f64 - 0.5)).clamp(0.0, 1.0)
        })
        .collect();
    let kind = if dims.len() == 3 {
        DataKind::Volume
    } else {
        DataKind::Image
    };
    Raster::new(dims.to_vec(), 1, Samples::from_f64(&v, ty), kind).unwrap()
}

fn encode(r: &Raster, rate: Rate, levels: usize) -> Vec<u8> {
    let o = EncodeOptions {
        rate,
        levels,
        ..Default::default()
    };
    codec::encode(r, &o).unwrap()
}

fn decoded(bytes: &[u8], level: usize, region: Option<Vec<Range<usize>>>) -> Raster {
    let o = DecodeOptions {
        level,
        region,
        ..Default::default()
    };
    codec::decode(bytes, &o).unwrap().raster
}

/// The file with its `HEAD` payload changed by `edit` (the chunk's CRC rewritten).
fn with_head(bytes: &[u8], edit: impl Fn(&mut Vec<u8>)) -> Vec<u8> {
    let mut rd = ChunkReader::new(bytes, bytes.len() as u64).unwrap();
    let mut out = mra::format::SIGNATURE.to_vec();
    while let Ok(ch) = rd.next_chunk().unwrap() {
        let mut p = ch.payload.clone();
        if &ch.kind == b"HEAD" {
            edit(&mut p);
        }
        put_chunk(&mut out, &ch.kind, &p);
    }
    out
}

/// §15.3's rule: images keep `HEAD`'s extents at the two finest levels and halve them
/// at each coarser one down to 32; volumes halve from the second level down to 16;
/// never below a smaller `HEAD` extent; 3.0 and 3.1 keep one extent.
#[test]
fn block_extents_follow_the_rule_of_each_version() {
    let bytes = encode(
        &field(&[40, 50], SampleType::U8, 1, 255.0),
        Rate::Bpp(2.0),
        2,
    );
    let mut h = codec::header_of(&bytes).unwrap();
    assert_eq!(h.version, Version::LEVEL_BLOCKS);
    assert_eq!(h.blocks, vec![8, 8]);
    let at = |h: &Header| -> Vec<Vec<usize>> { (0..=7).map(|l| h.block_extents_at(l)).collect() };
    let s = |v: &[usize]| v.to_vec();
    assert_eq!(
        at(&h),
        [
            s(&[256, 256]),
            s(&[256, 256]),
            s(&[256, 256]),
            s(&[128, 128]),
            s(&[64, 64]),
            s(&[32, 32]),
            s(&[32, 32]),
            s(&[32, 32])
        ]
    );
    h.blocks = vec![4, 9];
    assert_eq!(h.block_extents_at(6), vec![16, 32]);
    h.blocks = vec![5, 6, 6];
    assert_eq!(h.block_extents_at(1), vec![32, 64, 64]);
    assert_eq!(h.block_extents_at(2), vec![16, 32, 32]);
    assert_eq!(h.block_extents_at(3), vec![16, 16, 16]);
    assert_eq!(h.block_extents_at(9), vec![16, 16, 16]);
    for v in [Version::BLOCKS, Version::CODER_CHOICE] {
        h.version = v;
        for l in 0..8 {
            assert_eq!(h.block_extents_at(l), h.block_extents(), "{v} level {l}");
        }
    }
}

/// A region of a 3.2 file is the same window of the whole decode at every level: 2-D
/// and 3-D, lossy and lossless, odd sizes over blocks of every level's extent, windows
/// inside, at the edges and one sample wide.
#[test]
fn regions_of_level_blocks_are_windows_of_the_whole_decode() {
    let cases: Vec<(Raster, Rate, usize)> = vec![
        // levels 3 to 5 of the images are 2×2 blocks of 128, 64 and 32; level 2 of the
        // volumes 3×3×3 blocks of 16×32×32
        (
            field(&[1100, 1301], SampleType::U8, 3, 255.0),
            Rate::Quality(60.0),
            5,
        ),
        (
            field(&[1100, 1301], SampleType::U16, 5, 60000.0),
            Rate::Lossless,
            5,
        ),
        (
            field(&[70, 139, 133], SampleType::U16, 7, 4000.0),
            Rate::Bpp(1.0),
            3,
        ),
        (
            field(&[70, 139, 133], SampleType::U16, 9, 4000.0),
            Rate::Lossless,
            3,
        ),
    ];
    for (r, rate, levels) in cases {
        let bytes = encode(&r, rate, levels);
        assert_eq!(
            codec::header_of(&bytes).unwrap().version,
            Version::LEVEL_BLOCKS
        );
        if rate == Rate::Lossless {
            assert_eq!(decoded(&bytes, 0, None).samples, r.samples);
        }
        let wins: Vec<Vec<Range<usize>>> = vec![
            r.dims.iter().map(|&d| d / 2..d / 2 + d / 7 + 1).collect(),
            r.dims.iter().map(|&d| 0..d / 9 + 1).collect(),
            r.dims.iter().map(|&d| d - d / 8 - 1..d).collect(),
            r.dims.iter().map(|&d| d / 3..d / 3 + 1).collect(),
        ];
        for level in 0..=levels {
            let whole = decoded(&bytes, level, None);
            for win in &wins {
                let part = decoded(&bytes, level, Some(win.clone()));
                // the window at this level: its box scaled down, as the decoder cuts it
                let sub: Vec<Range<usize>> = win
                    .iter()
                    .zip(&r.dims)
                    .zip(&whole.dims)
                    .map(|((w, &d), &e)| {
                        let lo = w.start * e / d;
                        let hi = (w.end * e).div_ceil(d).max(lo + 1).min(e);
                        lo..hi
                    })
                    .collect();
                assert_eq!(
                    part.dims,
                    sub.iter().map(|s| s.len()).collect::<Vec<_>>(),
                    "{:?} {rate:?} {win:?} level {level}",
                    r.dims
                );
                let mut at = 0;
                let ok = for_each(&sub, &whole.dims, |i| {
                    let same = part.samples.get_f64(at) == whole.samples.get_f64(i);
                    at += 1;
                    same
                });
                assert!(ok, "{:?} {rate:?} {win:?} level {level}", r.dims);
            }
        }
    }
}

/// Visit the flat indices of box `b` of an array of extents `dims` in raster order;
/// false when `f` says so for any.
fn for_each(b: &[Range<usize>], dims: &[usize], mut f: impl FnMut(usize) -> bool) -> bool {
    let mut idx: Vec<usize> = b.iter().map(|r| r.start).collect();
    if b.iter().any(|r| r.is_empty()) {
        return true;
    }
    loop {
        let flat = idx.iter().zip(dims).fold(0, |a, (&i, &d)| a * d + i);
        if !f(flat) {
            return false;
        }
        let mut k = b.len();
        loop {
            if k == 0 {
                return true;
            }
            k -= 1;
            idx[k] += 1;
            if idx[k] < b[k].end {
                break;
            }
            idx[k] = b[k].start;
        }
    }
}

/// `mra decode --region … --json` of a 64² window of a 4096² 3.2 file reads under 4%
/// of it (with one block extent at every level, the 512² band is 2×2 blocks and the
/// coarser ones one block, about 6%), and the window is the whole decode's.
#[test]
fn a_region_of_level_blocks_reads_a_small_share() {
    let r = field(&[4096, 4096], SampleType::U8, 11, 255.0);
    let bytes = encode(&r, Rate::Quality(50.0), 6);
    let dir = std::env::temp_dir().join(format!("mra-level-blocks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("a.mra");
    std::fs::write(&input, &bytes).unwrap();
    let output = dir.join("a.nrrd");
    let o = Command::new(env!("CARGO_BIN_EXE_mra"))
        .args([
            "decode",
            input.to_str().unwrap(),
            "-o",
            output.to_str().unwrap(),
            "--region",
            "2100:2164,2100:2164",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let read = v["bytes_read"].as_u64().unwrap();
    eprintln!("level_blocks: {read} bytes read of {}", bytes.len());
    assert!(
        read * 25 < bytes.len() as u64,
        "{read} bytes read of {}",
        bytes.len()
    );
    let part = mra::io::read(&output).unwrap();
    let whole = decoded(&bytes, 0, None);
    let mut at = 0;
    let ok = for_each(&[2100..2164, 2100..2164], &whole.dims, |i| {
        let same = part.samples.get_f64(at) == whole.samples.get_f64(i);
        at += 1;
        same
    });
    assert!(ok);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 3.2 file relabelled 3.1 (its indices then count the blocks of one extent), or
/// with a finest exponent changed (every level's grid changes with it): each a one-line
/// error naming the file, exit 2, no output, whole and as a region.
#[test]
fn a_per_level_grid_that_does_not_match_the_index_is_refused() {
    // level 3's bands (138×132) are 2×2 blocks of 128 in 3.2, one block of 256 in 3.1
    let r = field(&[1100, 1050], SampleType::U8, 13, 255.0);
    let bytes = encode(&r, Rate::Bpp(2.0), 4);
    let h = codec::header_of(&bytes).unwrap();
    let nd = h.dims.len();
    // HEAD: the exponents are the N bytes before the coder byte, the payload's last
    let n = with_head(&bytes, |_| {}).len();
    assert_eq!(n, bytes.len(), "the HEAD rewrite keeps the file");
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("as31", with_head(&bytes, |p| p[1] = 1)),
        (
            "exponent",
            with_head(&bytes, |p| {
                let at = p.len() - 1 - nd;
                p[at] -= 1;
            }),
        ),
        (
            "floor",
            with_head(&bytes, |p| {
                let at = p.len() - 1 - nd;
                p[at] = 4;
                p[at + 1] = 4;
            }),
        ),
    ];
    let dir = std::env::temp_dir().join(format!("mra-level-blocks-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bad) in cases {
        assert!(
            codec::decode(&bad, &DecodeOptions::default()).is_err(),
            "{name}"
        );
        let input = dir.join(format!("{name}.mra"));
        std::fs::write(&input, &bad).unwrap();
        for extra in [vec![], vec!["--region", "10:200,20:100"]] {
            let output = dir.join(format!("{name}.png"));
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
