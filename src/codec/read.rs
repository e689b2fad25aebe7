//! The decoder's entries: a file's `HEAD` read, then a one-tile file decoded whole
//! ([`super::decode`]) and cut to a region, or a tiled file's tiles read in order or
//! only those a region meets ([`super::tiles`]).

use super::container::{read_head, read_rest, Parsed};
use super::decode::{reconstruct, reconstruct_window};
use super::options::{DecodeOptions, Decoded};
use super::sparse_read::Sparse;
use super::tiles;
use crate::format::{Chunk, ChunkReader, Header};
use crate::io::slab::{Shape, SlabSink};
use crate::io::Samples;
use crate::Result;
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;
use std::path::Path;

/// `level` is one the file of `header` holds (`0 ..= depth`, [`super::depth_of`]): a
/// deeper level is [`crate::Error::Level`], never clamped to the coarsest.
pub(super) fn check_level(header: &Header, level: usize) -> Result<()> {
    if level == 0 {
        return Ok(());
    }
    let levels = super::depth_of(header)?;
    if level > levels {
        return Err(crate::Error::Level { level, levels });
    }
    Ok(())
}

/// Decode from a stream of `len` bytes, read in order (a tiled file's tiles as they
/// come; [`decode_seek`] reads only those a region needs).
pub fn decode_stream<R: Read>(src: R, len: u64, opts: &DecodeOptions) -> Result<Decoded> {
    let (rd, first, header) = read_head(src, len)?;
    check_level(&header, opts.level)?;
    if header.is_tiled() {
        return tiles::decode_sequential(rd, header, opts);
    }
    one_tile(
        read_rest(rd, first, header, opts.level, opts.allow_truncated)?,
        opts,
    )
}

/// A one-tile file's chunks reconstructed, and cut to the region asked for.
pub(super) fn one_tile(mut p: Parsed, opts: &DecodeOptions) -> Result<Decoded> {
    let stitch = match &opts.region {
        Some(region) => Some(tiles::Stitch::new(&p.header, opts.level, Some(region))?),
        None => None,
    };
    // a format 3 file decodes only the code-blocks the region needs
    p.window = opts.region.clone();
    p.out_box = stitch.as_ref().map(|st| st.out_box().to_vec());
    if let Some(st) = &stitch {
        if let Some(raster) = reconstruct_window(&p, opts.level, st.out_box())? {
            return Ok(Decoded {
                raster,
                header: p.header,
                complete: p.complete,
            });
        }
    }
    let mut raster = reconstruct(&p, opts.level)?;
    if let Some(st) = stitch {
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
    check_level(&header, opts.level)?;
    let at = rd.position();
    if header.is_tiled() {
        return tiles::decode_seek(&mut src, len, at, header, opts);
    }
    one_piece(&mut src, at, len, first, header, opts)
}

/// A one-tile file decoded from a seekable stream whose `HEAD` (`first`) has been read
/// (the next chunk at byte `at`): a 3.0 file's region from only the code-blocks it needs
/// ([`read_region`]), anything else read whole ([`read_rest`]).
fn one_piece<R: Read + Seek>(
    src: &mut R,
    at: u64,
    len: u64,
    first: Chunk,
    header: Header,
    opts: &DecodeOptions,
) -> Result<Decoded> {
    if let Some(region) = &opts.region {
        if header.version.has_blocks() && !opts.allow_truncated {
            if let Some(p) = read_region(src, at, len, header.clone(), opts.level, region)? {
                return one_tile(p, opts);
            }
        }
    }
    src.seek(SeekFrom::Start(at))?;
    let rd = ChunkReader::at(src, at, len);
    one_tile(
        read_rest(rd, first, header, opts.level, opts.allow_truncated)?,
        opts,
    )
}

/// The chunks after `HEAD` (the next at byte `at` of `len`) of a one-piece 3.0 file read
/// for the full-resolution box `region` at level `stop_level`: the heads, `mETA` and
/// code-block indices, then only the code-blocks each band's decode needs
/// ([`Sparse`]). `None` for a file left to the whole read.
fn read_region<R: Read + Seek>(
    src: &mut R,
    at: u64,
    len: u64,
    header: Header,
    stop_level: usize,
    region: &[Range<usize>],
) -> Result<Option<Parsed>> {
    match Sparse::parse(src, at, len, header, stop_level)? {
        Some(s) => Ok(Some(s.parsed(src, stop_level, region)?)),
        None => Ok(None),
    }
}

/// The `HEAD` of an `.mra` file, read alone.
pub fn header_of_file(path: &Path) -> Result<Header> {
    let f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    Ok(read_head(std::io::BufReader::new(f), len)?.2)
}

/// The `HEAD` of the bytes of an `.mra` file, read alone (the other chunks are not
/// read or checked).
pub fn header_of(bytes: &[u8]) -> Result<Header> {
    Ok(read_head(bytes, bytes.len() as u64)?.2)
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

/// What [`decode_file_slabs`] decoded.
#[derive(Clone, Debug)]
pub struct SlabDecode {
    /// The output's extents, type and metadata.
    pub shape: Shape,
    /// False when the file ended before its `MEND` chunk (only with `allow_truncated`).
    pub complete: bool,
    /// Bytes of the file the decoder read: what a region costs.
    pub bytes_read: u64,
}

/// A reader counting the bytes it hands out.
struct Counting<R> {
    inner: R,
    count: std::rc::Rc<std::cell::Cell<u64>>,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count.set(self.count.get() + n as u64);
        Ok(n)
    }
}

impl<R: Seek> Seek for Counting<R> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(pos)
    }
}

type CountedFile = Counting<std::io::BufReader<std::fs::File>>;

/// A file decoded a slab of rows at a time: a tiled file one tile-row (2-D) or
/// tile-slab (3-D) at a time, reading only the tiles `opts.region` meets; a file of one
/// tile decoded whole and handed over as one slab.
pub struct SlabDecoder {
    tiled: Option<tiles::TiledSlabs<CountedFile>>,
    /// A one-piece lossy 3.0 file over the one-piece limit, synthesized a row at a time.
    streamed: Option<super::streamed::StreamedDecoder>,
    /// A file of one tile: its samples (until handed over) and completeness.
    whole: Option<Samples>,
    whole_complete: bool,
    shape: Shape,
    count: std::rc::Rc<std::cell::Cell<u64>>,
}

impl SlabDecoder {
    /// Open `path` and read its header (and a tiled file's index).
    pub fn open(path: &Path, opts: &DecodeOptions) -> Result<SlabDecoder> {
        let f = std::fs::File::open(path)?;
        let len = f.metadata()?.len();
        let count = std::rc::Rc::new(std::cell::Cell::new(0));
        let mut src = Counting {
            inner: std::io::BufReader::new(f),
            count: count.clone(),
        };
        let (rd, first, header) = read_head(&mut src, len)?;
        check_level(&header, opts.level)?;
        if header.is_tiled() {
            let at = rd.position();
            let t = tiles::TiledSlabs::new(src, len, at, header, opts)?;
            return Ok(SlabDecoder {
                shape: t.shape().clone(),
                tiled: Some(t),
                streamed: None,
                whole: None,
                whole_complete: true,
                count,
            });
        }
        if opts.region.is_none()
            && opts.level == 0
            && !opts.allow_truncated
            && super::streamed::decodes_streamed(&header)
        {
            // the code-blocks left in the file, read a batch at a time as decoded
            let at = rd.position();
            let file = src.inner.get_ref().try_clone()?;
            let p =
                match super::indexed_read::read_indexed(&mut src, file, (at, len), header.clone())?
                {
                    Some(p) => p,
                    None => {
                        src.seek(SeekFrom::Start(at))?;
                        read_rest(
                            ChunkReader::at(&mut src, at, len),
                            first.clone(),
                            header.clone(),
                            0,
                            false,
                        )?
                    }
                };
            let p = match super::StreamedDecoder::streaming(p)? {
                Ok(s) => {
                    return Ok(SlabDecoder {
                        shape: s.shape().clone(),
                        tiled: None,
                        streamed: Some(s),
                        whole: None,
                        whole_complete: true,
                        count,
                    })
                }
                // not laid out as the stream lays out its pyramid: read whole
                Err(p) if p.blocks_in.is_some() => {
                    src.seek(SeekFrom::Start(at))?;
                    read_rest(ChunkReader::at(&mut src, at, len), first, header, 0, false)?
                }
                Err(p) => p,
            };
            let d = one_tile(p, opts)?;
            return Ok(SlabDecoder {
                shape: Shape::of(&d.raster),
                tiled: None,
                streamed: None,
                whole: Some(d.raster.samples),
                whole_complete: d.complete,
                count,
            });
        }
        let at = rd.position();
        let d = one_piece(&mut src, at, len, first, header, opts)?;
        Ok(SlabDecoder {
            shape: Shape::of(&d.raster),
            tiled: None,
            streamed: None,
            whole: Some(d.raster.samples),
            whole_complete: d.complete,
            count,
        })
    }

    /// The output's extents, type and metadata.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// The next rows of the output (along the slowest axis), `None` after the last.
    pub fn next_slab(&mut self) -> Result<Option<Samples>> {
        if let Some(s) = &mut self.streamed {
            return s.next_slab();
        }
        match &mut self.tiled {
            Some(t) => t.next_slab(),
            None => Ok(self.whole.take()),
        }
    }

    /// False when the file ended before its `MEND` chunk (only with `allow_truncated`);
    /// final after the last slab.
    pub fn complete(&self) -> bool {
        match &self.tiled {
            Some(t) => t.complete(),
            None => self.whole_complete,
        }
    }

    /// Bytes of the file the decoder has read so far (the buffered reader under it
    /// reads ahead by up to 8 KiB after each seek).
    pub fn bytes_read(&self) -> u64 {
        self.count.get()
    }
}

/// Decode a file into `sink` a slab of rows at a time ([`SlabDecoder`]).
pub fn decode_file_slabs(
    path: &Path,
    opts: &DecodeOptions,
    sink: &mut dyn SlabSink,
) -> Result<SlabDecode> {
    let mut d = SlabDecoder::open(path, opts)?;
    sink.begin(d.shape())?;
    while let Some(s) = d.next_slab()? {
        sink.rows(&s)?;
    }
    sink.end()?;
    Ok(SlabDecode {
        shape: d.shape().clone(),
        complete: d.complete(),
        bytes_read: d.bytes_read(),
    })
}
