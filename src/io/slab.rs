//! Rasters read and written in slabs along the slowest axis (rows of an image, slices
//! of a volume), so that a file larger than memory is handled a slab at a time.
//!
//! Reading ([`SlabSource`]): a headerless `.raw` of a given layout and a NRRD of raw
//! encoding are read by seeking to the slab's first byte, a TIFF by its strips, tiles
//! or pages ([`open`]); any raster in
//! memory is a source too ([`MemorySlabs`]). Writing ([`write_slabs`]): `.raw`, NRRD of
//! raw encoding ([`sink_for`], a [`SlabSink`]) and TIFF take the slabs in order after
//! the header (a TIFF image in strips, a volume page by page).
//!
//! A slab of rows `a..b` of a raster of extents `[d0, d1, …]` × `c` channels holds the
//! `(b − a)·d1·…·c` samples of those rows, row-major, as the whole raster would.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::{bytes, DataKind, Format, Metadata, Raster, ReadOptions, SampleType, Samples};
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
        Shape {
            dims: r.dims.clone(),
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
    raster: &'a Raster,
    shape: Shape,
}

impl<'a> MemorySlabs<'a> {
    pub fn new(raster: &'a Raster) -> Self {
        MemorySlabs {
            shape: Shape::of(raster),
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

/// A file read in slabs.
pub enum Slabs {
    /// Samples at a byte offset: headerless raw, NRRD of raw encoding.
    File(Box<FileSlabs>),
    /// A TIFF's strips, tiles or pages.
    Tiff(Box<super::tiff::TiffSlabs>),
}

impl SlabSource for Slabs {
    fn shape(&self) -> &Shape {
        match self {
            Slabs::File(f) => f.as_ref().shape(),
            Slabs::Tiff(t) => t.shape(),
        }
    }

    fn read_rows(&mut self, rows: Range<usize>) -> Result<Samples> {
        match self {
            Slabs::File(f) => f.as_mut().read_rows(rows),
            Slabs::Tiff(t) => t.read_rows(rows),
        }
    }
}

/// A file readable in slabs: a `.raw` with its layout, a NRRD of raw encoding, or a
/// TIFF (strips, tiles or a page stack).
/// `None` for every other file (the caller reads it whole); errors as the whole reader
/// would give them (a raw file of the wrong size, a bad NRRD header).
pub fn open(path: &Path, opts: &ReadOptions) -> Result<Option<Slabs>> {
    let format = Format::detect(path)?;
    match (format, &opts.raw) {
        (Format::Raw, Some(spec)) => {
            let len = std::fs::metadata(path)?.len();
            let need = bytes::checked_bytes(&spec.dims, 1, spec.sample_type, len)?;
            if need as u64 != len {
                // the whole reader words the mismatch
                return super::raw::read(path, spec).map(|_| None);
            }
            let kind = match spec.dims.len() {
                1 => DataKind::Sequence,
                2 => DataKind::Image,
                _ => DataKind::Volume,
            };
            let shape = Shape {
                dims: spec.dims.clone(),
                channels: 1,
                sample_type: spec.sample_type,
                kind,
                meta: Metadata::default(),
            };
            FileSlabs::new(shape, path, 0, spec.big_endian).map(|f| Some(Slabs::File(Box::new(f))))
        }
        (Format::Nrrd, _) => super::nrrd::open_slabs(path),
        (Format::Tiff, _) => super::tiff::open_slabs(path).map(|t| Some(Slabs::Tiff(Box::new(t)))),
        _ => Ok(None),
    }
}

/// Where slabs go: the header first ([`SlabSink::begin`]), then every row of the
/// slowest axis in order ([`SlabSink::rows`]), then [`SlabSink::end`].
pub trait SlabSink {
    fn begin(&mut self, shape: &Shape) -> Result<()>;
    fn rows(&mut self, samples: &Samples) -> Result<()>;
    fn end(&mut self) -> Result<()>;
}

/// Which outputs [`write_slabs`] writes a slab at a time: `.raw`, attached `.nrrd`
/// (raw encoding) and `.tif` (uncompressed).
pub fn streams_output(path: &Path) -> bool {
    matches!(
        Format::from_extension(path),
        Some(Format::Raw | Format::Nrrd | Format::Tiff)
    ) && !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("nhdr"))
}

/// Samples written as stored (little-endian raw, or attached NRRD of raw encoding with
/// the header of [`super::nrrd::write`]).
pub struct StreamSink<W: Write> {
    w: W,
    nrrd: bool,
    left: u64,
}

/// Write a raster handed over in slabs (`next` gives the rows of the slowest axis in
/// order, `None` at the end) into `w` in the format of `path`'s extension (see
/// [`streams_output`]), as [`super::write`] would write it.
pub fn write_slabs<W: Write + Seek>(
    path: &Path,
    w: &mut W,
    shape: &Shape,
    next: &mut dyn FnMut() -> Result<Option<Samples>>,
) -> Result<()> {
    if Format::from_extension(path) == Some(Format::Tiff) {
        return super::tiff::write_slabs(w, shape, next);
    }
    let mut sink = sink_for(path, w)?;
    sink.begin(shape)?;
    while let Some(s) = next()? {
        sink.rows(&s)?;
    }
    sink.end()
}

/// A sink writing `.raw` or attached `.nrrd` into `w`.
pub fn sink_for<W: Write>(path: &Path, w: W) -> Result<StreamSink<W>> {
    let nrrd = match Format::from_extension(path) {
        Some(Format::Raw) => false,
        Some(Format::Nrrd)
            if !path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("nhdr")) =>
        {
            true
        }
        _ => {
            return Err(Error::Unsupported {
                what: "output written in slabs",
                value: format!("{} (expected .raw or .nrrd)", path.display()),
            })
        }
    };
    Ok(StreamSink { w, nrrd, left: 0 })
}

impl<W: Write> SlabSink for StreamSink<W> {
    fn begin(&mut self, shape: &Shape) -> Result<()> {
        self.left = bytes::sample_count(&shape.dims, shape.channels)? as u64;
        if self.nrrd {
            let head = super::nrrd::header_text(shape, "raw", None)?;
            self.w.write_all(head.as_bytes())?;
            self.w.write_all(b"\n")?;
        }
        Ok(())
    }

    fn rows(&mut self, samples: &Samples) -> Result<()> {
        let n = samples.len() as u64;
        if n > self.left {
            return Err(Error::parameter(
                "slab",
                format!("{n} samples with {} left", self.left),
                "the raster's samples, once",
            ));
        }
        self.left -= n;
        self.w.write_all(&bytes::encode(samples, false))?;
        Ok(())
    }

    fn end(&mut self) -> Result<()> {
        if self.left != 0 {
            return Err(Error::parameter(
                "slabs",
                format!("{} samples missing", self.left),
                "every row of the raster",
            ));
        }
        self.w.flush()?;
        Ok(())
    }
}
