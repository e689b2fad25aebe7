//! Any bytes through the `.mra` decoder (full, reduced resolution, truncated, a region
//! through the tile index, and read in order without seeking) and `info`: errors are
//! fine, panics and runaway allocations are findings. Seeds with tiled files (formats
//! 2.1 and 2.2) reach the `TRAT`, `TIDX` and `TILE` chunks (chunk and compact tiles).
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| common::exercise(data));
