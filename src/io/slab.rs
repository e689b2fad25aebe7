//! Rasters read and written in slabs along the slowest axis (rows of an image, slices
//! of a volume), so that a file larger than memory is handled a slab at a time.
//!
//! The pieces every format shares: a raster's [`Shape`], a [`SlabSource`] (a raster in
//! memory, [`MemorySlabs`]; samples at a byte offset of a file, [`FileSlabs`]) and a
//! [`SlabSink`]. Which files are read and written this way is [`super::stream`]'s.
//!
//! A slab of rows `a..b` of a raster of extents `[d0, d1, …]` × `c` channels holds the
//! `(b − a)·d1·…·c` samples of those rows, row-major, as the whole raster would.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::{bytes, DataKind, Metadata, Raster, RasterView, SampleType, Samples};
use crate::{Error, Result};

/// What a raster is, without its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// Extents, slowest axis first.
    pub dims: Vec<usize>,
    pub channels: usize,
    pub sample_type: SampleType,
    pub kind: DataKind,
    pub meta: Metadata,
}

impl Shape {
    /// The shape of a raster.
    pub fn of(r: &Raster) -> Shape {
        Shape::of_view(&r.view())
    }

    /// The shape of a borrowed raster.
    pub fn of_view(r: &RasterView<'_>) -> Shape {
        Shape {
            dims: r.dims.to_vec(),
            channels: r.channels,
            sample_type: r.sample_type(),
            kind: r.kind,
            meta: r.meta.clone(),
        }
    }

    /// Samples in one row of the slowest axis (`d1·…·c`).
    pub fn row_samples(&self) -> usize {
        self.dims[1..].iter().product::<usize>() * self.channels
    }

    /// Positions of the whole raster (`d0·d1·…`).
    pub fn positions(&self) -> usize {
        self.dims.iter().product()
    }

    /// A raster of this shape (its metadata included) holding `samples`.
    pub fn raster(&self, dims: Vec<usize>, samples: Samples) -> Result<Raster> {
        let mut r = Raster::new(dims, self.channels, samples, self.kind)?;
        r.meta = self.meta.clone();
        Ok(r)
    }
}

/// A raster that hands out its rows (along the slowest axis) a slab at a time.
pub trait SlabSource {
    /// The raster's extents, type and metadata.
    fn shape(&self) -> &Shape;
    /// The samples of rows `rows` of the slowest axis (within `0..dims[0]`).
    fn read_rows(&mut self, rows: Range<usize>) -> Result<Samples>;
    /// [`SlabSource::read_rows`], its pieces read on the threads of the pool where the
    /// source allows it (the same samples; for a caller with nothing else for the pool
    /// to do).
    fn read_rows_parallel(&mut self, rows: Range<usize>) -> Result<Samples> {
        self.read_rows(rows)
    }
}

/// A raster in memory as a [`SlabSource`].
pub struct MemorySlabs<'a> {
    raster: RasterView<'a>,
    shape: Shape,
}

impl<'a> MemorySlabs<'a> {
    pub fn new(raster: &'a Raster) -> Self {
        Self::of_view(raster.view())
    }

    /// Slabs of a borrowed raster (no copy but the slabs handed out).
    pub fn of_view(raster: RasterView<'a>) -> Self {
        MemorySlabs {
            shape: Shape::of_view(&raster),
            raster,
        }
    }
}

impl SlabSource for MemorySlabs<'_> {
    fn shape(&self) -> &Shape {
        &self.shape
    }

    fn read_rows(&mut self, rows: Range<usize>) -> Result<Samples> {
        check_rows(&self.shape, &rows)?;
        let per = self.shape.row_samples();
        Ok(self.raster.samples.range(rows.start * per..rows.end * per))
    }
}

fn check_rows(shape: &Shape, rows: &Range<usize>) -> Result<()> {
    if rows.start >= rows.end || rows.end > shape.dims[0] {
        return Err(Error::parameter(
            "rows",
            format!("{}..{} of {}", rows.start, rows.end, shape.dims[0]),
            "a non-empty range within the slowest axis",
        ));
    }
    Ok(())
}

/// A file whose samples lie contiguously from a byte offset (headerless raw, NRRD of raw
/// encoding), read a slab at a time by seeking.
pub struct FileSlabs {
    shape: Shape,
    file: File,
    path: PathBuf,
    offset: u64,
    big_endian: bool,
}

impl FileSlabs {
    /// The file the samples are read from (the data file of a detached NRRD header).
    pub fn data_path(&self) -> &Path {
        &self.path
    }

    /// Samples of `shape` at byte `offset` of `path`; the file must hold them all.
    pub(super) fn new(shape: Shape, path: &Path, offset: u64, big_endian: bool) -> Result<Self> {
        let file = File::open(path)?;
        let len = file.metadata()?.len();
        let need = bytes::checked_bytes(
            &shape.dims,
            shape.channels,
            shape.sample_type,
            len.saturating_sub(offset),
        )?;
        debug_assert!(offset + need as u64 <= len);
        Ok(FileSlabs {
            shape,
            file,
            path: path.to_path_buf(),
            offset,
            big_endian,
        })
    }
}

impl SlabSource for FileSlabs {
    fn shape(&self) -> &Shape {
        &self.shape
    }

    fn read_rows(&mut self, rows: Range<usize>) -> Result<Samples> {
        check_rows(&self.shape, &rows)?;
        let per = self.shape.row_samples();
        let size = self.shape.sample_type.size() as u64;
        let at = self.offset + (rows.start * per) as u64 * size;
        let n = rows.len() * per;
        self.file.seek(SeekFrom::Start(at))?;
        let rd = std::io::BufReader::with_capacity(1 << 20, (&self.file).take(n as u64 * size));
        bytes::read_samples(rd, n, self.shape.sample_type, self.big_endian)
            .map_err(|e| self.read_error(e, &rows))
    }

    #[cfg(unix)]
    fn read_rows_parallel(&mut self, rows: Range<usize>) -> Result<Samples> {
        check_rows(&self.shape, &rows)?;
        let per = self.shape.row_samples();
        let ty = self.shape.sample_type;
        let size = ty.size();
        let at = self.offset + (rows.start * per * size) as u64;
        let n = rows.len() * per;
        let mut pieces = Pieces {
            file: &self.file,
            at,
            size,
            big_endian: self.big_endian,
        };
        bytes::typed_samples(ty, n, &mut pieces).map_err(|e| self.read_error(e, &rows))
    }
}

impl FileSlabs {
    /// The error of a read of rows `rows`: the file ending early means it changed.
    fn read_error(&self, e: std::io::Error, rows: &Range<usize>) -> Error {
        match e.kind() {
            std::io::ErrorKind::UnexpectedEof => Error::format(
                format!(
                    "{} ends within rows {}..{} (file changed while reading)",
                    self.path.display(),
                    rows.start,
                    rows.end
                ),
                "a stable file",
            ),
            _ => e.into(),
        }
    }
}

/// Samples read in pieces of [`PIECE`], each at its own offset (`pread`) by a thread of the
/// pool: piece `k` starts at byte `at + k·PIECE·size`.
#[cfg(unix)]
struct Pieces<'a> {
    file: &'a File,
    at: u64,
    size: usize,
    big_endian: bool,
}

/// Samples per parallel piece.
#[cfg(unix)]
const PIECE: usize = 1 << 20;

#[cfg(unix)]
impl bytes::FillSamples for Pieces<'_> {
    type Error = std::io::Error;
    fn fill<T: bytes::ReadInto>(&mut self, v: &mut [T]) -> std::io::Result<()> {
        use rayon::prelude::*;
        let (file, at, size, big) = (self.file, self.at, self.size, self.big_endian);
        v.par_chunks_mut(PIECE).enumerate().try_for_each(|(k, c)| {
            let mut r = At {
                file,
                pos: at + (k * PIECE * size) as u64,
            };
            T::read_into(&mut r, big, c)
        })
    }
}

/// A reader at a byte offset of a shared file, by positioned reads (`pread`): readers at
/// different offsets of one file on several threads.
#[cfg(unix)]
struct At<'a> {
    file: &'a File,
    pos: u64,
}

#[cfg(unix)]
impl Read for At<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let k = std::os::unix::fs::FileExt::read_at(self.file, buf, self.pos)?;
        self.pos += k as u64;
        Ok(k)
    }
}

/// Where slabs go: the header first ([`SlabSink::begin`]), then every row of the
/// slowest axis in order ([`SlabSink::rows`]), then [`SlabSink::end`].
pub trait SlabSink {
    fn begin(&mut self, shape: &Shape) -> Result<()>;
    fn rows(&mut self, samples: &Samples) -> Result<()>;
    fn end(&mut self) -> Result<()>;
}
