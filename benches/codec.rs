//! Codec throughput: encode and decode of generated data in each mode.
//! Run: `cargo bench --bench codec`
use mra::codec::{decode, encode, DecodeOptions, EncodeOptions, Rate};
use mra::io::{DataKind, Raster, SampleType, Samples};
use std::time::Instant;

fn main() {
    let img = mra::demo::zone_plate(1024, 1024);
    let rgb: Vec<f32> = img.iter().flat_map(|&v| [v, 255.0 - v, v * 0.5]).collect();
    let r = Raster::new(
        vec![1024, 1024],
        3,
        Samples::from_f32(&rgb, SampleType::U8),
        DataKind::Image,
    )
    .unwrap();
    let vol = mra::demo::blob_volume(128);
    let v = Raster::new(
        vec![128, 128, 128],
        1,
        Samples::from_f32(&vol, SampleType::I16),
        DataKind::Volume,
    )
    .unwrap();
    for (what, raster, rate) in [
        (
            "zone plate 1024² RGB u8, quality 50",
            &r,
            Rate::Quality(50.0),
        ),
        ("zone plate 1024² RGB u8, lossless", &r, Rate::Lossless),
        ("blob 128³ i16, quality 60", &v, Rate::Quality(60.0)),
        ("blob 128³ i16, lossless", &v, Rate::Lossless),
        ("blob 128³ i16, max-error 2", &v, Rate::MaxError(2.0)),
    ] {
        let mb = raster.samples.len() as f64 * raster.sample_type().size() as f64 / 1e6;
        let t = Instant::now();
        let bytes = encode(
            raster,
            &EncodeOptions {
                rate,
                ..Default::default()
            },
        )
        .unwrap();
        let te = t.elapsed().as_secs_f64();
        let t = Instant::now();
        decode(&bytes, &DecodeOptions::default()).unwrap();
        let td = t.elapsed().as_secs_f64();
        println!(
            "{what:<40} {:>9} bytes  encode {te:.3} s ({:.1} MB/s)  decode {td:.3} s ({:.1} MB/s)",
            bytes.len(),
            mb / te,
            mb / td
        );
    }
}
