//! Compact tiles (format 2.2, formats/MRA.md §14): a lossy tile's `TILE` payload holds
//! its range and its band streams only; the rest of its one-tile file (the `HEAD`, the
//! `LEVL` framing, the step ratios and `MEND`) follows from the file's `HEAD`, the
//! tile's extents and the file's `TRAT` chunk, which lists the step ratios once per
//! tile class.
//!
//! A tile's class says on which axes it is the last, shorter tile of the grid (bit `a`
//! for axis `a`, slowest first): tiles of one class have the same extents, so the same
//! pyramid, bands and steps. Per tile this saves the `HEAD` chunk, 4 bytes a band and
//! channel of ratios, 14 bytes a level of `LEVL` framing and the `MEND` chunk (about
//! 400 bytes a tile of a 6-level RGB image), which at 1 bit per pixel is what most of
//! the seams of small tiles cost.

use super::Grid;
use crate::codec::colour::channel_weights;
use crate::codec::container::{HEAD, MEND};
use crate::codec::levels::LEVL;
use crate::codec::plan::Plan;
use crate::format::{self, put_chunk, put_varint, Chunk, Cursor, Header, Mode};
use crate::quantize;
use crate::{Error, Result};
use std::borrow::Cow;

/// The chunk type of the step ratios of each tile class.
pub(crate) const TRAT: &[u8; 4] = b"TRAT";

/// `TILE` payload forms of a 2.2 file (the byte after the tile index).
const FORM_CHUNKS: u8 = 0;
const FORM_COMPACT: u8 = 1;

impl Grid {
    /// Axes (bits, axis `a` → bit `a`) whose last tile is shorter than the others.
    fn short_axes(&self) -> usize {
        (0..self.dims.len())
            .filter(|&a| !self.dims[a].is_multiple_of(self.tile[a]))
            .fold(0, |m, a| m | 1 << a)
    }

    /// The classes of the grid's tiles, increasing: every subset of the short axes.
    pub(in crate::codec) fn classes(&self) -> Vec<usize> {
        let s = self.short_axes();
        (0..1usize << self.dims.len())
            .filter(|m| m & !s == 0)
            .collect()
    }

    /// The class of tile `i`: bit `a` set when it is the last, shorter tile on axis `a`.
    pub(in crate::codec) fn class(&self, i: usize) -> usize {
        self.coords(i)
            .iter()
            .enumerate()
            .filter(|&(a, &c)| self.extent(a, c) != self.tile[a])
            .fold(0, |m, (a, _)| m | 1 << a)
    }

    /// The extents of the tiles of class `m`.
    fn class_dims(&self, m: usize) -> Vec<usize> {
        (0..self.dims.len())
            .map(|a| {
                if m >> a & 1 == 1 {
                    self.extent(a, self.counts[a] - 1)
                } else {
                    self.tile[a]
                }
            })
            .collect()
    }
}

/// The `HEAD` of the one-tile file of a tile of extents `dims` in a file of header `h`.
fn tile_header(h: &Header, dims: &[usize]) -> Header {
    let mut t = h.clone();
    t.minor = format::MINOR;
    t.voids = false;
    t.dims = dims.to_vec();
    t.tile = dims.to_vec();
    t
}

/// The step ratios of every tile class of a lossy tiled file: per class (indexed by
/// class, `None` for classes the grid has not), its bands in file order (§7.2, level
/// by level from the coarse block), each band's channels: `f32(1 / (G_b · w_c))`, as
/// the lossy encoder writes them in a one-tile file.
pub(in crate::codec) struct Ratios {
    by_class: Vec<Option<Vec<f32>>>,
}

impl Ratios {
    /// The ratios the encoder uses for the tiles of `grid` in a file of header `h`.
    pub(in crate::codec) fn of(h: &Header, grid: &Grid) -> Result<Ratios> {
        let mut by_class = vec![None; 1 << grid.dims.len()];
        for m in grid.classes() {
            let plan = Plan::new(&tile_header(h, &grid.class_dims(m)))?;
            let gains = quantize::band_gains(&plan.pyr, &plan.bands);
            let w = channel_weights(h.colour, h.channels);
            let mut r = Vec::new();
            for (_, js) in plan.level_groups() {
                for j in js {
                    for wc in &w {
                        r.push((1.0 / (gains[j] * wc)) as f32);
                    }
                }
            }
            by_class[m] = Some(r);
        }
        Ok(Ratios { by_class })
    }

    /// The `TRAT` payload: the classes' ratios in class order, f32 LE.
    pub(in crate::codec) fn to_bytes(&self) -> Vec<u8> {
        self.by_class
            .iter()
            .flatten()
            .flat_map(|r| r.iter().flat_map(|x| x.to_le_bytes()))
            .collect()
    }

    /// Parse a `TRAT` chunk of a file of header `h` and grid `grid`: the ratios of each
    /// class, as many as its bands and channels, each positive and finite.
    pub(in crate::codec) fn parse(ch: &Chunk, h: &Header, grid: &Grid) -> Result<Ratios> {
        let mut by_class = vec![None; 1 << grid.dims.len()];
        let mut cur = Cursor::new(&ch.payload, "TRAT");
        for m in grid.classes() {
            let plan = Plan::new(&tile_header(h, &grid.class_dims(m)))?;
            let n = plan.bands.len() * h.channels;
            if (ch.payload.len() - cur.pos) < 4 * n {
                return Err(Error::format(
                    format!(
                        "TRAT chunk of {} bytes, short at tile class {m}",
                        ch.payload.len()
                    ),
                    "4 bytes per band and channel of every tile class",
                ));
            }
            let mut r = Vec::with_capacity(n);
            for _ in 0..n {
                let x = cur.f32()?;
                if !(x > 0.0 && x.is_finite()) {
                    return Err(Error::format(
                        format!("TRAT step ratio {x} for tile class {m}"),
                        "positive finite ratios",
                    ));
                }
                r.push(x);
            }
            by_class[m] = Some(r);
        }
        if cur.pos != ch.payload.len() {
            return Err(Error::format(
                format!(
                    "TRAT chunk of {} bytes with {} after the last tile class",
                    ch.payload.len(),
                    ch.payload.len() - cur.pos
                ),
                "4 bytes per band and channel of every tile class",
            ));
        }
        Ok(Ratios { by_class })
    }
}

/// One chunk of a file made by this crate: `(type, payload)` and the rest.
fn split_chunk(b: &[u8]) -> Option<(&[u8], &[u8], &[u8])> {
    let len = u32::from_le_bytes(b.get(..4)?.try_into().ok()?) as usize;
    let kind = b.get(4..8)?;
    let payload = b.get(8..8 + len)?;
    let rest = b.get(8 + len + 4..)?;
    Some((kind, payload, rest))
}

/// The `TILE` payload after the tile index of tile `i` in a 2.2 file of header `h`,
/// from the tile's one-tile file `f` (signature included): the compact form when `f` is
/// `HEAD`, one `LEVL` per level of the tile's pyramid and `MEND`, with the file's
/// fields and the ratios of the tile's class; else the form that holds `f`'s chunks.
pub(in crate::codec) fn tile_body(
    f: &[u8],
    h: &Header,
    grid: &Grid,
    ratios: &Ratios,
    i: usize,
) -> Vec<u8> {
    compact(f, h, grid, ratios, i).unwrap_or_else(|| {
        let mut v = Vec::with_capacity(f.len() - 7);
        v.push(FORM_CHUNKS);
        v.extend_from_slice(&f[8..]);
        v
    })
}

fn compact(f: &[u8], h: &Header, grid: &Grid, ratios: &Ratios, i: usize) -> Option<Vec<u8>> {
    if h.mode != Mode::Lossy {
        return None;
    }
    let (kind, head, mut rest) = split_chunk(f.get(8..)?)?;
    if kind != HEAD {
        return None;
    }
    let t = Header::parse(head).ok()?;
    let mut same = tile_header(h, &grid.tile_dims(i));
    (same.min, same.max) = (t.min, t.max);
    if t != same {
        return None;
    }
    let r = ratios.by_class.get(grid.class(i))?.as_ref()?;
    let plan = Plan::new(&t).ok()?;
    let mut out = vec![FORM_COMPACT];
    out.extend_from_slice(&t.min.to_le_bytes());
    out.extend_from_slice(&t.max.to_le_bytes());
    let mut k = 0;
    for (level, js) in plan.level_groups() {
        let (kind, p, more) = split_chunk(rest)?;
        rest = more;
        let mut cur = Cursor::new(p, "LEVL");
        if kind != LEVL || cur.u16().ok()? as usize != level {
            return None;
        }
        for _ in 0..js.len() * h.channels {
            if cur.f32().ok()?.to_bits() != r.get(k)?.to_bits() {
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
    (kind == MEND && p.is_empty() && rest.is_empty() && k == r.len()).then_some(out)
}

/// Bytes of the compact form of a lossy one-tile file `f` (signature included): the
/// form byte, the range, and each `LEVL` payload less its level and its ratios (for the
/// `--bpp` search, before the file's `HEAD` is known); `f`'s chunks and the form byte
/// when `f` is not `HEAD`, `LEVL`…, `MEND`.
pub(in crate::codec) fn compact_len(f: &[u8]) -> usize {
    let whole = f.len() - 7;
    let Some((kind, _, mut rest)) = split_chunk(&f[8..]) else {
        return whole;
    };
    if kind != HEAD {
        return whole;
    }
    let mut n = 1 + 16;
    while let Some((kind, p, more)) = split_chunk(rest) {
        rest = more;
        if kind == MEND {
            return if rest.is_empty() { n } else { whole };
        }
        if kind != LEVL {
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

/// The one-tile file (signature included) of tile `i` of a tiled file of header `h`
/// from its `TILE` payload after the index: the payload's chunks (2.1, or form 0 of
/// 2.2), or the file a compact payload makes with the ratios of the tile's class.
pub(in crate::codec) fn tile_file<'a>(
    h: &Header,
    grid: &Grid,
    ratios: Option<&Ratios>,
    i: usize,
    inner: &'a [u8],
) -> Result<Cow<'a, [u8]>> {
    let with_signature = |chunks: &[u8]| {
        let mut f = format::SIGNATURE.to_vec();
        f.extend_from_slice(chunks);
        Cow::Owned(f)
    };
    if h.minor < format::MINOR_COMPACT {
        return Ok(with_signature(inner));
    }
    let mut cur = Cursor::new(inner, "TILE");
    match cur.u8()? {
        FORM_CHUNKS => return Ok(with_signature(cur.rest())),
        FORM_COMPACT => {}
        f => {
            return Err(Error::format(
                format!("TILE of tile {i} in form {f}"),
                "form 0 (chunks) or 1 (compact)",
            ))
        }
    }
    let Some(r) = ratios.and_then(|r| r.by_class.get(grid.class(i))?.as_ref()) else {
        return Err(Error::format(
            format!("a compact TILE of tile {i} without the TRAT chunk before it"),
            "TRAT before the tiles of a 2.2 file",
        ));
    };
    if h.mode != Mode::Lossy {
        return Err(Error::format(
            format!("a compact TILE of tile {i} in a file of mode {:?}", h.mode),
            "compact tiles in lossy files only",
        ));
    }
    let mut t = tile_header(h, &grid.tile_dims(i));
    t.min = cur.f64()?;
    t.max = cur.f64()?;
    let plan = Plan::new(&t)?;
    let mut f = format::SIGNATURE.to_vec();
    f.reserve(inner.len() + 256);
    put_chunk(&mut f, HEAD, &t.to_bytes());
    let mut k = 0;
    for (level, js) in plan.level_groups() {
        let mut p = (level as u16).to_le_bytes().to_vec();
        for _ in 0..js.len() * h.channels {
            let len = cur.varint()?;
            let left = (inner.len() - cur.pos) as u64;
            if len > left {
                return Err(Error::format(
                    format!("compact TILE of tile {i}: a stream of {len} bytes, {left} left"),
                    "streams within the chunk",
                ));
            }
            p.extend_from_slice(&r[k].to_le_bytes());
            put_varint(&mut p, len);
            p.extend_from_slice(cur.take(len as usize)?);
            k += 1;
        }
        put_chunk(&mut f, LEVL, &p);
    }
    if cur.pos != inner.len() {
        return Err(Error::format(
            format!(
                "compact TILE of tile {i} with {} bytes after its last stream",
                inner.len() - cur.pos
            ),
            "a payload that ends with its last stream",
        ));
    }
    put_chunk(&mut f, MEND, &[]);
    Ok(Cow::Owned(f))
}
