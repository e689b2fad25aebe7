//! Which files are read and written a slab of rows at a time ([`super::slab`]), so that
//! a file larger than memory is handled a slab at a time.
//!
//! Reading ([`open`]): a headerless `.raw` of a given layout and a NRRD of raw encoding
//! are read by seeking to the slab's first byte, a TIFF by its strips, tiles or pages.
//! Writing ([`write_slabs`]): `.raw`, NRRD of raw encoding ([`sink_for`]), TIFF and PNM
//! take the slabs in order after the header (a TIFF image in strips, a volume page by
//! page).
//!
//! A slab of rows `a..b` of a raster of extents `[d0, d1, …]` × `c` channels holds the
//! `(b − a)·d1·…·c` samples of those rows, row-major, as the whole raster would.

use std::io::{Seek, Write};
use std::ops::Range;
use std::path::Path;

use super::slab::{FileSlabs, Shape, SlabSink, SlabSource};
use super::{bytes, DataKind, Format, Metadata, ReadOptions, Samples};
use crate::{Error, Result};

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

    fn read_rows_parallel(&mut self, rows: Range<usize>) -> Result<Samples> {
        match self {
            Slabs::File(f) => f.as_mut().read_rows_parallel(rows),
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
        (Format::Nrrd, _) => Ok(super::nrrd::open_slabs(path)?.map(|f| Slabs::File(Box::new(f)))),
        (Format::Tiff, _) => super::tiff::open_slabs(path).map(|t| Some(Slabs::Tiff(Box::new(t)))),
        _ => Ok(None),
    }
}

/// Which outputs [`write_slabs`] writes a slab at a time: `.raw`, attached `.nrrd`
/// (raw encoding), `.tif` (uncompressed) and PGM / PPM / PAM.
pub fn streams_output(path: &Path) -> bool {
    matches!(
        Format::from_extension(path),
        Some(Format::Raw | Format::Nrrd | Format::Tiff | Format::Pnm)
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
    /// The bytes of the piece being written.
    buf: Vec<u8>,
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
    match Format::from_extension(path) {
        Some(Format::Tiff) => return super::tiff::write_slabs(w, shape, next),
        Some(Format::Pnm) => return super::pnm::write_slabs(w, shape, next),
        _ => {}
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
    Ok(StreamSink {
        w,
        nrrd,
        left: 0,
        buf: Vec::new(),
    })
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
        // a piece at a time through one buffer: no byte copy of the whole slab beside it
        const PIECE: usize = 1 << 20;
        let len = samples.len();
        for at in (0..len).step_by(PIECE) {
            bytes::encode_into(samples, at..(at + PIECE).min(len), false, &mut self.buf);
            self.w.write_all(&self.buf)?;
        }
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
