//! What both fuzz targets run on one input: `info`, the decoder whole, at a reduced
//! level, truncated, as a region through the tile index, and read in order.
use mra::codec::{decode, decode_stream, info, DecodeOptions};

/// Every entry of the decoder on `data`: errors are fine, panics and runaway
/// allocations are findings.
pub fn exercise(data: &[u8]) {
    let _ = info(data);
    for level in [0usize, 1] {
        let _ = decode(
            data,
            &DecodeOptions {
                level,
                allow_truncated: level == 1,
                region: None,
            },
        );
    }
    let region = Some(vec![0..3, 1..2]);
    let _ = decode(
        data,
        &DecodeOptions {
            level: 0,
            allow_truncated: true,
            region,
        },
    );
    let _ = decode_stream(data, data.len() as u64, &DecodeOptions::default());
}
