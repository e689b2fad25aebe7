//! Encoding a tiled file from a [`SlabSource`]: the raster read one tile-row (2-D) or
//! tile-slab (3-D) at a time, the tiles of each slab coded in parallel and written, so
//! that memory holds a slab and the tiles in flight, not the raster.
//!
//! The output is written in order with `HEAD` and `TIDX` reserved (their sizes are
//! known from the grid) and rewritten in place at the end, when the raster's range and
//! every tile's offset and length are known.
//!
//! Rate modes: `--lossless`, `--max-error` and `--threshold` code each tile as it comes
//! (one pass). `--quality` takes a first pass for the raster's range. `--keep`, `--psnr`
//! and `--bpp` take a first pass for the range and a sample of tiles (every ⌈n/64⌉-th,
//! all of them up to 64 tiles): `--keep`'s threshold is that of the sample's details,
//! the `--psnr` / `--bpp` search measures the sample.

use super::compact::{self, Ratios};
use super::{crop_samples, Grid, SEARCH_SAMPLE_TILES};
use crate::codec::encode::encode_filled;
#[cfg(doc)]
use crate::codec::lossy::finite_range;
use crate::codec::lossy::{prepare, Prepared};
use crate::codec::meta;
use crate::codec::options::{EncodeOptions, Rate};
use crate::codec::rate::{check_rate, keep_step, quality_step};
use crate::codec::voids::with_voids_filled;
use crate::format::tag::{HEAD, MEND, META, TIDX, TILE, TRAT};
use crate::format::tiles::{head_of, put_index_entry, tile_prefix};
use crate::format::{self, write_chunk, Header, Mode};
use crate::io::slab::{Shape, SlabSource};
use crate::io::{Raster, Samples};
use crate::tensor::par::{caught, receive, Feed, Job};
use crate::{Error, Result};
use rayon::prelude::*;
use std::io::{Seek, SeekFrom, Write};

/// The range of finite samples and the range of all non-NaN samples (for the PSNR's
/// default peak), merged slab by slab.
#[derive(Clone, Copy)]
struct Ranges {
    finite: (f64, f64),
    all: Option<(f64, f64)>,
}

impl Ranges {
    fn new() -> Self {
        Ranges {
            finite: (f64::INFINITY, f64::NEG_INFINITY),
            all: None,
        }
    }

    /// Merge the ranges of `s` (in parallel, pieces of 2^16 samples).
    fn add(&mut self, s: &Samples) {
        const PIECE: usize = 1 << 16;
        let parts: Vec<Ranges> = (0..s.len().div_ceil(PIECE))
            .into_par_iter()
            .map(|k| {
                let mut r = Ranges::new();
                r.add_range(s, k * PIECE..((k + 1) * PIECE).min(s.len()));
                r
            })
            .collect();
        for p in parts {
            self.merge(&p);
        }
    }

    fn merge(&mut self, o: &Ranges) {
        self.finite = (self.finite.0.min(o.finite.0), self.finite.1.max(o.finite.1));
        self.all = match (self.all, o.all) {
            (Some(a), Some(b)) => Some((a.0.min(b.0), a.1.max(b.1))),
            (a, b) => a.or(b),
        };
    }

    fn add_range(&mut self, s: &Samples, r: std::ops::Range<usize>) {
        // integers are never NaN nor infinite: their extremes, in their own type
        macro_rules! ints {
            ($v:expr) => {{
                let part = &$v[r];
                if let Some(&first) = part.first() {
                    let (lo, hi) = part
                        .iter()
                        .fold((first, first), |(a, b), &x| (a.min(x), b.max(x)));
                    self.merge(&Ranges {
                        finite: (lo as f64, hi as f64),
                        all: Some((lo as f64, hi as f64)),
                    });
                }
                return;
            }};
        }
        match s {
            Samples::U8(v) => ints!(v),
            Samples::I8(v) => ints!(v),
            Samples::U16(v) => ints!(v),
            Samples::I16(v) => ints!(v),
            Samples::U32(v) => ints!(v),
            Samples::I32(v) => ints!(v),
            _ => {}
        }
        let (mut flo, mut fhi) = self.finite;
        let (mut lo, mut hi) = self.all.unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
        for i in r {
            let x = s.get_f64(i);
            if x.is_finite() {
                flo = flo.min(x);
                fhi = fhi.max(x);
            }
            if x < lo {
                lo = x;
            }
            if x > hi {
                hi = x;
            }
        }
        self.finite = (flo, fhi);
        self.all = (lo <= hi).then_some((lo, hi));
    }

    /// `(min, max)` of the finite samples, `(0, 0)` when there are none (as
    /// [`finite_range`] gives it).
    fn finite(&self) -> (f64, f64) {
        if self.finite.0 > self.finite.1 {
            (0.0, 0.0)
        } else {
            self.finite
        }
    }
}

/// How each tile is coded, once the first pass (if any) has been taken.
#[derive(Clone, Copy)]
enum Coding {
    /// The rate mode's coding, which does not depend on the samples of other tiles.
    Own,
    /// Lossy at this base step, with rate–distortion optimised indices when `rdo`.
    Step { step: f64, rdo: bool },
}

/// Tile `i` cut from `slab` (the rows of its grid row, from row `row0`), its voids
/// not filled.
fn cut_tile(grid: &Grid, shape: &Shape, slab: &Samples, row0: usize, i: usize) -> Result<Raster> {
    let mut g = grid.ranges(i);
    let slab_rows = grid.extent(0, grid.coords(i)[0]);
    g[0] = g[0].start - row0..g[0].end - row0;
    let mut sdims = shape.dims.clone();
    sdims[0] = slab_rows;
    let mut t = Raster::new(
        grid.tile_dims(i),
        shape.channels,
        crop_samples(slab, &sdims, shape.channels, &g),
        shape.kind,
    )?;
    t.meta.nodata = shape.meta.nodata;
    Ok(t)
}

/// Tile `i` cut from `slab` (rows from `row0`), its voids filled in the tile (for
/// measuring: NaN payloads need not be kept).
fn slab_tile(grid: &Grid, shape: &Shape, slab: &Samples, row0: usize, i: usize) -> Result<Raster> {
    let t = cut_tile(grid, shape, slab, row0, i)?;
    Ok(with_voids_filled(&t.view(), false)?.unwrap_or(t))
}

/// Encode the raster of `src` as tiles of extents `tile` (slowest first) into `out`,
/// reading it a slab of tile rows at a time; returns the bytes written. The bytes are
/// those of the same raster encoded in memory.
pub(crate) fn encode_slabs<S: SlabSource + ?Sized, W: Write + Seek>(
    src: &mut S,
    opts: &EncodeOptions,
    tile: &[usize],
    out: &mut W,
) -> Result<u64> {
    check_rate(opts.rate)?;
    // every tile is a format 2 one-tile file (§14)
    let opts = &opts.in_bands();
    let shape = src.shape().clone();
    let grid = Grid::new(&shape.dims, tile)?;
    let sampled = matches!(
        opts.rate,
        Rate::Keep(_) | Rate::Psnr(_) | Rate::PsnrRange(..) | Rate::Bpp(_)
    );
    let first_pass = sampled || matches!(opts.rate, Rate::Quality(_));
    let (ranges, sample) = if first_pass {
        measure_slabs(src, &grid, &shape, sampled)?
    } else {
        (Ranges::new(), Vec::new())
    };
    let coding = choose_coding(&grid, &shape, opts, &ranges, sample)?;

    // HEAD, mETA and TIDX are reserved when the first tile is written, and rewritten
    // at the end with the raster's range and the tiles' places
    let start = out.stream_position()?;
    out.write_all(&format::SIGNATURE)?;
    let mut w = TileWriter {
        grid: &grid,
        shape: &shape,
        head: None,
        ratios: None,
        index_at: 0,
        index: Vec::with_capacity(16 * grid.len()),
        at: start + 8,
    };
    let ranges_now = write_tiles(src, opts, coding, !first_pass, &mut w, out)?;
    w.at += write_chunk(out, MEND, &[])?;
    let at = w.at;
    let (head_at, mut h) = w
        .head
        .ok_or_else(|| Error::parameter("tile", 0, "a tile"))?;
    (h.min, h.max) = if first_pass {
        ranges.finite()
    } else {
        ranges_now.finite()
    };
    out.seek(SeekFrom::Start(head_at))?;
    write_chunk(out, HEAD, &[&h.to_bytes()])?;
    out.seek(SeekFrom::Start(w.index_at))?;
    write_chunk(out, TIDX, &[&w.index])?;
    out.seek(SeekFrom::Start(at))?;
    out.flush()?;
    Ok(at - start)
}

/// The `--keep k` step of a raster from its first pass's sampled tiles: the threshold
/// of the largest k% of their weighted details ([`keep_step`], `span` the range).
pub(in crate::codec) fn sampled_keep_step(
    sample: &[Raster],
    opts: &EncodeOptions,
    k: f64,
    span: f64,
) -> Result<f64> {
    let mut w: Vec<f32> = sample
        .par_iter()
        .map(|t| Ok(prepare(&t.view(), opts, Mode::Lossy)?.weighted_details()))
        .collect::<Result<Vec<_>>>()?
        .concat();
    Ok(keep_step(&mut w, k, span))
}

/// What the first pass of a one-transform file learns of its raster.
pub(in crate::codec) struct FirstPass {
    /// The least and greatest finite sample, `(0, 0)` when there is none.
    pub(in crate::codec) range: (f64, f64),
    /// The default PSNR peak of the whole raster (of its least and greatest non-NaN
    /// samples, as the tiled `--psnr` takes it).
    pub(in crate::codec) peak: f64,
    /// The sampled tiles (voids filled).
    pub(in crate::codec) sample: Vec<Raster>,
}

/// The first pass of a one-transform file over the raster of `src`
/// ([`crate::codec::streamed`], [`FirstPass`]): when `sampled`, every ⌈n/64⌉-th tile
/// of the default grid (the whole raster when that is one tile) is kept, as
/// [`encode_slabs`] measures them.
pub(in crate::codec) fn first_pass<S: SlabSource + ?Sized>(
    src: &mut S,
    sampled: bool,
) -> Result<FirstPass> {
    let shape = src.shape().clone();
    let grid = Grid::new(
        &shape.dims,
        &super::default_tile(&shape.dims, shape.channels),
    )?;
    let (ranges, sample) = measure_slabs(src, &grid, &shape, sampled)?;
    let (a, b) = ranges.all.unwrap_or((0.0, 0.0));
    let peak =
        crate::metrics::skimage_data_range(Samples::from_f64(&[a, b], shape.sample_type).view());
    Ok(FirstPass {
        range: ranges.finite(),
        peak,
        sample,
    })
}

/// The rows of the raster in tile row `g0` of `grid`.
fn rows_of(grid: &Grid, g0: usize) -> std::ops::Range<usize> {
    g0 * grid.tile[0]..g0 * grid.tile[0] + grid.extent(0, g0)
}

/// The first pass over the raster: its ranges and, when `sampled`, every ⌈n/64⌉-th
/// tile (voids filled). The pool has nothing else to do: each slab is read on all its
/// threads, then measured.
fn measure_slabs<S: SlabSource + ?Sized>(
    src: &mut S,
    grid: &Grid,
    shape: &Shape,
    sampled: bool,
) -> Result<(Ranges, Vec<Raster>)> {
    let n = grid.len();
    let per_row = n / grid.counts[0];
    let every = n.div_ceil(SEARCH_SAMPLE_TILES).max(1);
    let mut ranges = Ranges::new();
    let mut sample: Vec<Raster> = Vec::new();
    for g0 in 0..grid.counts[0] {
        let r = rows_of(grid, g0);
        let slab = src.read_rows_parallel(r.clone())?;
        ranges.add(&slab);
        let mine: Vec<usize> = (g0 * per_row..(g0 + 1) * per_row)
            .filter(|i| sampled && i % every == 0)
            .collect();
        let tiles: Vec<Raster> = mine
            .par_iter()
            .map(|&i| slab_tile(grid, shape, &slab, r.start, i))
            .collect::<Result<_>>()?;
        sample.extend(tiles);
    }
    Ok((ranges, sample))
}

/// How every tile is coded: by its own rate mode, or at the base step the rate mode
/// asks of the whole raster (from its `ranges` and the sampled tiles).
fn choose_coding(
    grid: &Grid,
    shape: &Shape,
    opts: &EncodeOptions,
    ranges: &Ranges,
    sample: Vec<Raster>,
) -> Result<Coding> {
    let (lo, hi) = ranges.finite();
    let range = (hi - lo).max(1e-30);
    Ok(match opts.rate {
        Rate::Quality(q) => Coding::Step {
            step: quality_step(q, range),
            rdo: true,
        },
        Rate::Keep(k) => Coding::Step {
            step: sampled_keep_step(&sample, opts, k, range)?,
            rdo: false,
        },
        Rate::Psnr(_) | Rate::PsnrRange(..) | Rate::Bpp(_) => {
            let peak = match (opts.rate, ranges.all) {
                (Rate::PsnrRange(_, p), _) => p,
                (_, all) => {
                    // the whole raster's default peak, from its extremes
                    let (a, b) = all.unwrap_or((0.0, 0.0));
                    crate::metrics::skimage_data_range(
                        Samples::from_f64(&[a, b], shape.sample_type).view(),
                    )
                }
            };
            let step = search_step(shape, grid, grid.len(), sample, opts, range, peak)?;
            Coding::Step { step, rdo: true }
        }
        _ => Coding::Own,
    })
}

/// Code every tile of `src` and write it with `w` in tile order; returns the range of
/// the samples when `measure`.
///
/// The tiles are coded one pool job each and written in tile order as they come.
/// With more than one thread the slabs are pipelined: the tiles of slab g are queued
/// behind those of slab g − 1 (the pool goes from one slab's last tiles to the next
/// slab's without waiting), and slab g + 1 is read while slab g is coded, once the
/// tiles of slab g − 1 are written (memory holds two slabs and a tile per thread).
/// With one thread each slab is coded and written before the next is read.
fn write_tiles<S: SlabSource + ?Sized, W: Write + Seek>(
    src: &mut S,
    opts: &EncodeOptions,
    coding: Coding,
    measure: bool,
    w: &mut TileWriter,
    out: &mut W,
) -> Result<Ranges> {
    let (grid, shape) = (w.grid, w.shape);
    let n = grid.len();
    let rows = grid.counts[0];
    let per_row = n / rows;
    // with more than one thread the next slab is read while this one is coded
    let ahead = rayon::current_num_threads() > 1;
    let mut ranges_now = Ranges::new();
    let feed = Feed::new();
    let _stop = feed.stop_on_drop();
    let common = std::sync::Arc::new((grid.clone(), shape.clone(), opts.clone()));
    let (tx, rx) = std::sync::mpsc::channel::<(usize, Result<(Vec<u8>, Ranges)>)>();
    // coded tiles that came before their turn to be written
    let mut early = std::collections::BTreeMap::new();
    let mut written = 0usize;
    let mut drain = |upto: usize, w: &mut TileWriter, out: &mut W, rn: &mut Ranges| {
        while written < upto {
            let c = match early.remove(&written) {
                Some(c) => c,
                None => {
                    let (i, r) = receive(&rx).ok_or_else(stopped)?;
                    let (c, got) = r?;
                    rn.merge(&got);
                    if i != written {
                        early.insert(i, c);
                        continue;
                    }
                    c
                }
            };
            w.put(out, written, &c)?;
            written += 1;
        }
        Ok::<(), Error>(())
    };
    let mut next = Some(src.read_rows(rows_of(grid, 0))?);
    for g0 in 0..rows {
        let row0 = rows_of(grid, g0).start;
        let slab = std::sync::Arc::new(next.take().expect("read before its turn"));
        feed.push((g0 * per_row..(g0 + 1) * per_row).map(|i| {
            let (tx, slab, common) = (tx.clone(), slab.clone(), common.clone());
            Box::new(move || {
                let (grid, shape, opts) = &*common;
                let got = caught(|| code_tile(grid, shape, &slab, row0, i, coding, opts, measure));
                drop(slab);
                // the receiver is gone when writing failed
                let _ = tx.send((i, got.unwrap_or_else(|| Err(stopped()))));
            }) as Job
        }));
        drop(slab);
        let upto = if ahead {
            g0 * per_row
        } else {
            (g0 + 1) * per_row
        };
        drain(upto, w, &mut *out, &mut ranges_now)?;
        if g0 + 1 < rows {
            next = Some(src.read_rows(rows_of(grid, g0 + 1))?);
        }
    }
    drop(tx);
    drain(n, w, &mut *out, &mut ranges_now)?;
    Ok(ranges_now)
}

/// The chunks of a tiled file written in order: `HEAD`, `mETA`, `TRAT` and `TIDX`
/// (zeroed) from the first tile's coded file, then each tile's `TILE` chunk.
struct TileWriter<'a> {
    grid: &'a Grid,
    shape: &'a Shape,
    /// Where `HEAD` is and the file's header (its range set at the end).
    head: Option<(u64, Header)>,
    /// The step ratios of each tile class when the tiles are compact (lossy, 2.2).
    ratios: Option<Ratios>,
    index_at: u64,
    index: Vec<u8>,
    /// The byte the next chunk starts at.
    at: u64,
}

impl TileWriter<'_> {
    /// Write tile `i` from its coded one-tile file `c` (tile 0 first).
    fn put<W: Write>(&mut self, out: &mut W, i: usize, c: &[u8]) -> Result<()> {
        let (grid, n) = (self.grid, self.grid.len());
        if self.head.is_none() {
            // the tiles' common fields from the first tile's HEAD (after the signature)
            let mut h = head_of(c)?;
            h.version = format::Version::for_tiled(h.mode == Mode::Lossy);
            h.dims = self.shape.dims.clone();
            h.tile = grid.tile.clone();
            let head_at = self.at;
            self.at += write_chunk(out, HEAD, &[&h.to_bytes()])?;
            let m = meta::to_bytes(&self.shape.meta);
            if !m.is_empty() {
                self.at += write_chunk(out, META, &[&m])?;
            }
            if h.mode == Mode::Lossy {
                let r = Ratios::of(&h, grid)?;
                self.at += write_chunk(out, TRAT, &[&r.to_bytes()])?;
                self.ratios = Some(r);
            }
            self.index_at = self.at;
            self.at += write_chunk(out, TIDX, &[&vec![0u8; 16 * n]])?;
            self.head = Some((head_at, h));
        }
        let h = &self.head.as_ref().expect("the head is written first").1;
        let body = match &self.ratios {
            Some(r) => std::borrow::Cow::Owned(compact::tile_body(c, h, grid, r, i)),
            None => std::borrow::Cow::Borrowed(&c[format::SIGNATURE.len()..]),
        };
        let bytes = write_chunk(out, TILE, &[&tile_prefix(i), &body])?;
        put_index_entry(&mut self.index, self.at, bytes);
        self.at += bytes;
        Ok(())
    }
}

/// The error of a slab's coding thread that ended without its result.
fn stopped() -> Error {
    Error::Io(std::io::Error::other("a tile slab's coder stopped"))
}

/// The coded one-tile file of tile `i` of the slab `slab` (rows from `row0`), and the
/// range of its samples when `measure` (before its voids are filled).
#[allow(clippy::too_many_arguments)]
fn code_tile(
    grid: &Grid,
    shape: &Shape,
    slab: &Samples,
    row0: usize,
    i: usize,
    coding: Coding,
    opts: &EncodeOptions,
    measure: bool,
) -> Result<(Vec<u8>, Ranges)> {
    let t = cut_tile(grid, shape, slab, row0, i)?;
    let mut got = Ranges::new();
    if measure {
        got.add_range(&t.samples, 0..t.samples.len());
    }
    let t = with_voids_filled(&t.view(), opts.keeps_bits())?.unwrap_or(t);
    let c = match coding {
        Coding::Own => encode_filled(&t.view(), opts)?,
        Coding::Step { step, rdo } => {
            let mut p = prepare(&t.view(), opts, Mode::Lossy)?;
            if rdo {
                p.optimise();
            }
            p.code(step)
        }
    };
    Ok((c, got))
}

/// The base step of `--psnr` and `--bpp` for the whole raster (`n` tiles): a search on
/// `x = ln step` over the sampled tiles, each candidate measured on all of them at
/// once: the PSNR of their summed squared error (peak `peak`), or their bits over their
/// positions (with their share of the bytes outside the tiles).
fn search_step(
    shape: &Shape,
    grid: &Grid,
    n: usize,
    sample: Vec<Raster>,
    opts: &EncodeOptions,
    range: f64,
    peak: f64,
) -> Result<f64> {
    let positions: f64 = sample.iter().map(|t| t.positions() as f64).sum();
    // the tiles' samples are kept for the PSNR only (a tile goes as soon as it is prepared)
    let keep = !matches!(opts.rate, Rate::Bpp(_));
    let prepared: Vec<(Option<Raster>, Prepared)> = sample
        .into_par_iter()
        .map(|t| {
            let mut p = prepare(&t.view(), opts, Mode::Lossy)?;
            p.optimise();
            Ok((keep.then_some(t), p))
        })
        .collect::<Result<_>>()?;
    // the bytes outside the tiles' compact bodies (signature, HEAD, mETA, TRAT, TIDX,
    // TILE framing and index, MEND), the sample's share of them
    let bands = prepared.first().map_or(0, |p| p.1.plan.bands.len());
    let outside = format::tiles::outside_bytes(
        shape.dims.len(),
        meta::to_bytes(&shape.meta).len(),
        grid.classes().len() * bands * shape.channels,
        n,
    );
    let outside = outside as f64 * positions / shape.positions() as f64;
    match opts.rate {
        Rate::Bpp(b) => {
            // the bytes of the tiles alone: the sample's rasters are not needed
            let prepared: Vec<Prepared> = prepared.into_iter().map(|(_, p)| p).collect();
            // met (≥ 0) within the budget; within 1% under it below −ln 0.99
            search(range, true, -(0.99f64.ln()), |step| {
                let bytes: usize = prepared
                    .par_iter()
                    .map(|p| compact::compact_len(&p.code(step)))
                    .sum();
                Ok(b.ln() - ((bytes as f64 + outside) * 8.0 / positions).ln())
            })
        }
        Rate::Psnr(db) | Rate::PsnrRange(db, _) => {
            let count = positions * shape.channels as f64;
            search(range, false, 0.02, |step| {
                let sse = prepared
                    .par_iter()
                    .map(|(t, p)| {
                        let t = t.as_ref().expect("kept for the PSNR");
                        let d = p.decoded(step)?;
                        let (a, b) = (t.samples.to_f64(), d.samples.to_f64());
                        Ok(a.iter()
                            .zip(&b)
                            .filter(|(x, _)| x.is_finite())
                            .map(|(x, y)| (x - y) * (x - y))
                            .sum::<f64>())
                    })
                    .collect::<Result<Vec<f64>>>()?
                    .iter()
                    .sum::<f64>();
                if sse == 0.0 {
                    return Ok(f64::INFINITY);
                }
                Ok(10.0 * (peak * peak * count / sse).log10() - db)
            })
        }
        _ => unreachable!("search_step is for --psnr and --bpp"),
    }
}

/// Search on `x = ln step` for the step whose `v = f(step)` is closest to 0 from above
/// (`v ≥ 0`: target met; met for large steps when `large_ok`, for small ones otherwise):
/// steps of doubling size until the target is bracketed, then the secant between the
/// bracket's ends kept inside its middle half (the bracket shrinks by at least a quarter
/// each time); stops at a met step within `tol` or a bracket under 0.1% of the step.
pub(in crate::codec) fn search(
    range: f64,
    large_ok: bool,
    tol: f64,
    f: impl Fn(f64) -> Result<f64>,
) -> Result<f64> {
    let (x_min, x_max) = ((range * 1e-7).ln(), (range * 4.0).ln());
    let mut met: Option<(f64, f64)> = None;
    let mut unmet: Option<(f64, f64)> = None;
    let mut x = (range / 32.0).ln();
    let mut jump = 1.0;
    for _ in 0..48 {
        let v = f(x.exp())?;
        if v >= 0.0 {
            if v <= tol {
                return Ok(x.exp());
            }
            met = Some((x, v));
        } else {
            unmet = Some((x, v));
        }
        x = match (met, unmet) {
            (Some((xm, vm)), Some((xu, vu))) => {
                let (lo, hi) = (xm.min(xu), xm.max(xu));
                if hi - lo < 1e-3 {
                    break;
                }
                let t = if vm.is_finite() {
                    xm + (vm - 0.5 * tol) * (xu - xm) / (vm - vu)
                } else {
                    0.5 * (lo + hi)
                };
                t.clamp(lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo))
            }
            _ => {
                // toward the other side: larger steps when met and small steps are not
                // the met side, …
                let toward_large = (v >= 0.0) != large_ok;
                let next = (x + if toward_large { jump } else { -jump }).clamp(x_min, x_max);
                jump *= 2.0;
                if next == x {
                    break;
                }
                next
            }
        };
    }
    Ok(match met {
        Some((x, _)) => x.exp(),
        None if large_ok => x_max.exp(),
        None => x_min.exp(),
    })
}
