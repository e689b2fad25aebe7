//! `--bpp` at and above the lossless cost.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::generate::images;
use mra::io::SampleType;

/// A `--bpp` budget above the lossless cost of integer samples gives the lossless file
/// (decoded exactly, within the budget); a budget well under it, a lossy file within it.
#[test]
fn bpp_above_the_lossless_cost_is_lossless() {
    let r = images::strokes(64, 80, 3)
        .to_raster(SampleType::U8)
        .unwrap();
    let pos = r.positions() as f64;
    let lossless = codec::encode(
        &r,
        &EncodeOptions {
            rate: Rate::Lossless,
            ..Default::default()
        },
    )
    .unwrap();
    let cost = lossless.len() as f64 * 8.0 / pos;
    for (b, exact) in [(cost * 1.3, true), (cost * 0.3, false)] {
        let file = codec::encode(
            &r,
            &EncodeOptions {
                rate: Rate::Bpp(b),
                ..Default::default()
            },
        )
        .unwrap();
        assert!(
            file.len() as f64 * 8.0 <= b * pos,
            "{b} bpp: {} bytes",
            file.len()
        );
        let d = codec::decode(&file[..], &DecodeOptions::default()).unwrap();
        assert_eq!(
            d.raster.samples == r.samples,
            exact,
            "{b} bpp (lossless {cost})"
        );
    }
}
