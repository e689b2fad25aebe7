//! The chunks of an `.mra` file as the codec writes and reads them: `HEAD`, `mETA`,
//! one `BAND` per band and channel (channel, band, step, coded indices), `RESI` per
//! channel in `--max-error` files (channel, step, exceptions, coded residuals), `MEND`.
//! Framing and CRCs are [`crate::format`]'s.

use super::meta;
use super::plan::Plan;
use crate::format::{ChunkEnd, ChunkReader, Cursor, Header};
use crate::{Error, Result};
use std::io::Read;

pub(super) const BAND: &[u8; 4] = b"BAND";
pub(super) const HEAD: &[u8; 4] = b"HEAD";
pub(super) const RESI: &[u8; 4] = b"RESI";
pub(super) const MEND: &[u8; 4] = b"MEND";
pub(super) const META: &[u8; 4] = b"mETA";

pub(super) fn band_payload(channel: usize, band: usize, step: f64, coded: &[u8]) -> Vec<u8> {
    let mut p = Vec::with_capacity(12 + coded.len());
    p.extend_from_slice(&(channel as u16).to_le_bytes());
    p.extend_from_slice(&(band as u16).to_le_bytes());
    p.extend_from_slice(&step.to_le_bytes());
    p.extend_from_slice(coded);
    p
}

/// A BAND chunk's contents.
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
    }];
    let mut complete = false;
    let mut last = "HEAD".to_string();
    loop {
        let ch = match rd.next_chunk()? {
            Ok(c) => c,
            Err(end) => {
                if !allow_truncated {
                    let at = match end {
                        ChunkEnd::Eof => len,
                        ChunkEnd::Truncated { offset } => offset,
                    };
                    return Err(Error::format(
                        format!("file truncated after chunk {last} (byte {at} of {len})"),
                        "a complete file ending with MEND (or --allow-truncated)",
                    ));
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
        };
        last = ch.name();
        match &ch.kind {
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
                    complete = true;
                    break;
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
                let mut exc = Vec::with_capacity(n);
                for _ in 0..n {
                    let i = u64::from_le_bytes(c.take(8)?.try_into().unwrap());
                    let v = c.f64()?;
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
                complete = true;
                break;
            }
            b"mETA" => meta = meta::parse(&ch.payload),
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
