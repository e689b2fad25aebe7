//! Any bytes through the `.mra` decoder (full, reduced resolution, truncated) and
//! `info`: errors are fine, panics and runaway allocations are findings.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mra::codec::{decode, info, DecodeOptions};

fuzz_target!(|data: &[u8]| {
    let _ = info(data);
    for level in [0usize, 1] {
        let _ = decode(data, &DecodeOptions { level, allow_truncated: level == 1 });
    }
});
