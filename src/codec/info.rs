//! What `mra info` reports of a file: its header, sizes by level, and chunk table.

use super::container::{read_chunks, read_head};
use super::plan::Plan;
use super::tiles::read_tiled_info;
use crate::format::body::ChunkInfo;
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
    /// Tile extents, slowest axis first (equal to `dims`: one tile).
    pub tile: Vec<usize>,
    /// Number of tiles (1 for a file of one tile).
    pub tiles: usize,
    /// The block coder of the code-blocks (`context`, `ht`; formats/MRA.md §15.1),
    /// `None` in a file without code-blocks.
    pub coder: Option<String>,
    pub chunks: Vec<ChunkInfo>,
}

/// Read a file's header and chunk table (verifying every CRC).
pub fn info(bytes: &[u8]) -> Result<Info> {
    let (_, _, head) = read_head(bytes, bytes.len() as u64)?;
    let mut lv: std::collections::BTreeMap<usize, u64> = Default::default();
    let (h, depth, complete, chunks, tiles) = if head.is_tiled() {
        let t = read_tiled_info(bytes)?;
        // bytes per level summed over the tiles; a compact tile holds of each level's
        // LEVL chunk its streams and their lengths only (no framing, level or ratios)
        for (_, f, compact) in &t.tiles {
            let fi = info(f)?;
            let streams: Vec<(usize, u64)> = if *compact {
                let th = super::read::header_of(f)?;
                Plan::new(&th)?
                    .level_groups()
                    .into_iter()
                    .map(|(l, js)| (l, (js.len() * th.channels) as u64))
                    .collect()
            } else {
                Vec::new()
            };
            for (l, b, _) in fi.levels_bytes {
                let k = streams.iter().find(|s| s.0 == l).map_or(0, |s| s.1);
                let framing = if *compact {
                    crate::format::bands::level_framing(k)
                } else {
                    0
                };
                *lv.entry(l).or_default() += b.saturating_sub(framing);
            }
        }
        let mut th = t.header.clone();
        th.dims = th.tile.clone();
        let depth = Plan::new(&th)?.pyr.depth();
        let n = super::tiles::Grid::new(&t.header.dims, &t.header.tile)?.len();
        (t.header, depth, t.complete, t.chunks, n)
    } else {
        let p = read_chunks(bytes, bytes.len() as u64, 0, true)?;
        for c in &p.chunks {
            if let Some(l) = c.level {
                *lv.entry(l).or_default() += c.bytes;
            }
        }
        (p.header, p.plan.pyr.depth(), p.complete, p.chunks, 1)
    };
    let h = &h;
    let pos: f64 = h.dims.iter().map(|&d| d as f64).product();
    let mut levels_bytes: Vec<(usize, u64, f64)> = lv
        .into_iter()
        .map(|(l, b)| (l, b, b as f64 * 8.0 / pos))
        .collect();
    levels_bytes.sort_by_key(|&(l, _, _)| if l == 0 { 0 } else { usize::MAX - l });
    Ok(Info {
        version: h.version.to_string(),
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
        levels: depth,
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
        complete,
        levels_bytes,
        tile: h.tile.clone(),
        tiles,
        coder: h
            .version
            .has_blocks()
            .then(|| super::plan::coder_of(h).name().to_string()),
        chunks,
    })
}

/// The levels a file of header `h` holds (those of a tile's pyramid in a tiled file),
/// as [`info`] gives them.
pub fn depth_of(h: &crate::format::Header) -> Result<usize> {
    let mut th = h.clone();
    th.dims = th.tile.clone();
    Ok(Plan::new(&th)?.pyr.depth())
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
