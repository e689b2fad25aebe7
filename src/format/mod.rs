//! The `.mra` container (normative spec: formats/MRA.md). A file is the 8-byte
//! signature followed by chunks `length u32 LE | type [4] | payload | CRC-32C u32 LE`
//! (CRC over type and payload). `HEAD` comes first, `MEND` last; the coded bands sit
//! in between in coarse-to-fine order. Unknown chunks whose type starts with a
//! lowercase letter are skipped; unknown uppercase (critical) chunks are rejected.

pub mod crc;
pub mod header;
pub mod sha256;

pub use header::{Header, Mode};

use crate::{Error, Result};
use std::io::Read;

/// The file signature (PNG-style: a high byte, the name, CR LF, ^Z, LF).
pub const SIGNATURE: [u8; 8] = [0x8B, b'M', b'R', b'A', 0x0D, 0x0A, 0x1A, 0x0A];
/// The major version written (2: level chunks, format-2 coefficient coding); readers
/// decode majors [`OLDEST_MAJOR`] to this one and reject others.
pub const MAJOR: u8 = 2;
/// The oldest major version readers still decode.
pub const OLDEST_MAJOR: u8 = 1;
/// The minor version written for a file with neither tiles nor format 2.3's coding.
pub const MINOR: u8 = 0;
/// The minor version of a file split into tiles (`TIDX` and `TILE` chunks, 2.1).
pub const MINOR_TILED: u8 = 1;
/// The minor version of a lossy tiled file whose tiles may be compact (a `TRAT` chunk
/// of step ratios per tile class, a form byte in each `TILE`, 2.2).
pub const MINOR_COMPACT: u8 = 2;
/// The minor version from which every band's stream chooses its magnitude classes,
/// narrow or wide (2.3; mra writes it for lossless files and tiles).
pub const MINOR_WIDE: u8 = 3;
/// The minor version from which `HEAD` ends with a flags byte whose bit 0 says the
/// `mETA` lists void samples (2.4; mra writes it for files with voids, so that a file
/// whose ancillary `mETA` was dropped is refused rather than decoding its voids as
/// values).
pub const MINOR_VOIDS: u8 = 4;
/// The highest minor version of [`MAJOR`] readers implement; they reject higher ones
/// (a 2.3 band would decode wrongly as a 2.2 one).
pub const LATEST_MINOR: u8 = MINOR_VOIDS;
/// Largest chunk payload accepted (1 GiB).
pub const MAX_CHUNK: u64 = 1 << 30;

/// Append one chunk to `out`.
pub fn put_chunk(out: &mut Vec<u8>, kind: &[u8; 4], payload: &[u8]) {
    out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    out.extend_from_slice(kind);
    out.extend_from_slice(payload);
    let mut c = crc::Crc32c::new();
    c.update(kind);
    c.update(payload);
    out.extend_from_slice(&c.finish().to_le_bytes());
}

/// Write a chunk whose payload is the concatenation of `parts` (as [`put_chunk`] would
/// frame it); returns the bytes written, framing included.
pub fn write_chunk<W: std::io::Write>(
    w: &mut W,
    kind: &[u8; 4],
    parts: &[&[u8]],
) -> std::io::Result<u64> {
    let len: usize = parts.iter().map(|p| p.len()).sum();
    w.write_all(&(len as u32).to_le_bytes())?;
    w.write_all(kind)?;
    let mut c = crc::Crc32c::new();
    c.update(kind);
    for p in parts {
        w.write_all(p)?;
        c.update(p);
    }
    w.write_all(&c.finish().to_le_bytes())?;
    Ok(len as u64 + 12)
}

/// Append `v` as an unsigned LEB128 integer (7 bits a byte, low first).
pub fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8 & 0x7F) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// One chunk as read: its type, payload, and byte offset in the file.
#[derive(Clone, Debug)]
pub struct Chunk {
    pub kind: [u8; 4],
    pub payload: Vec<u8>,
    pub offset: u64,
}

impl Chunk {
    pub fn name(&self) -> String {
        self.kind
            .iter()
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
            .collect()
    }
}

/// What stopped a chunk read.
#[derive(Debug)]
pub enum ChunkEnd {
    /// The file ends exactly at a chunk boundary.
    Eof,
    /// The file ends inside a chunk (truncated).
    Truncated { offset: u64 },
}

/// Reads chunks one at a time from a stream of known total length, checking every
/// declared length against the bytes that remain before allocating.
pub struct ChunkReader<R: Read> {
    src: R,
    pos: u64,
    len: u64,
}

impl<R: Read> ChunkReader<R> {
    /// Check the signature; `len` is the total stream length.
    pub fn new(mut src: R, len: u64) -> Result<Self> {
        let mut sig = [0u8; 8];
        if len < 8 || read_full(&mut src, &mut sig)? < 8 {
            return Err(Error::format(
                format!("file of {len} bytes is too short for an .mra signature"),
                "an .mra file (8-byte signature 8B 4D 52 41 0D 0A 1A 0A)",
            ));
        }
        if sig != SIGNATURE {
            // a file of another format says which (its first 8 bytes are enough for
            // the formats with a signature there)
            let found = match crate::io::Format::sniff(&sig) {
                Some(f) => format!("this is a {} file, not .mra", f.name()),
                None => format!("signature {:02X?}", sig),
            };
            return Err(Error::format(
                found,
                "an .mra file (8B 4D 52 41 0D 0A 1A 0A; `mra convert` or `mra encode` reads other formats)",
            ));
        }
        Ok(ChunkReader { src, pos: 8, len })
    }

    /// A reader whose stream is positioned at byte `pos` of a file of `len` bytes (after
    /// a seek to a chunk an index points at); no signature is read.
    pub fn at(src: R, pos: u64, len: u64) -> Self {
        ChunkReader {
            src,
            pos: pos.min(len),
            len,
        }
    }

    /// The byte offset of the next chunk.
    pub fn position(&self) -> u64 {
        self.pos
    }

    /// Bytes of the stream.
    pub fn total(&self) -> u64 {
        self.len
    }

    /// The next chunk, or why there is none. A CRC mismatch is an error naming the chunk.
    pub fn next_chunk(&mut self) -> Result<std::result::Result<Chunk, ChunkEnd>> {
        let offset = self.pos;
        if self.pos == self.len {
            return Ok(Err(ChunkEnd::Eof));
        }
        let mut head = [0u8; 8];
        if self.len - self.pos < 12 {
            return Ok(Err(ChunkEnd::Truncated { offset }));
        }
        read_full(&mut self.src, &mut head)?;
        let n = u32::from_le_bytes(head[..4].try_into().unwrap()) as u64;
        let kind: [u8; 4] = head[4..].try_into().unwrap();
        if n > MAX_CHUNK {
            return Err(Error::LimitsExceeded {
                what: "chunk length",
                requested: n,
                limit: MAX_CHUNK,
            });
        }
        if n + 12 > self.len - self.pos {
            return Ok(Err(ChunkEnd::Truncated { offset }));
        }
        let mut payload = vec![0u8; n as usize];
        read_full(&mut self.src, &mut payload)?;
        let mut crc4 = [0u8; 4];
        read_full(&mut self.src, &mut crc4)?;
        self.pos += n + 12;
        let chunk = Chunk {
            kind,
            payload,
            offset,
        };
        let mut c = crc::Crc32c::new();
        c.update(&kind);
        c.update(&chunk.payload);
        let want = u32::from_le_bytes(crc4);
        let got = c.finish();
        if want != got {
            return Err(Error::format(
                format!(
                    "CRC-32C mismatch in chunk {} at byte {offset} (stored {want:08x}, computed {got:08x})",
                    chunk.name()
                ),
                "an undamaged file",
            ));
        }
        Ok(Ok(chunk))
    }
}

fn read_full<R: Read>(r: &mut R, buf: &mut [u8]) -> Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(got)
}

/// Little-endian cursor over a payload; every read is bounds-checked.
pub struct Cursor<'a> {
    pub data: &'a [u8],
    pub pos: usize,
    pub what: &'static str,
}

impl<'a> Cursor<'a> {
    pub fn new(data: &'a [u8], what: &'static str) -> Self {
        Cursor { data, pos: 0, what }
    }
    pub fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        if self.data.len() - self.pos < n {
            return Err(Error::format(
                format!(
                    "{} chunk ends at byte {} of {}",
                    self.what,
                    self.pos,
                    self.data.len()
                ),
                "a complete chunk payload",
            ));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    pub fn u8(&mut self) -> Result<u8> {
        Ok(self.take(1)?[0])
    }
    pub fn u16(&mut self) -> Result<u16> {
        Ok(u16::from_le_bytes(self.take(2)?.try_into().unwrap()))
    }
    pub fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    pub fn f32(&mut self) -> Result<f32> {
        Ok(f32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    pub fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    /// An unsigned LEB128 integer (7 bits a byte, low first) of at most 10 bytes that
    /// fits in 64 bits.
    pub fn varint(&mut self) -> Result<u64> {
        let mut v = 0u64;
        for k in 0..10 {
            let b = self.u8()?;
            let bits = (b & 0x7F) as u64;
            if k == 9 && bits > 1 {
                break;
            }
            v |= bits << (7 * k);
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(Error::format(
            format!(
                "{} chunk: an integer over 64 bits at byte {}",
                self.what, self.pos
            ),
            "LEB128 integers of at most 64 bits",
        ))
    }
    pub fn rest(&mut self) -> &'a [u8] {
        let s = &self.data[self.pos..];
        self.pos = self.data.len();
        s
    }
}
