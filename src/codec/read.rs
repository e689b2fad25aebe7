//! The decoder's entries: a file's `HEAD` read, then a one-tile file decoded whole
//! ([`super::decode`]) and cut to a region, or a tiled file's tiles read in order or
//! only those a region meets ([`super::tiles`]).

use super::container::{read_head, read_rest, Parsed};
use super::decode::reconstruct;
use super::options::{DecodeOptions, Decoded};
use super::tiles;
use crate::format::Header;
use crate::io::slab::{Shape, SlabSink};
use crate::Result;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// Decode from a stream of `len` bytes, read in order (a tiled file's tiles as they
/// come; [`decode_seek`] reads only those a region needs).
pub fn decode_stream<R: Read>(src: R, len: u64, opts: &DecodeOptions) -> Result<Decoded> {
    let (rd, first, header) = read_head(src, len)?;
    if header.is_tiled() {
        return tiles::decode_sequential(rd, header, opts);
    }
    one_tile(
        read_rest(rd, first, header, opts.level, opts.allow_truncated)?,
        opts,
    )
}

/// A one-tile file's chunks reconstructed, and cut to the region asked for.
fn one_tile(p: Parsed, opts: &DecodeOptions) -> Result<Decoded> {
    let mut raster = reconstruct(&p, opts.level)?;
    if let Some(region) = &opts.region {
        let st = tiles::Stitch::new(&p.header, opts.level, Some(region))?;
        raster = tiles::crop_raster(&raster, st.out_box())?;
    }
    Ok(Decoded {
        raster,
        header: p.header,
        complete: p.complete,
    })
}

/// Decode from a seekable stream of `len` bytes: a tiled file's `HEAD`, `mETA` and tile
/// index, then only the tiles that `opts.region` meets (all without a region).
pub fn decode_seek<R: Read + Seek>(mut src: R, len: u64, opts: &DecodeOptions) -> Result<Decoded> {
    src.seek(SeekFrom::Start(0))?;
    let (rd, first, header) = read_head(&mut src, len)?;
    if header.is_tiled() {
        let at = rd.position();
        drop(rd);
        return tiles::decode_seek(&mut src, len, at, header, opts);
    }
    one_tile(
        read_rest(rd, first, header, opts.level, opts.allow_truncated)?,
        opts,
    )
}

/// The `HEAD` of an `.mra` file, read alone.
pub fn header_of_file(path: &Path) -> Result<Header> {
    let f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    Ok(read_head(std::io::BufReader::new(f), len)?.2)
}

/// Decode the bytes of an `.mra` file.
pub fn decode(bytes: &[u8], opts: &DecodeOptions) -> Result<Decoded> {
    decode_seek(std::io::Cursor::new(bytes), bytes.len() as u64, opts)
}

/// Decode a file, reading only the chunks needed.
pub fn decode_file(path: &Path, opts: &DecodeOptions) -> Result<Decoded> {
    let f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    decode_seek(std::io::BufReader::new(f), len, opts)
}

/// Decode a file into `sink` a slab of rows at a time: a tiled file one tile-row (2-D)
/// or tile-slab (3-D) at a time, reading only the tiles `opts.region` meets; a file of
/// one tile decoded whole and handed over as one slab. Returns the output's shape and
/// whether the file was complete.
pub fn decode_file_slabs(
    path: &Path,
    opts: &DecodeOptions,
    sink: &mut dyn SlabSink,
) -> Result<(Shape, bool)> {
    let f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    let mut src = std::io::BufReader::new(f);
    let (rd, first, header) = read_head(&mut src, len)?;
    if header.is_tiled() {
        let at = rd.position();
        drop(rd);
        return tiles::decode_seek_slabs(&mut src, len, at, header, opts, sink);
    }
    let d = one_tile(
        read_rest(rd, first, header, opts.level, opts.allow_truncated)?,
        opts,
    )?;
    let shape = Shape::of(&d.raster);
    sink.begin(&shape)?;
    sink.rows(&d.raster.samples)?;
    sink.end()?;
    Ok((shape, d.complete))
}
