//! The `.mra` container (normative spec: formats/MRA.md). A file is the 8-byte
//! signature followed by chunks `length u32 LE | type [4] | payload | CRC-32C u32 LE`
//! (CRC over type and payload). `HEAD` comes first, `MEND` last; the coded bands sit
//! in between in coarse-to-fine order. Unknown chunks whose type starts with a
//! lowercase letter are skipped; unknown uppercase (critical) chunks are rejected.

pub mod bands;
pub mod body;
pub mod crc;
pub mod header;
pub mod meta;
pub mod sha256;
pub mod sparse;
pub mod tag;
pub mod tiles;
pub mod version;

pub use bands::Residual;
pub use header::{Header, Mode};
pub use tag::Tag;
pub use version::Version;

use crate::{FormatError, Result};
use std::io::Read;

/// The file signature (PNG-style: a high byte, the name, CR LF, ^Z, LF).
pub const SIGNATURE: [u8; 8] = [0x8B, b'M', b'R', b'A', 0x0D, 0x0A, 0x1A, 0x0A];
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
    /// The chunk's type if this crate knows it.
    pub fn tag(&self) -> Option<Tag> {
        Tag::of(&self.kind)
    }

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
            return Err(FormatError::signature(
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
            return Err(FormatError::signature(
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
            return Err(FormatError::budget("chunk length", n, MAX_CHUNK));
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
            return Err(FormatError::Crc {
                chunk: chunk.name(),
                offset,
                stored: want,
                computed: got,
            }
            .into());
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

/// An unsigned LEB128 integer (`v = Σ_k (b_k & 0x7F)·2^{7k}`, low group first, the top
/// bit of each byte saying another follows) of the bytes `next` gives: at most 10 bytes,
/// `None` when it does not fit in 64 bits.
pub(crate) fn leb128(mut next: impl FnMut() -> Result<u8>) -> Result<Option<u64>> {
    let mut v = 0u64;
    for k in 0..10 {
        let b = next()?;
        let bits = (b & 0x7F) as u64;
        if k == 9 && bits > 1 {
            break;
        }
        v |= bits << (7 * k);
        if b & 0x80 == 0 {
            return Ok(Some(v));
        }
    }
    Ok(None)
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
            return Err(FormatError::truncated(
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
        if let Some(v) = leb128(|| self.u8())? {
            return Ok(v);
        }
        Err(FormatError::invalid(
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
