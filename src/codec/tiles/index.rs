//! A tiled file's chunks as the tile decoder receives them: [`crate::format::tiles`]
//! parses `TIDX`, `TILE`, `TRAT` and finds the tiles by index; here the tile grid and
//! the tile classes' ratios are attached, and the in-order reading `info` uses.

use super::*;
use crate::format::body::ChunkInfo;
pub(super) use crate::format::tiles::{check_end, fetch_tile, parse_index, tile_payload};
use crate::format::Tag;

/// What a tiled file's chunks say, read in order.
pub(in crate::codec) struct TiledInfo {
    pub(in crate::codec) header: Header,
    pub(in crate::codec) chunks: Vec<ChunkInfo>,
    /// Each tile's one-tile file, for its bytes per level, and whether the tile is
    /// compact (2.2: its `LEVL` chunks are the file's streams and their lengths only).
    pub(in crate::codec) tiles: Vec<(usize, Vec<u8>, bool)>,
    pub(in crate::codec) complete: bool,
}

/// Read a tiled file's chunks in order (for `info`): every CRC checked, the tiles kept.
pub(in crate::codec) fn read_tiled_info(bytes: &[u8]) -> Result<TiledInfo> {
    let len = bytes.len() as u64;
    let (mut rd, first, header) = read_head(bytes, len)?;
    let grid = Grid::new(&header.dims, &header.tile)?;
    let n = grid.len();
    let mut chunks = vec![ChunkInfo::of(&first, None)];
    let mut tiles = Vec::new();
    let mut seen = vec![false; n];
    let mut complete = false;
    let mut ratios = None;
    while let Ok(ch) = rd.next_chunk()? {
        match ch.tag() {
            Some(Tag::Trat) if header.version.has_compact_tiles() => {
                ratios = Some(Ratios::parse(&ch, &header, &grid)?);
                chunks.push(ChunkInfo::of(&ch, None));
            }
            Some(Tag::Tile) => {
                let (i, inner) = tile_payload(&ch, n)?;
                if std::mem::replace(&mut seen[i], true) {
                    return Err(crate::FormatError::duplicate(
                        format!("a second TILE chunk for tile {i} (byte {})", ch.offset),
                        "each tile once",
                    ));
                }
                let f = tile_file(&header, &grid, ratios.as_ref(), i, inner)?;
                let compact = header.version.has_compact_tiles()
                    && inner.first() == Some(&crate::format::tiles::FORM_COMPACT);
                tiles.push((i, f.into_owned(), compact));
                chunks.push(ChunkInfo::of(&ch, Some(i)));
            }
            Some(Tag::Mend) => {
                chunks.push(ChunkInfo::of(&ch, None));
                complete = seen.iter().all(|&s| s);
                break;
            }
            _ => chunks.push(ChunkInfo::of(&ch, None)),
        }
    }
    Ok(TiledInfo {
        header,
        chunks,
        tiles,
        complete,
    })
}

/// What a tiled file says before its tiles: its metadata, the place of each tile and
/// the step ratios of compact tiles.
pub(super) type Index = crate::format::tiles::Index<std::sync::Arc<Ratios>>;

/// Read `mETA`, `TRAT` (2.2) and `TIDX` of the tiled file of `st` from a seekable stream
/// of `len` bytes, from byte `after_head` (just after `HEAD`).
pub(super) fn read_index<R: Read + Seek>(
    src: &mut R,
    len: u64,
    after_head: u64,
    st: &Stitch,
) -> Result<Index> {
    let h = &st.header;
    crate::format::tiles::read_index(src, len, after_head, h, st.tiles(), |ch| {
        Ok(std::sync::Arc::new(Ratios::parse(ch, h, &st.grid)?))
    })
}
