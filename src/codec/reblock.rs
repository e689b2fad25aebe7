//! Format 3.2 files (formats/MRA.md §15) from one-piece format 2 files: every band's
//! indices decoded and coded again in independent code-blocks ([`crate::entropy::codeblocks`],
//! the blocks of all bands and channels in parallel, the streams gathered in block
//! order, so the bytes do not depend on the thread count). The indices, and so the
//! decoded samples, are those of the format 2 file; the other chunks are kept.

use super::container::read_chunks;
use super::decode::decode_channel;
use crate::entropy::band::{self, Coding};
use crate::entropy::codeblocks::{self, Grid};
use crate::entropy::range::Decoder;
use crate::entropy::{BandKind, Parent};
use crate::format::bands::{blocks_payload, residual_payload};
use crate::format::body::with_band_entries;
use crate::format::Version;
use crate::{Error, Result};
use rayon::prelude::*;

/// The side of the code-blocks of 2-D rasters (and `SIDE²` samples of 1-D ones), chosen
/// by `benches/coder.rs` (docs/codec.md, "Code-blocks").
pub const SIDE: usize = 256;
/// The code-blocks of rasters of three axes or more (Z, Y, X; 1 on any axis before):
/// 32³ at the finest level (then 16³, formats/MRA.md §15.3), so that a 64³ window
/// meets blocks of about its own size at every level (docs/codec.md, "Regions").
pub const VOLUME: [usize; 3] = [32, 32, 32];

/// The block extents of a raster of `nd` axes, as the exponents `HEAD` stores.
pub(super) fn exponents(nd: usize) -> Vec<u8> {
    codeblocks::block_shape(nd, SIDE, VOLUME)
        .iter()
        .map(|b| b.trailing_zeros() as u8)
        .collect()
}

/// The format 3.0 file of the one-piece format 2 file `bytes` (a format 3 file comes
/// back as it is). Tiled and format 1 files are refused.
pub fn to_blocks(bytes: &[u8]) -> Result<Vec<u8>> {
    let p = read_chunks(bytes, bytes.len() as u64, 0, false)?;
    let h = &p.header;
    if h.version.has_blocks() {
        return Ok(bytes.to_vec());
    }
    if !h.version.has_levels() {
        return Err(Error::format(
            format!("a format {} file", h.version),
            "a one-piece format 2 file to cut into code-blocks",
        ));
    }
    let plan = &p.plan;
    let q: Vec<Vec<Option<Vec<i64>>>> = (0..h.channels)
        .into_par_iter()
        .map(|c| decode_channel(&p, c, 0))
        .collect::<Result<_>>()?;
    let nb = plan.bands.len();
    let mut h3 = h.clone();
    h3.version = Version::LEVEL_BLOCKS;
    h3.blocks = exponents(h.dims.len());
    let plan3 = super::plan::Plan::new(&h3)?;
    let entries: Vec<Vec<u8>> = (0..h.channels * nb)
        .into_par_iter()
        .map(|i| {
            let (c, j) = (i / nb, i % nb);
            let grid = Grid::new(&plan.dims[j], plan3.block(j));
            let kind = if plan.bands[j].level == 0 {
                BandKind::Coarse
            } else {
                BandKind::Detail
            };
            let parent = plan.parents[j].and_then(|pj| {
                q[c][pj].as_ref().map(|v| Parent {
                    data: v,
                    dims: &plan.dims[pj],
                })
            });
            let band = q[c][j].as_deref().unwrap_or(&[]);
            let streams = codeblocks::encode_blocks(
                band,
                &grid,
                kind,
                parent,
                Coding::Chosen,
                codeblocks::Coder::Context,
            );
            blocks_payload(&streams)
        })
        .collect();
    // 3.0's residual streams open with the class bit (§9.1): those of an older coding
    // are coded again
    let positions: usize = h.dims.iter().product();
    let from = plan.coding;
    let resi: Vec<Option<Vec<u8>>> = p
        .resi
        .par_iter()
        .map(|r| -> Result<Option<Vec<u8>>> {
            let Some(r) = r.as_ref().filter(|_| from != Coding::Chosen) else {
                return Ok(None);
            };
            let mut d = Decoder::new_short(&r.data);
            let q = band::decode(&mut d, &h.dims, BandKind::Detail, None, from)?;
            let s = band::encode_stream(&q, &h.dims, BandKind::Detail, None, Coding::Chosen);
            Ok(Some(residual_payload(r.channel, r.step, &r.exceptions, &s)))
        })
        .collect::<Result<_>>()?;
    with_band_entries(
        bytes,
        &h3.to_bytes(),
        &plan.level_groups(),
        (h.channels, positions as u64),
        |j, c| entries[c * nb + j].clone(),
        &resi,
    )
}
