//! A tiled file's chunks before and around its tiles: the `TIDX` index, `TILE` payloads,
//! the `mETA`/`TRAT` read ahead of them, the closing `MEND`, and the in-order reading
//! `info` uses. Every offset and length is checked against the file before use.

use super::*;

/// The tile index of a `TILE` chunk and the rest of its payload.
pub(super) fn tile_payload(ch: &Chunk, n: usize) -> Result<(usize, &[u8])> {
    let mut c = Cursor::new(&ch.payload, "TILE");
    let i = c.u32()? as usize;
    if i >= n {
        return Err(Error::format(
            format!("TILE chunk at byte {} for tile {i}", ch.offset),
            "a tile of the grid",
        ));
    }
    Ok((i, c.rest()))
}

/// Parse a `TIDX` payload: `(offset, length)` of each tile's chunk.
pub(super) fn parse_index(ch: &Chunk, n: usize, len: u64) -> Result<Vec<(u64, u64)>> {
    if ch.payload.len() as u64 != 16 * n as u64 {
        return Err(Error::format(
            format!("TIDX chunk of {} bytes for {n} tiles", ch.payload.len()),
            "16 bytes per tile",
        ));
    }
    let first = ch.offset + 12 + ch.payload.len() as u64;
    let mut c = Cursor::new(&ch.payload, "TIDX");
    let mut v = Vec::with_capacity(n);
    for i in 0..n {
        let (o, l) = (
            u64::from_le_bytes(c.take(8)?.try_into().unwrap()),
            u64::from_le_bytes(c.take(8)?.try_into().unwrap()),
        );
        if o < first || !(16..=format::MAX_CHUNK + 12).contains(&l) || o.checked_add(l).is_none() {
            return Err(Error::format(
                format!("TIDX entry of tile {i}: {l} bytes at byte {o} (the index ends at {first}, the file at {len})"),
                "chunks after the index",
            ));
        }
        v.push((o, l));
    }
    Ok(v)
}

pub(super) fn chunk_info(ch: &Chunk, tile: Option<usize>) -> crate::codec::container::ChunkInfo {
    crate::codec::container::ChunkInfo {
        kind: ch.name(),
        offset: ch.offset,
        bytes: ch.payload.len() as u64 + 12,
        channel: None,
        band: None,
        level: None,
        coefficients: None,
        tile,
    }
}

/// What a tiled file's chunks say, read in order.
pub(in crate::codec) struct TiledInfo {
    pub(in crate::codec) header: Header,
    pub(in crate::codec) chunks: Vec<crate::codec::container::ChunkInfo>,
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
    let mut chunks = vec![chunk_info(&first, None)];
    let mut tiles = Vec::new();
    let mut seen = vec![false; n];
    let mut complete = false;
    let mut ratios = None;
    while let Ok(ch) = rd.next_chunk()? {
        match &ch.kind {
            b"TRAT" if header.minor >= format::MINOR_COMPACT => {
                ratios = Some(Ratios::parse(&ch, &header, &grid)?);
                chunks.push(chunk_info(&ch, None));
            }
            b"TILE" => {
                let (i, inner) = tile_payload(&ch, n)?;
                if std::mem::replace(&mut seen[i], true) {
                    return Err(Error::format(
                        format!("a second TILE chunk for tile {i} (byte {})", ch.offset),
                        "each tile once",
                    ));
                }
                let f = tile_file(&header, &grid, ratios.as_ref(), i, inner)?;
                let compact = header.minor >= format::MINOR_COMPACT && inner.first() == Some(&1);
                tiles.push((i, f.into_owned(), compact));
                chunks.push(chunk_info(&ch, Some(i)));
            }
            b"MEND" => {
                chunks.push(chunk_info(&ch, None));
                complete = seen.iter().all(|&s| s);
                break;
            }
            _ => chunks.push(chunk_info(&ch, None)),
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
pub(super) type Index = (Metadata, Vec<(u64, u64)>, Option<std::sync::Arc<Ratios>>);

/// Read `mETA`, `TRAT` (2.2) and `TIDX` of the tiled file of `st` from a seekable stream
/// of `len` bytes, from byte `after_head` (just after `HEAD`).
pub(super) fn read_index<R: Read + Seek>(
    src: &mut R,
    len: u64,
    after_head: u64,
    st: &Stitch,
) -> Result<Index> {
    let n = st.tiles();
    let h = &st.header;
    let mut ratios = None;
    let mut meta = Metadata::default();
    let (mut meta_seen, mut first_data) = (false, None);
    src.seek(SeekFrom::Start(after_head))?;
    let mut rd = ChunkReader::at(&mut *src, after_head, len);
    loop {
        let ch = match rd.next_chunk()? {
            Ok(c) => c,
            Err(_) => {
                return Err(Error::format(
                    format!("tiled file of {len} bytes without its TIDX chunk"),
                    "a TIDX chunk after HEAD",
                ))
            }
        };
        match &ch.kind {
            b"mETA" => meta = meta_chunk(&ch, &mut meta_seen, first_data)?,
            b"TRAT" if h.minor >= format::MINOR_COMPACT => {
                first_data = Some(ch.offset);
                ratios = Some(std::sync::Arc::new(Ratios::parse(&ch, h, &st.grid)?));
            }
            b"TIDX" => return Ok((meta, parse_index(&ch, n, len)?, ratios)),
            b"HEAD" => return Err(Error::format("a second HEAD chunk", "one HEAD chunk")),
            k => {
                if k[0].is_ascii_uppercase() {
                    return Err(Error::format(
                        format!("chunk {} at byte {} before TIDX", ch.name(), ch.offset),
                        "HEAD, mETA, TRAT (2.2), then TIDX",
                    ));
                }
            }
        }
    }
}

/// The `TILE` payload (after its index) of tile `i`, found by its index entry
/// `(off, l)`; `None` when the file ends before it and truncated input is allowed.
pub(super) fn fetch_tile<R: Read + Seek>(
    src: &mut R,
    len: u64,
    n: usize,
    i: usize,
    (off, l): (u64, u64),
    allow_truncated: bool,
) -> Result<Option<Vec<u8>>> {
    if off + l > len {
        if !allow_truncated {
            return Err(Error::format(
                format!(
                    "file truncated: tile {i} at bytes {off}..{} of {len}",
                    off + l
                ),
                "a complete file (or --allow-truncated)",
            ));
        }
        return Ok(None);
    }
    src.seek(SeekFrom::Start(off))?;
    let ch = match ChunkReader::at(&mut *src, off, off + l).next_chunk()? {
        Ok(c) if &c.kind == TILE && c.payload.len() as u64 + 12 == l => c,
        _ => {
            return Err(Error::format(
                format!("TIDX entry of tile {i} ({l} bytes at byte {off}) not on its TILE chunk"),
                "an index pointing at each tile's chunk",
            ))
        }
    };
    let (j, inner) = tile_payload(&ch, n)?;
    if j != i {
        return Err(Error::format(
            format!("TIDX entry of tile {i} on the chunk of tile {j} (byte {off})"),
            "an index pointing at each tile's chunk",
        ));
    }
    Ok(Some(inner.to_vec()))
}

/// Whether a `MEND` chunk follows the last tile (a whole decode checks it).
pub(super) fn check_end<R: Read + Seek>(
    src: &mut R,
    len: u64,
    after_head: u64,
    index: &[(u64, u64)],
    allow_truncated: bool,
) -> Result<bool> {
    let end = index
        .iter()
        .map(|&(o, l)| o + l)
        .max()
        .unwrap_or(after_head);
    src.seek(SeekFrom::Start(end))?;
    let ok = matches!(ChunkReader::at(&mut *src, end, len).next_chunk()?, Ok(c) if &c.kind == MEND);
    if !ok && !allow_truncated {
        return Err(Error::format(
            format!("no MEND chunk after the last tile (byte {end} of {len})"),
            "a complete file ending with MEND (or --allow-truncated)",
        ));
    }
    Ok(ok)
}
