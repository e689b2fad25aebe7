//! Pictures of pyramids (like the notes' Figure 9.11): each block of coefficients is
//! contrast-stretched on its own and drawn where it sits in the Mallat layout. The
//! coarse block maps its `[min, max]` to `[0, 255]`; a detail block maps `v` to
//! `128 + 127 · v / s`, clamped, with `s` the 99.5th percentile of `|v|` over the block
//! (so that a few large details do not flatten the rest; zero details are mid-grey).
//! Stretches are per channel.

use std::ops::Range;

use super::{DataKind, Raster, Samples};
use crate::{Error, Result};

/// One block of a pyramid: a range per spatial axis, and whether it is the coarse block.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    pub ranges: Vec<Range<usize>>,
    pub coarse: bool,
}

/// An 8-bit picture `[H, W]` × `channels` of a 2-D pyramid `data` (`[H, W, channels]`).
pub fn picture(data: &[f32], dims: &[usize], channels: usize, blocks: &[Block]) -> Result<Raster> {
    if dims.len() != 2 {
        return Err(Error::parameter(
            "picture dims",
            format!("{dims:?}"),
            "2-D data (use a slice of a volume)",
        ));
    }
    let (h, w) = (dims[0], dims[1]);
    if data.len() != h * w * channels {
        return Err(Error::parameter(
            "picture data",
            data.len(),
            "H × W × channels values",
        ));
    }
    let mut out = vec![128u8; data.len()];
    for b in blocks {
        let (ry, rx) = (b.ranges[0].clone(), b.ranges[1].clone());
        for c in 0..channels {
            let at = |y: usize, x: usize| data[(y * w + x) * channels + c];
            let mut lo = f32::INFINITY;
            let mut hi = f32::NEG_INFINITY;
            let mut mags: Vec<f32> = Vec::with_capacity(ry.len() * rx.len());
            for y in ry.clone() {
                for x in rx.clone() {
                    let v = at(y, x);
                    if v.is_finite() {
                        lo = lo.min(v);
                        hi = hi.max(v);
                        mags.push(v.abs());
                    }
                }
            }
            let amax = if b.coarse || mags.is_empty() {
                0.0
            } else {
                let k = ((mags.len() - 1) as f64 * 0.995).ceil() as usize;
                *mags.select_nth_unstable_by(k, f32::total_cmp).1
            };
            for y in ry.clone() {
                for x in rx.clone() {
                    let v = at(y, x);
                    let p = if b.coarse {
                        if hi > lo {
                            255.0 * (v - lo) / (hi - lo)
                        } else {
                            128.0
                        }
                    } else if amax > 0.0 {
                        128.0 + 127.0 * v / amax
                    } else {
                        128.0
                    };
                    out[(y * w + x) * channels + c] = p.round().clamp(0.0, 255.0) as u8;
                }
            }
        }
    }
    Raster::new(vec![h, w], channels, Samples::U8(out), DataKind::Image)
}

/// Slice `z` of a volume `[D, H, W, channels]` and the blocks that cross it, projected
/// onto `(y, x)`.
pub fn slice(
    data: &[f32],
    dims: &[usize],
    channels: usize,
    blocks: &[Block],
    z: usize,
) -> Result<(Vec<f32>, Vec<Block>)> {
    if dims.len() != 3 || z >= dims[0] {
        return Err(Error::parameter(
            "slice",
            z,
            "a slice index below the volume's depth",
        ));
    }
    let n = dims[1] * dims[2] * channels;
    let s = data[z * n..(z + 1) * n].to_vec();
    let b = blocks
        .iter()
        .filter(|b| b.ranges[0].contains(&z))
        .map(|b| Block {
            ranges: b.ranges[1..].to_vec(),
            coarse: b.coarse,
        })
        .collect();
    Ok((s, b))
}

/// Blocks of a standard-order pyramid from each axis' lane lengths level by level
/// (`lengths[k][0]` = full length): every product of one band per axis.
pub fn standard_blocks(lengths: &[Vec<usize>]) -> Vec<Block> {
    let bands: Vec<Vec<(Range<usize>, bool)>> = lengths
        .iter()
        .map(|l| {
            let last = *l.last().unwrap_or(&0);
            let mut v = vec![(0..last, true)];
            for k in (0..l.len().saturating_sub(1)).rev() {
                v.push((l[k + 1]..l[k], false));
            }
            v
        })
        .collect();
    let mut out = vec![Block {
        ranges: vec![],
        coarse: true,
    }];
    for axis in &bands {
        let mut next = Vec::new();
        for b in &out {
            for (r, low) in axis {
                let mut ranges = b.ranges.clone();
                ranges.push(r.clone());
                next.push(Block {
                    ranges,
                    coarse: b.coarse && *low,
                });
            }
        }
        out = next;
    }
    out
}
