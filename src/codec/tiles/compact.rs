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
use crate::codec::plan::Plan;
use crate::format::tiles::{self as grammar, TileForm};
use crate::format::{self, Chunk, Header, Mode};
use crate::quantize;
use crate::Result;
use std::borrow::Cow;

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
    t.version = format::Version::of_compact_tile();
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
        grammar::ratios_payload(&self.by_class)
    }

    /// Parse a `TRAT` chunk of a file of header `h` and grid `grid`: the ratios of each
    /// class, as many as its bands and channels, each positive and finite.
    pub(in crate::codec) fn parse(ch: &Chunk, h: &Header, grid: &Grid) -> Result<Ratios> {
        let mut classes = Vec::new();
        for m in grid.classes() {
            let plan = Plan::new(&tile_header(h, &grid.class_dims(m)))?;
            classes.push((m, plan.bands.len() * h.channels));
        }
        let by_class = grammar::parse_ratios(&ch.payload, &classes, 1 << grid.dims.len())?;
        Ok(Ratios { by_class })
    }
}

/// The streams of each level of a plan's one-tile file of `channels` channels:
/// `(level, bands of the level × channels)` in file order.
fn level_streams(plan: &Plan, channels: usize) -> Vec<(usize, usize)> {
    plan.level_groups()
        .into_iter()
        .map(|(l, js)| (l, js.len() * channels))
        .collect()
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
    compact(f, h, grid, ratios, i).unwrap_or_else(|| grammar::chunks_body(f))
}

fn compact(f: &[u8], h: &Header, grid: &Grid, ratios: &Ratios, i: usize) -> Option<Vec<u8>> {
    if h.mode != Mode::Lossy {
        return None;
    }
    let same = tile_header(h, &grid.tile_dims(i));
    let r = ratios.by_class.get(grid.class(i))?.as_ref()?;
    let plan = Plan::new(&same).ok()?;
    grammar::compact_body(f, &same, &level_streams(&plan, h.channels), r)
}

/// Bytes of the compact form of a lossy one-tile file `f` (signature included), as
/// [`grammar::compact_len`] counts them.
pub(in crate::codec) fn compact_len(f: &[u8]) -> usize {
    grammar::compact_len(f)
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
    let (min, max, streams) = match TileForm::parse(inner, h.version.has_compact_tiles(), i)? {
        TileForm::Chunks(chunks) => return Ok(Cow::Owned(grammar::chunks_file(chunks))),
        TileForm::Compact { min, max, streams } => (min, max, streams),
    };
    let Some(r) = ratios.and_then(|r| r.by_class.get(grid.class(i))?.as_ref()) else {
        return Err(crate::FormatError::order(
            format!("a compact TILE of tile {i} without the TRAT chunk before it"),
            "TRAT before the tiles of a 2.2 file",
        ));
    };
    if h.mode != Mode::Lossy {
        return Err(crate::FormatError::invalid(
            format!("a compact TILE of tile {i} in a file of mode {:?}", h.mode),
            "compact tiles in lossy files only",
        ));
    }
    let mut t = tile_header(h, &grid.tile_dims(i));
    (t.min, t.max) = (min, max);
    let plan = Plan::new(&t)?;
    let f = grammar::compact_file(&t, &level_streams(&plan, h.channels), r, streams, i)?;
    Ok(Cow::Owned(f))
}
