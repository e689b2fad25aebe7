//! Headerless raw samples: `.raw` with an explicit layout ([`RawSpec`]: dims, sample type,
//! byte order), and the heightmap conventions `.r16` (u16 little-endian) and `.r32`
//! (f32 little-endian), square unless a layout is given. The file size must equal the
//! layout's size exactly.

use std::io::Write;
use std::path::Path;

use super::bytes;
use super::{DataKind, Raster, RawSpec, SampleType};
use crate::{Error, Result};

/// Read `path` with the given layout; the size must match exactly.
pub fn read(path: &Path, spec: &RawSpec) -> Result<Raster> {
    let len = std::fs::metadata(path)?.len();
    let channels = 1;
    let need = bytes::checked_bytes(&spec.dims, channels, spec.sample_type, len)?;
    if need as u64 != len {
        return Err(Error::format(
            format!(
                "raw size mismatch: {} of {} needs {need} bytes but the file holds {len}",
                spec.dims
                    .iter()
                    .rev()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join("x"),
                spec.sample_type
            ),
            "file size = product of dims × bytes per sample",
        ));
    }
    let b = bytes::read_all(path)?;
    if b.len() != need {
        return Err(Error::format("file changed while reading", "a stable file"));
    }
    let samples = bytes::decode(&b, spec.sample_type, spec.big_endian);
    let kind = match spec.dims.len() {
        1 => DataKind::Sequence,
        2 => DataKind::Image,
        _ => DataKind::Volume,
    };
    Raster::new(spec.dims.clone(), channels, samples, kind)
}

fn square(path: &Path, ty: SampleType, spec: Option<&RawSpec>) -> Result<Raster> {
    if let Some(s) = spec {
        let spec = RawSpec {
            sample_type: ty,
            big_endian: false,
            dims: s.dims.clone(),
        };
        let mut r = read(path, &spec)?;
        r.kind = DataKind::Heightmap;
        return Ok(r);
    }
    let len = std::fs::metadata(path)?.len();
    let n = len / ty.size() as u64;
    let side = (n as f64).sqrt().round() as u64;
    if len % ty.size() as u64 != 0 || side * side != n || side == 0 {
        return Err(Error::format(
            format!("{len} bytes is not a square grid of {ty} samples"),
            "a square grid, or --dims WxH",
        ));
    }
    let spec = RawSpec {
        dims: vec![side as usize, side as usize],
        sample_type: ty,
        big_endian: false,
    };
    let mut r = read(path, &spec)?;
    r.kind = DataKind::Heightmap;
    Ok(r)
}

/// Read a `.r16` heightmap (u16 little-endian).
pub fn read_r16(path: &Path, spec: Option<&RawSpec>) -> Result<Raster> {
    square(path, SampleType::U16, spec)
}

/// Read a `.r32` heightmap (f32 little-endian).
pub fn read_r32(path: &Path, spec: Option<&RawSpec>) -> Result<Raster> {
    square(path, SampleType::F32, spec)
}

/// Write the samples as stored, in the given byte order, no header.
pub fn write<W: Write>(w: &mut W, r: &Raster, big_endian: bool) -> Result<()> {
    w.write_all(&bytes::encode(&r.samples, big_endian))?;
    Ok(())
}

fn check(r: &Raster, ty: SampleType, what: &'static str) -> Result<()> {
    if r.sample_type() != ty || r.channels != 1 {
        return Err(Error::Unsupported {
            what,
            value: format!("{} (expected single-channel {ty})", r.summary()),
        });
    }
    Ok(())
}

/// Write a single-channel u16 raster as `.r16`.
pub fn write_r16<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    check(r, SampleType::U16, "R16 output")?;
    write(w, r, false)
}

/// Write a single-channel f32 raster as `.r32`.
pub fn write_r32<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    check(r, SampleType::F32, "R32 output")?;
    write(w, r, false)
}
