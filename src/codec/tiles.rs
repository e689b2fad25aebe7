//! Files of more than one tile (format 2.1, formats/MRA.md §14): the raster cut on a
//! grid of tiles of extents `t` (the last tile of an axis shorter), each tile coded on
//! its own as a one-tile file (its own pyramid, levels and bands) at one base step for
//! the whole raster, so every tile gets the same quality.
//!
//! Layout: `HEAD` (the whole raster's extents, the tile extents `t`), `mETA`, `TIDX` (the
//! byte offset and length of each `TILE` chunk), one `TILE` per tile in tile order (its
//! index, then the chunks of the tile's one-tile file after the signature), `MEND`. A
//! reader that can seek reads `HEAD`, `mETA` and `TIDX`, then only the tiles a region
//! meets; a reader that cannot reads the chunks in order.
//!
//! Tiles are coded and decoded in parallel (rayon); each tile's bytes depend on the tile
//! alone, so the file is the same whatever the thread count.

use super::container::read_head;
use super::decode::{coarse_maps_of, decode_untiled};
use super::layout;
use super::options::{DecodeOptions, Decoded, EncodeOptions};
use super::plan::Plan;
#[cfg(doc)]
use super::voids::with_voids_filled;
use crate::format::body::{meta_chunk, truncated};
use crate::format::{Chunk, ChunkReader, Header, Tag};
use crate::io::slab::{MemorySlabs, Shape};
use crate::io::{AxisMap, Metadata, Raster, RasterView, Samples};
use crate::tensor::par::{receive, Feed, Job, StopOnDrop};
use crate::{Error, Result};
use rayon::prelude::*;
use std::io::{Read, Seek};
use std::ops::Range;

/// Most tiles a file may have.
pub const MAX_TILES: u64 = 1 << 24;
/// Rasters of at most this many positions are one tile by default, whatever their
/// channels.
pub const ONE_PIECE_POSITIONS: u64 = 1 << 24;
/// Rasters of at most this many samples (positions × channels) are one tile by default:
/// a 6000² u16 image or a 512×512×256 u16 volume encodes and decodes in one piece (no
/// seams) within about 560 MiB (docs/codec.md, "Code-blocks").
pub const ONE_PIECE_SAMPLES: u64 = 1 << 26;
/// Default tile extent of 1-D and 2-D rasters over [`ONE_PIECE_POSITIONS`].
pub const DEFAULT_TILE_2D: usize = 1024;
/// Default tile extent of 3-D and 4-D rasters over [`ONE_PIECE_POSITIONS`].
pub const DEFAULT_TILE_3D: usize = 128;
/// Tiles sampled by the `--psnr` and `--bpp` searches on rasters of more tiles.
pub const SEARCH_SAMPLE_TILES: usize = 64;

/// The extents of a file's raster at `level`, slowest axis first: what a decode at that
/// level returns without a region (a tiled file's tiles each reduced, then stitched).
pub fn level_extents(h: &Header, level: usize) -> Result<Vec<usize>> {
    Ok(Stitch::geometry(h, level, None)?
        .out
        .iter()
        .map(|g| g.len())
        .collect())
}

/// Default tile extents of a raster of extents `dims` (slowest first) and `channels`
/// channels: one tile up to [`ONE_PIECE_POSITIONS`] positions or
/// [`ONE_PIECE_SAMPLES`] samples, else [`DEFAULT_TILE_2D`] per axis in 1-D and 2-D and
/// [`DEFAULT_TILE_3D`] in 3-D and 4-D (each at most the axis extent).
pub fn default_tile(dims: &[usize], channels: usize) -> Vec<usize> {
    let n = dims
        .iter()
        .try_fold(1u64, |a, &d| a.checked_mul(d as u64))
        .unwrap_or(u64::MAX);
    if n <= ONE_PIECE_POSITIONS || n.saturating_mul(channels.max(1) as u64) <= ONE_PIECE_SAMPLES {
        return dims.to_vec();
    }
    let t = if dims.len() >= 3 {
        DEFAULT_TILE_3D
    } else {
        DEFAULT_TILE_2D
    };
    dims.iter().map(|&d| d.min(t)).collect()
}

/// A grid of tiles: `counts[k] = ⌈dims[k] / tile[k]⌉` tiles on axis k, numbered in
/// row-major order (slowest axis first).
#[derive(Clone, Debug)]
pub(super) struct Grid {
    pub(super) dims: Vec<usize>,
    pub(super) tile: Vec<usize>,
    pub(super) counts: Vec<usize>,
}

impl Grid {
    pub(super) fn new(dims: &[usize], tile: &[usize]) -> Result<Grid> {
        if tile.len() != dims.len() || tile.iter().zip(dims).any(|(&t, &d)| t == 0 || t > d) {
            return Err(Error::parameter(
                "tile",
                format!("{tile:?} for extents {dims:?}"),
                "one extent per axis, each from 1 to the axis extent",
            ));
        }
        let counts: Vec<usize> = dims
            .iter()
            .zip(tile)
            .map(|(&d, &t)| d.div_ceil(t))
            .collect();
        let n = counts
            .iter()
            .try_fold(1u64, |a, &c| a.checked_mul(c as u64))
            .unwrap_or(u64::MAX);
        if n > MAX_TILES {
            return Err(Error::LimitsExceeded {
                what: "tile count",
                requested: n,
                limit: MAX_TILES,
            });
        }
        Ok(Grid {
            dims: dims.to_vec(),
            tile: tile.to_vec(),
            counts,
        })
    }

    pub(super) fn len(&self) -> usize {
        self.counts.iter().product()
    }

    /// The grid coordinates of tile `i`, slowest axis first.
    pub(super) fn coords(&self, mut i: usize) -> Vec<usize> {
        let mut c = vec![0; self.counts.len()];
        for a in (0..c.len()).rev() {
            c[a] = i % self.counts[a];
            i /= self.counts[a];
        }
        c
    }

    /// Extent on axis `a` of the tiles at grid coordinate `i`.
    pub(super) fn extent(&self, a: usize, i: usize) -> usize {
        self.tile[a].min(self.dims[a] - i * self.tile[a])
    }

    /// The samples of tile `i`, a range per axis.
    pub(super) fn ranges(&self, i: usize) -> Vec<Range<usize>> {
        self.coords(i)
            .iter()
            .enumerate()
            .map(|(a, &c)| c * self.tile[a]..c * self.tile[a] + self.extent(a, c))
            .collect()
    }

    /// The extents of tile `i`.
    pub(super) fn tile_dims(&self, i: usize) -> Vec<usize> {
        self.ranges(i).iter().map(|r| r.len()).collect()
    }
}

macro_rules! map_samples {
    ($s:expr, $v:ident => $body:expr) => {
        match $s {
            Samples::U8($v) => Samples::U8($body),
            Samples::I8($v) => Samples::I8($body),
            Samples::U16($v) => Samples::U16($body),
            Samples::I16($v) => Samples::I16($body),
            Samples::U32($v) => Samples::U32($body),
            Samples::I32($v) => Samples::I32($body),
            Samples::F16($v) => Samples::F16($body),
            Samples::F32($v) => Samples::F32($body),
            Samples::F64($v) => Samples::F64($body),
        }
    };
}

/// The extents and block of samples over `dims` × `channels` as [`layout::rows`] walks
/// them with the longest runs: the channels folded into the fastest spatial axis, and
/// every axis the block covers whole folded into the next slower one (a run per row of
/// the block, not per sample).
fn runs(
    dims: &[usize],
    channels: usize,
    ranges: &[Range<usize>],
) -> (Vec<usize>, Vec<Range<usize>>) {
    let mut shape = dims.to_vec();
    let mut r = ranges.to_vec();
    let last = shape.len() - 1;
    shape[last] *= channels;
    r[last] = r[last].start * channels..r[last].end * channels;
    while shape.len() > 1 {
        let k = shape.len() - 1;
        if r[k].start != 0 || r[k].end != shape[k] {
            break;
        }
        let e = shape.pop().expect("more than one axis");
        r.pop();
        shape[k - 1] *= e;
        r[k - 1] = r[k - 1].start * e..r[k - 1].end * e;
    }
    (shape, r)
}

/// The block `ranges` (one per spatial axis) of samples over `dims` × `channels`.
fn crop_samples(s: &Samples, dims: &[usize], channels: usize, ranges: &[Range<usize>]) -> Samples {
    let (shape, r) = runs(dims, channels, ranges);
    map_samples!(s, v => layout::gather(v, &shape, &r))
}

/// Copy the block `from` of `src` (extents `sdims` × channels) into the block `to` of
/// `dst` (extents `ddims` × channels); both blocks have the same extents.
fn copy_block(
    dst: &mut Samples,
    ddims: &[usize],
    to: &[Range<usize>],
    src: &Samples,
    sdims: &[usize],
    from: &[Range<usize>],
    channels: usize,
) -> Result<()> {
    // a whole tile (the usual case) is scattered as it is, without a packed copy
    let whole = from
        .iter()
        .zip(sdims)
        .all(|(g, &d)| g.start == 0 && g.end == d);
    let packed = if whole {
        std::borrow::Cow::Borrowed(src)
    } else {
        std::borrow::Cow::Owned(crop_samples(src, sdims, channels, from))
    };
    let (shape, r) = runs(ddims, channels, to);
    macro_rules! pair {
        ($($var:ident),*) => {
            match (dst, &*packed) {
                $((Samples::$var(d), Samples::$var(p)) => layout::scatter(d, &shape, &r, p),)*
                (_, p) => {
                    return Err(Error::format(
                        format!("a tile of {} samples", p.sample_type().name()),
                        "tiles of the file's sample type",
                    ))
                }
            }
        };
    }
    pair!(U8, I8, U16, I16, U32, I32, F16, F32, F64);
    Ok(())
}

/// The block `ranges` (one per spatial axis, slowest first) of a raster, its metadata
/// moved to the block's first sample.
pub(super) fn crop_raster(r: &Raster, ranges: &[Range<usize>]) -> Result<Raster> {
    if ranges
        .iter()
        .zip(&r.dims)
        .all(|(g, &d)| g.start == 0 && g.end == d)
    {
        return Ok(r.clone());
    }
    let dims: Vec<usize> = ranges.iter().map(|g| g.len()).collect();
    let samples = crop_samples(&r.samples, &r.dims, r.channels, ranges);
    let mut out = Raster::new(dims.clone(), r.channels, samples, r.kind)?;
    let maps: Vec<AxisMap> = ranges.iter().map(|g| AxisMap::crop(g.start)).collect();
    out.meta = r.meta.resampled(&r.dims, &dims, &maps);
    Ok(out)
}

// ---------------------------------------------------------------- encoding

mod compact;
mod encode;
mod index;
use compact::{tile_file, Ratios};
pub(crate) use encode::encode_slabs;
pub(super) use encode::{first_pass, sampled_keep_step, search};
pub(super) use index::read_tiled_info;
use index::{check_end, fetch_tile, parse_index, read_index, tile_payload};

/// Encode a raster as tiles of extents `tile` (slowest first), as [`encode_slabs`]
/// does from a raster in memory. Each tile's voids are filled in the tile
/// ([`with_voids_filled`]) and listed in the tile's own `mETA`, with the raster's
/// no-data value, so that the tile's decode marks them again.
pub(super) fn encode_tiled(
    r: &RasterView<'_>,
    opts: &EncodeOptions,
    tile: &[usize],
) -> Result<Vec<u8>> {
    let mut out = std::io::Cursor::new(Vec::new());
    encode_slabs(&mut MemorySlabs::of_view(*r), opts, tile, &mut out)?;
    Ok(out.into_inner())
}

// ---------------------------------------------------------------- decoding

/// Where each tile's samples go in the output of a decode at level `k`: per axis, the
/// level-k offset of each tile (prefix sums of the tiles' level-k extents), and the
/// output box.
pub(super) struct Stitch {
    grid: Grid,
    level: usize,
    header: Header,
    /// Per axis: level-k start of each tile along it, then the axis' level-k extent.
    offs: Vec<Vec<usize>>,
    /// Output box in level-k coordinates, slowest axis first.
    out: Vec<Range<usize>>,
    samples: Samples,
    /// The step ratios of compact tiles (2.2), once `TRAT` is read.
    ratios: Option<std::sync::Arc<Ratios>>,
}

impl Stitch {
    pub(super) fn new(h: &Header, level: usize, region: Option<&[Range<usize>]>) -> Result<Stitch> {
        let mut st = Stitch::geometry(h, level, region)?;
        st.alloc()?;
        Ok(st)
    }

    /// Zero samples for the output box.
    fn alloc(&mut self) -> Result<()> {
        let n = crate::io::bytes::sample_count(
            &self.out.iter().map(|g| g.len()).collect::<Vec<_>>(),
            self.header.channels,
        )?;
        crate::limits::check_elems(
            "decoded bytes (memory budget MRA_MAX_BYTES)",
            n as u64,
            self.header.sample_type.size() as u64,
        )?;
        self.samples = Samples::zeros(self.header.sample_type, n);
        Ok(())
    }

    /// The places of the tiles and the output box, without the output's samples.
    fn geometry(h: &Header, level: usize, region: Option<&[Range<usize>]>) -> Result<Stitch> {
        let grid = Grid::new(&h.dims, &h.tile)?;
        let nd = h.dims.len();
        // the level-k extent of a tile depends on its extent along each axis alone
        let full_tile = grid.tile.clone();
        let mut cache: Vec<(usize, usize, usize)> = Vec::new();
        let mut extent_at = |a: usize, e: usize| -> Result<usize> {
            if let Some(&(_, _, r)) = cache.iter().find(|c| c.0 == a && c.1 == e) {
                return Ok(r);
            }
            let mut th = h.clone();
            th.dims = full_tile.clone();
            th.dims[a] = e;
            th.tile = th.dims.clone();
            let r = Plan::new(&th)?.region(level)[a];
            cache.push((a, e, r));
            Ok(r)
        };
        let mut offs = Vec::with_capacity(nd);
        for a in 0..nd {
            let mut o = vec![0usize];
            for i in 0..grid.counts[a] {
                let e = extent_at(a, grid.extent(a, i))?;
                o.push(o[i] + e);
            }
            offs.push(o);
        }
        let out: Vec<Range<usize>> = match region {
            None => offs.iter().map(|o| 0..*o.last().unwrap()).collect(),
            Some(reg) => {
                if reg.len() != nd {
                    return Err(Error::parameter(
                        "region",
                        format!("{} ranges", reg.len()),
                        "one range per spatial axis",
                    ));
                }
                (0..nd)
                    .map(|a| {
                        // slowest first, in the option as here
                        let g = &reg[a];
                        let d = h.dims[a];
                        if g.start >= g.end || g.end > d {
                            return Err(Error::parameter(
                                "region",
                                format!("{}..{} on an axis of {d}", g.start, g.end),
                                "a non-empty range within the axis",
                            ));
                        }
                        let r = *offs[a].last().unwrap() as u128;
                        let lo = (g.start as u128 * r / d as u128) as usize;
                        let hi = ((g.end as u128 * r).div_ceil(d as u128) as usize)
                            .clamp(lo + 1, r as usize);
                        Ok(lo..hi)
                    })
                    .collect::<Result<_>>()?
            }
        };
        crate::io::bytes::sample_count(
            &out.iter().map(|g| g.len()).collect::<Vec<_>>(),
            h.channels,
        )?;
        Ok(Stitch {
            samples: Samples::zeros(h.sample_type, 0),
            grid,
            level,
            header: h.clone(),
            offs,
            out,
            ratios: None,
        })
    }

    /// The output box, level-k coordinates, slowest axis first.
    pub(super) fn out_box(&self) -> &[Range<usize>] {
        &self.out
    }

    pub(super) fn tiles(&self) -> usize {
        self.grid.len()
    }

    /// Tile `i`'s level-k box (global level-k coordinates).
    fn tile_box(&self, i: usize) -> Vec<Range<usize>> {
        self.grid
            .coords(i)
            .iter()
            .enumerate()
            .map(|(a, &c)| self.offs[a][c]..self.offs[a][c + 1])
            .collect()
    }

    /// Whether tile `i` meets the output box.
    pub(super) fn wanted(&self, i: usize) -> bool {
        self.tile_box(i)
            .iter()
            .zip(&self.out)
            .all(|(t, o)| t.start < o.end && o.start < t.end)
    }

    /// Decode the one-tile file of tile `i` (the `TILE` payload after its index) and
    /// check it against the file's header.
    pub(super) fn decode_tile(
        &self,
        i: usize,
        inner: &[u8],
        allow_truncated: bool,
    ) -> Result<Decoded> {
        let f = tile_file(&self.header, &self.grid, self.ratios.as_deref(), i, inner)?;
        let d = decode_untiled(
            &f[..],
            f.len() as u64,
            &DecodeOptions {
                level: self.level,
                allow_truncated,
                region: None,
            },
        )
        .map_err(|e| Error::format(format!("tile {i}: {e}"), "a valid tile"))?;
        let (h, t) = (&self.header, &d.header);
        let want = self.grid.tile_dims(i);
        if t.version.major != h.version.major
            || t.sample_type != h.sample_type
            || t.channels != h.channels
            || t.colour != h.colour
            || t.mode != h.mode
            || t.scheme != h.scheme
            || t.boundary != h.boundary
            || t.levels != h.levels
            || t.dims != want
        {
            return Err(Error::format(
                format!(
                    "tile {i} of extents {:?}, {} {:?} {:?}",
                    t.dims,
                    t.sample_type.name(),
                    t.mode,
                    t.scheme
                ),
                "tiles of the grid's extents with the file's type, mode and scheme",
            ));
        }
        let b = self.tile_box(i);
        let got: Vec<usize> = b.iter().map(|g| g.len()).collect();
        if d.raster.dims != got {
            return Err(Error::format(
                format!("tile {i} decoding to extents {:?}", d.raster.dims),
                "the tile's extents at the level decoded",
            ));
        }
        Ok(d)
    }

    /// Copy the part of tile `i`'s decoded samples `r` that falls in the output box into
    /// `samples` (the output's samples, taken out of the stitch so that the tiles decoded
    /// in parallel can share them under a lock while the stitch is read).
    fn place(&self, samples: &mut Samples, i: usize, r: &Raster) -> Result<()> {
        let b = self.tile_box(i);
        let mut from = Vec::with_capacity(b.len());
        let mut to = Vec::with_capacity(b.len());
        for (t, o) in b.iter().zip(&self.out) {
            let (lo, hi) = (t.start.max(o.start), t.end.min(o.end));
            if lo >= hi {
                return Ok(());
            }
            from.push(lo - t.start..hi - t.start);
            to.push(lo - o.start..hi - o.start);
        }
        let dims: Vec<usize> = self.out.iter().map(|g| g.len()).collect();
        copy_block(
            samples,
            &dims,
            &to,
            &r.samples,
            &r.dims,
            &from,
            self.header.channels,
        )
    }

    /// The output raster with the file's metadata moved to it.
    pub(super) fn finish(self, meta: &Metadata) -> Result<Raster> {
        let m = self.out_meta(meta)?;
        let h = &self.header;
        let dims: Vec<usize> = self.out.iter().map(|g| g.len()).collect();
        let mut r = Raster::new(dims, h.channels, self.samples, h.kind)?;
        r.meta = m;
        Ok(r)
    }

    /// The output's shape: the output box's extents, the file's metadata moved to it.
    fn out_shape(&self, meta: &Metadata) -> Result<Shape> {
        let h = &self.header;
        Ok(Shape {
            dims: self.out.iter().map(|g| g.len()).collect(),
            channels: h.channels,
            sample_type: h.sample_type,
            kind: h.kind,
            meta: self.out_meta(meta)?,
        })
    }

    /// The rows of the output that grid row `g0` (along the slowest axis) covers, as a
    /// stitch of their own with zero samples; `None` when the row is outside the box.
    fn row_slab(&self, g0: usize) -> Result<Option<Stitch>> {
        let (lo, hi) = (
            self.offs[0][g0].max(self.out[0].start),
            self.offs[0][g0 + 1].min(self.out[0].end),
        );
        if lo >= hi {
            return Ok(None);
        }
        let mut out = self.out.clone();
        out[0] = lo..hi;
        let mut st = Stitch {
            grid: self.grid.clone(),
            level: self.level,
            header: self.header.clone(),
            offs: self.offs.clone(),
            out,
            samples: Samples::zeros(self.header.sample_type, 0),
            ratios: self.ratios.clone(),
        };
        st.alloc()?;
        Ok(Some(st))
    }

    /// The file's metadata moved to the output box.
    fn out_meta(&self, meta: &Metadata) -> Result<Metadata> {
        let h = &self.header;
        let dims: Vec<usize> = self.out.iter().map(|g| g.len()).collect();
        // a full tile's pyramid places the coarse samples as the whole raster's would
        let mut th = h.clone();
        th.dims = self.grid.tile.clone();
        th.tile = th.dims.clone();
        let plan = Plan::new(&th)?;
        let maps: Vec<AxisMap> = coarse_maps_of(&th, &plan, self.level)
            .into_iter()
            .zip(&self.out)
            .map(|(m, g)| m.then(AxisMap::crop(g.start)))
            .collect();
        // voids were marked in each tile's decode
        Ok(meta.resampled(&h.dims, &dims, &maps))
    }
}

/// Decode tiles `(i, payload after the index)` in parallel and place them, each as
/// soon as it is decoded (the output's samples shared under a lock), so that memory
/// holds the tiles in flight, not the batch decoded.
fn decode_batch(
    st: &mut Stitch,
    batch: &mut Vec<(usize, Vec<u8>)>,
    allow_truncated: bool,
    complete: &mut bool,
) -> Result<()> {
    let empty = Samples::zeros(st.header.sample_type, 0);
    let samples = std::sync::Mutex::new(std::mem::replace(&mut st.samples, empty));
    let shared = &*st;
    let placed: Vec<Result<bool>> = batch
        .par_iter()
        .map(|(i, inner)| {
            let d = shared.decode_tile(*i, inner, allow_truncated)?;
            let mut s = samples.lock().unwrap_or_else(|e| e.into_inner());
            shared.place(&mut s, *i, &d.raster)?;
            Ok(d.complete)
        })
        .collect();
    st.samples = samples.into_inner().unwrap_or_else(|e| e.into_inner());
    for p in placed {
        *complete &= p?;
    }
    batch.clear();
    Ok(())
}

/// Tiles fetched before they are decoded together: enough to keep every thread busy
/// (each is placed as soon as it is decoded, so this bounds the coded bytes held).
fn batch_size() -> usize {
    8 * rayon::current_num_threads()
}

/// Decode a tiled file read in order (no seeking): the tiles the region meets decoded in
/// batches as they come.
pub(super) fn decode_sequential<R: Read>(
    mut rd: ChunkReader<R>,
    header: Header,
    opts: &DecodeOptions,
) -> Result<Decoded> {
    let len = rd.total();
    let mut st = Stitch::new(&header, opts.level, opts.region.as_deref())?;
    let n = st.tiles();
    let mut meta = Metadata::default();
    let mut seen = vec![false; n];
    let mut index_seen = false;
    let (mut meta_seen, mut first_data) = (false, None);
    let mut batch = Vec::new();
    let mut complete = true;
    let mut last = "HEAD".to_string();
    let mut ended = false;
    loop {
        let ch = match rd.next_chunk()? {
            Ok(c) => c,
            Err(end) => {
                if !opts.allow_truncated {
                    return Err(truncated(end, &last, len));
                }
                break;
            }
        };
        last = ch.name();
        let tag = ch.tag();
        if matches!(tag, Some(Tag::Trat | Tag::Tidx | Tag::Tile)) && first_data.is_none() {
            first_data = Some(ch.offset);
        }
        match tag {
            Some(Tag::Meta) => meta = meta_chunk(&ch, &mut meta_seen, first_data)?,
            Some(Tag::Trat) if header.version.has_compact_tiles() && !index_seen => {
                let g = Grid::new(&header.dims, &header.tile)?;
                st.ratios = Some(std::sync::Arc::new(Ratios::parse(&ch, &header, &g)?));
            }
            Some(Tag::Tidx) => {
                if index_seen {
                    return Err(crate::FormatError::duplicate(
                        "a second TIDX chunk",
                        "one TIDX chunk",
                    ));
                }
                parse_index(&ch, n, len)?;
                index_seen = true;
            }
            Some(Tag::Tile) => {
                let (i, inner) = tile_in_order(&ch, index_seen, &mut seen)?;
                if st.wanted(i) {
                    batch.push((i, inner.to_vec()));
                    if batch.len() >= batch_size() {
                        decode_batch(&mut st, &mut batch, opts.allow_truncated, &mut complete)?;
                    }
                }
            }
            Some(Tag::Mend) => {
                ended = true;
                break;
            }
            Some(Tag::Head) => {
                return Err(crate::FormatError::duplicate(
                    "a second HEAD chunk",
                    "one HEAD chunk",
                ))
            }
            _ => {
                if Tag::is_critical(&ch.kind) {
                    return Err(crate::FormatError::UnknownChunk(ch.name()).into());
                }
            }
        }
    }
    decode_batch(&mut st, &mut batch, opts.allow_truncated, &mut complete)?;
    complete &= every_tile(&seen, ended, opts.allow_truncated)? && ended;
    let raster = st.finish(&meta)?;
    Ok(Decoded {
        raster,
        header,
        complete,
    })
}

/// The tile number and payload of the `TILE` chunk `ch` read in order, marked in `seen`
/// (one flag a tile of the grid); an error when the index has not come yet or the tile
/// came before.
fn tile_in_order<'c>(
    ch: &'c Chunk,
    index_seen: bool,
    seen: &mut [bool],
) -> Result<(usize, &'c [u8])> {
    if !index_seen {
        return Err(crate::FormatError::order(
            format!("TILE chunk at byte {} before the TIDX chunk", ch.offset),
            "TIDX before the tiles",
        ));
    }
    let (i, inner) = tile_payload(ch, seen.len())?;
    if std::mem::replace(&mut seen[i], true) {
        return Err(crate::FormatError::duplicate(
            format!("a second TILE chunk for tile {i} (byte {})", ch.offset),
            "each tile once",
        ));
    }
    Ok((i, inner))
}

/// Whether every tile was `seen`; a missing tile is an error unless `allow_truncated`
/// (`ended`: the file reached `MEND`).
fn every_tile(seen: &[bool], ended: bool, allow_truncated: bool) -> Result<bool> {
    match seen.iter().position(|&s| !s) {
        None => Ok(true),
        Some(_) if allow_truncated => Ok(false),
        Some(i) => Err(crate::FormatError::missing(
            format!(
                "TILE chunk of tile {i} missing ({})",
                if ended { "MEND reached" } else { "file ends" }
            ),
            "every tile of the grid (or --allow-truncated)",
        )),
    }
}

/// Decode a tiled file from a seekable stream of `len` bytes whose `HEAD` has been read
/// (ending at byte `after_head`): `mETA` and `TIDX` read in order, then only the tiles
/// the region meets, each found by the index.
pub(super) fn decode_seek<R: Read + Seek>(
    src: &mut R,
    len: u64,
    after_head: u64,
    header: Header,
    opts: &DecodeOptions,
) -> Result<Decoded> {
    let mut st = Stitch::new(&header, opts.level, opts.region.as_deref())?;
    let n = st.tiles();
    let (meta, index, ratios) = read_index(src, len, after_head, &st)?;
    st.ratios = ratios;
    let mut complete = true;
    let mut batch = Vec::new();
    for (i, &e) in index.iter().enumerate() {
        if !st.wanted(i) {
            continue;
        }
        match fetch_tile(src, len, n, i, e, opts.allow_truncated)? {
            Some(t) => batch.push((i, t)),
            None => complete = false,
        }
        if batch.len() >= batch_size() {
            decode_batch(&mut st, &mut batch, opts.allow_truncated, &mut complete)?;
        }
    }
    decode_batch(&mut st, &mut batch, opts.allow_truncated, &mut complete)?;
    if opts.region.is_none() {
        complete &= check_end(src, len, after_head, &index, opts.allow_truncated)?;
    }
    let raster = st.finish(&meta)?;
    Ok(Decoded {
        raster,
        header,
        complete,
    })
}

/// A grid row's decode handed to the thread pool: its samples and completeness.
type RowResult = Result<(Samples, bool)>;

/// A grid row to decode: its stitch and its tiles' payloads.
type RowTiles = (Stitch, Vec<(usize, Vec<u8>)>);

/// A grid row being decoded in the pool, one job per tile: each tile places its samples
/// as soon as it is decoded, and the last tile to finish sends the row.
struct RowJob {
    /// The row's geometry (its samples are in `samples`).
    st: Stitch,
    samples: std::sync::Mutex<Samples>,
    /// Tiles not yet placed.
    left: std::sync::atomic::AtomicUsize,
    /// Whether every tile decoded so far was complete, and the failure of the first tile
    /// (in tile order) that failed.
    state: std::sync::Mutex<(bool, Option<(usize, Error)>)>,
    tx: std::sync::mpsc::SyncSender<RowResult>,
}

impl RowJob {
    /// Decode and place tile `i`; the last tile sends the row.
    fn tile(&self, i: usize, inner: &[u8], allow_truncated: bool) {
        let r = self
            .st
            .decode_tile(i, inner, allow_truncated)
            .and_then(|d| {
                let mut s = self.samples.lock().unwrap_or_else(|e| e.into_inner());
                self.st.place(&mut s, i, &d.raster)?;
                Ok(d.complete)
            });
        {
            let mut g = self.state.lock().unwrap_or_else(|e| e.into_inner());
            match r {
                Ok(c) => g.0 &= c,
                Err(e) => {
                    if g.1.as_ref().is_none_or(|(j, _)| i < *j) {
                        g.1 = Some((i, e));
                    }
                }
            }
        }
        if self.left.fetch_sub(1, std::sync::atomic::Ordering::AcqRel) == 1 {
            self.send();
        }
    }

    /// Send the row (or the first failure) to the caller.
    fn send(&self) {
        let empty = Samples::zeros(self.st.header.sample_type, 0);
        let samples = std::mem::replace(
            &mut *self.samples.lock().unwrap_or_else(|e| e.into_inner()),
            empty,
        );
        let mut g = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let r = match g.1.take() {
            Some((_, e)) => Err(e),
            None => Ok((samples, g.0)),
        };
        // the receiver is gone when the caller stopped early
        let _ = self.tx.send(r);
    }
}

/// [`decode_seek`] one tile-row (2-D) or tile-slab (3-D) at a time, so that memory
/// holds a few rows of tiles, not the output: the output's shape first, then its rows
/// in order ([`TiledSlabs::next_slab`]).
///
/// With more than one thread the rows are pipelined, one pool job per tile: when the
/// caller asks for row `g`, the tiles of row `g + 1` are read (on the caller's thread,
/// while the pool decodes row `g`) and queued behind row `g`'s, so that the pool goes
/// from the last tiles of one row to the next row without waiting, and decodes row
/// `g + 1` while the caller writes row `g`. Memory holds two rows: the one written
/// and the one decoded (the next is queued when the caller has let go of the one it
/// wrote). With one thread every row is decoded when asked for, so that one thread is
/// one busy core.
pub(super) struct TiledSlabs<R> {
    src: R,
    len: u64,
    after_head: u64,
    st: Stitch,
    index: Vec<(u64, u64)>,
    shape: Shape,
    opts: DecodeOptions,
    /// The next grid row along the slowest axis.
    g0: usize,
    /// The rows queued in the pool, in order.
    pending: std::collections::VecDeque<std::sync::mpsc::Receiver<RowResult>>,
    complete: bool,
    ended: bool,
    /// The tiles queued for the pool (dropped with the decoder).
    feed: std::sync::Arc<Feed>,
    _stop: StopOnDrop,
}

impl<R: Read + Seek> TiledSlabs<R> {
    /// Read `mETA` and `TIDX` of a tiled file whose `HEAD` ends at byte `after_head`.
    pub(super) fn new(
        mut src: R,
        len: u64,
        after_head: u64,
        header: Header,
        opts: &DecodeOptions,
    ) -> Result<Self> {
        let mut st = Stitch::geometry(&header, opts.level, opts.region.as_deref())?;
        let (meta, index, ratios) = read_index(&mut src, len, after_head, &st)?;
        st.ratios = ratios;
        let shape = st.out_shape(&meta)?;
        let feed = Feed::new();
        Ok(TiledSlabs {
            src,
            len,
            after_head,
            st,
            index,
            shape,
            opts: opts.clone(),
            g0: 0,
            pending: std::collections::VecDeque::new(),
            complete: true,
            ended: false,
            _stop: feed.stop_on_drop(),
            feed,
        })
    }

    /// The output's extents, type and metadata.
    pub(super) fn shape(&self) -> &Shape {
        &self.shape
    }

    /// Whether every tile read was complete (known after the last slab).
    pub(super) fn complete(&self) -> bool {
        self.complete
    }

    /// The next grid row that meets the output box: its stitch and its tiles' payloads
    /// (read now), `None` after the last.
    fn fetch_row(&mut self) -> Result<Option<RowTiles>> {
        let n = self.st.tiles();
        let rows = self.st.grid.counts[0];
        let per_row = n / rows;
        while self.g0 < rows {
            let g0 = self.g0;
            self.g0 += 1;
            let Some(row) = self.st.row_slab(g0)? else {
                continue;
            };
            let mut batch = Vec::new();
            for i in g0 * per_row..(g0 + 1) * per_row {
                if !row.wanted(i) {
                    continue;
                }
                let allow = self.opts.allow_truncated;
                match fetch_tile(&mut self.src, self.len, n, i, self.index[i], allow)? {
                    Some(t) => batch.push((i, t)),
                    None => self.complete = false,
                }
            }
            return Ok(Some((row, batch)));
        }
        Ok(None)
    }

    /// Read the next row's tiles and queue their decode in the pool, a job per tile.
    fn launch(&mut self) -> Result<()> {
        let Some((mut row, batch)) = self.fetch_row()? else {
            return Ok(());
        };
        let allow = self.opts.allow_truncated;
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        let samples =
            std::mem::replace(&mut row.samples, Samples::zeros(row.header.sample_type, 0));
        let job = std::sync::Arc::new(RowJob {
            st: row,
            samples: std::sync::Mutex::new(samples),
            left: std::sync::atomic::AtomicUsize::new(batch.len()),
            state: std::sync::Mutex::new((true, None)),
            tx,
        });
        if batch.is_empty() {
            job.send();
        }
        self.feed.push(batch.into_iter().map(|(i, inner)| {
            let job = job.clone();
            Box::new(move || job.tile(i, &inner, allow)) as Job
        }));
        self.pending.push_back(rx);
        Ok(())
    }

    /// The next rows of the output (those of one grid row), `None` after the last.
    pub(super) fn next_slab(&mut self) -> Result<Option<Samples>> {
        if rayon::current_num_threads() > 1 {
            if self.g0 == 0 {
                self.launch()?;
            }
            // the next row is read and queued while this one is decoded
            self.launch()?;
            if let Some(rx) = self.pending.pop_front() {
                let (samples, complete) = receive(&rx).ok_or_else(|| {
                    Error::Io(std::io::Error::other("a tile row's decoder stopped"))
                })??;
                self.complete &= complete;
                return Ok(Some(samples));
            }
        } else if let Some((mut row, mut batch)) = self.fetch_row()? {
            let allow = self.opts.allow_truncated;
            decode_batch(&mut row, &mut batch, allow, &mut self.complete)?;
            return Ok(Some(row.samples));
        }
        if !self.ended {
            self.ended = true;
            if self.opts.region.is_none() {
                self.complete &= check_end(
                    &mut self.src,
                    self.len,
                    self.after_head,
                    &self.index,
                    self.opts.allow_truncated,
                )?;
            }
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The samples of `block` of a raster `dims` × `c` counted out one sample at a time.
    fn by_hand(v: &[u32], dims: &[usize], c: usize, block: &[Range<usize>]) -> Vec<u32> {
        let mut out = Vec::new();
        let n: usize = block.iter().map(|g| g.len()).product();
        for k in 0..n {
            // the k-th position of the block, slowest axis first
            let (mut rest, mut flat) = (k, 0);
            let mut idx = vec![0; dims.len()];
            for a in (0..dims.len()).rev() {
                idx[a] = block[a].start + rest % block[a].len();
                rest /= block[a].len();
            }
            for a in 0..dims.len() {
                flat = flat * dims[a] + idx[a];
            }
            out.extend((0..c).map(|ch| v[flat * c + ch]));
        }
        out
    }

    /// Extents, channels and a block.
    type Case = (&'static [usize], usize, Vec<Range<usize>>);

    #[test]
    fn blocks_cut_and_placed_in_long_runs_hold_the_samples_counted_one_by_one() {
        let cases: [Case; 6] = [
            (&[6, 7], 1, vec![0..6, 0..7]),
            (&[6, 7], 3, vec![2..5, 0..7]),
            (&[6, 7], 3, vec![0..6, 3..4]),
            (&[4, 5, 6], 1, vec![1..3, 0..5, 0..6]),
            (&[4, 5, 6], 2, vec![0..4, 2..5, 1..6]),
            (&[4, 5, 6], 1, vec![3..4, 4..5, 5..6]),
        ];
        for (dims, c, block) in cases {
            let n = dims.iter().product::<usize>() * c;
            let v: Vec<u32> = (0..n as u32).map(|x| x * 7 + 1).collect();
            let want = by_hand(&v, dims, c, &block);
            let got = crop_samples(&Samples::U32(v.clone()), dims, c, &block);
            assert_eq!(got, Samples::U32(want.clone()), "{dims:?} {c} {block:?}");
            // placed back into zeros: the block's samples where they were, zeros elsewhere
            let bdims: Vec<usize> = block.iter().map(|g| g.len()).collect();
            let whole: Vec<Range<usize>> = bdims.iter().map(|&d| 0..d).collect();
            let mut dst = Samples::U32(vec![0; n]);
            copy_block(&mut dst, dims, &block, &got, &bdims, &whole, c).unwrap();
            let back = crop_samples(&dst, dims, c, &block);
            assert_eq!(back, Samples::U32(want), "{dims:?} {c} {block:?}");
            let Samples::U32(d) = &dst else {
                unreachable!()
            };
            let placed = d.iter().filter(|&&x| x != 0).count();
            assert_eq!(
                placed,
                bdims.iter().product::<usize>() * c,
                "{dims:?} {block:?}"
            );
        }
    }
}
