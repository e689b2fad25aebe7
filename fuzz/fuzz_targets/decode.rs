//! Any bytes through the `.mra` decoder (full, reduced resolution, truncated, a region
//! through the tile index, and read in order without seeking) and `info`: errors are
//! fine, panics and runaway allocations are findings. Seeds with tiled files (formats
//! 2.1 and 2.2) reach the `TRAT`, `TIDX` and `TILE` chunks (chunk and compact tiles).
#![no_main]
use libfuzzer_sys::fuzz_target;
use mra::codec::{decode, decode_stream, info, DecodeOptions};

fuzz_target!(|data: &[u8]| {
    let _ = info(data);
    for level in [0usize, 1] {
        let _ = decode(data, &DecodeOptions { level, allow_truncated: level == 1, region: None });
    }
    let region = Some(vec![0..3, 1..2]);
    let _ = decode(data, &DecodeOptions { level: 0, allow_truncated: true, region });
    let _ = decode_stream(data, data.len() as u64, &DecodeOptions::default());
});
