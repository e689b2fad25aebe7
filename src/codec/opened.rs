//! A file parsed once for many regions: [`Opened::open`] reads the `HEAD`, `mETA` and,
//! of a one-piece format 3.0 file, every band entry's step and code-block index
//! ([`crate::format::sparse`]); [`Opened::region`] then reads by positioned reads only
//! the code-blocks a region's decode needs and decodes it. Other files (format 2.x,
//! tiled, `--max-error`) are read again on each call, only where the region needs them
//! ([`super::decode_seek`]).

use super::container::read_head;
use super::options::{DecodeOptions, Decoded};
use super::sparse_read::Sparse;
use crate::format::Header;
use crate::io::Metadata;
use crate::Result;
use std::io::{Read, Seek};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
        self.sparse.as_ref().map(|s| s.meta())
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
