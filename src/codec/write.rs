//! The encoder's entries: a raster checked, then coded whole (its voids filled) or cut
//! into tiles ([`super::tiles`]), each tile coded by [`super::encode`].

use super::encode::encode_filled;
use super::options::EncodeOptions;
use super::voids::with_voids_filled;
use crate::io::Raster;
use crate::{Error, Result};

/// Encode a raster into the bytes of an `.mra` file. Void samples (NaN, `meta.nodata`)
/// are filled by pull-push before the transform and listed in the metadata, so that the
/// decoder marks them again ([`crate::io::nodata`]). Large rasters are cut into the
/// tiles of [`super::tiles::default_tile`] ([`encode_tiled`]).
pub fn encode(r: &Raster, opts: &EncodeOptions) -> Result<Vec<u8>> {
    let n = crate::io::bytes::sample_count(&r.dims, r.channels)?;
    if n != r.samples.len() {
        return Err(Error::parameter(
            "samples",
            r.samples.len(),
            "dims × channels samples",
        ));
    }
    encode_tiled(r, opts, &super::tiles::default_tile(&r.dims))
}

/// [`encode`] with the raster cut into tiles of extents `tile` (slowest axis first,
/// each from 1 to the axis extent; equal to the extents: one tile, a format 2.0 file),
/// each coded on its own at one base step for the whole raster (formats/MRA.md §14).
pub fn encode_tiled(r: &Raster, opts: &EncodeOptions, tile: &[usize]) -> Result<Vec<u8>> {
    let n = crate::io::bytes::sample_count(&r.dims, r.channels)?;
    if n != r.samples.len() {
        return Err(Error::parameter(
            "samples",
            r.samples.len(),
            "dims × channels samples",
        ));
    }
    if tile != r.dims.as_slice() {
        // voids are filled tile by tile (each tile's file lists its own)
        return super::tiles::encode_tiled(r, opts, tile);
    }
    match with_voids_filled(r)? {
        Some(filled) => encode_filled(&filled, opts),
        None => encode_filled(r, opts),
    }
}
