//! A one-piece format 3.0 file read for a whole decode with its code-blocks left in the
//! file: the chunks read as [`crate::format::sparse`] reads them (the heads, `mETA`,
//! each band entry's code-block index; every `LEVL` chunk's CRC checked a piece at a
//! time) into a [`Parsed`] whose band entries hold their index alone, the blocks read
//! from the file as they are decoded ([`BlockFile`]).

use super::block_file::BlockFile;
use super::container::Parsed;
use super::plan::Plan;
use crate::format::Header;
use crate::Result;

/// The chunks after `HEAD` (the next at byte `at`; header `header`) of the one-piece
/// 3.0 file of `len` bytes that `src` reads and `file` is, read for a whole decode: its band entries' indices
/// in the returned [`Parsed`]'s bands, their blocks left in the file
/// ([`Parsed::blocks_in`]); every chunk checked as the whole read checks it (each
/// `LEVL` CRC a piece at a time, each index by [`crate::format::bands::parse_index`]
/// when the decoder parses it). `None` for a file the sparse reader leaves to the whole
/// read (a tiled file, one before format 3, one with `RESI` chunks).
pub(super) fn read_indexed<R: std::io::Read + std::io::Seek>(
    src: &mut R,
    file: std::fs::File,
    (at, len): (u64, u64),
    header: Header,
) -> Result<Option<Parsed>> {
    if header.is_tiled() || !header.version.has_blocks() {
        return Ok(None);
    }
    let plan = Plan::new(&header)?;
    let groups = plan.level_groups();
    let layout = plan.band_layout(&groups);
    let sb = crate::format::sparse::read_body_sparse(src, at, len, &header, &layout, (0, true))?;
    let Some(sb) = sb else {
        return Ok(None);
    };
    let blocks = BlockFile::new(file, len, sb.entries);
    Ok(Some(Parsed {
        header,
        meta: sb.body.meta,
        plan,
        bands: sb.body.bands,
        resi: sb.body.resi,
        complete: sb.body.complete,
        chunks: sb.body.chunks,
        window: None,
        out_box: None,
        blocks_in: Some(std::sync::Arc::new(blocks)),
    }))
}

/// The file at `path` read for [`super::StreamedDecoder`]: a one-piece 3.0 file as
/// [`read_indexed`] reads it (its blocks left in the file), any other one whole
/// ([`super::container::read_chunks`]).
pub(super) fn read_for_stream(path: &std::path::Path) -> Result<Parsed> {
    use std::io::{Seek, SeekFrom};
    let f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    let mut src = std::io::BufReader::new(f.try_clone()?);
    let (rd, _, header) = super::container::read_head(&mut src, len)?;
    let at = rd.position();
    if let Some(p) = read_indexed(&mut src, f, (at, len), header)? {
        return Ok(p);
    }
    src.seek(SeekFrom::Start(0))?;
    super::container::read_chunks(src, len, 0, false)
}
