//! The code-blocks of a one-piece format 3.0 file left in the file for a whole decode
//! ([`BlockFile`], made by [`super::indexed_read`]): each batch of blocks read by one
//! positioned read when it is decoded. Nothing the size of the file's coded bytes is
//! held.

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
    /// The band entries `entries` (`[channel][band]`: offset and length `L`) of `file`,
    /// `len` bytes.
    pub(super) fn new(
        file: std::fs::File,
        len: u64,
        entries: Vec<Vec<Option<(u64, u64)>>>,
    ) -> BlockFile {
        BlockFile {
            file,
            len,
            entries,
            #[cfg(not(unix))]
            lock: std::sync::Mutex::new(()),
        }
    }

    /// The length `L` of the entry of band `j` of channel `c` (`None`: absent).
    pub(super) fn entry_len(&self, c: usize, j: usize) -> Option<u64> {
        self.entries.get(c)?.get(j)?.map(|e| e.1)
    }

    /// Bytes `r` of the entry of band `j` of channel `c` into `buf` (resized to them):
    /// an error, nothing read, unless the entry is present and `r` lies within it and
    /// the entry within the file.
    pub(super) fn read(
        &self,
        c: usize,
        j: usize,
        r: Range<usize>,
        buf: &mut Vec<u8>,
    ) -> Result<()> {
        let Some((at, l)) = self
            .entries
            .get(c)
            .and_then(|e| e.get(j))
            .copied()
            .flatten()
        else {
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
        let _g = self
            .lock
            .lock()
            .map_err(|_| Error::format("a reader of the file that failed", "a readable file"))?;
        let mut f = &self.file;
        f.seek(SeekFrom::Start(at))?;
        f.read_exact(buf)?;
        Ok(())
    }
}
