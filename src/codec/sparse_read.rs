//! A one-piece format 3.0 file parsed for region reads ([`Sparse`]): its chunk heads,
//! `mETA` and every band entry's step and code-block index, read by positioned reads
//! ([`crate::format::sparse`]); then, for one region, only the code-blocks it needs.
//! Used by the one-shot region read ([`super::read`]) and by [`super::Opened`], which
//! keeps one between regions.

use super::container::Parsed;
use super::plan::Plan;
use crate::format::body::{BandChunk, ChunkInfo};
use crate::format::Header;
use crate::io::Metadata;
use crate::Result;
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;

/// One band entry of a `LEVL` chunk as parsed for region reads: where its `L` bytes
/// start in the file, its step, its code-block index bytes and where each block's
/// stream sits in the entry.
struct Entry {
    at: u64,
    step: f64,
    len: usize,
    index: Vec<u8>,
    streams: Vec<Range<usize>>,
}

/// The chunks of a one-piece 3.0 file parsed for region reads: everything but the
/// code-blocks' streams.
pub(super) struct Sparse {
    header: Header,
    meta: Metadata,
    complete: bool,
    chunks: Vec<ChunkInfo>,
    /// `[channel][band]`.
    entries: Vec<Vec<Option<Entry>>>,
    /// The level of each band (0: the coarse block, 1: the finest details).
    levels: Vec<usize>,
}

impl Sparse {
    /// The file's `mETA` as parsed.
    pub(super) fn meta(&self) -> &Metadata {
        &self.meta
    }

    /// The chunks after `HEAD` (the next at byte `at` of `len`) of a one-piece 3.0 file
    /// read for decodes at levels from `stop_level` up (0: every level): the heads,
    /// `mETA` and code-block indices ([`crate::format::sparse`]), every index checked.
    /// `None` for a file left to the whole read.
    pub(super) fn parse<R: Read + Seek>(
        src: &mut R,
        at: u64,
        len: u64,
        header: Header,
        stop_level: usize,
    ) -> Result<Option<Sparse>> {
        let plan = Plan::new(&header)?;
        let groups = plan.level_groups();
        let layout = plan.band_layout(&groups);
        let Some(sb) = crate::format::sparse::read_body_sparse(
            src,
            at,
            len,
            &header,
            &layout,
            (stop_level, false),
        )?
        else {
            return Ok(None);
        };
        let mut entries = Vec::with_capacity(sb.body.bands.len());
        for (c, bands) in sb.body.bands.into_iter().enumerate() {
            let mut row = Vec::with_capacity(bands.len());
            for (j, bc) in bands.into_iter().enumerate() {
                let (Some(bc), Some((off, l))) = (bc, sb.entries[c][j]) else {
                    row.push(None);
                    continue;
                };
                let set =
                    crate::format::bands::parse_index(&bc.data, l, &plan.dims[j], plan.block(j))
                        .map_err(|e| {
                            crate::Error::format(
                                format!("band {j} of channel {c}: {e}"),
                                "a valid band",
                            )
                        })?;
                row.push(Some(Entry {
                    at: off,
                    step: bc.step,
                    len: l as usize,
                    index: bc.data,
                    streams: set.streams,
                }));
            }
            entries.push(row);
        }
        Ok(Some(Sparse {
            levels: layout.levels.clone(),
            header,
            meta: sb.body.meta,
            complete: sb.body.complete,
            chunks: sb.body.chunks,
            entries,
        }))
    }

    /// The chunks a decode at level `level` of the full-resolution box `region` needs,
    /// with the code-blocks its bands' decodes need ([`super::support::band_windows`]) read
    /// from `src` by positioned reads (runs of neighbouring blocks in one read); the
    /// other blocks' bytes are zeros and never decoded.
    pub(super) fn parsed<R: Read + Seek>(
        &self,
        src: &mut R,
        level: usize,
        region: &[Range<usize>],
    ) -> Result<Parsed> {
        let mut p = Parsed {
            header: self.header.clone(),
            meta: self.meta.clone(),
            plan: Plan::new(&self.header)?,
            bands: Vec::new(),
            resi: (0..self.header.channels).map(|_| None).collect(),
            complete: self.complete,
            chunks: self.chunks.clone(),
            window: Some(region.to_vec()),
            out_box: super::tiles::Stitch::new(&self.header, level, Some(region))
                .ok()
                .map(|st| st.out_box().to_vec()),
            blocks_in: None,
        };
        let wins = super::support::band_windows(&p, level);
        let mut bands = Vec::with_capacity(self.entries.len());
        for row in &self.entries {
            let mut out = Vec::with_capacity(row.len());
            for (j, e) in row.iter().enumerate() {
                let lv = self.levels[j];
                let (Some(e), false) = (e, lv >= 1 && lv <= level) else {
                    out.push(None);
                    continue;
                };
                let mut data = vec![0u8; e.len];
                data[..e.index.len()].copy_from_slice(&e.index);
                let grid = crate::entropy::codeblocks::Grid::new(&p.plan.dims[j], p.plan.block(j));
                let which = match &wins[j] {
                    Some(w) => grid.touching(w),
                    None => (0..grid.len()).collect(),
                };
                // runs of blocks that follow one another in the entry, one read each
                let mut runs: Vec<Range<usize>> = Vec::new();
                for i in which {
                    let r = e.streams[i].clone();
                    match runs.last_mut() {
                        Some(last) if last.end == r.start => last.end = r.end,
                        _ => runs.push(r),
                    }
                }
                for r in runs {
                    src.seek(SeekFrom::Start(e.at + r.start as u64))?;
                    src.read_exact(&mut data[r])?;
                }
                out.push(Some(BandChunk { step: e.step, data }));
            }
            bands.push(out);
        }
        p.bands = bands;
        Ok(p)
    }
}
