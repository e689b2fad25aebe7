//! What `mra info` reports of a file: its header, sizes by level, and chunk table.

use super::container::{read_chunks, ChunkInfo};
use crate::format::header::Colour;
use crate::format::Mode;
use crate::io::DataKind;
use crate::Result;

/// What `mra info` shows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Info {
    pub version: String,
    pub kind: String,
    pub dims: Vec<usize>,
    pub channels: usize,
    pub sample_type: String,
    pub mode: String,
    pub scheme: String,
    pub boundary: String,
    pub levels: usize,
    /// The colour transform, if any (`YCoCg`, or `YCoCg-R` in integers).
    pub colour: Option<String>,
    pub step: f64,
    /// The bound a `--max-error` file guarantees (none in other files).
    pub max_error: Option<f64>,
    pub range: [f64; 2],
    pub file_bytes: u64,
    pub bits_per_position: f64,
    pub complete: bool,
    /// Bytes and bits per position by level (0 = coarse block, then coarsest details first).
    pub levels_bytes: Vec<(usize, u64, f64)>,
    pub chunks: Vec<ChunkInfo>,
}

/// Read a file's header and chunk table (verifying every CRC).
pub fn info(bytes: &[u8]) -> Result<Info> {
    let p = read_chunks(bytes, bytes.len() as u64, 0, true)?;
    let h = &p.header;
    let pos: f64 = h.dims.iter().map(|&d| d as f64).product();
    let mut lv: std::collections::BTreeMap<usize, u64> = Default::default();
    for c in &p.chunks {
        if let Some(l) = c.level {
            *lv.entry(l).or_default() += c.bytes;
        }
    }
    let mut levels_bytes: Vec<(usize, u64, f64)> = lv
        .into_iter()
        .map(|(l, b)| (l, b, b as f64 * 8.0 / pos))
        .collect();
    levels_bytes.sort_by_key(|&(l, _, _)| if l == 0 { 0 } else { usize::MAX - l });
    Ok(Info {
        version: format!("{}.{}", h.major, h.minor),
        kind: format!("{:?}", h.kind).to_lowercase(),
        dims: h.dims.clone(),
        channels: h.channels,
        sample_type: h.sample_type.name().into(),
        mode: format!("{:?}", h.mode).to_lowercase(),
        scheme: if h.mode == Mode::Lossless {
            match h.scheme {
                crate::scheme::Scheme::Linear => "integer-5/3".into(),
                _ => "integer-haar".into(),
            }
        } else {
            h.scheme.name().into()
        },
        boundary: h.boundary.name().into(),
        levels: p.plan.pyr.depth(),
        colour: match h.colour {
            Colour::None => None,
            Colour::YCoCg => Some("YCoCg".into()),
            Colour::YCoCgR => Some("YCoCg-R".into()),
        },
        step: h.step,
        // stored only by `--max-error` (0 otherwise)
        max_error: (h.max_error > 0.0).then_some(h.max_error),
        range: [h.min, h.max],
        file_bytes: bytes.len() as u64,
        bits_per_position: bytes.len() as f64 * 8.0 / pos,
        complete: p.complete,
        levels_bytes,
        chunks: p.chunks,
    })
}

/// Kind names for the CLI.
pub fn kind_name(k: DataKind) -> &'static str {
    match k {
        DataKind::Image => "image",
        DataKind::Volume => "volume",
        DataKind::Heightmap => "heightmap",
        DataKind::Sequence => "sequence",
    }
}
