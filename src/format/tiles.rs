//! The chunks of a file of more than one tile (2.1, formats/MRA.md §14): `TIDX` (the
//! byte offset and length of every `TILE` chunk), `TILE` (the tile's index, then — from
//! 2.2 — a form byte and either the chunks of the tile's one-tile file or its compact
//! form), `TRAT` (2.2: the step ratios of each tile class), and the reads by index a
//! seeking reader makes. Every offset and length is checked against the file before use.
//!
//! A compact tile holds its range and its band streams only; the rest of its one-tile
//! file (`HEAD`, the `LEVL` framing, the step ratios and `MEND`) follows from the file's
//! `HEAD`, the tile's extents and the ratios of its class. The codec gives the number of
//! streams of each level of a tile class as `(level, streams)` pairs.

use super::body::meta_chunk;
use super::{put_chunk, put_varint, Chunk, ChunkReader, Cursor, Header, Tag, MAX_CHUNK, SIGNATURE};
use crate::io::Metadata;
use crate::{FormatError, Result};
use std::io::{Read, Seek, SeekFrom};

/// `TILE` payload form (2.2, the byte after the tile index): the chunks of the tile's
/// one-tile file after its signature.
pub const FORM_CHUNKS: u8 = 0;
/// `TILE` payload form: the compact form.
pub const FORM_COMPACT: u8 = 1;

/// The bytes a `TILE` payload starts with: the tile's index (u32 LE).
pub fn tile_prefix(i: usize) -> [u8; 4] {
    (i as u32).to_le_bytes()
}

/// The bytes of a 2.2 tiled file outside its tiles' compact bodies: the signature, `HEAD`
/// (of `axes` axes, no flags byte), `mETA` (its payload `meta` bytes, absent when 0),
/// `TRAT` (`ratios` ratios), `TIDX` and the framing and index of `tiles` `TILE`
/// chunks, `MEND`.
pub fn outside_bytes(axes: usize, meta: usize, ratios: usize, tiles: usize) -> usize {
    let frame = 12;
    let meta = if meta > 0 { frame + meta } else { 0 };
    SIGNATURE.len()
        + frame
        + 52
        + 8 * axes
        + meta
        + frame
        + 4 * ratios
        + frame
        + 16 * tiles
        + (frame + 4) * tiles
        + frame
}

/// The tile index of a `TILE` chunk of a grid of `n` tiles and the rest of its payload.
pub fn tile_payload(ch: &Chunk, n: usize) -> Result<(usize, &[u8])> {
    let mut c = Cursor::new(&ch.payload, "TILE");
    let i = c.u32()? as usize;
    if i >= n {
        return Err(FormatError::out_of_range(
            format!("TILE chunk at byte {} for tile {i}", ch.offset),
            "a tile of the grid",
        ));
    }
    Ok((i, c.rest()))
}

/// Append a `TIDX` entry: the `TILE` chunk at byte `offset` of `bytes` bytes (framing
/// included).
pub fn put_index_entry(index: &mut Vec<u8>, offset: u64, bytes: u64) {
    index.extend_from_slice(&offset.to_le_bytes());
    index.extend_from_slice(&bytes.to_le_bytes());
}

/// Parse the `TIDX` chunk `ch` of a grid of `n` tiles in a file of `len` bytes:
/// `(offset, length)` of each tile's chunk, each after the index.
pub fn parse_index(ch: &Chunk, n: usize, len: u64) -> Result<Vec<(u64, u64)>> {
    if ch.payload.len() as u64 != 16 * n as u64 {
        return Err(FormatError::invalid(
            format!("TIDX chunk of {} bytes for {n} tiles", ch.payload.len()),
            "16 bytes per tile",
        ));
    }
    let first = ch.offset + 12 + ch.payload.len() as u64;
    let mut c = Cursor::new(&ch.payload, "TIDX");
    let mut v = Vec::with_capacity(n);
    for i in 0..n {
        let (o, l) = (
            u64::from_le_bytes(c.take(8)?.try_into().unwrap()),
            u64::from_le_bytes(c.take(8)?.try_into().unwrap()),
        );
        if o < first || !(16..=MAX_CHUNK + 12).contains(&l) || o.checked_add(l).is_none() {
            return Err(FormatError::out_of_range(
                format!("TIDX entry of tile {i}: {l} bytes at byte {o} (the index ends at {first}, the file at {len})"),
                "chunks after the index",
            ));
        }
        v.push((o, l));
    }
    Ok(v)
}

/// The `TRAT` payload: the ratios of each class present, in class order, f32 LE.
pub fn ratios_payload(by_class: &[Option<Vec<f32>>]) -> Vec<u8> {
    by_class
        .iter()
        .flatten()
        .flat_map(|r| r.iter().flat_map(|x| x.to_le_bytes()))
        .collect()
}

/// Parse a `TRAT` payload: `classes` lists `(class, ratios)` of every class the grid
/// has, increasing; the result is indexed by class (`slots` of them, `None` for the
/// classes the grid has not), each ratio positive and finite.
pub fn parse_ratios(
    payload: &[u8],
    classes: &[(usize, usize)],
    slots: usize,
) -> Result<Vec<Option<Vec<f32>>>> {
    let mut by_class = vec![None; slots];
    let mut cur = Cursor::new(payload, "TRAT");
    for &(m, n) in classes {
        if (payload.len() - cur.pos) < 4 * n {
            return Err(FormatError::truncated(
                format!(
                    "TRAT chunk of {} bytes, short at tile class {m}",
                    payload.len()
                ),
                "4 bytes per band and channel of every tile class",
            ));
        }
        let mut r = Vec::with_capacity(n);
        for _ in 0..n {
            let x = cur.f32()?;
            if !(x > 0.0 && x.is_finite()) {
                return Err(FormatError::invalid(
                    format!("TRAT step ratio {x} for tile class {m}"),
                    "positive finite ratios",
                ));
            }
            r.push(x);
        }
        by_class[m] = Some(r);
    }
    if cur.pos != payload.len() {
        return Err(FormatError::invalid(
            format!(
                "TRAT chunk of {} bytes with {} after the last tile class",
                payload.len(),
                payload.len() - cur.pos
            ),
            "4 bytes per band and channel of every tile class",
        ));
    }
    Ok(by_class)
}

/// A `TILE` payload after the tile index, by its form.
pub enum TileForm<'a> {
    /// The chunks of the tile's one-tile file after its signature (2.1, or form 0).
    Chunks(&'a [u8]),
    /// The compact form: the tile's range, then its streams (each `varint length |
    /// stream`) in file order.
    Compact {
        min: f64,
        max: f64,
        streams: &'a [u8],
    },
}

impl<'a> TileForm<'a> {
    /// The form of tile `i`'s payload `inner` in a file of version-capabilities `compact`
    /// ([`super::Version::has_compact_tiles`]).
    pub fn parse(inner: &'a [u8], compact: bool, i: usize) -> Result<TileForm<'a>> {
        if !compact {
            return Ok(TileForm::Chunks(inner));
        }
        let mut cur = Cursor::new(inner, "TILE");
        match cur.u8()? {
            FORM_CHUNKS => Ok(TileForm::Chunks(cur.rest())),
            FORM_COMPACT => {
                let min = cur.f64()?;
                let max = cur.f64()?;
                Ok(TileForm::Compact {
                    min,
                    max,
                    streams: cur.rest(),
                })
            }
            f => Err(FormatError::invalid(
                format!("TILE of tile {i} in form {f}"),
                "form 0 (chunks) or 1 (compact)",
            )),
        }
    }
}

/// The one-tile file (signature included) of the chunks `chunks` of form 0.
pub fn chunks_file(chunks: &[u8]) -> Vec<u8> {
    let mut f = SIGNATURE.to_vec();
    f.extend_from_slice(chunks);
    f
}

/// The one-tile file (signature included) a compact tile `i` stands for: `HEAD` of
/// header `t`, one `LEVL` per level of `levels` (`(level, streams)`) whose streams are
/// read from `streams` with the ratios `ratios` in order, `MEND`.
pub fn compact_file(
    t: &Header,
    levels: &[(usize, usize)],
    ratios: &[f32],
    streams: &[u8],
    i: usize,
) -> Result<Vec<u8>> {
    let mut cur = Cursor::new(streams, "TILE");
    let mut f = SIGNATURE.to_vec();
    f.reserve(streams.len() + 256);
    put_chunk(&mut f, Tag::Head.bytes(), &t.to_bytes());
    let mut k = 0;
    for &(level, count) in levels {
        let mut p = (level as u16).to_le_bytes().to_vec();
        for _ in 0..count {
            let len = cur.varint()?;
            let left = (streams.len() - cur.pos) as u64;
            if len > left {
                return Err(FormatError::out_of_range(
                    format!("compact TILE of tile {i}: a stream of {len} bytes, {left} left"),
                    "streams within the chunk",
                ));
            }
            let r = ratios.get(k).ok_or_else(|| {
                FormatError::missing(
                    format!("compact TILE of tile {i}: stream {k} without its TRAT ratio"),
                    "a ratio for every stream",
                )
            })?;
            p.extend_from_slice(&r.to_le_bytes());
            put_varint(&mut p, len);
            p.extend_from_slice(cur.take(len as usize)?);
            k += 1;
        }
        put_chunk(&mut f, Tag::Levl.bytes(), &p);
    }
    if cur.pos != streams.len() {
        return Err(FormatError::invalid(
            format!(
                "compact TILE of tile {i} with {} bytes after its last stream",
                streams.len() - cur.pos
            ),
            "a payload that ends with its last stream",
        ));
    }
    put_chunk(&mut f, Tag::Mend.bytes(), &[]);
    Ok(f)
}

/// One chunk of a file made by this crate: `(type, payload)` and the rest.
fn split_chunk(b: &[u8]) -> Option<(&[u8], &[u8], &[u8])> {
    let len = u32::from_le_bytes(b.get(..4)?.try_into().ok()?) as usize;
    let kind = b.get(4..8)?;
    let payload = b.get(8..8 + len)?;
    let rest = b.get(8 + len + 4..)?;
    Some((kind, payload, rest))
}

/// The header of a file made by this crate (`f` from its signature on).
pub fn head_of(f: &[u8]) -> Result<Header> {
    match f.get(SIGNATURE.len()..).and_then(split_chunk) {
        Some((kind, head, _)) if kind == Tag::Head.bytes() => Header::parse(head),
        _ => Err(FormatError::missing(
            "a coded tile without HEAD",
            "HEAD first",
        )),
    }
}

/// The compact form (form byte included) of the one-tile file `f` (signature included)
/// when `f` is `HEAD`, one `LEVL` per level of `levels` (`(level, streams)`) and `MEND`,
/// its header `same` but for its range and its ratios `ratios`; `None` else.
pub fn compact_body(
    f: &[u8],
    same: &Header,
    levels: &[(usize, usize)],
    ratios: &[f32],
) -> Option<Vec<u8>> {
    let (kind, head, mut rest) = split_chunk(f.get(SIGNATURE.len()..)?)?;
    if kind != Tag::Head.bytes() {
        return None;
    }
    let t = Header::parse(head).ok()?;
    let mut same = same.clone();
    (same.min, same.max) = (t.min, t.max);
    if t != same {
        return None;
    }
    let mut out = vec![FORM_COMPACT];
    out.extend_from_slice(&t.min.to_le_bytes());
    out.extend_from_slice(&t.max.to_le_bytes());
    let mut k = 0;
    for &(level, count) in levels {
        let (kind, p, more) = split_chunk(rest)?;
        rest = more;
        let mut cur = Cursor::new(p, "LEVL");
        if kind != Tag::Levl.bytes() || cur.u16().ok()? as usize != level {
            return None;
        }
        for _ in 0..count {
            if cur.f32().ok()?.to_bits() != ratios.get(k)?.to_bits() {
                return None;
            }
            k += 1;
            let len = cur.varint().ok()?;
            put_varint(&mut out, len);
            out.extend_from_slice(cur.take(len as usize).ok()?);
        }
        if cur.pos != p.len() {
            return None;
        }
    }
    let (kind, p, rest) = split_chunk(rest)?;
    (kind == Tag::Mend.bytes() && p.is_empty() && rest.is_empty() && k == ratios.len())
        .then_some(out)
}

/// The form-0 body (form byte, then the chunks) of the one-tile file `f` (signature
/// included).
pub fn chunks_body(f: &[u8]) -> Vec<u8> {
    let mut v = Vec::with_capacity(f.len() - 7);
    v.push(FORM_CHUNKS);
    v.extend_from_slice(&f[SIGNATURE.len()..]);
    v
}

/// Bytes of the compact form of a lossy one-tile file `f` (signature included): the
/// form byte, the range, and each `LEVL` payload less its level and its ratios (for the
/// `--bpp` search, before the file's `HEAD` is known); `f`'s chunks and the form byte
/// when `f` is not `HEAD`, `LEVL`…, `MEND`.
pub fn compact_len(f: &[u8]) -> usize {
    let whole = f.len() - 7;
    let Some((kind, _, mut rest)) = split_chunk(&f[SIGNATURE.len()..]) else {
        return whole;
    };
    if kind != Tag::Head.bytes() {
        return whole;
    }
    let mut n = 1 + 16;
    while let Some((kind, p, more)) = split_chunk(rest) {
        rest = more;
        if kind == Tag::Mend.bytes() {
            return if rest.is_empty() { n } else { whole };
        }
        if kind != Tag::Levl.bytes() {
            return whole;
        }
        let mut cur = Cursor::new(p, "LEVL");
        if cur.u16().is_err() {
            return whole;
        }
        let mut streams = 0;
        while cur.pos < p.len() {
            let stream = cur.f32().and_then(|_| cur.varint());
            match stream.and_then(|len| cur.take(len as usize).map(|_| ())) {
                Ok(()) => streams += 1,
                Err(_) => return whole,
            }
        }
        n += p.len() - 2 - 4 * streams;
    }
    whole
}

/// What a tiled file says before its tiles: its metadata, the place of each tile and
/// what its `TRAT` chunk (2.2) parsed to.
pub type Index<T> = (Metadata, Vec<(u64, u64)>, Option<T>);

/// Read `mETA`, `TRAT` (2.2, parsed by `trat`) and `TIDX` of a tiled file of header
/// `h` and `n` tiles from a seekable stream of `len` bytes, from byte `after_head` (just
/// after `HEAD`).
pub fn read_index<R: Read + Seek, T>(
    src: &mut R,
    len: u64,
    after_head: u64,
    h: &Header,
    n: usize,
    mut trat: impl FnMut(&Chunk) -> Result<T>,
) -> Result<Index<T>> {
    let mut ratios = None;
    let mut meta = Metadata::default();
    let (mut meta_seen, mut first_data) = (false, None);
    src.seek(SeekFrom::Start(after_head))?;
    let mut rd = ChunkReader::at(&mut *src, after_head, len);
    loop {
        let ch = match rd.next_chunk()? {
            Ok(c) => c,
            Err(_) => {
                return Err(FormatError::missing(
                    format!("tiled file of {len} bytes without its TIDX chunk"),
                    "a TIDX chunk after HEAD",
                ))
            }
        };
        match ch.tag() {
            Some(Tag::Meta) => meta = meta_chunk(&ch, &mut meta_seen, first_data)?,
            Some(Tag::Trat) if h.version.has_compact_tiles() => {
                first_data = Some(ch.offset);
                ratios = Some(trat(&ch)?);
            }
            Some(Tag::Tidx) => return Ok((meta, parse_index(&ch, n, len)?, ratios)),
            Some(Tag::Head) => {
                return Err(FormatError::duplicate(
                    "a second HEAD chunk",
                    "one HEAD chunk",
                ))
            }
            _ => {
                if Tag::is_critical(&ch.kind) {
                    return Err(FormatError::order(
                        format!("chunk {} at byte {} before TIDX", ch.name(), ch.offset),
                        "HEAD, mETA, TRAT (2.2), then TIDX",
                    ));
                }
            }
        }
    }
}

/// The `TILE` payload (after its index) of tile `i` of `n`, found by its index entry
/// `(off, l)`; `None` when the file ends before it and truncated input is allowed.
pub fn fetch_tile<R: Read + Seek>(
    src: &mut R,
    len: u64,
    n: usize,
    i: usize,
    (off, l): (u64, u64),
    allow_truncated: bool,
) -> Result<Option<Vec<u8>>> {
    if off + l > len {
        if !allow_truncated {
            return Err(FormatError::truncated(
                format!(
                    "file truncated: tile {i} at bytes {off}..{} of {len}",
                    off + l
                ),
                "a complete file (or --allow-truncated)",
            ));
        }
        return Ok(None);
    }
    src.seek(SeekFrom::Start(off))?;
    let ch = match ChunkReader::at(&mut *src, off, off + l).next_chunk()? {
        Ok(c) if c.tag() == Some(Tag::Tile) && c.payload.len() as u64 + 12 == l => c,
        _ => {
            return Err(FormatError::out_of_range(
                format!("TIDX entry of tile {i} ({l} bytes at byte {off}) not on its TILE chunk"),
                "an index pointing at each tile's chunk",
            ))
        }
    };
    let (j, inner) = tile_payload(&ch, n)?;
    if j != i {
        return Err(FormatError::out_of_range(
            format!("TIDX entry of tile {i} on the chunk of tile {j} (byte {off})"),
            "an index pointing at each tile's chunk",
        ));
    }
    Ok(Some(inner.to_vec()))
}

/// Whether a `MEND` chunk follows the last tile (a whole decode checks it).
pub fn check_end<R: Read + Seek>(
    src: &mut R,
    len: u64,
    after_head: u64,
    index: &[(u64, u64)],
    allow_truncated: bool,
) -> Result<bool> {
    let end = index
        .iter()
        .map(|&(o, l)| o + l)
        .max()
        .unwrap_or(after_head);
    src.seek(SeekFrom::Start(end))?;
    let ok = matches!(ChunkReader::at(&mut *src, end, len).next_chunk()?, Ok(c) if c.tag() == Some(Tag::Mend));
    if !ok && !allow_truncated {
        return Err(FormatError::truncated(
            format!("no MEND chunk after the last tile (byte {end} of {len})"),
            "a complete file ending with MEND (or --allow-truncated)",
        ));
    }
    Ok(ok)
}
