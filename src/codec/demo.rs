//! `mra demo` rows for the codec: encode/decode a zone plate at a target PSNR (and a
//! before/after picture of it), a CT-like blob volume losslessly and with a guaranteed
//! maximum error.

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
    let mut before_after = None;
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
        if raster.kind == DataKind::Image {
            // the picture a reader looks at: the source and the decoded file side by side
            let pic = out.join("zone_plate_before_after.png");
            crate::io::write(&pic, &side_by_side(raster, &back, 8)?)?;
            before_after = Some(pic);
        }
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
    if let Some(pic) = before_after {
        rows.push(DemoRow {
            job: "before/after".into(),
            data: "zone plate: the source (left), decoded at --psnr 40 (right)".into(),
            result: "one PNG, the two images side by side".into(),
            seconds: 0.0,
            output: Some(pic),
        });
    }
    Ok(rows)
}

/// Two single-channel 2-D rasters of one shape side by side, `gap` columns of white
/// between them, in their sample type.
fn side_by_side(a: &Raster, b: &Raster, gap: usize) -> Result<Raster> {
    let (h, w) = (a.dims[0], a.dims[1]);
    let width = 2 * w + gap;
    let (_, hi) = a.samples.min_max().unwrap_or((0.0, 255.0));
    let mut v = vec![hi; h * width];
    for y in 0..h {
        for x in 0..w {
            v[y * width + x] = a.samples.get_f64(y * w + x);
            v[y * width + w + gap + x] = b.samples.get_f64(y * w + x);
        }
    }
    Raster::new(
        vec![h, width],
        1,
        Samples::from_f64(&v, a.sample_type()),
        DataKind::Image,
    )
}
