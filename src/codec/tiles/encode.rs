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

use super::compact::{self, Ratios, TRAT};
use super::{crop_samples, Grid, SEARCH_SAMPLE_TILES, TIDX, TILE};
use crate::codec::container::{HEAD, MEND, META};
use crate::codec::encode::encode_filled;
#[cfg(doc)]
use crate::codec::lossy::finite_range;
use crate::codec::lossy::{prepare, Prepared};
use crate::codec::meta;
use crate::codec::options::{EncodeOptions, Rate};
use crate::codec::voids::with_voids_filled;
use crate::format::{self, write_chunk, Header, Mode};
use crate::io::slab::{Shape, SlabSource};
use crate::io::{Raster, Samples};
use crate::quantize::{self, RHO};
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

/// The tiles of the slab of grid row `g0` (tiles `g0·per_row ..`), each cut from `slab`
/// (the rows of that grid row), its voids filled in the tile.
fn slab_tile(grid: &Grid, shape: &Shape, slab: &Samples, row0: usize, i: usize) -> Result<Raster> {
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
    Ok(with_voids_filled(&t.view())?.unwrap_or(t))
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
    let shape = src.shape().clone();
    let grid = Grid::new(&shape.dims, tile)?;
    let n = grid.len();
    let rows = grid.counts[0];
    let per_row = n / rows;
    let rows_of = |g0: usize| g0 * grid.tile[0]..g0 * grid.tile[0] + grid.extent(0, g0);
    match opts.rate {
        Rate::Quality(q) if !(1.0..=100.0).contains(&q) => {
            return Err(Error::parameter("quality", q, "1 to 100"))
        }
        Rate::Keep(k) if !(0.0..=100.0).contains(&k) => {
            return Err(Error::parameter("keep", k, "a percentage from 0 to 100"))
        }
        Rate::Bpp(b) if !(b > 0.0 && b.is_finite()) => {
            return Err(Error::parameter(
                "bpp",
                b,
                "a positive number of bits per position",
            ))
        }
        Rate::Psnr(db) | Rate::PsnrRange(db, _) if !(db > 0.0 && db < 400.0) => {
            return Err(Error::parameter(
                "psnr",
                db,
                "a target in dB between 0 and 400",
            ))
        }
        Rate::PsnrRange(_, p) if !(p.is_finite() && p > 0.0) => {
            return Err(Error::parameter(
                "data range",
                p,
                "a positive, finite peak-to-peak range",
            ))
        }
        _ => {}
    }
    let sampled = matches!(
        opts.rate,
        Rate::Keep(_) | Rate::Psnr(_) | Rate::PsnrRange(..) | Rate::Bpp(_)
    );
    let first_pass = sampled || matches!(opts.rate, Rate::Quality(_));
    let every = n.div_ceil(SEARCH_SAMPLE_TILES).max(1);
    let mut ranges = Ranges::new();
    let mut sample: Vec<Raster> = Vec::new();
    // with more than one thread the next slab is read while this one is measured and
    // coded
    let ahead = rayon::current_num_threads() > 1;
    if first_pass {
        let mut next = Some(src.read_rows(rows_of(0))?);
        for g0 in 0..rows {
            let r = rows_of(g0);
            let slab = match next.take() {
                Some(s) => s,
                None => src.read_rows(r.clone())?,
            };
            let job = || -> Result<(Ranges, Vec<Raster>)> {
                let mut got = Ranges::new();
                got.add(&slab);
                let mine: Vec<usize> = (g0 * per_row..(g0 + 1) * per_row)
                    .filter(|i| sampled && i % every == 0)
                    .collect();
                let tiles: Vec<Raster> = mine
                    .par_iter()
                    .map(|&i| slab_tile(&grid, &shape, &slab, r.start, i))
                    .collect::<Result<_>>()?;
                Ok((got, tiles))
            };
            let (got, tiles) = if ahead && g0 + 1 < rows {
                let (got, read) = std::thread::scope(|s| {
                    let measuring = s.spawn(job);
                    let read = src.read_rows(rows_of(g0 + 1));
                    (measuring.join(), read)
                });
                next = Some(read?);
                got.map_err(|_| stopped())??
            } else {
                job()?
            };
            ranges.merge(&got);
            sample.extend(tiles);
        }
    }
    let (lo, hi) = ranges.finite();
    let range = (hi - lo).max(1e-30);
    let coding = match opts.rate {
        Rate::Lossless | Rate::MaxError(_) | Rate::Threshold(_) => Coding::Own,
        Rate::Quality(q) => Coding::Step {
            step: range * (2f64).powf(-q / 10.0),
            rdo: true,
        },
        Rate::Keep(k) => {
            // the threshold of the largest k% over the sampled tiles' details
            let mut w: Vec<f32> = sample
                .par_iter()
                .map(|t| Ok(prepare(&t.view(), opts, Mode::Lossy)?.weighted_details()))
                .collect::<Result<Vec<_>>>()?
                .concat();
            let t = quantize::keep_threshold(&mut w, k);
            let step = if t.is_infinite() {
                range * 1e6
            } else {
                (t / (1.0 - RHO)).max(range * 1e-9)
            };
            Coding::Step { step, rdo: false }
        }
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
            let step = search_step(
                &shape,
                &grid,
                n,
                std::mem::take(&mut sample),
                opts,
                range,
                peak,
            )?;
            Coding::Step { step, rdo: true }
        }
    };
    drop(sample);

    // HEAD, mETA and TIDX are reserved when the first slab is coded, and rewritten at
    // the end with the raster's range and the tiles' places
    let start = out.stream_position()?;
    out.write_all(&format::SIGNATURE)?;
    let mut head: Option<(u64, Header)> = None;
    // the step ratios of each tile class when the tiles are compact (lossy files, 2.2)
    let mut ratios: Option<Ratios> = None;
    let mut index_at = 0u64;
    let mut index = Vec::with_capacity(16 * n);
    let mut at = start + 8;
    let mut ranges_now = Ranges::new();
    let mut next = Some(src.read_rows(rows_of(0))?);
    for g0 in 0..rows {
        let r = rows_of(g0);
        let slab = match next.take() {
            Some(s) => s,
            None => src.read_rows(r.clone())?,
        };
        if !first_pass {
            ranges_now.add(&slab);
        }
        let mine: Vec<usize> = (g0 * per_row..(g0 + 1) * per_row).collect();
        let job = || code_slab(&grid, &shape, &slab, r.start, &mine, coding, opts);
        let coded = if ahead && g0 + 1 < rows {
            let (coded, read) = std::thread::scope(|s| {
                let coding = s.spawn(job);
                let read = src.read_rows(rows_of(g0 + 1));
                (coding.join(), read)
            });
            next = Some(read?);
            coded.map_err(|_| stopped())??
        } else {
            job()?
        };
        drop(slab);
        if head.is_none() {
            // the tiles' common fields from the first tile's HEAD (after the signature)
            let first = &coded[0];
            let hl = u32::from_le_bytes(first[8..12].try_into().unwrap()) as usize;
            let mut h = Header::parse(&first[16..16 + hl])?;
            h.minor = if h.mode == Mode::Lossy {
                format::MINOR_COMPACT
            } else {
                format::MINOR_TILED
            };
            h.dims = shape.dims.clone();
            h.tile = grid.tile.clone();
            at += write_chunk(out, HEAD, &[&h.to_bytes()])?;
            let m = meta::to_bytes(&shape.meta);
            if !m.is_empty() {
                at += write_chunk(out, META, &[&m])?;
            }
            if h.mode == Mode::Lossy {
                let r = Ratios::of(&h, &grid)?;
                at += write_chunk(out, TRAT, &[&r.to_bytes()])?;
                ratios = Some(r);
            }
            index_at = at;
            at += write_chunk(out, TIDX, &[&vec![0u8; 16 * n]])?;
            head = Some((start + 8, h));
        }
        let h = &head.as_ref().expect("the head is written first").1;
        for (&i, c) in mine.iter().zip(&coded) {
            let body = match &ratios {
                Some(r) => std::borrow::Cow::Owned(compact::tile_body(c, h, &grid, r, i)),
                None => std::borrow::Cow::Borrowed(&c[8..]),
            };
            let bytes = write_chunk(out, TILE, &[&(i as u32).to_le_bytes(), &body])?;
            index.extend_from_slice(&at.to_le_bytes());
            index.extend_from_slice(&bytes.to_le_bytes());
            at += bytes;
        }
    }
    at += write_chunk(out, MEND, &[])?;
    let (head_at, mut h) = head.ok_or_else(|| Error::parameter("tile", 0, "a tile"))?;
    (h.min, h.max) = if first_pass {
        ranges.finite()
    } else {
        ranges_now.finite()
    };
    out.seek(SeekFrom::Start(head_at))?;
    write_chunk(out, HEAD, &[&h.to_bytes()])?;
    out.seek(SeekFrom::Start(index_at))?;
    write_chunk(out, TIDX, &[&index])?;
    out.seek(SeekFrom::Start(at))?;
    out.flush()?;
    Ok(at - start)
}

/// The error of a slab's coding thread that ended without its result.
fn stopped() -> Error {
    Error::Io(std::io::Error::other("a tile slab's coder stopped"))
}

/// The coded one-tile files of tiles `mine` of the slab `slab` (rows from `row0`), in
/// parallel.
fn code_slab(
    grid: &Grid,
    shape: &Shape,
    slab: &Samples,
    row0: usize,
    mine: &[usize],
    coding: Coding,
    opts: &EncodeOptions,
) -> Result<Vec<Vec<u8>>> {
    mine.par_iter()
        .map(|&i| {
            let t = slab_tile(grid, shape, slab, row0, i)?;
            match coding {
                Coding::Own => encode_filled(&t.view(), opts),
                Coding::Step { step, rdo } => {
                    let mut p = prepare(&t.view(), opts, Mode::Lossy)?;
                    if rdo {
                        p.optimise();
                    }
                    Ok(p.code(step))
                }
            }
        })
        .collect()
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
    let ratios = 4 * grid.classes().len() * bands * shape.channels;
    let outside = 8
        + 12
        + 52
        + 8 * shape.dims.len()
        + {
            let m = meta::to_bytes(&shape.meta).len();
            if m > 0 {
                12 + m
            } else {
                0
            }
        }
        + 12
        + ratios
        + 12
        + 16 * n
        + (12 + 4) * n
        + 12;
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
fn search(range: f64, large_ok: bool, tol: f64, f: impl Fn(f64) -> Result<f64>) -> Result<f64> {
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
