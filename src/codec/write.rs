//! The encoder's entries: a raster checked, then coded whole (its voids filled) or cut
//! into tiles ([`super::tiles`]), each tile coded by [`super::encode`].

use super::encode::encode_filled;
use super::options::EncodeOptions;
use super::voids::with_voids_filled;
use crate::io::slab::{MemorySlabs, Shape, SlabSource};
use crate::io::{Raster, RasterView};
use crate::{Error, Result};

/// Encode a raster into the bytes of an `.mra` file. Void samples (NaN, `meta.nodata`)
/// are filled by pull-push before the transform and listed in the metadata, so that the
/// decoder marks them again ([`crate::io::nodata`]). The layout is [`default_layout`]'s,
/// as [`encode_stream`] writes it for `mra encode`: over the one-piece limit one
/// transform streamed a slab at a time where [`streams`] covers the raster, else the
/// tiles of [`super::tiles::default_tile`] ([`encode_tiled`]); so a raster gives the same
/// file whether it is encoded in memory (Python) or from a file.
pub fn encode(r: &Raster, opts: &EncodeOptions) -> Result<Vec<u8>> {
    encode_view(&r.view(), opts)
}

/// [`encode`] of a borrowed raster (samples read where they are, e.g. in a NumPy array).
pub fn encode_view(r: &RasterView<'_>, opts: &EncodeOptions) -> Result<Vec<u8>> {
    check_count(r)?;
    encode_tiled_view(r, opts, &default_layout(&Shape::of_view(r), opts))
}

/// [`encode`] with the raster cut into tiles of extents `tile` (slowest axis first,
/// each from 1 to the axis extent; equal to the extents: one tile, a format 2.0 file),
/// each coded on its own at one base step for the whole raster (formats/MRA.md §14).
/// One tile over the one-piece limit is the streamed file where [`streams`] covers the
/// raster, as [`encode_stream`] writes it.
pub fn encode_tiled(r: &Raster, opts: &EncodeOptions, tile: &[usize]) -> Result<Vec<u8>> {
    encode_tiled_view(&r.view(), opts, tile)
}

/// [`encode_tiled`] of a borrowed raster.
pub fn encode_tiled_view(
    r: &RasterView<'_>,
    opts: &EncodeOptions,
    tile: &[usize],
) -> Result<Vec<u8>> {
    check_count(r)?;
    if tile == r.dims && streams(&Shape::of_view(r), opts) {
        // the raster as a slab source, as `mra encode` reads a file
        let mut out = std::io::Cursor::new(Vec::new());
        encode_stream(&mut MemorySlabs::of_view(*r), opts, tile, &mut out)?;
        return Ok(out.into_inner());
    }
    if tile != r.dims {
        // voids are filled tile by tile (each tile's file lists its own)
        return super::tiles::encode_tiled(r, opts, tile);
    }
    match with_voids_filled(r, opts.keeps_bits())? {
        Some(filled) => encode_filled(&filled.view(), opts),
        None => encode_filled(r, opts),
    }
}

/// Whether [`encode_stream`] writes the raster of `shape` as one transform streamed a
/// slab at a time ([`super::encode_streamed`], format 3.0) when it is given the whole
/// raster as its tile: a raster over the one-piece limit
/// ([`super::tiles::default_tile`] cuts it) at options the stream covers (lossy at one
/// base step or `--psnr`, `--max-error` above the lossless range, or 8/16-bit lossless,
/// voids or not: NaN samples and samples equal to the nodata value are filled and listed
/// as the whole-array encoder does; [`super::streamed::covers`]).
pub fn streams(shape: &Shape, opts: &EncodeOptions) -> bool {
    super::tiles::default_tile(&shape.dims, shape.channels) != shape.dims
        && super::streamed::covers(shape, opts)
}

/// The default tile extents of a raster of `shape` at `opts`, read in slabs
/// ([`encode_stream`], `mra encode`) or in memory ([`encode`], Python): the whole raster
/// (one transform) when it is one piece or when [`streams`] covers it and it has 2 or 3
/// axes (images and volumes: the axes [`super::StreamedDecoder`] decodes in bounded
/// memory, lossy, `--max-error` and 8/16-bit lossless alike, with voids or not:
/// its code-blocks read from the file a batch at a time), else
/// [`super::tiles::default_tile`]'s grid (the modes the stream does not cover:
/// format 2, lossless 32-bit; and 4 axes).
pub fn default_layout(shape: &Shape, opts: &EncodeOptions) -> Vec<usize> {
    if streams(shape, opts) && shape.dims.len() <= 3 {
        shape.dims.clone()
    } else {
        super::tiles::default_tile(&shape.dims, shape.channels)
    }
}

/// An error unless the raster holds dims × channels samples.
fn check_count(r: &RasterView<'_>) -> Result<()> {
    let n = crate::io::bytes::sample_count(r.dims, r.channels)?;
    if n != r.samples.len() {
        return Err(Error::parameter(
            "samples",
            r.samples.len(),
            "dims × channels samples",
        ));
    }
    Ok(())
}

/// [`encode_tiled`] of the raster `src` hands out in slabs, written into `out`; returns
/// the bytes written. A tiled file is coded one tile-row (2-D) or tile-slab (3-D) at a
/// time, so memory holds a slab and the tiles in flight (the rate modes that need the
/// whole raster take a first pass over it, see [`super::tiles`]); one tile is read
/// slab by slab into the transform's planes where the rate mode needs nothing else
/// ([`super::encode::encode_slabs`]), else whole. The bytes are those of [`encode_tiled`] of the same raster.
pub fn encode_stream<S: SlabSource + ?Sized, W: std::io::Write + std::io::Seek>(
    src: &mut S,
    opts: &EncodeOptions,
    tile: &[usize],
    out: &mut W,
) -> Result<u64> {
    let shape = src.shape().clone();
    if tile == shape.dims.as_slice() && streams(&shape, opts) {
        return super::encode_streamed(src, opts, out);
    }
    if tile != shape.dims.as_slice() {
        return super::tiles::encode_slabs(src, opts, tile, out);
    }
    let bytes = match super::encode::encode_slabs(src, opts)? {
        Some(bytes) => bytes,
        None => {
            let r = shape.raster(shape.dims.clone(), src.read_rows(0..shape.dims[0])?)?;
            encode_tiled(&r, opts, tile)?
        }
    };
    out.write_all(&bytes)?;
    Ok(bytes.len() as u64)
}
