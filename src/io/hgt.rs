//! SRTM `.hgt` tiles: headerless big-endian i16, N×N samples (1201² for SRTM3, 3601² for
//! SRTM1), row 0 = northern edge. Voids are −32768; they are kept as stored and reported
//! through `meta.nodata` (use [`void_count`] to count them).
//!
//! A tile named for its south-west corner (`N37W122.hgt`: latitude 37…38 N, longitude
//! 122…121 W) is georeferenced: sample `(row, col)` is at longitude `W + col/(N−1)`,
//! latitude `S + 1 − row/(N−1)` (WGS 84, samples are points). That is kept as origin
//! `(lon, lat)` of sample 0 with space directions `(1/(N−1), 0)`, `(0, −1/(N−1))`, and as
//! the GeoTIFF tags a `.tif` output carries: ModelPixelScale `(1/(N−1), 1/(N−1), 0)`,
//! ModelTiepoint `(0, 0, 0, lon, lat, 0)`, GeoKeyDirectory geographic, PixelIsPoint,
//! EPSG 4326.

use std::io::Write;
use std::path::Path;

use super::bytes;
use super::{DataKind, GeoTag, GeoValue, Raster, SampleType, Samples};
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
    if let Some((lat, lon)) = path
        .file_name()
        .and_then(|n| south_west(&n.to_string_lossy()))
    {
        let d = 1.0 / (side as f64 - 1.0);
        let top = lat + 1.0;
        r.meta.origin = Some(vec![lon, top]);
        r.meta.directions = Some(vec![vec![d, 0.0], vec![0.0, -d]]);
        r.meta.geotiff = vec![
            GeoTag {
                tag: 33550,
                value: GeoValue::Doubles(vec![d, d, 0.0]),
            },
            GeoTag {
                tag: 33922,
                value: GeoValue::Doubles(vec![0.0, 0.0, 0.0, lon, top, 0.0]),
            },
            GeoTag {
                tag: 34735,
                value: GeoValue::Shorts(vec![
                    1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 2, 2048, 0, 1, 4326,
                ]),
            },
        ];
    }
    Ok(r)
}

/// `(latitude, longitude)` of the south-west corner a tile name states (`N37W122…`).
pub fn south_west(name: &str) -> Option<(f64, f64)> {
    let b = name.as_bytes();
    if b.len() < 7 || !b[1..3].iter().chain(&b[4..7]).all(u8::is_ascii_digit) {
        return None;
    }
    let lat: f64 = name[1..3].parse().ok()?;
    let lon: f64 = name[4..7].parse().ok()?;
    let lat = match b[0].to_ascii_uppercase() {
        b'N' => lat,
        b'S' => -lat,
        _ => return None,
    };
    let lon = match b[3].to_ascii_uppercase() {
        b'E' => lon,
        b'W' => -lon,
        _ => return None,
    };
    (lat.abs() <= 90.0 && lon.abs() <= 180.0).then_some((lat, lon))
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
