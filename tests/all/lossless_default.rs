//! `--lossless` over the one-piece limit is one transform by default (`mra encode`
//! without `--tile`, `codec::encode`): a format 3 file of one piece, whose streamed
//! decode (`StreamedDecoder` reading each batch of code-blocks from the file) gives the
//! samples and metadata back exactly on 1 and 2 threads; a file whose code-block index
//! or blocks are damaged is a one-line error, exit code 2, no output.

use super::common;
use mra::codec::{self, EncodeOptions, Format, Rate};
use mra::io::slab::Shape;
use mra::io::{Raster, SampleType};
use mra::scheme::{Boundary, Scheme};
use std::path::Path;

fn opts(rate: Rate) -> EncodeOptions {
    EncodeOptions {
        rate,
        levels: 5,
        boundary: Boundary::Symmetric,
        scheme: Scheme::Cdf97,
        format: Format::Blocks,
        effort: codec::DEFAULT_EFFORT,
    }
}

/// A 4736² RGB u8 image (2^24 positions and 2^26 samples exceeded: over the limit) with
/// a spacing.
fn big() -> Raster {
    let mut r = common::wave_field(
        &[4736, 4736],
        3,
        SampleType::U8,
        52,
        255.0,
        common::Wave {
            fx: 0.02,
            fy: 0.01,
            noise: 0.04,
        },
    );
    r.meta.spacing = Some(vec![0.5, 0.25]);
    r
}

/// `mra args` in `dir` on `threads` threads.
fn mra(dir: &Path, threads: usize, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .current_dir(dir)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .output()
        .unwrap()
}

/// The default layout of 8/16-bit lossless (and exact `--max-error`) rasters over the
/// limit is the whole raster, images and volumes; 32-bit and 4 axes stay tiled.
#[test]
fn lossless_over_the_limit_is_one_transform_by_default() {
    let mut s = Shape::of(&big());
    assert_ne!(codec::default_tile(&s.dims, 3), s.dims);
    for rate in [Rate::Lossless, Rate::MaxError(0.5)] {
        assert_eq!(codec::default_layout(&s, &opts(rate)), s.dims, "{rate:?}");
    }
    s.sample_type = SampleType::U16;
    s.channels = 1;
    s.dims = vec![1024, 1024, 1024];
    assert_eq!(codec::default_layout(&s, &opts(Rate::Lossless)), s.dims);
    s.sample_type = SampleType::U32;
    assert_eq!(
        codec::default_layout(&s, &opts(Rate::Lossless)),
        codec::default_tile(&s.dims, 1)
    );
    s.sample_type = SampleType::U16;
    s.dims = vec![16, 256, 256, 256];
    assert_eq!(
        codec::default_layout(&s, &opts(Rate::Lossless)),
        codec::default_tile(&s.dims, 1)
    );
}

/// `mra encode --lossless` of an NRRD over the limit writes one transform (format 3,
/// one tile, lossless, read back by `mra info`); `mra decode` (the streamed decode,
/// blocks read from the file a batch at a time) gives the very samples and the spacing
/// back on 1 and 2 threads. Then damaged copies: a block length in the
/// index changed (CRC fixed up: the index check), and a byte of a block flipped (the
/// CRC check): each a one-line error naming the file, exit 2, no output file.
#[test]
fn a_lossless_file_over_the_limit_streams_and_decodes_exactly() {
    let dir = common::scratch_dir("lossless_default");
    let r = big();
    mra::io::write(&dir.join("in.nrrd"), &r).unwrap();
    let o = mra(
        &dir,
        2,
        &["encode", "in.nrrd", "-o", "in.mra", "--lossless"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = std::fs::read(dir.join("in.mra")).unwrap();
    let info = codec::info(&file).unwrap();
    assert!(info.version.starts_with('3'), "{}", info.version);
    assert_eq!(info.tiles, 1);
    assert_eq!(info.tile, r.dims);
    assert_eq!(info.mode, "lossless");
    for threads in [1, 2] {
        let out = format!("out{threads}.nrrd");
        let o = mra(&dir, threads, &["decode", "in.mra", "-o", &out]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let d = mra::io::read(&dir.join(&out)).unwrap();
        assert_eq!(d.dims, r.dims);
        assert!(d.samples == r.samples, "{threads} threads");
        assert_eq!(d.meta.spacing, r.meta.spacing);
        std::fs::remove_file(dir.join(&out)).unwrap();
    }
    std::fs::remove_file(dir.join("in.nrrd")).unwrap();

    // the first LEVL chunk's first band entry: level u16, ratio f32, L, then the index
    // (the block count, then each block's length)
    let levl = levl_at(&file);
    let n = u32::from_le_bytes(file[levl..levl + 4].try_into().unwrap()) as usize;
    let mut at = levl + 8 + 2 + 4;
    skip_varint(&file, &mut at); // L
    skip_varint(&file, &mut at); // the block count
    let mut bad_index = file.clone();
    // the first block one byte longer: the blocks no longer fill the entry
    assert_ne!(
        bad_index[at] & 0x7F,
        0x7F,
        "a length whose low bits take one more"
    );
    bad_index[at] += 1;
    fix_crc(&mut bad_index, levl, n);
    let mut bad_block = file.clone();
    let last = levl + 8 + n - 1;
    bad_block[last] ^= 0x5A;
    for (name, bytes) in [("index.mra", &bad_index), ("block.mra", &bad_block)] {
        std::fs::write(dir.join(name), bytes).unwrap();
        assert!(stream_fails(&dir.join(name)), "{name}");
        let o = mra(&dir, 2, &["decode", name, "-o", "bad.nrrd"]);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(name), "{err}");
        assert!(!dir.join("bad.nrrd").exists(), "{name}");
        assert!(!dir.join("bad.raw").exists(), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Whether the streamed decode of the file at `path` ends in an error: at its opening
/// (a damaged chunk) or at the batch whose blocks it cannot read (a damaged index, read
/// when the batch is decoded).
fn stream_fails(path: &Path) -> bool {
    let Ok(mut d) = codec::StreamedDecoder::open(path) else {
        return true;
    };
    loop {
        match d.next_slab() {
            Err(_) => return true,
            Ok(None) => return false,
            Ok(Some(_)) => {}
        }
    }
}

/// The offset of the first `LEVL` chunk of `file` (chunks after the 8-byte signature:
/// length u32, type, payload, CRC).
fn levl_at(file: &[u8]) -> usize {
    let mut at = 8;
    while at + 12 <= file.len() {
        let n = u32::from_le_bytes(file[at..at + 4].try_into().unwrap()) as usize;
        if &file[at + 4..at + 8] == b"LEVL" {
            return at;
        }
        at += n + 12;
    }
    panic!("no LEVL chunk");
}

fn skip_varint(file: &[u8], at: &mut usize) {
    while file[*at] & 0x80 != 0 {
        *at += 1;
    }
    *at += 1;
}

/// Recompute the CRC-32C (over type and payload) of the chunk of `n` payload bytes at `at`.
fn fix_crc(file: &mut [u8], at: usize, n: usize) {
    let c = crc32c::crc32c(&file[at + 4..at + 8 + n]);
    file[at + 8 + n..at + 12 + n].copy_from_slice(&c.to_le_bytes());
}
