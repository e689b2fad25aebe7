//! The payloads of the chunks that hold coded bands: `LEVL` (format 2, one per level:
//! the level, then for every band of the level and every channel the band's step ratio,
//! the length of its stream and the stream, formats/MRA.md §8), `BAND` (format 1: one
//! band of one channel) and `RESI` (mode 2: one channel's residual layer, §10).

use super::{put_varint, Cursor};
use crate::{FormatError, Result};

/// The bands of a file's levels in file order, as `(level, bands)`: the coarse block
/// (level 0) first, then the detail levels from the coarsest to the finest, each with
/// the indices of its bands. The codec derives it from the header ([`super::Header`]).
pub type LevelGroups = [(usize, Vec<usize>)];

/// One band of one channel as read from a `LEVL` chunk.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelBand {
    /// The band's step over the header's base step.
    pub ratio: f32,
    /// The band's range-coded stream.
    pub data: Vec<u8>,
}

/// `(band, channel, its step ratio and stream)` of one band of a `LEVL` chunk.
pub type BandOfLevel = (usize, usize, LevelBand);

/// The bytes of a `LEVL` chunk of `streams` streams besides their lengths and bytes:
/// the chunk's framing (12), its level (2) and a ratio (4) per stream — what a compact
/// tile (§14.1) does not hold.
pub fn level_framing(streams: u64) -> u64 {
    12 + 2 + 4 * streams
}

/// The payload of the `LEVL` chunk of `level`: for each band of the level (in order)
/// and each channel, `(ratio, stream)` as `f32 LE | varint length | stream`.
pub fn level_payload<'a>(
    level: usize,
    streams: impl IntoIterator<Item = (f32, &'a [u8])>,
) -> Vec<u8> {
    let mut p = Vec::new();
    p.extend_from_slice(&(level as u16).to_le_bytes());
    for (ratio, s) in streams {
        p.extend_from_slice(&ratio.to_le_bytes());
        put_varint(&mut p, s.len() as u64);
        p.extend_from_slice(s);
    }
    p
}

/// Parse the payload of a `LEVL` chunk of a file with `channels` channels whose levels
/// are `groups`: its level and, for each band of that level and each channel, the
/// band's step ratio and stream.
pub fn parse_level(
    payload: &[u8],
    groups: &LevelGroups,
    channels: usize,
) -> Result<(usize, Vec<BandOfLevel>)> {
    let mut cur = Cursor::new(payload, "LEVL");
    let level = cur.u16()? as usize;
    let Some((_, js)) = groups.iter().find(|(l, _)| *l == level) else {
        return Err(FormatError::out_of_range(
            format!(
                "LEVL chunk for level {level} (the pyramid has levels 0 to {})",
                groups.iter().map(|g| g.0).max().unwrap_or(0)
            ),
            "a level of the file's pyramid",
        ));
    };
    let mut bands = Vec::with_capacity(js.len() * channels);
    for &j in js {
        for c in 0..channels {
            let ratio = cur.f32()?;
            if !(ratio > 0.0 && ratio.is_finite()) {
                return Err(FormatError::invalid(
                    format!("LEVL {level}: band {j} of channel {c} with step ratio {ratio}"),
                    "a positive finite ratio",
                ));
            }
            let len = cur.varint()?;
            let left = (cur.data.len() - cur.pos) as u64;
            if len > left {
                return Err(FormatError::out_of_range(
                    format!(
                        "LEVL {level}: band {j} of channel {c} declaring {len} bytes, {left} left"
                    ),
                    "streams within the chunk",
                ));
            }
            let data = cur.take(len as usize)?.to_vec();
            bands.push((j, c, LevelBand { ratio, data }));
        }
    }
    if cur.pos != cur.data.len() {
        return Err(FormatError::invalid(
            format!(
                "LEVL {level} with {} bytes after its last band",
                cur.data.len() - cur.pos
            ),
            "a chunk that ends with its last band",
        ));
    }
    Ok((level, bands))
}

/// The code-blocks of one band of a format 3 file (§15): where each block's stream
/// sits in the band's `LEVL` entry (block order: raster order of the block grid).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlockSet {
    pub streams: Vec<std::ops::Range<usize>>,
}

/// The band entry of a format 3 `LEVL` chunk (§15): the block count, each block's
/// length (LEB128), then the blocks.
pub fn blocks_payload(streams: &[Vec<u8>]) -> Vec<u8> {
    let mut p = Vec::new();
    put_varint(&mut p, streams.len() as u64);
    for s in streams {
        put_varint(&mut p, s.len() as u64);
    }
    for s in streams {
        p.extend_from_slice(s);
    }
    p
}

/// Parse the band entry `data` of a format 3 `LEVL` chunk for a band of extents `dims`
/// in code-blocks of extents `block` (§15): a block count that must be the band's
/// grid's, and block lengths that must tile the rest of the entry exactly (no block
/// outside the entry, none overlapping, no byte left over).
pub fn parse_blocks(data: &[u8], dims: &[usize], block: &[usize]) -> Result<BlockSet> {
    parse_index(data, data.len() as u64, dims, block)
}

/// [`parse_blocks`] of a band entry of `len` bytes of which only the first, `head`, are
/// at hand (at least its index: the count and the block lengths; the blocks' streams
/// are read later by position, e.g. [`super::sparse`]): the same checks against `len`.
pub fn parse_index(head: &[u8], len: u64, dims: &[usize], block: &[usize]) -> Result<BlockSet> {
    let mut cur = Cursor::new(head, "code-block index");
    let count = dims.iter().zip(block).fold(1u64, |n, (&d, &b)| {
        n.saturating_mul(d.div_ceil(b.max(1)) as u64)
    });
    let n = cur.varint()?;
    if n != count || dims.len() != block.len() {
        return Err(FormatError::invalid(
            format!("{n} code-blocks declared for a band of {dims:?} in blocks of {block:?}"),
            "the band's block count",
        ));
    }
    if n > len.saturating_sub(cur.pos as u64) {
        return Err(FormatError::out_of_range(
            format!("{n} code-blocks in an entry of {len} bytes"),
            "at least one index byte per block",
        ));
    }
    let lens = (0..n).map(|_| cur.varint()).collect::<Result<Vec<u64>>>()?;
    let mut at = cur.pos as u64;
    let mut streams = Vec::with_capacity(lens.len());
    for (i, &l) in lens.iter().enumerate() {
        let end = at.saturating_add(l);
        if end > len {
            return Err(FormatError::out_of_range(
                format!("code-block {i} at bytes {at}..{end} of an entry of {len} bytes"),
                "blocks within the band's entry",
            ));
        }
        streams.push(at as usize..end as usize);
        at = end;
    }
    if at != len {
        return Err(FormatError::invalid(
            format!("code-blocks ending at byte {at} of an entry of {len} bytes"),
            "blocks that fill the band's entry exactly",
        ));
    }
    Ok(BlockSet { streams })
}

/// A format 1 `BAND` chunk: `channel u16 | band u16 | step f64 | stream`.
#[derive(Clone, Debug, PartialEq)]
pub struct BandPayload {
    pub channel: usize,
    pub band: usize,
    pub step: f64,
    pub data: Vec<u8>,
}

/// Parse the `BAND` chunk at byte `offset` of a file of `channels` channels and `bands`
/// bands.
pub fn parse_band(
    payload: &[u8],
    offset: u64,
    channels: usize,
    bands: usize,
) -> Result<BandPayload> {
    let mut c = Cursor::new(payload, "BAND");
    let channel = c.u16()? as usize;
    let band = c.u16()? as usize;
    let step = c.f64()?;
    if channel >= channels || band >= bands {
        return Err(FormatError::out_of_range(
            format!("BAND chunk at byte {offset} for channel {channel}, band {band}"),
            "channel < channels and band < number of bands",
        ));
    }
    if !(step > 0.0 && step.is_finite()) {
        return Err(FormatError::invalid(
            format!("BAND chunk step {step}"),
            "a positive finite step",
        ));
    }
    Ok(BandPayload {
        channel,
        band,
        step,
        data: c.rest().to_vec(),
    })
}

/// A `RESI` chunk: one channel's residual layer of a mode 2 file.
#[derive(Clone, Debug, PartialEq)]
pub struct Residual {
    pub channel: usize,
    /// The residual quantizer's step.
    pub step: f64,
    /// `(sample index, exact value)` of the samples the layer does not bound.
    pub exceptions: Vec<(u64, f64)>,
    /// The residual's range-coded stream.
    pub data: Vec<u8>,
}

/// The payload of a `RESI` chunk: `channel u16 | step f64 | n u32 | n × (index u64,
/// value f64) | stream`.
pub fn residual_payload(
    channel: usize,
    step: f64,
    exceptions: &[(u64, f64)],
    stream: &[u8],
) -> Vec<u8> {
    let mut pl = Vec::with_capacity(14 + 16 * exceptions.len() + stream.len());
    pl.extend_from_slice(&(channel as u16).to_le_bytes());
    pl.extend_from_slice(&step.to_le_bytes());
    pl.extend_from_slice(&(exceptions.len() as u32).to_le_bytes());
    for (i, v) in exceptions {
        pl.extend_from_slice(&i.to_le_bytes());
        pl.extend_from_slice(&v.to_le_bytes());
    }
    pl.extend_from_slice(stream);
    pl
}

/// Parse a `RESI` payload of a file of `channels` channels and `positions` samples a
/// channel.
pub fn parse_residual(payload: &[u8], channels: usize, positions: u64) -> Result<Residual> {
    let mut c = Cursor::new(payload, "RESI");
    let channel = c.u16()? as usize;
    let step = c.f64()?;
    let n = c.u32()? as usize;
    if channel >= channels || !(step > 0.0 && step.is_finite()) {
        return Err(FormatError::out_of_range(
            format!("RESI chunk for channel {channel}, step {step}"),
            "a valid channel and step",
        ));
    }
    if n > (payload.len() - c.pos) / 16 {
        return Err(FormatError::out_of_range(
            format!("RESI chunk declaring {n} exceptions"),
            "exceptions that fit the chunk",
        ));
    }
    let mut exceptions = Vec::with_capacity(n);
    for _ in 0..n {
        let i = u64::from_le_bytes(c.take(8)?.try_into().unwrap());
        let v = c.f64()?;
        if i >= positions {
            return Err(FormatError::out_of_range(
                format!("RESI exception at sample {i} of channel {channel} (of {positions})"),
                "sample indices within the raster",
            ));
        }
        exceptions.push((i, v));
    }
    Ok(Residual {
        channel,
        step,
        exceptions,
        data: c.rest().to_vec(),
    })
}
