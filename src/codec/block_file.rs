//! The code-blocks of a one-piece format 3.0 file left in the file for a whole decode
//! ([`BlockFile`]): the chunks read as [`crate::format::sparse`] reads them (the heads,
//! `mETA`, each band entry's code-block index; every `LEVL` chunk's CRC checked a piece
//! at a time) into a [`Parsed`] whose band entries hold their index alone, and each
//! batch of blocks read by one positioned read when it is decoded. Nothing the size of
//! the file's coded bytes is held.

use super::container::Parsed;
use super::plan::Plan;
use crate::format::Header;
use crate::{Error, Result};
use std::ops::Range;

/// A file's band entries by position: each batch of code-blocks is read from the file
/// as it is decoded ([`BlockFile::read`]).
pub(super) struct BlockFile {
    file: std::fs::File,
    /// Bytes of the file.
    len: u64,
    /// `[channel][band]`: the file offset of the entry's first byte and its length `L`.
    entries: Vec<Vec<Option<(u64, u64)>>>,
    /// Serializes the seek and read of a platform without positioned reads.
    #[cfg(not(unix))]
    lock: std::sync::Mutex<()>,
}

impl BlockFile {
    /// The length `L` of the entry of band `j` of channel `c` (`None`: absent).
    pub(super) fn entry_len(&self, c: usize, j: usize) -> Option<u64> {
        self.entries.get(c)?.get(j)?.map(|e| e.1)
    }

    /// Bytes `r` of the entry of band `j` of channel `c` into `buf` (resized to them):
    /// an error, nothing read, unless the entry is present and `r` lies within it and
    /// the entry within the file.
    pub(super) fn read(&self, c: usize, j: usize, r: Range<usize>, buf: &mut Vec<u8>) -> Result<()> {
        let Some((at, l)) = self.entries.get(c).and_then(|e| e.get(j)).copied().flatten() else {
            return Err(Error::format(
                format!("band {j} of channel {c}: no entry"),
                "a band read from its LEVL chunk",
            ));
        };
        let (start, end) = (r.start as u64, r.end as u64);
        if start > end || end > l || at.saturating_add(l) > self.len {
            return Err(Error::format(
                format!(
                    "band {j} of channel {c}: bytes {start}..{end} of an entry of {l} bytes at byte {at} of a file of {} bytes",
                    self.len
                ),
                "code-blocks within their entry, within the file",
            ));
        }
        buf.clear();
        buf.resize(r.len(), 0);
        self.read_at(buf, at + start)
    }

    #[cfg(unix)]
    fn read_at(&self, buf: &mut [u8], at: u64) -> Result<()> {
        std::os::unix::fs::FileExt::read_exact_at(&self.file, buf, at)?;
        Ok(())
    }

    #[cfg(not(unix))]
    fn read_at(&self, buf: &mut [u8], at: u64) -> Result<()> {
        use std::io::{Read, Seek, SeekFrom};
        let _g = self.lock.lock().map_err(|_| {
            Error::format("a reader of the file that failed", "a readable file")
        })?;
        let mut f = &self.file;
        f.seek(SeekFrom::Start(at))?;
        f.read_exact(buf)?;
        Ok(())
    }
}

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
    let sb =
        crate::format::sparse::read_body_sparse(src, at, len, &header, &layout, (0, true))?;
    let Some(sb) = sb else {
        return Ok(None);
    };
    let blocks = BlockFile {
        file,
        len,
        entries: sb.entries,
        #[cfg(not(unix))]
        lock: std::sync::Mutex::new(()),
    };
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
