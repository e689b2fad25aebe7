//! The chunks of a one-tile `.mra` file as the decoder receives them: [`crate::format`]
//! reads and checks them ([`crate::format::body`]); here the header's plan gives the
//! reader the pyramid's bands, and the parsed body is kept with that plan.

use super::plan::Plan;
use crate::format::body::{self, BandChunk, ChunkInfo};
use crate::format::{Chunk, ChunkReader, Header, Residual};
use crate::{Error, Result};
use std::io::Read;

pub(super) use crate::format::body::read_head;

/// Everything read from a file before reconstruction.
pub(super) struct Parsed {
    pub(super) header: Header,
    pub(super) meta: crate::io::Metadata,
    pub(super) plan: Plan,
    pub(super) bands: Vec<Vec<Option<BandChunk>>>,
    pub(super) resi: Vec<Option<Residual>>,
    pub(super) complete: bool,
    pub(super) chunks: Vec<ChunkInfo>,
    /// The full-resolution box a decode needs (its region): a format 3 file decodes
    /// only the code-blocks its support meets; `None`: every block.
    pub(super) window: Option<Vec<std::ops::Range<usize>>>,
    /// The box of the decoded level's raster that `window` maps to (as
    /// [`super::tiles::Stitch`] maps it), when known: the box the window synthesis makes.
    pub(super) out_box: Option<Vec<std::ops::Range<usize>>>,
    /// Where the code-blocks' bytes are when `bands` holds each entry's index alone
    /// (the one-piece file read by `indexed_read`: read from the file as they are decoded,
    /// by [`super::StreamedDecoder`] only); `None`: `bands` holds the entries whole.
    pub(super) blocks_in: Option<std::sync::Arc<super::block_file::BlockFile>>,
}

pub(super) fn read_chunks<R: Read>(
    src: R,
    len: u64,
    stop_level: usize,
    allow_truncated: bool,
) -> Result<Parsed> {
    let (rd, first, header) = read_head(src, len)?;
    if header.is_tiled() {
        return Err(Error::format(
            format!("a file of {:?} tiles {:?}", header.dims, header.tile),
            "one tile here (tiled files go through codec::tiles)",
        ));
    }
    read_rest(rd, first, header, stop_level, allow_truncated)
}

/// The chunks after `HEAD` of a file of one tile.
pub(super) fn read_rest<R: Read>(
    rd: ChunkReader<R>,
    first: Chunk,
    header: Header,
    stop_level: usize,
    allow_truncated: bool,
) -> Result<Parsed> {
    let plan = Plan::new(&header)?;
    let groups = plan.level_groups();
    let layout = plan.band_layout(&groups);
    let b = body::read_body(rd, &first, &header, &layout, stop_level, allow_truncated)?;
    Ok(Parsed {
        header,
        meta: b.meta,
        plan,
        bands: b.bands,
        resi: b.resi,
        complete: b.complete,
        chunks: b.chunks,
        window: None,
        out_box: None,
        blocks_in: None,
    })
}
