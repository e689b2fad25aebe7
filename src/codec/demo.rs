//! `mra demo` rows for the codec: encode/decode a zone plate at a target PSNR, a CT-like
//! blob volume losslessly and with a guaranteed maximum error.

use super::{decode, encode, DecodeOptions, EncodeOptions, Rate};
use crate::demo::{blob_volume, zone_plate, DemoRow};
use crate::io::{DataKind, Raster, SampleType, Samples};
use crate::Result;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Run the codec jobs, writing the `.mra` files under `out`.
pub fn rows(out: &Path) -> Result<Vec<DemoRow>> {
    let mut rows = Vec::new();
    let img = zone_plate(512, 512);
    let r = Raster::new(
        vec![512, 512],
        1,
        Samples::from_f32(&img, SampleType::U8),
        DataKind::Image,
    )?;
    let vol = blob_volume(64);
    let v = Raster::new(
        vec![64, 64, 64],
        1,
        Samples::from_f32(&vol, SampleType::I16),
        DataKind::Volume,
    )?;
    let jobs: [(&str, &Raster, Rate, &str); 3] = [
        (
            "zone plate 512x512 u8, haar, --psnr 40",
            &r,
            Rate::Psnr(40.0),
            "zone_plate_psnr40.mra",
        ),
        (
            "blob volume 64^3 i16, --lossless",
            &v,
            Rate::Lossless,
            "blob_lossless.mra",
        ),
        (
            "blob volume 64^3 i16, --max-error 4",
            &v,
            Rate::MaxError(4.0),
            "blob_maxerr4.mra",
        ),
    ];
    for (what, raster, rate, name) in jobs {
        let t = Instant::now();
        let bytes = encode(
            raster,
            &EncodeOptions {
                rate,
                ..Default::default()
            },
        )?;
        let back = decode(&bytes, &DecodeOptions::default())?.raster;
        let secs = t.elapsed().as_secs_f64();
        let path = out.join(name);
        crate::fsutil::write_atomic(&path, |w| w.write_all(&bytes))?;
        let c = crate::metrics::compare(raster, &back, &Default::default())?;
        let raw = raster.samples.len() * raster.sample_type().size();
        rows.push(DemoRow {
            job: "encode+decode".into(),
            data: what.into(),
            result: format!(
                "{} bytes ({:.3} bits/sample, ratio {:.1}), PSNR {}, max error {}",
                bytes.len(),
                bytes.len() as f64 * 8.0 / raster.samples.len() as f64,
                raw as f64 / bytes.len() as f64,
                c.psnr.map_or("inf".into(), |p| format!("{p:.2} dB")),
                c.max_abs_error
            ),
            seconds: secs,
            output: Some(path),
        });
    }
    Ok(rows)
}
