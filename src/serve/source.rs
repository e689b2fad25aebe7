//! A served file: its header, its levels' extents, the plane an image request reads (a
//! 2-D raster, or a slice of a volume), and windows of one level: a tiled file's from the
//! tiles the window meets, each decoded at the level and kept in the cache; a file of one
//! tile's from the whole level, decoded once and kept (or, too large to keep, decoded for
//! the request).
//!
//! A window `rows × cols` of level k covers, in full-resolution samples, the box
//! `⌊r0·d/R⌋ .. ⌈r1·d/R⌉` (extent d, level extent R); the decoder returns the level's
//! samples `⌊x0·R/d⌋ .. ⌈x1·R/d⌉` of that box, a superset of the window, which is cut out.

use super::cache::{Key, LevelCache};
use super::ident::Slice;
use super::ServeError;
use crate::codec::{self, DecodeOptions};
use crate::format::Header;
use crate::io::{Raster, Samples};
use crate::limits::Limits;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::UNIX_EPOCH;

/// A window of one level: `h × w` positions of `c` channels, row-major, channels last.
#[derive(Clone, Debug, PartialEq)]
pub struct Plane {
    pub h: usize,
    pub w: usize,
    pub c: usize,
    pub data: Vec<f32>,
}

/// Where a window came from (for the `Server-Timing` header of an answer).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Via {
    /// Cut from a whole level decoded before.
    #[default]
    Level,
    /// The whole level decoded for this request (and kept if it fits).
    LevelDecoded,
    /// From patches of a one-piece 3.0 file, `decoded` of them decoded for this request
    /// and kept, `own` of them (first asked) read by decoding the window's part alone.
    Patches { decoded: usize, own: usize },
    /// From tiles of a tiled file, `decoded` of them decoded for this request.
    Tiles { decoded: usize },
}

impl Via {
    /// A short name: `level`, `level-decoded`, `patches-kept`, `patches-decoded`,
    /// `window-decoded`, `tiles-kept`, `tiles-decoded`.
    pub fn name(self) -> &'static str {
        match self {
            Via::Level => "level",
            Via::LevelDecoded => "level-decoded",
            Via::Patches { own: 1.., .. } => "window-decoded",
            Via::Patches { decoded: 0, .. } => "patches-kept",
            Via::Patches { .. } => "patches-decoded",
            Via::Tiles { decoded: 0 } => "tiles-kept",
            Via::Tiles { .. } => "tiles-decoded",
        }
    }
}

/// Bytes a decoder may take per decoded sample beyond the samples themselves (its
/// coefficient planes in `f32`, the pyramid's scratch): the planning factor of the
/// memory check before a decode.
const DECODE_BYTES_PER_SAMPLE: u64 = 12;

/// An opened file.
#[derive(Clone, Debug)]
pub struct Source {
    pub path: PathBuf,
    /// File length and modification time (ns): the version an `ETag` and the cache name.
    pub len: u64,
    pub mtime: u128,
    pub header: Header,
    /// Each level's extents, slowest axis first (`levels[0]` is the full resolution).
    pub levels: Vec<Vec<usize>>,
    /// The slice of a volume (`None` for a 2-D raster).
    pub slice: Option<Slice>,
    /// The axes of the image: rows, then columns (indices into `header.dims`).
    pub row_axis: usize,
    pub col_axis: usize,
    /// A one-piece 3.0 file parsed once (its code-block indices), when the server keeps
    /// it: patches are then decoded from it without reading the indices again.
    pub opened: Option<OpenedFile>,
}

/// A file parsed once ([`codec::Opened`]), shared by the requests of its version.
#[derive(Clone)]
pub struct OpenedFile(pub Arc<codec::Opened>);

impl std::fmt::Debug for OpenedFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("OpenedFile")
    }
}

/// A file's version: its length and modification time (nanoseconds since the epoch, 0
/// where the system gives none); a file replaced on disk has another.
pub fn version(md: &std::fs::Metadata) -> (u64, u128) {
    let mtime = md
        .modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    (md.len(), mtime)
}

/// The `ETag` of a file's version: `"len-mtime"` in hexadecimal.
pub fn etag(len: u64, mtime: u128) -> String {
    format!("\"{len:x}-{mtime:x}\"")
}

impl Source {
    /// Read the header of `path` and plan the image of `slice` (a volume without one is
    /// shown at its middle z slice).
    pub fn open(path: &Path, slice: Option<Slice>) -> Result<Source, ServeError> {
        let md = std::fs::metadata(path).map_err(|_| ServeError::NotFound)?;
        let (_, mtime) = version(&md);
        let header = codec::header_of_file(path)?;
        let nd = header.dims.len();
        let (slice, row_axis, col_axis) = match (nd, slice) {
            (2, None) => (None, 0, 1),
            (2, Some(_)) => {
                return Err(ServeError::bad(
                    "identifier",
                    "a slice",
                    "a slice of a 3-D file only",
                ))
            }
            (3, s) => {
                let s = s.unwrap_or(Slice {
                    axis: 0,
                    index: header.dims[0] as u64 / 2,
                });
                if s.index >= header.dims[s.axis] as u64 {
                    return Err(ServeError::bad(
                        "identifier",
                        &format!("slice {} of {}", s.index, header.dims[s.axis]),
                        "a slice within the volume",
                    ));
                }
                let rest: Vec<usize> = (0..3).filter(|&a| a != s.axis).collect();
                (Some(s), rest[0], rest[1])
            }
            _ => {
                return Err(ServeError::bad(
                    "identifier",
                    &format!("a {nd}-D file"),
                    "a 2-D image or heightmap, or a 3-D volume",
                ))
            }
        };
        let depth = codec::depth_of(&header)?;
        let levels = (0..=depth)
            .map(|k| codec::level_extents(&header, k))
            .collect::<crate::Result<Vec<_>>>()?;
        Ok(Source {
            path: path.to_path_buf(),
            len: md.len(),
            mtime,
            header,
            levels,
            slice,
            row_axis,
            col_axis,
            opened: None,
        })
    }

    /// The image's width and height in full-resolution pixels.
    pub fn size(&self) -> (u64, u64) {
        (
            self.header.dims[self.col_axis] as u64,
            self.header.dims[self.row_axis] as u64,
        )
    }

    /// Level `k`'s width and height.
    pub fn level_size(&self, k: usize) -> (usize, usize) {
        (self.levels[k][self.col_axis], self.levels[k][self.row_axis])
    }

    /// The deepest level.
    pub fn depth(&self) -> usize {
        self.levels.len() - 1
    }

    /// Whether patches of this file are decoded from a parsed [`codec::Opened`]: a
    /// one-piece 3.0 file (code-blocks).
    pub fn parses_once(&self) -> bool {
        self.header.version.has_blocks() && !self.header.is_tiled()
    }

    /// Whether level `k` is held whole in `cache`, decoded: a window of it is a cut.
    pub fn level_held(&self, cache: &LevelCache, k: usize) -> bool {
        cache.get(&self.key(k, Vec::new())).is_some()
    }

    /// The entity tag of this version of the file.
    pub fn etag(&self) -> String {
        etag(self.len, self.mtime)
    }

    /// The window `rows × cols` of level `k` (level coordinates, within the level).
    pub fn window(
        &self,
        cache: &LevelCache,
        limits: &Limits,
        k: usize,
        rows: Range<usize>,
        cols: Range<usize>,
        via: &mut Via,
    ) -> Result<Plane, ServeError> {
        let h = &self.header;
        let ext = &self.levels[k];
        let c = h.channels as u64;
        let window = (rows.len() as u64).saturating_mul(cols.len() as u64);
        limits.check_elems("the window of a request", window.saturating_mul(c), 4)?;
        let level_samples = ext.iter().fold(c, |n, &e| n.saturating_mul(e as u64));
        let level_bytes = level_samples.saturating_mul(h.sample_type.size() as u64);
        // the level's samples at the slice, and the window's box in the level
        let mut bx: Vec<Range<usize>> = (0..ext.len()).map(|_| 0..0).collect();
        bx[self.row_axis] = rows.clone();
        bx[self.col_axis] = cols.clone();
        if let Some(s) = self.slice {
            let lo = level_index(s.index as usize, ext[s.axis], h.dims[s.axis]);
            bx[s.axis] = lo..lo + 1;
        }
        // a tiled file is read tile by tile (the first request of a level must not wait
        // for every tile of it); a file of one tile is decoded whole once and kept
        if h.is_tiled() {
            return self.window_from_tiles(cache, limits, k, &bx, via);
        }
        // a 3.0 file: the window's code-blocks read and its support synthesized alone
        if h.version.has_blocks() {
            // the whole level when it is decoded and kept ([`Source::warm`]), without
            // waiting for a decode of it under way
            if let Some(r) = cache.get(&self.key(k, Vec::new())) {
                *via = Via::Level;
                let zero: Vec<usize> = vec![0; ext.len()];
                return cut(&r, &zero, &bx, self.row_axis, self.col_axis);
            }
            return self.window_from_patches(cache, limits, k, &bx, via);
        }
        if level_bytes <= cache.entry_limit() {
            limits.check_elems("a decoded level", level_samples, DECODE_BYTES_PER_SAMPLE)?;
            let key = self.key(k, Vec::new());
            *via = Via::Level;
            let r = cache
                .get_or_decode(key, level_bytes, || {
                    *via = Via::LevelDecoded;
                    self.decode(k, None)
                })
                .map_err(ServeError::File)?;
            let zero: Vec<usize> = vec![0; ext.len()];
            return cut(&r, &zero, &bx, self.row_axis, self.col_axis);
        }
        // a file of one tile too large to keep: reconstructed whole for the request, cut
        limits.check_elems(
            "the decode of a request",
            level_samples,
            DECODE_BYTES_PER_SAMPLE,
        )?;
        *via = Via::LevelDecoded;
        let r = self.decode(k, None)?;
        let zero: Vec<usize> = vec![0; ext.len()];
        cut(&r, &zero, &bx, self.row_axis, self.col_axis)
    }

    /// Decode whole, coarsest first, the levels of a one-piece 3.0 image that the cache
    /// keeps (each at most [`LevelCache::entry_limit`], all of them at most half the
    /// budget, each decode within `limits`), and keep them: the pyramid a tile server
    /// reads. Requests meanwhile decode their patches; a level once kept is cut from.
    pub fn warm(&self, cache: &LevelCache, limits: &Limits) {
        if !self.parses_once() || self.slice.is_some() {
            return;
        }
        let h = &self.header;
        let mut total = 0u64;
        for k in (0..self.levels.len()).rev() {
            let samples = self.levels[k]
                .iter()
                .fold(h.channels as u64, |n, &e| n.saturating_mul(e as u64));
            let bytes = samples.saturating_mul(h.sample_type.size() as u64);
            total = total.saturating_add(bytes);
            if bytes > cache.entry_limit()
                || total > cache.budget() / 2
                || limits
                    .check_elems("a decoded level", samples, DECODE_BYTES_PER_SAMPLE)
                    .is_err()
            {
                break;
            }
            if cache
                .get_or_decode(self.key(k, Vec::new()), bytes, || self.decode(k, None))
                .is_err()
            {
                break;
            }
        }
    }

    fn key(&self, level: usize, tile: Vec<usize>) -> Key {
        Key {
            path: self.path.clone(),
            len: self.len,
            mtime: self.mtime,
            level,
            tile,
        }
    }

    /// Level `k` of the file, or of the full-resolution box `region` (slowest axis first).
    fn decode(&self, k: usize, region: Option<Vec<Range<usize>>>) -> crate::Result<Arc<Raster>> {
        if let Some(o) = &self.opened {
            return o.0.region(k, region.as_deref()).map(|d| Arc::new(d.raster));
        }
        let opts = DecodeOptions {
            level: k,
            region,
            ..Default::default()
        };
        codec::decode_file(&self.path, &opts).map(|d| Arc::new(d.raster))
    }

    /// The window `bx` of level `k` of a tiled file from the tiles it meets, each decoded
    /// at level k and kept in the cache. Tile `j` (full-resolution `j·T .. (j+1)·T` on
    /// an axis) holds the level samples `⌊j·T·R/d⌋ .. ⌈(j+1)·T·R/d⌉`.
    fn window_from_tiles(
        &self,
        cache: &LevelCache,
        limits: &Limits,
        k: usize,
        bx: &[Range<usize>],
        via: &mut Via,
    ) -> Result<Plane, ServeError> {
        let h = &self.header;
        let ext = &self.levels[k];
        let nd = ext.len();
        let mut decoded = 0;
        let level_box = |a: usize, j: usize| -> Range<usize> {
            let (d, r, t) = (h.dims[a] as u128, ext[a] as u128, h.tile[a] as u128);
            let j = j as u128;
            let lo = (j * t * r / d) as usize;
            let hi = (((j + 1) * t).min(d) * r).div_ceil(d) as usize;
            lo..hi.min(ext[a]).max(lo + 1)
        };
        // per axis, the tiles whose level box meets the window (the axis indexes the
        // header, the level and the window alike)
        let mut meets: Vec<Vec<usize>> = Vec::with_capacity(nd);
        #[allow(clippy::needless_range_loop)]
        for a in 0..nd {
            let n = h.dims[a].div_ceil(h.tile[a].max(1));
            meets.push(
                (0..n)
                    .filter(|&j| {
                        let g = level_box(a, j);
                        g.start < bx[a].end && g.end > bx[a].start
                    })
                    .collect(),
            );
        }
        if meets.iter().any(|m| m.is_empty()) {
            return Err(ServeError::from(crate::Error::format(
                format!("no tile meets the window {bx:?} of level {k}"),
                "a window within the level",
            )));
        }
        let pieces: Vec<Vec<(usize, Range<usize>)>> = meets
            .iter()
            .enumerate()
            .map(|(a, m)| m.iter().map(|&j| (j, level_box(a, j))).collect())
            .collect();
        let out = self.assemble(bx, &pieces, |coords, boxes| {
            let region: Vec<Range<usize>> = (0..nd)
                .map(|a| coords[a] * h.tile[a]..((coords[a] + 1) * h.tile[a]).min(h.dims[a]))
                .collect();
            let samples = boxes
                .iter()
                .fold(h.channels as u64, |n, g| n * g.len() as u64);
            limits.check_elems("a decoded tile", samples, DECODE_BYTES_PER_SAMPLE)?;
            let bytes = samples * h.sample_type.size() as u64;
            let r = cache
                .get_or_decode(self.key(k, coords.to_vec()), bytes, || {
                    decoded += 1;
                    self.decode(k, Some(region))
                })
                .map_err(ServeError::File)?;
            Ok((r, boxes.iter().map(|g| g.start).collect()))
        });
        *via = Via::Tiles { decoded };
        out
    }

    /// The window `bx` of level `k` of a one-piece 3.0 file from the patches it meets:
    /// level k cut on the image's axes into `PATCH × PATCH` squares aligned to multiples
    /// of `PATCH` (a level no larger is one patch), each decoded as `mra decode --level
    /// k --region …` of its box and kept in the cache, so that neighbouring tiles share
    /// one decode of their code-blocks and of the synthesis of their support.
    fn window_from_patches(
        &self,
        cache: &LevelCache,
        limits: &Limits,
        k: usize,
        bx: &[Range<usize>],
        via: &mut Via,
    ) -> Result<Plane, ServeError> {
        let h = &self.header;
        let ext = &self.levels[k];
        let p = patch_extent();
        let mut decoded = 0;
        let pieces: Vec<Vec<(usize, Range<usize>)>> = (0..ext.len())
            .map(|a| {
                if a != self.row_axis && a != self.col_axis {
                    // the slice axis: the window's one sample
                    return vec![(bx[a].start, bx[a].clone())];
                }
                (bx[a].start / p..bx[a].end.div_ceil(p))
                    .map(|j| (j, j * p..((j + 1) * p).min(ext[a])))
                    .collect()
            })
            .collect();
        let mut own = 0;
        let out = self.assemble(bx, &pieces, |coords, boxes| {
            let key = self.key(k, coords.to_vec());
            if !cache.seen_before(&key) {
                // the first request of a patch decodes its own part of it alone (what
                // it waits for is its window's support, not the patch's); a second
                // request of the patch decodes the patch and keeps it
                let part: Vec<Range<usize>> = boxes
                    .iter()
                    .zip(bx)
                    .map(|(g, w)| w.start.max(g.start)..w.end.min(g.end))
                    .collect();
                let (region, origin) = full_region(&h.dims, ext, &part);
                let samples = part
                    .iter()
                    .fold(h.channels as u64, |n, g| n * (g.len() as u64 + 2));
                limits.check_elems("a decoded window", samples, DECODE_BYTES_PER_SAMPLE)?;
                own += 1;
                return Ok((self.decode(k, Some(region))?, origin));
            }
            let (region, origin) = full_region(&h.dims, ext, boxes);
            // the decode may hold a sample more on each side of the box
            let samples = boxes
                .iter()
                .fold(h.channels as u64, |n, g| n * (g.len() as u64 + 2));
            limits.check_elems("a decoded patch", samples, DECODE_BYTES_PER_SAMPLE)?;
            let bytes = samples * h.sample_type.size() as u64;
            let r = cache
                .get_or_decode(key, bytes, || {
                    decoded += 1;
                    self.decode(k, Some(region))
                })
                .map_err(ServeError::File)?;
            Ok((r, origin))
        });
        *via = Via::Patches { decoded, own };
        out
    }

    /// The window `bx` from pieces: on each axis the pieces meeting it, each an index
    /// and its box of the level; `fetch(indices, boxes)` gives a piece's decode and the
    /// level position of its first sample. Every piece's part of the window is copied.
    fn assemble(
        &self,
        bx: &[Range<usize>],
        pieces: &[Vec<(usize, Range<usize>)>],
        mut fetch: impl FnMut(
            &[usize],
            &[Range<usize>],
        ) -> Result<(Arc<Raster>, Vec<usize>), ServeError>,
    ) -> Result<Plane, ServeError> {
        let nd = bx.len();
        let c = self.header.channels;
        let (oh, ow) = (bx[self.row_axis].len(), bx[self.col_axis].len());
        if pieces.iter().any(|m| m.is_empty()) {
            return Err(ServeError::from(crate::Error::format(
                format!("no piece meets the window {bx:?}"),
                "a window within the level",
            )));
        }
        let mut out = Plane {
            h: oh,
            w: ow,
            c,
            data: vec![0.0; oh * ow * c],
        };
        let mut at = vec![0usize; nd];
        'pieces: loop {
            let coords: Vec<usize> = (0..nd).map(|a| pieces[a][at[a]].0).collect();
            let boxes: Vec<Range<usize>> = (0..nd).map(|a| pieces[a][at[a]].1.clone()).collect();
            let part: Vec<Range<usize>> = (0..nd)
                .map(|a| bx[a].start.max(boxes[a].start)..bx[a].end.min(boxes[a].end))
                .collect();
            if part.iter().all(|g| !g.is_empty()) {
                let (r, origin) = fetch(&coords, &boxes)?;
                let p = cut(&r, &origin, &part, self.row_axis, self.col_axis)?;
                let (y0, x0) = (
                    part[self.row_axis].start - bx[self.row_axis].start,
                    part[self.col_axis].start - bx[self.col_axis].start,
                );
                for y in 0..p.h {
                    let dst = ((y0 + y) * ow + x0) * c;
                    out.data[dst..dst + p.w * c]
                        .copy_from_slice(&p.data[y * p.w * c..(y + 1) * p.w * c]);
                }
            }
            // the next piece, last axis fastest
            for a in (0..nd).rev() {
                at[a] += 1;
                if at[a] < pieces[a].len() {
                    continue 'pieces;
                }
                at[a] = 0;
            }
            break;
        }
        Ok(out)
    }
}

/// The side of a patch of a one-piece 3.0 file's level, in level samples.
pub const PATCH: usize = 512;

fn patch_extent() -> usize {
    std::env::var("MRA_SERVE_PATCH")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|&p: &usize| p >= 16)
        .unwrap_or(PATCH)
}

/// The level index of full-resolution index `x` on an axis of extent `d` and level
/// extent `r`: `⌊x·r/d⌋`, at most `r − 1`.
pub fn level_index(x: usize, r: usize, d: usize) -> usize {
    ((x as u128 * r as u128 / d.max(1) as u128) as usize).min(r.saturating_sub(1))
}

/// The box `bx` (level coordinates) of a raster whose first sample sits at `origin`,
/// as a plane of rows `row_axis` and columns `col_axis` (the other axis, if any, one
/// sample thick).
/// The full-resolution box (extents `dims`) whose decode at a level of extents `ext`
/// covers the level box `bx`, and where that decode starts in the level: on each axis
/// `[⌊lo·d/r⌋, ⌈hi·d/r⌉)`, which a decode maps back to `[⌊g₀·r/d⌋, ⌈g₁·r/d⌉) ⊇ [lo, hi)`.
fn full_region(
    dims: &[usize],
    ext: &[usize],
    bx: &[Range<usize>],
) -> (Vec<Range<usize>>, Vec<usize>) {
    dims.iter()
        .zip(ext)
        .zip(bx)
        .map(|((&d, &r), g)| {
            let (d, r) = (d.max(1) as u128, r.max(1) as u128);
            let lo = (g.start as u128 * d / r) as usize;
            let hi = ((g.end as u128 * d).div_ceil(r) as usize).clamp(lo + 1, d as usize);
            let at = (lo as u128 * r / d) as usize;
            (lo..hi, at)
        })
        .unzip()
}

fn cut(
    r: &Raster,
    origin: &[usize],
    bx: &[Range<usize>],
    row_axis: usize,
    col_axis: usize,
) -> Result<Plane, ServeError> {
    let nd = r.dims.len();
    let inside = nd == bx.len()
        && (0..nd).all(|a| bx[a].start >= origin[a] && bx[a].end <= origin[a] + r.dims[a]);
    if !inside {
        return Err(ServeError::from(crate::Error::format(
            format!("a decoded box of {:?} for a window {bx:?}", r.dims),
            "the window inside the decoded box",
        )));
    }
    let c = r.channels;
    // strides of the raster, slowest axis first, in positions
    let mut stride = vec![1usize; nd];
    for a in (0..nd.saturating_sub(1)).rev() {
        stride[a] = stride[a + 1] * r.dims[a + 1];
    }
    let base: usize = (0..nd)
        .filter(|&a| a != row_axis && a != col_axis)
        .map(|a| (bx[a].start - origin[a]) * stride[a])
        .sum();
    let (hh, ww) = (bx[row_axis].len(), bx[col_axis].len());
    let mut data = Vec::with_capacity(hh * ww * c);
    let x0 = bx[col_axis].start - origin[col_axis];
    if stride[col_axis] == 1 {
        // a row of the window is contiguous in the raster: copied row by row
        for y in 0..hh {
            let ry = bx[row_axis].start - origin[row_axis] + y;
            let p = (base + ry * stride[row_axis] + x0) * c;
            push_samples(&r.samples, p, ww * c, &mut data);
        }
        return Ok(Plane {
            h: hh,
            w: ww,
            c,
            data,
        });
    }
    for y in 0..hh {
        let ry = bx[row_axis].start - origin[row_axis] + y;
        for x in 0..ww {
            let rx = bx[col_axis].start - origin[col_axis] + x;
            let p = (base + ry * stride[row_axis] + rx * stride[col_axis]) * c;
            push_samples(&r.samples, p, c, &mut data);
        }
    }
    Ok(Plane {
        h: hh,
        w: ww,
        c,
        data,
    })
}

/// Samples `p .. p + n` as `f32`, appended.
fn push_samples(s: &Samples, p: usize, n: usize, out: &mut Vec<f32>) {
    match s {
        Samples::U8(v) => out.extend(v[p..p + n].iter().map(|&x| x as f32)),
        Samples::U16(v) => out.extend(v[p..p + n].iter().map(|&x| x as f32)),
        Samples::F32(v) => out.extend_from_slice(&v[p..p + n]),
        _ => out.extend((p..p + n).map(|i| s.get_f64(i) as f32)),
    }
}
