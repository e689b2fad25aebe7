//! A file parsed once for many regions: [`Opened::open`] reads the `HEAD`, `mETA` and,
//! of a one-piece format 3.0 file, every band entry's step and code-block index
//! ([`crate::format::sparse`]); [`Opened::region`] then reads by positioned reads only
//! the code-blocks a region's decode needs and decodes it. Other files (format 2.x,
//! tiled, `--max-error`) are read again on each call, only where the region needs them
//! ([`super::decode_seek`]).

use super::container::{read_head, Parsed};
use super::options::{DecodeOptions, Decoded};
use super::plan::Plan;
use crate::format::body::{BandChunk, ChunkInfo};
use crate::format::Header;
use crate::io::Metadata;
use crate::Result;
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
        let Some(sb) =
            crate::format::sparse::read_body_sparse(src, at, len, &header, &layout, stop_level)?
        else {
            return Ok(None);
        };
        let block = header.block_extents();
        let mut entries = Vec::with_capacity(sb.body.bands.len());
        for (c, bands) in sb.body.bands.into_iter().enumerate() {
            let mut row = Vec::with_capacity(bands.len());
            for (j, bc) in bands.into_iter().enumerate() {
                let (Some(bc), Some(off)) = (bc, sb.entries[c][j]) else {
                    row.push(None);
                    continue;
                };
                let set = crate::format::bands::parse_blocks(&bc.data, &plan.dims[j], &block)
                    .map_err(|e| {
                        crate::Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
                    })?;
                let head = set.streams.first().map_or(bc.data.len(), |r| r.start);
                row.push(Some(Entry {
                    at: off,
                    step: bc.step,
                    len: bc.data.len(),
                    index: bc.data[..head].to_vec(),
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
    /// with the code-blocks its bands' decodes need ([`super::decode::band_windows`]) read
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
        };
        let wins = super::decode::band_windows(&p);
        let block = self.header.block_extents();
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
                let grid = crate::entropy::codeblocks::Grid::new(&p.plan.dims[j], &block);
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

/// Where an [`Opened`] file's bytes are read from on each region.
enum Source {
    /// A file, opened again for each region (so that regions may be read at once from
    /// several threads).
    File(PathBuf),
    /// The bytes of a file.
    Bytes(Arc<[u8]>),
}

/// A file of `len` bytes read through `f` with a fresh reader of its source.
fn with_reader<T>(
    source: &Source,
    f: impl FnOnce(&mut dyn ReadSeek, u64) -> Result<T>,
) -> Result<T> {
    match source {
        Source::File(path) => {
            let mut file = std::fs::File::open(path)?;
            let len = file.metadata()?.len();
            f(&mut file, len)
        }
        Source::Bytes(b) => f(&mut std::io::Cursor::new(&b[..]), b.len() as u64),
    }
}

/// A reader that can also seek.
trait ReadSeek: Read + Seek {}
impl<T: Read + Seek> ReadSeek for T {}

/// An `.mra` file parsed once, for decoding many regions (and levels) of it without
/// reading its chunk heads, `mETA` or code-block indices again: `Send + Sync`, so that
/// one value serves regions on several threads at once. A one-piece format 3.0 file
/// keeps its code-block indices and reads only the blocks each region needs; any
/// other file is decoded as [`super::decode_seek`] decodes it on each call. A file
/// changed on disk after [`Opened::open`] is not noticed (its regions then fail or
/// decode wrongly): open it again.
pub struct Opened {
    header: Header,
    sparse: Option<Sparse>,
    source: Source,
}

impl Opened {
    /// Parse the file at `path` (its `HEAD`, `mETA` and, of a one-piece 3.0 file,
    /// every band's code-block index).
    pub fn open(path: &Path) -> Result<Opened> {
        Opened::parse(Source::File(path.to_path_buf()))
    }

    /// Parse the bytes of an `.mra` file (as [`Opened::open`]).
    pub fn from_bytes(bytes: impl Into<Arc<[u8]>>) -> Result<Opened> {
        Opened::parse(Source::Bytes(bytes.into()))
    }

    fn parse(source: Source) -> Result<Opened> {
        let (header, sparse) = with_reader(&source, |mut src, len| {
            let mut buf = std::io::BufReader::new(&mut *src);
            let (rd, _, header) = read_head(&mut buf, len)?;
            let at = rd.position();
            drop(buf);
            let sparse = if header.version.has_blocks() && !header.is_tiled() {
                Sparse::parse(&mut src, at, len, header.clone(), 0)?
            } else {
                None
            };
            Ok((header, sparse))
        })?;
        Ok(Opened {
            header,
            sparse,
            source,
        })
    }

    /// The file's header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The file's metadata (`mETA`) when it was parsed once (a one-piece 3.0 file).
    pub fn meta(&self) -> Option<&Metadata> {
        self.sparse.as_ref().map(|s| &s.meta)
    }

    /// Decode the file at level `level` (`0 ..= depth`), over the full-resolution box
    /// `window` (a range per axis, slowest first; `None`: the whole level), as
    /// [`super::decode_seek`] with [`DecodeOptions`] `{ level, region: window }` does:
    /// the same samples and metadata.
    pub fn region(&self, level: usize, window: Option<&[Range<usize>]>) -> Result<Decoded> {
        let opts = DecodeOptions {
            level,
            allow_truncated: false,
            region: window.map(|w| w.to_vec()),
        };
        super::read::check_level(&self.header, level)?;
        with_reader(&self.source, |mut src, len| match (&self.sparse, window) {
            (Some(s), Some(w)) => super::read::one_tile(s.parsed(&mut src, level, w)?, &opts),
            _ => super::read::decode_seek(src, len, &opts),
        })
    }
}
