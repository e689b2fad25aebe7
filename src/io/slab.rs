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
        bytes::read_samples(rd, n, self.shape.sample_type, self.big_endian).map_err(|e| {
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
        })
    }
}

/// Where slabs go: the header first ([`SlabSink::begin`]), then every row of the
/// slowest axis in order ([`SlabSink::rows`]), then [`SlabSink::end`].
pub trait SlabSink {
    fn begin(&mut self, shape: &Shape) -> Result<()>;
    fn rows(&mut self, samples: &Samples) -> Result<()>;
    fn end(&mut self) -> Result<()>;
}
