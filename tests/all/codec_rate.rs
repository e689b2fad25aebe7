//! `--psnr` and `--quality` at and above the lossless cost.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::generate::images;
use mra::io::SampleType;

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
