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

/// `--psnr` and `--quality` targets past the lossless cost of integer samples give no
/// file larger than the lossless one (the rate control falls back to it, as `--bpp`
/// does), and reach their target; a modest target stays a smaller lossy file.
#[test]
fn psnr_and_quality_past_the_lossless_cost_fall_back_to_lossless() {
    let r = images::strokes(64, 80, 3)
        .to_raster(SampleType::U8)
        .unwrap();
    let enc = |rate| {
        codec::encode(
            &r,
            &EncodeOptions {
                rate,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let lossless = enc(Rate::Lossless).len();
    let cmp = mra::metrics::CompareOptions::default();
    for (rate, target) in [
        (Rate::Psnr(70.0), 70.0),
        (Rate::Psnr(200.0), 200.0),
        (Rate::Quality(100.0), 0.0),
    ] {
        let file = enc(rate);
        assert!(
            file.len() <= lossless,
            "{rate:?}: {} bytes, lossless {lossless}",
            file.len()
        );
        let d = codec::decode(&file[..], &DecodeOptions::default()).unwrap();
        let psnr = mra::metrics::compare(&r, &d.raster, &cmp).unwrap().psnr;
        assert!(psnr.is_none_or(|p| p >= target), "{rate:?}: {psnr:?} dB");
    }
    let modest = enc(Rate::Psnr(30.0));
    assert!(modest.len() < lossless, "30 dB: {} bytes", modest.len());
}
