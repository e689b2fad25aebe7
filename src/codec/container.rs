//! The chunks of a one-tile `.mra` file as the decoder receives them: [`crate::format`]
//! reads and checks them ([`crate::format::body`]); here the header's plan gives the
//! reader the pyramid's bands, and the parsed body is kept with that plan.

use super::plan::Plan;
use crate::format::body::{self, BandChunk, BandLayout, ChunkInfo};
use crate::format::{Chunk, ChunkReader, Header, Residual};
use crate::{Error, Result};
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;

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
    let layout = BandLayout {
        groups: &groups,
        levels: plan.bands.iter().map(|b| b.level).collect(),
        parents: &plan.parents,
        coefficients: plan
            .dims
            .iter()
            .map(|d| d.iter().product::<usize>() as u64)
            .collect(),
    };
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
    })
}

/// The chunks after `HEAD` (the next at byte `at` of `len`) of a one-piece 3.0 file read
/// for the full-resolution box `region` at level `stop_level`: the heads, `mETA` and
/// code-block indices ([`crate::format::sparse`]), then by positioned reads only the
/// code-blocks each band's decode needs ([`super::decode::band_windows`]; runs of
/// neighbouring blocks in one read). `None` for a file left to the whole read.
pub(super) fn read_region<R: Read + Seek>(
    src: &mut R,
    at: u64,
    len: u64,
    header: Header,
    stop_level: usize,
    region: &[Range<usize>],
) -> Result<Option<Parsed>> {
    let plan = Plan::new(&header)?;
    let groups = plan.level_groups();
    let layout = BandLayout {
        groups: &groups,
        levels: plan.bands.iter().map(|b| b.level).collect(),
        parents: &plan.parents,
        coefficients: plan
            .dims
            .iter()
            .map(|d| d.iter().product::<usize>() as u64)
            .collect(),
    };
    let Some(sb) =
        crate::format::sparse::read_body_sparse(src, at, len, &header, &layout, stop_level)?
    else {
        return Ok(None);
    };
    let b = sb.body;
    let mut p = Parsed {
        header,
        meta: b.meta,
        plan,
        bands: b.bands,
        resi: b.resi,
        complete: b.complete,
        chunks: b.chunks,
        window: Some(region.to_vec()),
    };
    let wins = super::decode::band_windows(&p);
    let block = p.header.block_extents();
    for (c, bands) in p.bands.iter_mut().enumerate() {
        for (j, bc) in bands.iter_mut().enumerate() {
            let (Some(bc), Some(off)) = (bc.as_mut(), sb.entries[c][j]) else {
                continue;
            };
            let dims = &p.plan.dims[j];
            let set = crate::format::bands::parse_blocks(&bc.data, dims, &block).map_err(|e| {
                Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
            })?;
            let grid = crate::entropy::codeblocks::Grid::new(dims, &block);
            let which = match &wins[j] {
                Some(w) => grid.touching(w),
                None => (0..grid.len()).collect(),
            };
            // runs of blocks that follow one another in the entry, one read each
            let mut runs: Vec<Range<usize>> = Vec::new();
            for i in which {
                let r = set.streams[i].clone();
                match runs.last_mut() {
                    Some(last) if last.end == r.start => last.end = r.end,
                    _ => runs.push(r),
                }
            }
            for r in runs {
                src.seek(SeekFrom::Start(off + r.start as u64))?;
                src.read_exact(&mut bc.data[r])?;
            }
        }
    }
    Ok(Some(p))
}
