//! SRTM `.hgt` tiles: headerless big-endian i16, N×N samples (1201² for SRTM3, 3601² for
//! SRTM1), row 0 = northern edge. Voids are −32768; they are kept as stored and reported
//! through `meta.nodata` (use [`void_count`] to count them).

use std::io::Write;
use std::path::Path;

use super::bytes;
use super::{DataKind, Raster, SampleType, Samples};
use crate::{Error, Result};

/// The SRTM void marker.
pub const VOID: i16 = -32768;

/// Read a `.hgt` tile; the side is the square root of the sample count.
pub fn read(path: &Path) -> Result<Raster> {
    let b = bytes::read_all(path)?;
    let n = b.len() / 2;
    let side = (n as f64).sqrt().round() as usize;
    if b.len() % 2 != 0 || side * side != n || side < 2 {
        return Err(Error::format(
            format!("{} bytes is not a square grid of 16-bit samples", b.len()),
            "2 × N² bytes, N = 1201 (SRTM3) or 3601 (SRTM1)",
        ));
    }
    let samples = bytes::decode(&b, SampleType::I16, true);
    let mut r = Raster::new(vec![side, side], 1, samples, DataKind::Heightmap)?;
    r.meta.nodata = Some(VOID as f64);
    r.meta.units = Some("degree".into());
    r.meta.spacing = Some(vec![1.0 / (side as f64 - 1.0); 2]);
    r.meta.extra.insert("elevation_units".into(), "m".into());
    Ok(r)
}

/// Number of void samples (−32768) in an i16 raster.
pub fn void_count(r: &Raster) -> usize {
    match &r.samples {
        Samples::I16(v) => v.iter().filter(|&&x| x == VOID).count(),
        _ => 0,
    }
}

/// Write a square single-channel i16 raster as big-endian `.hgt`.
pub fn write<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    if r.dims.len() != 2 || r.dims[0] != r.dims[1] || r.channels != 1 {
        return Err(Error::Unsupported {
            what: "HGT output",
            value: format!("{} (expected a square single-channel grid)", r.summary()),
        });
    }
    let Samples::I16(_) = &r.samples else {
        return Err(Error::Unsupported {
            what: "HGT output",
            value: format!("{} samples (expected i16)", r.sample_type()),
        });
    };
    w.write_all(&bytes::encode(&r.samples, true))?;
    Ok(())
}
