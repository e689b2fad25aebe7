//! The chunks of a one-piece format 3.0 file read for a region (formats/MRA.md §15):
//! every chunk's 8-byte head, the small chunks whole (`mETA`, `MEND`, checked as
//! [`super::body`] checks them), and of each `LEVL` chunk only its level, each band
//! entry's ratio, length and code-block index, never the blocks' streams. Each band's
//! entry comes back as its index bytes, with its offset and length `L` in the file, so
//! that the caller reads just the blocks it needs by positioned reads. The `LEVL`
//! chunks' CRCs are checked only when asked (a whole decode: each chunk's payload read
//! through the CRC a piece at a time, nothing held; a region read skips them, that
//! would read them whole); the index is checked as [`super::bands::parse_index`] checks
//! it once the caller parses it.

use super::body::{mend, other_chunk, truncated, BandChunk, BandLayout, Body, ChunkInfo};
use super::{ChunkEnd, ChunkReader, Header, Mode, Tag, MAX_CHUNK};
use crate::io::Metadata;
use crate::{FormatError, Result};
use std::io::{Read, Seek, SeekFrom};

/// [`Body`] of a file read sparsely (each band's [`BandChunk::data`] its entry's
/// code-block index alone), with the file offset and length `L` of each band's entry
/// (`[channel][band]`, the offset of the first of its `L` bytes).
pub struct SparseBody {
    pub body: Body,
    pub entries: Vec<Vec<Option<(u64, u64)>>>,
}

/// A source read by position that counts what it consumes.
struct At<'a, R> {
    src: &'a mut R,
    pos: u64,
    end: u64,
}

impl<R: Read + Seek> At<'_, R> {
    fn seek(&mut self, pos: u64) -> Result<()> {
        self.src.seek(SeekFrom::Start(pos))?;
        self.pos = pos;
        Ok(())
    }

    fn bytes<const N: usize>(&mut self, what: &str) -> Result<[u8; N]> {
        if self.end - self.pos < N as u64 {
            return Err(FormatError::truncated(
                format!("LEVL chunk ends inside {what} at byte {}", self.pos),
                "band entries within the chunk",
            ));
        }
        let mut b = [0u8; N];
        self.src.read_exact(&mut b)?;
        self.pos += N as u64;
        Ok(b)
    }

    /// A LEB128 integer (at most 64 bits), its bytes appended to `raw` when given.
    fn varint(&mut self, what: &str, mut raw: Option<&mut Vec<u8>>) -> Result<u64> {
        let v = super::leb128(|| {
            let [b] = self.bytes::<1>(what)?;
            if let Some(r) = raw.as_deref_mut() {
                r.push(b);
            }
            Ok(b)
        })?;
        if let Some(v) = v {
            return Ok(v);
        }
        Err(FormatError::invalid(
            format!("LEVL chunk: {what} over 64 bits at byte {}", self.pos),
            "LEB128 integers of at most 64 bits",
        ))
    }
}

/// One band entry of a `LEVL` chunk at `r` (band `j` of channel `ch` of `level`): its
/// ratio, `L` and code-block index read, the blocks' streams skipped. Returns the entry
/// as its index bytes, and its file offset and `L`.
fn band_entry<R: Read + Seek>(
    r: &mut At<'_, R>,
    header: &Header,
    level: usize,
    j: usize,
    ch: usize,
) -> Result<(BandChunk, (u64, u64))> {
    let ratio = f32::from_le_bytes(r.bytes::<4>("a step ratio")?);
    if !(ratio > 0.0 && ratio.is_finite()) {
        return Err(FormatError::invalid(
            format!("LEVL {level}: band {j} of channel {ch} with step ratio {ratio}"),
            "a positive finite ratio",
        ));
    }
    let l = r.varint("a band length", None)?;
    let start = r.pos;
    if l > r.end - start {
        return Err(FormatError::out_of_range(
            format!(
                "LEVL {level}: band {j} of channel {ch} declaring {l} bytes, {} left",
                r.end - start
            ),
            "streams within the chunk",
        ));
    }
    // the code-block index: a count, then a length per block (each at least a byte, so
    // no more than the entry holds)
    let mut index = Vec::new();
    let mut e = At {
        src: &mut *r.src,
        pos: start,
        end: start + l,
    };
    let count = e.varint("a code-block count", Some(&mut index))?;
    if count > l {
        return Err(FormatError::out_of_range(
            format!("{count} code-blocks in an entry of {l} bytes"),
            "at least one index byte per block",
        ));
    }
    for _ in 0..count {
        e.varint("a code-block length", Some(&mut index))?;
    }
    // `l` is within the chunk, itself within the file
    r.seek(start + l)?;
    let band = BandChunk {
        step: header.step * ratio as f64,
        data: index,
    };
    Ok((band, (start, l)))
}

/// The state of a sparse read: what the file's header commits to and what has been
/// gathered so far.
struct Reading<'h> {
    header: &'h Header,
    layout: &'h BandLayout<'h>,
    stop_level: usize,
    len: u64,
    crc: bool,
    body: Body,
    entries: Vec<Vec<Option<(u64, u64)>>>,
    meta_seen: bool,
    first_band: Option<u64>,
    last: String,
}

impl Reading<'_> {
    /// The `LEVL` chunk of `n` payload bytes at byte `pos`: its level, then every band
    /// entry's ratio, length and index ([`band_entry`]). Returns whether the read stops
    /// there (the first level over the one asked for).
    fn levl<R: Read + Seek>(
        &mut self,
        src: &mut R,
        pos: u64,
        n: u64,
        kind: [u8; 4],
    ) -> Result<bool> {
        if self.crc {
            check_crc(src, pos, n, kind)?;
            src.seek(SeekFrom::Start(pos + 8))?;
        }
        let (header, layout, b) = (self.header, self.layout, &mut self.body);
        self.first_band.get_or_insert(pos);
        let mut r = At {
            src,
            pos: pos + 8,
            end: pos + 8 + n,
        };
        let level = u16::from_le_bytes(r.bytes::<2>("the level")?) as usize;
        let Some((_, js)) = layout.groups.iter().find(|(l, _)| *l == level) else {
            return Err(FormatError::out_of_range(
                format!("LEVL chunk for level {level} at byte {pos}"),
                "a level of the file's pyramid",
            ));
        };
        let stop = self.stop_level;
        if stop > 0 && level >= 1 && level <= stop {
            super::body::coarse_present(header, layout, &b.bands, stop, pos, false)?;
            b.complete = true;
            return Ok(true);
        }
        let first = js.first().copied().unwrap_or(0);
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
                format!("a second LEVL chunk for level {level} (byte {pos})"),
                "each level once",
            ));
        }
        for &j in js {
            for ch in 0..header.channels {
                let (band, start) = band_entry(&mut r, header, level, j, ch)?;
                b.bands[ch][j] = Some(band);
                self.entries[ch][j] = Some(start);
            }
        }
        if r.pos != r.end {
            return Err(FormatError::invalid(
                format!(
                    "LEVL {level} with {} bytes after its last band",
                    r.end - r.pos
                ),
                "a chunk that ends with its last band",
            ));
        }
        let chunk = super::Chunk {
            kind,
            payload: Vec::new(),
            offset: pos,
        };
        let mut info = ChunkInfo::of(&chunk, None);
        info.bytes = n + 12;
        info.level = Some(level);
        b.chunks.push(info);
        Ok(false)
    }

    /// A chunk other than `LEVL` at byte `pos`, read whole and checked as
    /// [`super::body::read_body`] checks it. Returns whether it ends the body (`MEND`).
    fn whole<R: Read + Seek>(&mut self, src: &mut R, pos: u64) -> Result<bool> {
        let (len, b) = (self.len, &mut self.body);
        src.seek(SeekFrom::Start(pos))?;
        let ch = match ChunkReader::at(&mut *src, pos, len).next_chunk()? {
            Ok(ch) => ch,
            Err(end) => return Err(truncated(end, &self.last, len)),
        };
        if Tag::of(&ch.kind) == Some(Tag::Mend) {
            let (bands, resi) = (&b.bands, &b.resi);
            b.complete = mend(
                self.header,
                self.layout,
                (bands, resi),
                self.stop_level,
                pos,
                false,
            )?;
            b.chunks.push(ChunkInfo::of(&ch, None));
            return Ok(true);
        }
        other_chunk(&ch, &mut b.meta, &mut self.meta_seen, self.first_band)?;
        b.chunks.push(ChunkInfo::of(&ch, None));
        Ok(false)
    }
}

/// The chunks after `HEAD` (the next at byte `at`) of a one-piece 3.0 file of `len`
/// bytes whose bands are `layout`, read sparsely (module doc); reading stops at the first
/// chunk of a level from 1 to `stop_level` as [`super::body::read_body`]'s does. `None`
/// for a file this reader leaves to the whole read (one with `RESI` chunks). With `crc`
/// every `LEVL` chunk's CRC is checked too ([`check_crc`]).
pub fn read_body_sparse<R: Read + Seek>(
    src: &mut R,
    at: u64,
    len: u64,
    header: &Header,
    layout: &BandLayout,
    (stop_level, crc): (usize, bool),
) -> Result<Option<SparseBody>> {
    if header.mode == Mode::MaxError {
        return Ok(None);
    }
    let nb = layout.levels.len();
    let c = header.channels;
    let mut g = Reading {
        header,
        layout,
        stop_level,
        len,
        crc,
        body: Body {
            meta: Metadata::default(),
            bands: (0..c).map(|_| (0..nb).map(|_| None).collect()).collect(),
            resi: (0..c).map(|_| None).collect(),
            complete: false,
            chunks: Vec::new(),
        },
        entries: vec![vec![None; nb]; c],
        meta_seen: false,
        first_band: None,
        last: "HEAD".to_string(),
    };
    let mut pos = at;
    loop {
        if pos == len {
            return Err(truncated(ChunkEnd::Eof, &g.last, len));
        }
        if len - pos < 12 {
            return Err(truncated(ChunkEnd::Truncated { offset: pos }, &g.last, len));
        }
        src.seek(SeekFrom::Start(pos))?;
        let mut head = [0u8; 8];
        src.read_exact(&mut head)?;
        let n = u32::from_le_bytes(head[..4].try_into().expect("4 bytes")) as u64;
        let kind: [u8; 4] = head[4..].try_into().expect("4 bytes");
        if n > MAX_CHUNK {
            return Err(FormatError::budget("chunk length", n, MAX_CHUNK));
        }
        if n + 12 > len - pos {
            return Err(truncated(ChunkEnd::Truncated { offset: pos }, &g.last, len));
        }
        g.last = String::from_utf8_lossy(&kind).into_owned();
        let done = match Tag::of(&kind) {
            Some(Tag::Levl) => g.levl(src, pos, n, kind)?,
            Some(Tag::Resi | Tag::Band) => return Ok(None),
            _ => g.whole(src, pos)?,
        };
        if done {
            break;
        }
        pos += n + 12;
    }
    if header.voids && g.first_band.is_some() && !super::meta::lists_voids(&g.body.meta) {
        return Err(FormatError::missing(
            "no void list in mETA, though the header says the file has voids",
            "the mETA chunk with extra.nodata.voids (format 2.4 HEAD flag)",
        ));
    }
    Ok(Some(SparseBody {
        body: g.body,
        entries: g.entries,
    }))
}

/// Bytes of a chunk's payload [`check_crc`] reads at a time.
const CRC_PIECE: usize = 1 << 20;

/// Check the CRC of the chunk of type `kind` and `n` payload bytes at byte `pos` (its
/// 8-byte head there, the payload and CRC after; within the file, as the caller
/// checked), reading the payload a piece of [`CRC_PIECE`] bytes at a time: an error
/// naming the chunk when it does not match, as [`super::ChunkReader`] gives.
pub fn check_crc<R: Read + Seek>(src: &mut R, pos: u64, n: u64, kind: [u8; 4]) -> Result<()> {
    src.seek(SeekFrom::Start(pos + 8))?;
    let mut c = super::crc::Crc32c::new();
    c.update(&kind);
    let mut buf = vec![0u8; CRC_PIECE.min(n as usize)];
    let mut left = n;
    while left > 0 {
        let k = (left as usize).min(buf.len());
        src.read_exact(&mut buf[..k])?;
        c.update(&buf[..k]);
        left -= k as u64;
    }
    let mut crc4 = [0u8; 4];
    src.read_exact(&mut crc4)?;
    let (stored, computed) = (u32::from_le_bytes(crc4), c.finish());
    if stored != computed {
        let chunk = super::Chunk {
            kind,
            payload: Vec::new(),
            offset: pos,
        };
        return Err(FormatError::Crc {
            chunk: chunk.name(),
            offset: pos,
            stored,
            computed,
        }
        .into());
    }
    Ok(())
}
