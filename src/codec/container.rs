//! The chunks of an `.mra` file as the codec writes and reads them: `HEAD`, `mETA`,
//! the bands (format 2: one `LEVL` per level, [`super::levels`]; format 1: one `BAND`
//! per band and channel), `RESI` per channel in `--max-error` files (channel, step,
//! exceptions, coded residuals), `MEND`. Framing and CRCs are [`crate::format`]'s.
//!
//! The header commits to the chunks that follow: the bands its pyramid has, every one
//! exactly once and coarse to fine, and a `RESI` per channel in mode 2. A file that ends
//! or reaches `MEND` without one of them is an error naming what is missing (with
//! `--allow-truncated`, a decode that reports itself incomplete).

use super::levels::parse_level;
use super::meta;
use super::plan::Plan;
use crate::format::Mode;
use crate::format::{Chunk, ChunkEnd, ChunkReader, Cursor, Header};
use crate::{Error, Result};
use std::io::Read;

pub(super) const HEAD: &[u8; 4] = b"HEAD";
pub(super) const RESI: &[u8; 4] = b"RESI";
pub(super) const MEND: &[u8; 4] = b"MEND";
pub(super) const META: &[u8; 4] = b"mETA";

/// The error of a file of `len` bytes that ends (at `end`) after chunk `last` without
/// its `MEND`.
pub(super) fn truncated(end: ChunkEnd, last: &str, len: u64) -> Error {
    let at = match end {
        ChunkEnd::Eof => len,
        ChunkEnd::Truncated { offset } => offset,
    };
    Error::format(
        format!("file truncated after chunk {last} (byte {at} of {len})"),
        "a complete file ending with MEND (or --allow-truncated)",
    )
}

/// One band of one channel as read (from a `LEVL` or a `BAND` chunk): its step and
/// coded bytes.
pub(super) struct BandChunk {
    pub(super) step: f64,
    pub(super) data: Vec<u8>,
}

/// A RESI chunk's contents.
pub(super) struct ResiChunk {
    pub(super) step: f64,
    pub(super) exceptions: Vec<(u64, f64)>,
    pub(super) data: Vec<u8>,
}

/// One chunk as listed by [`super::info()`].
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

/// Everything read from a file before reconstruction.
pub(super) struct Parsed {
    pub(super) header: Header,
    pub(super) meta: crate::io::Metadata,
    pub(super) plan: Plan,
    pub(super) bands: Vec<Vec<Option<BandChunk>>>,
    pub(super) resi: Vec<Option<ResiChunk>>,
    pub(super) complete: bool,
    pub(super) chunks: Vec<ChunkInfo>,
}

pub(super) fn read_chunks<R: Read>(
    src: R,
    len: u64,
    stop_level: usize,
    allow_truncated: bool,
) -> Result<Parsed> {
    let (rd, first, header) = read_head(src, len)?;
    if header.is_tiled() {
        return Err(Error::format(
            format!("a file of {:?} tiles {:?}", header.dims, header.tile),
            "one tile here (tiled files go through codec::tiles)",
        ));
    }
    read_rest(rd, first, header, stop_level, allow_truncated)
}

/// The signature and the `HEAD` chunk, parsed and checked against the limits of §4.
pub(super) fn read_head<R: Read>(src: R, len: u64) -> Result<(ChunkReader<R>, Chunk, Header)> {
    let mut rd = ChunkReader::new(src, len)?;
    let first = match rd.next_chunk()? {
        Ok(c) => c,
        Err(_) => {
            return Err(Error::format(
                "file ends before its HEAD chunk",
                "a HEAD chunk after the signature",
            ))
        }
    };
    if &first.kind != HEAD {
        return Err(Error::format(
            format!("first chunk {}", first.name()),
            "HEAD first",
        ));
    }
    let header = Header::parse(&first.payload)?;
    let samples = header.samples()?;
    let limit = crate::io::MAX_SAMPLES.min(len.saturating_mul(12_000).max(1 << 20));
    if samples > limit {
        return Err(Error::LimitsExceeded {
            what: "declared samples",
            requested: samples,
            limit,
        });
    }
    Ok((rd, first, header))
}

/// The chunks after `HEAD` of a file of one tile.
pub(super) fn read_rest<R: Read>(
    mut rd: ChunkReader<R>,
    first: Chunk,
    header: Header,
    stop_level: usize,
    allow_truncated: bool,
) -> Result<Parsed> {
    let len = rd.total();
    let plan = Plan::new(&header)?;
    let nb = plan.bands.len();
    let mut bands: Vec<Vec<Option<BandChunk>>> = (0..header.channels)
        .map(|_| (0..nb).map(|_| None).collect())
        .collect();
    let mut resi: Vec<Option<ResiChunk>> = (0..header.channels).map(|_| None).collect();
    let mut meta = crate::io::Metadata::default();
    let mut chunks = vec![ChunkInfo {
        kind: "HEAD".into(),
        offset: first.offset,
        bytes: first.payload.len() as u64 + 12,
        channel: None,
        band: None,
        level: None,
        coefficients: None,
        tile: None,
    }];
    let mut complete = false;
    let mut last = "HEAD".to_string();
    let (mut meta_seen, mut first_band) = (false, None);
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
        let mut info = ChunkInfo {
            kind: ch.name(),
            offset: ch.offset,
            bytes: ch.payload.len() as u64 + 12,
            channel: None,
            band: None,
            level: None,
            coefficients: None,
            tile: None,
        };
        last = ch.name();
        if matches!(&ch.kind, b"LEVL" | b"BAND" | b"RESI") && first_band.is_none() {
            first_band = Some(ch.offset);
        }
        match &ch.kind {
            b"BAND" if header.major >= 2 => {
                return Err(Error::format(
                    format!(
                        "BAND chunk at byte {} in a format {} file",
                        ch.offset, header.major
                    ),
                    "LEVL chunks (BAND belongs to format 1)",
                ));
            }
            b"LEVL" if header.major < 2 => {
                return Err(Error::format(
                    format!("LEVL chunk at byte {} in a format 1 file", ch.offset),
                    "BAND chunks",
                ));
            }
            b"LEVL" => {
                let (level, got) = parse_level(&ch.payload, &plan, header.channels)?;
                if stop_level > 0 && level >= 1 && level <= stop_level {
                    complete = coarse_present(
                        &header,
                        &plan,
                        &bands,
                        stop_level,
                        ch.offset,
                        allow_truncated,
                    )?;
                    break;
                }
                let first = got.first().map(|b| b.0).unwrap_or(0);
                if let Some(pj) = plan.parents[first] {
                    if bands[0][pj].is_none() {
                        return Err(Error::format(
                            format!("LEVL {level} before the level of its parent bands"),
                            "levels in coarse-to-fine order",
                        ));
                    }
                }
                if bands[0][first].is_some() {
                    return Err(Error::format(
                        format!("a second LEVL chunk for level {level} (byte {})", ch.offset),
                        "each level once",
                    ));
                }
                info.level = Some(level);
                info.coefficients = Some(
                    got.iter()
                        .map(|(j, _, _)| plan.dims[*j].iter().product::<usize>() as u64)
                        .sum(),
                );
                for (j, c, lb) in got {
                    bands[c][j] = Some(BandChunk {
                        step: header.step * lb.ratio as f64,
                        data: lb.data,
                    });
                }
            }
            b"BAND" => {
                let mut c = Cursor::new(&ch.payload, "BAND");
                let channel = c.u16()? as usize;
                let band = c.u16()? as usize;
                let step = c.f64()?;
                if channel >= header.channels || band >= nb {
                    return Err(Error::format(
                        format!(
                            "BAND chunk at byte {} for channel {channel}, band {band}",
                            ch.offset
                        ),
                        "channel < channels and band < number of bands",
                    ));
                }
                if !(step > 0.0 && step.is_finite()) {
                    return Err(Error::format(
                        format!("BAND chunk step {step}"),
                        "a positive finite step",
                    ));
                }
                let level = plan.bands[band].level;
                if stop_level > 0 && level >= 1 && level <= stop_level {
                    complete = coarse_present(
                        &header,
                        &plan,
                        &bands,
                        stop_level,
                        ch.offset,
                        allow_truncated,
                    )?;
                    break;
                }
                if bands[channel][band].is_some() {
                    return Err(Error::format(
                        format!(
                            "a second BAND chunk for band {band} of channel {channel} (byte {})",
                            ch.offset
                        ),
                        "each band once",
                    ));
                }
                if let Some(p) = plan.parents[band] {
                    if bands[channel][p].is_none() {
                        return Err(Error::format(
                            format!("BAND {band} of channel {channel} before its parent band {p}"),
                            "bands in coarse-to-fine order",
                        ));
                    }
                }
                info.channel = Some(channel);
                info.band = Some(band);
                info.level = Some(level);
                info.coefficients = Some(plan.dims[band].iter().product::<usize>() as u64);
                bands[channel][band] = Some(BandChunk {
                    step,
                    data: c.rest().to_vec(),
                });
            }
            b"RESI" => {
                let mut c = Cursor::new(&ch.payload, "RESI");
                let channel = c.u16()? as usize;
                let step = c.f64()?;
                let n = c.u32()? as usize;
                if channel >= header.channels || !(step > 0.0 && step.is_finite()) {
                    return Err(Error::format(
                        format!("RESI chunk for channel {channel}, step {step}"),
                        "a valid channel and step",
                    ));
                }
                if n > (ch.payload.len() - c.pos) / 16 {
                    return Err(Error::format(
                        format!("RESI chunk declaring {n} exceptions"),
                        "exceptions that fit the chunk",
                    ));
                }
                if resi[channel].is_some() {
                    return Err(Error::format(
                        format!(
                            "a second RESI chunk for channel {channel} (byte {})",
                            ch.offset
                        ),
                        "one RESI chunk per channel",
                    ));
                }
                let positions: u64 = header.dims.iter().map(|&d| d as u64).product();
                let mut exc = Vec::with_capacity(n);
                for _ in 0..n {
                    let i = u64::from_le_bytes(c.take(8)?.try_into().unwrap());
                    let v = c.f64()?;
                    if i >= positions {
                        return Err(Error::format(
                            format!("RESI exception at sample {i} of channel {channel} (of {positions})"),
                            "sample indices within the raster",
                        ));
                    }
                    exc.push((i, v));
                }
                info.channel = Some(channel);
                resi[channel] = Some(ResiChunk {
                    step,
                    exceptions: exc,
                    data: c.rest().to_vec(),
                });
            }
            b"MEND" => {
                chunks.push(info);
                if let Some(missing) = first_missing(&header, &plan, &bands, &resi) {
                    if !allow_truncated {
                        return Err(Error::format(
                            format!("{missing} missing (MEND at byte {})", ch.offset),
                            "every chunk the header commits to (or --allow-truncated)",
                        ));
                    }
                    break;
                }
                complete = true;
                break;
            }
            b"mETA" => meta = meta_chunk(&ch, &mut meta_seen, first_band)?,
            b"HEAD" => return Err(Error::format("a second HEAD chunk", "one HEAD chunk")),
            k => {
                if k[0].is_ascii_uppercase() {
                    return Err(Error::Unsupported {
                        what: "critical chunk",
                        value: ch.name(),
                    });
                }
            }
        }
        chunks.push(info);
    }
    if header.voids && first_band.is_some() && !super::voids::lists_voids(&meta) {
        // past where the mETA must be, without the void list the header promises
        return Err(Error::format(
            "no void list in mETA, though the header says the file has voids",
            "the mETA chunk with extra.nodata.voids (format 2.4 HEAD flag)",
        ));
    }
    Ok(Parsed {
        header,
        meta,
        plan,
        bands,
        resi,
        complete,
        chunks,
    })
}

/// A `mETA` chunk's metadata: at most one, before the first band chunk (or `TIDX` in a
/// tiled file) at byte `first_band` when one was read.
pub(super) fn meta_chunk(
    ch: &Chunk,
    seen: &mut bool,
    first_band: Option<u64>,
) -> Result<crate::io::Metadata> {
    if *seen {
        return Err(Error::format(
            format!("a second mETA chunk at byte {}", ch.offset),
            "at most one mETA chunk",
        ));
    }
    if let Some(at) = first_band {
        return Err(Error::format(
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

/// Whether a decode stopping at level `stop_level` (on reaching a chunk of a level it
/// does not need, at byte `at`) has every band it does need: the coarse block and the
/// detail levels above `stop_level`. A band missing there (a `LEVL` left out, or two
/// swapped so that a finer one comes first) is an error naming it, or with
/// `allow_truncated` an incomplete decode (`Ok(false)`).
fn coarse_present(
    header: &Header,
    plan: &Plan,
    bands: &[Vec<Option<BandChunk>>],
    stop_level: usize,
    at: u64,
    allow_truncated: bool,
) -> Result<bool> {
    let Some(missing) = first_missing_above(header, plan, bands, &[], stop_level) else {
        return Ok(true);
    };
    if allow_truncated {
        return Ok(false);
    }
    Err(Error::format(
        format!("{missing} missing before the chunk of level {stop_level} or finer at byte {at}"),
        "every coarser level before the finer ones",
    ))
}

/// The first chunk the header commits to that `bands` and `resi` lack, named.
fn first_missing(
    header: &Header,
    plan: &Plan,
    bands: &[Vec<Option<BandChunk>>],
    resi: &[Option<ResiChunk>],
) -> Option<String> {
    first_missing_above(header, plan, bands, resi, 0)
}

/// [`first_missing`] among the chunks a decode at level `stop_level` needs (every one at
/// level 0: the coarse block, the detail levels above `stop_level`, and the `RESI`
/// chunks only at level 0).
fn first_missing_above(
    header: &Header,
    plan: &Plan,
    bands: &[Vec<Option<BandChunk>>],
    resi: &[Option<ResiChunk>],
    stop_level: usize,
) -> Option<String> {
    for (j, b) in plan.bands.iter().enumerate() {
        if stop_level > 0 && b.level >= 1 && b.level <= stop_level {
            continue;
        }
        for (c, ch) in bands.iter().enumerate() {
            if ch[j].is_none() {
                return Some(if header.major >= 2 {
                    format!("LEVL chunk of level {} (band {j}, channel {c})", b.level)
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
