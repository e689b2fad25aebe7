//! Mesh files, one module per format: OBJ, PLY (ASCII and binary little/big endian), OFF.
//! [`read()`] and [`write()`] choose the format by file extension. Readers never trust a count
//! declared in a header: sizes are checked against the bytes present before allocating.

pub mod obj;
pub mod off;
pub mod ply;

use super::Mesh;
use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// The mesh file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Obj,
    /// PLY with the given encoding.
    Ply(ply::Encoding),
    Off,
}

impl Format {
    /// The format implied by a path's extension (`.ply` is written binary little endian).
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "obj" => Ok(Format::Obj),
            "ply" => Ok(Format::Ply(ply::Encoding::BinaryLittleEndian)),
            "off" => Ok(Format::Off),
            _ => Err(Error::Unsupported {
                what: "mesh file extension",
                value: format!("{:?}", path.display().to_string()),
            }),
        }
    }
}

/// Parse a mesh from bytes in the given format.
pub fn parse(bytes: &[u8], format: Format) -> Result<Mesh> {
    match format {
        Format::Obj => obj::parse(bytes),
        Format::Ply(_) => ply::parse(bytes),
        Format::Off => off::parse(bytes),
    }
}

/// Serialise a mesh in the given format.
pub fn to_bytes(mesh: &Mesh, format: Format) -> Result<Vec<u8>> {
    match format {
        Format::Obj => obj::to_bytes(mesh),
        Format::Ply(enc) => ply::to_bytes(mesh, enc),
        Format::Off => off::to_bytes(mesh),
    }
}

/// Read a mesh file, choosing the reader by extension.
pub fn read(path: impl AsRef<Path>) -> Result<Mesh> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    let bytes = std::fs::read(path)?;
    parse(&bytes, format)
}

/// Write a mesh file, choosing the writer by extension (PLY: binary little endian). The file
/// is written to a temporary name in the same folder and renamed, so a failed write never
/// leaves a partial file.
pub fn write(path: impl AsRef<Path>, mesh: &Mesh) -> Result<()> {
    let path = path.as_ref();
    write_as(path, mesh, Format::from_path(path)?)
}

/// Write a mesh file in an explicit format (temporary file + rename).
pub fn write_as(path: &Path, mesh: &Mesh, format: Format) -> Result<()> {
    let bytes = to_bytes(mesh, format)?;
    write_atomic(path, &bytes)
}

/// Write bytes to `path` through a temporary file in the same folder and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    Ok(crate::fsutil::write_atomic(path, |w| w.write_all(bytes))?)
}

/// Byte-level tokenising helpers shared by the text readers.
pub(crate) mod text {
    use crate::{Error, Result};

    /// Split `s` at ASCII whitespace.
    #[inline]
    pub fn tokens(s: &[u8]) -> impl Iterator<Item = &[u8]> {
        s.split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty())
    }

    #[inline]
    pub fn parse_f64(t: &[u8], line: usize) -> Result<f64> {
        std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| {
                Error::format(
                    format!(
                        "line {line}: {:?} is not a number",
                        String::from_utf8_lossy(t)
                    ),
                    "a decimal number",
                )
            })
    }

    #[inline]
    pub fn parse_i64(t: &[u8], line: usize) -> Result<i64> {
        let mut neg = false;
        let mut s = t;
        if let Some((&b'-', rest)) = s.split_first() {
            neg = true;
            s = rest;
        } else if let Some((&b'+', rest)) = s.split_first() {
            s = rest;
        }
        if s.is_empty() || s.len() > 18 || !s.iter().all(|b| b.is_ascii_digit()) {
            return Err(Error::format(
                format!(
                    "line {line}: {:?} is not an integer",
                    String::from_utf8_lossy(t)
                ),
                "an integer index",
            ));
        }
        let v = s.iter().fold(0i64, |a, &b| a * 10 + (b - b'0') as i64);
        Ok(if neg { -v } else { v })
    }
}
