//! The chunk sequence of an `.mra` file of one tile, read into parsed structures:
//! `HEAD`, `mETA`, the bands (format 2: one `LEVL` per level; format 1: one `BAND` per
//! band and channel), `RESI` per channel in mode 2, `MEND` (formats/MRA.md §2).
//!
//! The header commits to the chunks that follow: the bands its pyramid has, every one
//! exactly once and coarse to fine, and a `RESI` per channel in mode 2. A file that ends
//! or reaches `MEND` without one of them is an error naming what is missing (with
//! `allow_truncated`, a body that reports itself incomplete). The pyramid's bands come
//! from the codec as a [`BandLayout`], plain numbers derived from the header.

use super::bands::{parse_band, parse_level, parse_residual, LevelGroups, Residual};
use super::{meta, Chunk, ChunkEnd, ChunkReader, Header, Mode, Tag};
use crate::io::Metadata;
use crate::{Error, FormatError, Result};
use std::io::Read;

/// The error of a file of `len` bytes that ends (at `end`) after chunk `last` without
/// its `MEND`.
pub fn truncated(end: ChunkEnd, last: &str, len: u64) -> Error {
    let at = match end {
        ChunkEnd::Eof => len,
        ChunkEnd::Truncated { offset } => offset,
    };
    FormatError::truncated(
        format!("file truncated after chunk {last} (byte {at} of {len})"),
        "a complete file ending with MEND (or --allow-truncated)",
    )
}

/// The signature and the `HEAD` chunk of a stream of `len` bytes, parsed and checked
/// against the limits of §4: the reader (at the chunk after `HEAD`), the `HEAD` chunk
/// and its header.
pub fn read_head<R: Read>(src: R, len: u64) -> Result<(ChunkReader<R>, Chunk, Header)> {
    let mut rd = ChunkReader::new(src, len)?;
    let first = match rd.next_chunk()? {
        Ok(c) => c,
        Err(_) => {
            return Err(FormatError::truncated(
                "file ends before its HEAD chunk",
                "a HEAD chunk after the signature",
            ))
        }
    };
    if first.tag() != Some(Tag::Head) {
        return Err(FormatError::order(
            format!("first chunk {}", first.name()),
            "HEAD first",
        ));
    }
    let header = Header::parse(&first.payload)?;
    let samples = header.samples()?;
    let limit = crate::io::MAX_SAMPLES.min(len.saturating_mul(12_000).max(1 << 20));
    if samples > limit {
        return Err(FormatError::budget("declared samples", samples, limit));
    }
    Ok((rd, first, header))
}

/// The bands of a file's pyramid as the chunk reader needs them (the codec's plan of
/// the header, as numbers).
pub struct BandLayout<'a> {
    /// The bands of each level in file order.
    pub groups: &'a LevelGroups,
    /// The level of each band (0: the coarse block).
    pub levels: Vec<usize>,
    /// The parent of each band (one level coarser), whose chunk must come first.
    pub parents: &'a [Option<usize>],
    /// The coefficients of each band (a channel's).
    pub coefficients: Vec<u64>,
}

/// One band of one channel as read (from a `LEVL` or a `BAND` chunk): its step and
/// coded bytes.
#[derive(Clone, Debug)]
pub struct BandChunk {
    pub step: f64,
    pub data: Vec<u8>,
}

/// One chunk as listed by `mra info`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ChunkInfo {
    pub kind: String,
    pub offset: u64,
    pub bytes: u64,
    pub channel: Option<usize>,
    pub band: Option<usize>,
    pub level: Option<usize>,
    pub coefficients: Option<u64>,
    /// The tile a `TILE` chunk holds (files of more than one tile).
    pub tile: Option<usize>,
}

impl ChunkInfo {
    /// The listing of chunk `ch` alone (`tile`: the tile a `TILE` chunk holds).
    pub fn of(ch: &Chunk, tile: Option<usize>) -> ChunkInfo {
        ChunkInfo {
            kind: ch.name(),
            offset: ch.offset,
            bytes: ch.payload.len() as u64 + 12,
            channel: None,
            band: None,
            level: None,
            coefficients: None,
            tile,
        }
    }
}

/// Everything a one-tile file holds after `HEAD`, parsed.
pub struct Body {
    pub meta: Metadata,
    /// `[channel][band]`: each band's chunk, `None` when absent (not read, or missing
    /// in a truncated file).
    pub bands: Vec<Vec<Option<BandChunk>>>,
    /// Each channel's residual layer (mode 2).
    pub resi: Vec<Option<Residual>>,
    /// Whether every chunk the decode needs was read and checked.
    pub complete: bool,
    pub chunks: Vec<ChunkInfo>,
}

/// The chunks after `HEAD` (chunk `first`, header `header`) of a file of one tile whose
/// bands are `layout`. With `stop_level > 0` reading stops at the first chunk of a level
/// from 1 to `stop_level` (a decode at that level does not need them).
pub fn read_body<R: Read>(
    mut rd: ChunkReader<R>,
    first: &Chunk,
    header: &Header,
    layout: &BandLayout,
    stop_level: usize,
    allow_truncated: bool,
) -> Result<Body> {
    let len = rd.total();
    let nb = layout.levels.len();
    let mut b = Body {
        meta: Metadata::default(),
        bands: (0..header.channels)
            .map(|_| (0..nb).map(|_| None).collect())
            .collect(),
        resi: (0..header.channels).map(|_| None).collect(),
        complete: false,
        chunks: vec![ChunkInfo::of(first, None)],
    };
    let mut last = "HEAD".to_string();
    let (mut meta_seen, mut first_band) = (false, None);
    let reading = Reading {
        header,
        layout,
        stop_level,
        allow_truncated,
    };
    loop {
        let ch = match rd.next_chunk()? {
            Ok(c) => c,
            Err(end) => {
                if !allow_truncated {
                    return Err(truncated(end, &last, len));
                }
                break;
            }
        };
        let mut info = ChunkInfo::of(&ch, None);
        last = ch.name();
        let tag = ch.tag();
        if matches!(tag, Some(Tag::Levl | Tag::Band | Tag::Resi)) && first_band.is_none() {
            first_band = Some(ch.offset);
        }
        let stop = match tag {
            Some(Tag::Levl | Tag::Band) => reading.band_chunk(&ch, &mut b, &mut info)?,
            Some(Tag::Resi) => {
                reading.resi_chunk(&ch, &mut b.resi, &mut info)?;
                None
            }
            Some(Tag::Mend) => {
                b.chunks.push(info);
                let (bands, resi) = (&b.bands, &b.resi);
                b.complete = mend(header, layout, (bands, resi), 0, ch.offset, allow_truncated)?;
                break;
            }
            _ => {
                other_chunk(&ch, &mut b.meta, &mut meta_seen, first_band)?;
                None
            }
        };
        if let Some(complete) = stop {
            b.complete = complete;
            break;
        }
        b.chunks.push(info);
    }
    if header.voids && first_band.is_some() && !meta::lists_voids(&b.meta) {
        // past where the mETA must be, without the void list the header promises
        return Err(FormatError::missing(
            "no void list in mETA, though the header says the file has voids",
            "the mETA chunk with extra.nodata.voids (format 2.4 HEAD flag)",
        ));
    }
    Ok(b)
}

/// What [`read_body`] reads against.
struct Reading<'a> {
    header: &'a Header,
    layout: &'a BandLayout<'a>,
    stop_level: usize,
    allow_truncated: bool,
}

impl Reading<'_> {
    /// Whether a decode stopping at `stop_level` stops at a chunk of `level` (byte
    /// `at`): `Some(complete)` when it does ([`coarse_present`]), `None` to go on.
    fn stops_at(
        &self,
        bands: &[Vec<Option<BandChunk>>],
        level: usize,
        at: u64,
    ) -> Result<Option<bool>> {
        let k = self.stop_level;
        if k == 0 || level == 0 || level > k {
            return Ok(None);
        }
        let (h, l) = (self.header, self.layout);
        coarse_present(h, l, bands, k, at, self.allow_truncated).map(Some)
    }

    /// A `LEVL` (format 2 and 3) or `BAND` (format 1) chunk read into `b`: `Some(complete)`
    /// when the decode stops there ([`Reading::stops_at`]).
    fn band_chunk(&self, ch: &Chunk, b: &mut Body, info: &mut ChunkInfo) -> Result<Option<bool>> {
        let (header, layout) = (self.header, self.layout);
        let has_levels = header.version.has_levels();
        match ch.tag() {
            Some(Tag::Band) if has_levels => Err(FormatError::invalid(
                format!(
                    "BAND chunk at byte {} in a format {} file",
                    ch.offset, header.version.major
                ),
                "LEVL chunks (BAND belongs to format 1)",
            )),
            Some(Tag::Levl) if !has_levels => Err(FormatError::invalid(
                format!("LEVL chunk at byte {} in a format 1 file", ch.offset),
                "BAND chunks",
            )),
            Some(Tag::Levl) => {
                let (level, got) = parse_level(&ch.payload, layout.groups, header.channels)?;
                if let Some(complete) = self.stops_at(&b.bands, level, ch.offset)? {
                    return Ok(Some(complete));
                }
                let first = got.first().map(|g| g.0).unwrap_or(0);
                if let Some(pj) = layout.parents[first] {
                    if b.bands[0][pj].is_none() {
                        return Err(FormatError::order(
                            format!("LEVL {level} before the level of its parent bands"),
                            "levels in coarse-to-fine order",
                        ));
                    }
                }
                if b.bands[0][first].is_some() {
                    return Err(FormatError::duplicate(
                        format!("a second LEVL chunk for level {level} (byte {})", ch.offset),
                        "each level once",
                    ));
                }
                info.level = Some(level);
                info.coefficients = Some(got.iter().map(|(j, _, _)| layout.coefficients[*j]).sum());
                for (j, c, lb) in got {
                    b.bands[c][j] = Some(BandChunk {
                        step: header.step * lb.ratio as f64,
                        data: lb.data,
                    });
                }
                Ok(None)
            }
            _ => self.format1_band(ch, b, info),
        }
    }

    /// A format 1 `BAND` chunk read into `b` (see [`Reading::band_chunk`]).
    fn format1_band(&self, ch: &Chunk, b: &mut Body, info: &mut ChunkInfo) -> Result<Option<bool>> {
        let (header, layout) = (self.header, self.layout);
        let nb = layout.levels.len();
        let bp = parse_band(&ch.payload, ch.offset, header.channels, nb)?;
        let (channel, band) = (bp.channel, bp.band);
        let level = layout.levels[band];
        if let Some(complete) = self.stops_at(&b.bands, level, ch.offset)? {
            return Ok(Some(complete));
        }
        if b.bands[channel][band].is_some() {
            return Err(FormatError::duplicate(
                format!(
                    "a second BAND chunk for band {band} of channel {channel} (byte {})",
                    ch.offset
                ),
                "each band once",
            ));
        }
        if let Some(p) = layout.parents[band] {
            if b.bands[channel][p].is_none() {
                return Err(FormatError::order(
                    format!("BAND {band} of channel {channel} before its parent band {p}"),
                    "bands in coarse-to-fine order",
                ));
            }
        }
        info.channel = Some(channel);
        info.band = Some(band);
        info.level = Some(level);
        info.coefficients = Some(layout.coefficients[band]);
        b.bands[channel][band] = Some(BandChunk {
            step: bp.step,
            data: bp.data,
        });
        Ok(None)
    }

    /// A `RESI` chunk read into `resi`.
    fn resi_chunk(
        &self,
        ch: &Chunk,
        resi: &mut [Option<Residual>],
        info: &mut ChunkInfo,
    ) -> Result<()> {
        let header = self.header;
        let positions: u64 = header.dims.iter().map(|&d| d as u64).product();
        let r = parse_residual(&ch.payload, header.channels, positions)?;
        let channel = r.channel;
        if resi[channel].is_some() {
            return Err(FormatError::duplicate(
                format!(
                    "a second RESI chunk for channel {channel} (byte {})",
                    ch.offset
                ),
                "one RESI chunk per channel",
            ));
        }
        info.channel = Some(channel);
        resi[channel] = Some(r);
        Ok(())
    }
}

/// A `mETA` chunk's metadata: at most one, before the first band chunk (or `TIDX` in a
/// tiled file) at byte `first_band` when one was read.
pub fn meta_chunk(ch: &Chunk, seen: &mut bool, first_band: Option<u64>) -> Result<Metadata> {
    if *seen {
        return Err(FormatError::duplicate(
            format!("a second mETA chunk at byte {}", ch.offset),
            "at most one mETA chunk",
        ));
    }
    if let Some(at) = first_band {
        return Err(FormatError::order(
            format!(
                "mETA chunk at byte {} after the data chunk at byte {at}",
                ch.offset
            ),
            "mETA right after HEAD, before the bands or the tile index",
        ));
    }
    *seen = true;
    Ok(meta::parse(&ch.payload))
}

/// A chunk of the body other than a band's, `RESI` or `MEND`, checked: `mETA` parsed
/// into `meta` ([`meta_chunk`]'s rules), a second `HEAD` or an unknown critical chunk
/// an error, any other ancillary chunk skipped.
pub(super) fn other_chunk(
    ch: &Chunk,
    meta: &mut Metadata,
    meta_seen: &mut bool,
    first_band: Option<u64>,
) -> Result<()> {
    match ch.tag() {
        Some(Tag::Meta) => *meta = meta_chunk(ch, meta_seen, first_band)?,
        Some(Tag::Head) => {
            return Err(FormatError::duplicate(
                "a second HEAD chunk",
                "one HEAD chunk",
            ))
        }
        _ if Tag::is_critical(&ch.kind) => {
            return Err(FormatError::UnknownChunk(ch.name()).into());
        }
        _ => {}
    }
    Ok(())
}

/// `MEND` at byte `at`: whether the body before it is complete (every chunk the header
/// commits to that a decode at `stop_level` needs, [`first_missing`]); one missing is
/// an error naming it, or with `allow_truncated` an incomplete body (`Ok(false)`).
pub(super) fn mend(
    header: &Header,
    layout: &BandLayout,
    (bands, resi): (&[Vec<Option<BandChunk>>], &[Option<Residual>]),
    stop_level: usize,
    at: u64,
    allow_truncated: bool,
) -> Result<bool> {
    match first_missing(header, layout, bands, resi, stop_level) {
        None => Ok(true),
        Some(_) if allow_truncated => Ok(false),
        Some(missing) => Err(FormatError::missing(
            format!("{missing} missing (MEND at byte {at})"),
            "every chunk the header commits to (or --allow-truncated)",
        )),
    }
}

/// Whether a decode stopping at level `stop_level` (on reaching a chunk of a level it
/// does not need, at byte `at`) has every band it does need: the coarse block and the
/// detail levels above `stop_level`. A band missing there (a `LEVL` left out, or two
/// swapped so that a finer one comes first) is an error naming it, or with
/// `allow_truncated` an incomplete decode (`Ok(false)`).
pub(super) fn coarse_present(
    header: &Header,
    layout: &BandLayout,
    bands: &[Vec<Option<BandChunk>>],
    stop_level: usize,
    at: u64,
    allow_truncated: bool,
) -> Result<bool> {
    let Some(missing) = first_missing(header, layout, bands, &[], stop_level) else {
        return Ok(true);
    };
    if allow_truncated {
        return Ok(false);
    }
    Err(FormatError::missing(
        format!("{missing} missing before the chunk of level {stop_level} or finer at byte {at}"),
        "every coarser level before the finer ones",
    ))
}

/// The first chunk the header commits to that `bands` and `resi` lack, named, among the
/// chunks a decode at level `stop_level` needs (every one at level 0: the coarse block,
/// the detail levels above `stop_level`, and the `RESI` chunks only at level 0).
pub(super) fn first_missing(
    header: &Header,
    layout: &BandLayout,
    bands: &[Vec<Option<BandChunk>>],
    resi: &[Option<Residual>],
    stop_level: usize,
) -> Option<String> {
    for (j, &level) in layout.levels.iter().enumerate() {
        if stop_level > 0 && level >= 1 && level <= stop_level {
            continue;
        }
        for (c, ch) in bands.iter().enumerate() {
            if ch[j].is_none() {
                return Some(if header.version.has_levels() {
                    format!("LEVL chunk of level {level} (band {j}, channel {c})")
                } else {
                    format!("BAND chunk of band {j}, channel {c}")
                });
            }
        }
    }
    if header.mode == Mode::MaxError && stop_level == 0 {
        if let Some(c) = resi.iter().position(|r| r.is_none()) {
            return Some(format!("RESI chunk of channel {c}"));
        }
    }
    None
}

/// The file `file` (one tile, every chunk read and checked) written again with `HEAD`'s
/// payload `head`, every band entry of its `LEVL` chunks replaced by
/// `entry(band, channel)` (its ratio kept) and the `RESI` chunk of channel `c` by
/// `resi[c]` where that is given; every other chunk copied as it is. `groups`,
/// `channels` and `positions` are those of the file's header.
pub fn with_band_entries(
    file: &[u8],
    head: &[u8],
    groups: &LevelGroups,
    (channels, positions): (usize, u64),
    entry: impl Fn(usize, usize) -> Vec<u8>,
    resi: &[Option<Vec<u8>>],
) -> Result<Vec<u8>> {
    let mut rd = ChunkReader::new(file, file.len() as u64)?;
    let mut out = super::SIGNATURE.to_vec();
    while let Ok(ch) = rd.next_chunk()? {
        match ch.tag() {
            Some(Tag::Head) => super::put_chunk(&mut out, &ch.kind, head),
            Some(Tag::Levl) => {
                let (level, got) = parse_level(&ch.payload, groups, channels)?;
                let entries: Vec<(f32, Vec<u8>)> = got
                    .into_iter()
                    .map(|(j, c, lb)| (lb.ratio, entry(j, c)))
                    .collect();
                let payload = super::bands::level_payload(
                    level,
                    entries.iter().map(|(r, e)| (*r, e.as_slice())),
                );
                super::put_chunk(&mut out, &ch.kind, &payload);
            }
            Some(Tag::Resi) => {
                let c = parse_residual(&ch.payload, channels, positions)?.channel;
                match resi.get(c).and_then(|r| r.as_ref()) {
                    Some(p) => super::put_chunk(&mut out, &ch.kind, p),
                    None => super::put_chunk(&mut out, &ch.kind, &ch.payload),
                }
            }
            _ => super::put_chunk(&mut out, &ch.kind, &ch.payload),
        }
    }
    Ok(out)
}
