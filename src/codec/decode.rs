//! Decoding: the chunks read, each channel's bands entropy-decoded level by level,
//! dequantized and synthesized (or the integer transform inverted), the residual layer
//! added, and the metadata and voids of the level decoded.

use super::colour::map3;
use super::container::{read_head, read_rest, Parsed};
use super::int_window::IntWindow;
use super::options::{DecodeOptions, Decoded};
use super::plan::Plan;
use super::plan::{band_delta, band_rows, dequantize_row, lossy_values};
use super::support::band_windows;
use super::voids::mark_voids;
use super::window_decode;
use super::{layout, lossless};
use crate::entropy::codeblocks::Grid;
use crate::entropy::range::Decoder;
use crate::entropy::{self, BandKind, Parent};
use crate::format::header::Colour;
use crate::format::Header;
use crate::format::Mode;
use crate::io::{Raster, SampleType, Samples};
use crate::scheme::Scheme;
use crate::{Error, Result};
use rayon::prelude::*;
use std::io::Read;
use std::ops::Range;

/// Whether a band is decoded whole into a buffer before dequantizing: every band of a
/// format 1 file and of a code-block file, the coarse block, and a band whose values are
/// a finer band's parent context; the others are dequantized row by row as they decode.
fn decoded_whole(h: &Header, level: usize, is_parent: bool) -> bool {
    !h.version.has_levels() || h.version.has_blocks() || level == 0 || is_parent
}

/// The band kind of a level: the coarse block at level 0, details above.
fn kind_of(level: usize) -> BandKind {
    if level == 0 {
        BandKind::Coarse
    } else {
        BandKind::Detail
    }
}

/// One band's indices from its coded bytes, by the coding of the file of header `h`. In
/// format 3 (formats/MRA.md §15) the code-block index (blocks of extents `block`) is parsed and the blocks `window`
/// meets (every block without one) are decoded, in parallel, into their boxes of the band.
fn decode_band(
    h: &Header,
    data: &[u8],
    dims: &[usize],
    block: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
    window: Option<&[Range<usize>]>,
) -> Result<Vec<i64>> {
    let coding = super::plan::coding_of(h);
    if !h.version.has_blocks() && h.version.has_levels() {
        return entropy::band::decode(&mut Decoder::new_short(data), dims, kind, parent, coding);
    }
    if !h.version.has_blocks() {
        return entropy::decode_band(data, dims, kind, parent);
    }
    let (grid, which, streams) = block_streams(data, dims, block, window)?;
    let mut v = vec![0i64; dims.iter().product()];
    let coder = super::plan::coder_of(h);
    entropy::codeblocks::decode_blocks(
        &mut v, &grid, &which, &streams, kind, parent, coding, coder,
    )?;
    Ok(v)
}

/// A band's code-block grid, the blocks to decode and their streams.
type BlockStreams<'d> = (Grid, Vec<usize>, Vec<&'d [u8]>);

/// The code-block grid (blocks of extents `block`) of a band of a code-block file (format 3), the blocks `window`
/// meets (every block without one) and their streams in `data`.
fn block_streams<'d>(
    data: &'d [u8],
    dims: &[usize],
    block: &[usize],
    window: Option<&[Range<usize>]>,
) -> Result<BlockStreams<'d>> {
    let set = crate::format::bands::parse_blocks(data, dims, block)?;
    let grid = Grid::new(dims, block);
    let which: Vec<usize> = match window {
        Some(w) => grid.touching(w),
        None => (0..grid.len()).collect(),
    };
    let streams = which
        .iter()
        .map(|&i| &data[set.streams[i].clone()])
        .collect();
    Ok((grid, which, streams))
}

/// A band of a code-block file decoded and dequantized straight into its `rows` of a
/// plane (`x = dequantize(q, step, δ)`), only the blocks `window` meets (the others'
/// positions stay as they are): the samples of [`decode_band`] then
/// [`dequantize_band`], without the band of `i64` indices between them.
fn decode_band_into(
    h: &Header,
    data: &[u8],
    (dims, block): (&[usize], &[usize]),
    (kind, parent): (BandKind, Option<Parent>),
    window: Option<&[Range<usize>]>,
    (step, delta): (f64, f64),
    rows: Vec<&mut [f32]>,
) -> Result<()> {
    let put = super::plan::dequantizing_put(step, delta);
    decode_band_by(h, data, (dims, block), (kind, parent), window, rows, &put)
}

/// The code-blocks of a band (those `window` meets, or all) decoded into its `rows`
/// through `put` (the shared body of [`decode_band_into`] and [`decode_band_narrow`]).
fn decode_band_by<T, W, N>(
    h: &Header,
    data: &[u8],
    (dims, block): (&[usize], &[usize]),
    (kind, parent): (BandKind, Option<Parent>),
    window: Option<&[Range<usize>]>,
    rows: Vec<&mut [T]>,
    put: &entropy::codeblocks::Put<W, N>,
) -> Result<()>
where
    T: Send,
    W: Fn(&mut [T], &[i64]) + Sync,
    N: Fn(&mut [T], &[i32]) + Sync,
{
    let (grid, which, streams) = block_streams(data, dims, block, window)?;
    let (coding, coder) = (super::plan::coding_of(h), super::plan::coder_of(h));
    entropy::codeblocks::decode_blocks_into(
        rows,
        &grid,
        &which,
        &streams,
        (kind, parent),
        coding,
        coder,
        put,
    )
}

/// The code-blocks of a band of a lossless code-block file decoded straight into its
/// `rows` of an `i32` plane ([`decode_band_into`]'s way: the blocks `window` meets, the
/// others left as they are): a narrow coder's indices copied, the context coder's
/// stored when they fit. False when an index does not fit 32 bits.
fn decode_band_narrow(
    h: &Header,
    data: &[u8],
    (dims, block): (&[usize], &[usize]),
    (kind, parent): (BandKind, Option<Parent>),
    window: Option<&[Range<usize>]>,
    rows: Vec<&mut [i32]>,
) -> Result<bool> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let fits = AtomicBool::new(true);
    let put = entropy::codeblocks::Put {
        wide: |o: &mut [i32], v: &[i64]| {
            if !narrow_row(v, o) {
                fits.store(false, Ordering::Relaxed);
            }
        },
        narrow: |o: &mut [i32], v: &[i32]| o.copy_from_slice(v),
    };
    decode_band_by(h, data, (dims, block), (kind, parent), window, rows, &put)?;
    Ok(fits.into_inner())
}

/// The parent of band `j` of channel `c` from `held` (a band number and its indices):
/// none for a band without one, an error when `held` is not its parent.
fn parent_of<'a>(
    plan: &'a Plan,
    j: usize,
    c: usize,
    held: Option<(usize, &'a [i64])>,
) -> Result<Option<Parent<'a>>> {
    let Some(pj) = plan.parents[j] else {
        return Ok(None);
    };
    match held {
        Some((at, v)) if at == pj => Ok(Some(Parent {
            data: v,
            dims: &plan.dims[pj],
        })),
        _ => Err(Error::format(
            format!("band {j} of channel {c} without its parent"),
            "complete parents",
        )),
    }
}

/// Decode one channel's bands into its coefficient indices (None = absent). A band's
/// context is its parent band (one level coarser), so the bands of one level decode
/// in parallel, level after level from the coarse block down.
pub(super) fn decode_channel(p: &Parsed, c: usize, k: usize) -> Result<Vec<Option<Vec<i64>>>> {
    let plan = &p.plan;
    let wins = band_windows(p, k);
    let nb = plan.bands.len();
    let mut q: Vec<Option<Vec<i64>>> = (0..nb).map(|_| None).collect();
    let mut levels: Vec<usize> = plan.bands.iter().map(|b| b.level).collect();
    levels.sort_unstable_by_key(|&l| (l != 0, std::cmp::Reverse(l)));
    levels.dedup();
    for level in levels {
        if k > 0 && level >= 1 && level <= k {
            continue;
        }
        let bands: Vec<usize> = (0..nb).filter(|&j| plan.bands[j].level == level).collect();
        let decoded: Vec<Result<Option<Vec<i64>>>> = bands
            .par_iter()
            .map(|&j| {
                let Some(bc) = &p.bands[c][j] else {
                    return Ok(None);
                };
                let kind = if level == 0 {
                    BandKind::Coarse
                } else {
                    BandKind::Detail
                };
                let held = plan.parents[j].and_then(|pj| q[pj].as_deref().map(|v| (pj, v)));
                let parent = parent_of(plan, j, c, held)?;
                decode_band(
                    &p.header,
                    &bc.data,
                    &plan.dims[j],
                    plan.block(j),
                    kind,
                    parent,
                    wins[j].as_deref(),
                )
                .map(Some)
                .map_err(|e| Error::format(format!("band {j} of channel {c}: {e}"), "a valid band"))
            })
            .collect();
        // the first failing band in file order, as one at a time would report it
        for (&j, v) in bands.iter().zip(decoded) {
            q[j] = v?;
        }
    }
    Ok(q)
}

/// A chain of bands ([`Plan::chains`]) and the rows of each in a plane.
type ChainRows<'a, 'p> = (&'a Vec<usize>, Vec<Vec<&'p mut [f32]>>);

/// Decode one channel's bands of a lossy file straight into its `plane` (laid out as the
/// pyramid's shape, zeroed; absent bands stay 0), dequantized as they are decoded. The
/// bands go chain by chain ([`Plan::chains`]: an orientation's bands from the coarsest
/// level down, each the context of the next), the chains in parallel, so that only the
/// indices of the bands in flight and their parents are held, not those of a whole
/// level; a band without children is decoded a row at a time
/// ([`entropy::band::decode_rows`]) straight into the plane. Of several failing bands
/// the first in file order is reported, as a decoder going level by level would.
fn decode_channel_into(p: &Parsed, c: usize, k: usize, plane: &mut [f32]) -> Result<()> {
    let (h, plan) = (&p.header, &p.plan);
    let wins = band_windows(p, k);
    let nb = plan.bands.len();
    let has_children: Vec<bool> = (0..nb).map(|j| plan.parents.contains(&Some(j))).collect();
    let skipped = |j: usize| {
        let level = plan.bands[j].level;
        k > 0 && level >= 1 && level <= k
    };
    let chains: Vec<Vec<usize>> = plan
        .chains()
        .into_iter()
        .map(|ch| ch.into_iter().filter(|&j| !skipped(j)).collect::<Vec<_>>())
        .filter(|ch| !ch.is_empty())
        .collect();
    let all: Vec<usize> = chains.iter().flatten().copied().collect();
    let mut rows = band_rows(plan, &all, plane).into_iter();
    // each chain with the row slices of its bands
    let work: Vec<ChainRows> = chains
        .iter()
        .map(|ch| (ch, rows.by_ref().take(ch.len()).collect()))
        .collect();
    // position of each band in the file: the levels' order, then the bands'
    let mut order = vec![0usize; nb];
    for (i, j) in plan
        .level_groups()
        .into_iter()
        .flat_map(|(_, js)| js)
        .enumerate()
    {
        order[j] = i;
    }
    let failures: Vec<(usize, Error)> = work
        .into_par_iter()
        .filter_map(|(chain, band_rows)| {
            // the indices of the band before in the chain, when it has children
            let mut prev: Option<(usize, Vec<i64>)> = None;
            for (&j, mut rows) in chain.iter().zip(band_rows) {
                let failed = |e: Error| {
                    Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
                };
                let level = plan.bands[j].level;
                let Some(bc) = &p.bands[c][j] else {
                    prev = None;
                    continue;
                };
                let held = prev.as_ref().map(|(at, v)| (*at, v.as_slice()));
                let parent = match parent_of(plan, j, c, held) {
                    Ok(p) => p,
                    Err(e) => return Some((j, e)),
                };
                let (step, delta) = (bc.step, band_delta(h, plan, j));
                let dims = &plan.dims[j];
                if h.version.has_blocks() && !has_children[j] {
                    let at = (kind_of(level), parent);
                    let done = decode_band_into(
                        h,
                        &bc.data,
                        (dims, plan.block(j)),
                        at,
                        wins[j].as_deref(),
                        (step, delta),
                        rows,
                    );
                    if let Err(e) = done {
                        return Some((j, failed(e)));
                    }
                    prev = None;
                    continue;
                }
                if decoded_whole(h, level, has_children[j]) {
                    let v = match decode_band(
                        h,
                        &bc.data,
                        dims,
                        plan.block(j),
                        kind_of(level),
                        parent,
                        wins[j].as_deref(),
                    ) {
                        Ok(v) => v,
                        Err(e) => return Some((j, failed(e))),
                    };
                    dequantize_band(
                        &v,
                        dims,
                        decoded_box(dims, plan.block(j), wins[j].as_deref()),
                        (step, delta),
                        &mut rows,
                    );
                    prev = has_children[j].then_some((j, v));
                    continue;
                }
                let mut d = Decoder::new_short(&bc.data);
                let mut at_row = 0;
                let done = entropy::band::decode_rows(&mut d, dims, parent, plan.coding, |_, r| {
                    dequantize_row(r, step, delta, rows[at_row]);
                    at_row += 1;
                });
                if let Err(e) = done {
                    return Some((j, failed(e)));
                }
                prev = None;
            }
            None
        })
        .collect();
    match failures.into_iter().min_by_key(|(j, _)| order[*j]) {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

/// The box of a band of extents `dims` and code-blocks `block` that a decode of its window `w` fills: the
/// code-blocks `w` meets ([`band_windows`]), `None` for the whole band.
fn decoded_box(
    dims: &[usize],
    block: &[usize],
    w: Option<&[Range<usize>]>,
) -> Option<Vec<Range<usize>>> {
    let w = w?;
    (w.len() == dims.len() && block.len() == dims.len()).then(|| {
        w.iter()
            .zip(block)
            .zip(dims)
            .map(|((r, &b), &e)| {
                let b = b.max(1);
                (r.start / b * b).min(e)..r.end.div_ceil(b).saturating_mul(b).min(e)
            })
            .collect()
    })
}

/// The indices `v` of a band of extents `dims` dequantized into its `rows` of a plane
/// (`x = dequantize(q, step, δ)`), only over the box `bx` when given (the positions
/// outside stay as they are).
fn dequantize_band(
    v: &[i64],
    dims: &[usize],
    bx: Option<Vec<Range<usize>>>,
    (step, delta): (f64, f64),
    rows: &mut [&mut [f32]],
) {
    let cols = dims.last().copied().unwrap_or(1).max(1);
    match bx {
        Some(bx) => layout::rows(dims, &bx, |at, len, _| {
            let (g, c0) = (at / cols, at % cols);
            dequantize_row(&v[at..at + len], step, delta, &mut rows[g][c0..c0 + len]);
        }),
        None => {
            for (r, out) in v.chunks(cols).zip(rows.iter_mut()) {
                dequantize_row(r, step, delta, out);
            }
        }
    }
}

/// Decode one channel's bands of a lossless file of 8- or 16-bit samples straight into
/// its `i32` plane (laid out as the pyramid's shape, zeroed; absent bands stay 0), level
/// by level from the coarse block down, as [`decode_channel`] decodes them. A band's
/// parent is copied out of the plane while the band is decoded (the bands of a level go
/// a pool's width at a time, so that only that many parents are held); a band without
/// children is decoded a row at a time ([`entropy::band::decode_rows`]). False when an
/// index does not fit 32 bits (the plane then holds garbage).
fn decode_channel_narrow(p: &Parsed, c: usize, k: usize, plane: &mut [i32]) -> Result<bool> {
    let (h, plan) = (&p.header, &p.plan);
    let wins = band_windows(p, k);
    let nb = plan.bands.len();
    let has_children: Vec<bool> = (0..nb).map(|j| plan.parents.contains(&Some(j))).collect();
    let width = rayon::current_num_threads().max(1);
    let mut fits = true;
    for (level, js) in plan.level_groups() {
        if k > 0 && level >= 1 && level <= k {
            continue;
        }
        for js in js.chunks(width) {
            // the parents of these bands, from the plane (one level coarser: decoded)
            let parents: Vec<Option<Vec<i64>>> = js
                .iter()
                .map(|&j| {
                    let pj = plan.parents[j]?;
                    p.bands[c][pj].as_ref()?;
                    Some(widened(plane, &plan.pyr.shape, &plan.bands[pj].ranges))
                })
                .collect();
            let rows = band_rows(plan, js, plane);
            let decoded: Vec<Result<bool>> = js
                .par_iter()
                .zip(rows)
                .zip(&parents)
                .map(|((&j, mut rows), pq)| {
                    let Some(bc) = &p.bands[c][j] else {
                        return Ok(true);
                    };
                    let held = plan.parents[j].and_then(|pj| pq.as_deref().map(|v| (pj, v)));
                    let parent = parent_of(plan, j, c, held)?;
                    let dims = &plan.dims[j];
                    let failed = |e: Error| {
                        Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
                    };
                    let mut ok = true;
                    if h.version.has_blocks() {
                        let bands = (dims.as_slice(), plan.block(j));
                        let at = (kind_of(level), parent);
                        return decode_band_narrow(
                            h,
                            &bc.data,
                            bands,
                            at,
                            wins[j].as_deref(),
                            rows,
                        )
                        .map_err(failed);
                    }
                    if decoded_whole(h, level, has_children[j]) {
                        let v = decode_band(
                            h,
                            &bc.data,
                            dims,
                            plan.block(j),
                            kind_of(level),
                            parent,
                            wins[j].as_deref(),
                        )
                        .map_err(failed)?;
                        let cols = dims.last().copied().unwrap_or(1).max(1);
                        for (r, out) in v.chunks(cols).zip(rows.iter_mut()) {
                            ok &= narrow_row(r, out);
                        }
                        return Ok(ok);
                    }
                    let mut d = Decoder::new_short(&bc.data);
                    let mut at_row = 0;
                    entropy::band::decode_rows(&mut d, dims, parent, plan.coding, |_, r| {
                        ok &= narrow_row(r, rows[at_row]);
                        at_row += 1;
                    })
                    .map_err(failed)?;
                    Ok(ok)
                })
                .collect();
            // the first failing band in file order, as one at a time would report it
            for v in decoded {
                fits &= v?;
            }
            if !fits {
                return Ok(false);
            }
        }
    }
    Ok(fits)
}

/// The block `ranges` of an `i32` plane, packed and widened to `i64`.
fn widened(plane: &[i32], shape: &[usize], ranges: &[std::ops::Range<usize>]) -> Vec<i64> {
    let mut out = Vec::with_capacity(ranges.iter().map(|r| r.len()).product());
    layout::rows(shape, ranges, |off, run, _| {
        out.extend(plane[off..off + run].iter().map(|&v| v as i64))
    });
    out
}

/// `out = q` as `i32`; false when a value does not fit.
fn narrow_row(q: &[i64], out: &mut [i32]) -> bool {
    let mut ok = true;
    for (o, &v) in out.iter_mut().zip(q) {
        *o = v as i32;
        ok &= *o as i64 == v;
    }
    ok
}

/// A lossless file of 8- or 16-bit samples ([`lossless::narrow`]) decoded at level `k`
/// in `i32` planes ([`decode_channel_narrow`], [`lossless::inverse`]), and taken to the
/// sample type as the `i64` path does (YCoCg-R undone, clamped to the type's range)
/// while the planes are consumed from their ends ([`narrow_samples`]); `None` when a
/// value does not fit 32 bits (the `i64` path then decodes the file).
pub(super) fn lossless_narrow(p: &Parsed, k: usize) -> Result<Option<Samples>> {
    let (h, plan) = (&p.header, &p.plan);
    let region = plan.region(k);
    let npos: usize = region.iter().product();
    let planes = (0..h.channels)
        .into_par_iter()
        .map(|ch| {
            let mut plane = vec![0i32; plan.pyr.shape.iter().product()];
            if !decode_channel_narrow(p, ch, k, &mut plane)?
                || !lossless::inverse(&mut plane[..], &plan.pyr, k)
            {
                return Ok(None);
            }
            Ok(Some(if k == 0 {
                plane
            } else {
                let full: Vec<std::ops::Range<usize>> = region.iter().map(|&e| 0..e).collect();
                layout::gather(&plane, &plan.pyr.shape, &full)
            }))
        })
        .collect::<Result<Vec<Option<Vec<i32>>>>>()?;
    let Some(planes) = planes.into_iter().collect::<Option<Vec<_>>>() else {
        return Ok(None);
    };
    Ok(Some(narrow_samples(
        planes,
        npos,
        h.colour == Colour::YCoCgR,
        h.sample_type,
    )))
}

/// Interleaved samples of the 8- or 16-bit type `ty` from `planes` (`npos` values
/// each; the first three taken back from YCoCg-R when `ycocg`), clamped to the type's
/// range, as `Samples::from_f64` makes them from the values. The planes are consumed
/// from their ends ([`super::plan::to_samples`]'s way), so that the samples and the
/// planes are not both held whole.
fn narrow_samples(mut planes: Vec<Vec<i32>>, npos: usize, ycocg: bool, ty: SampleType) -> Samples {
    let mut out = Samples::zeros(ty, npos * planes.len());
    let mut end = npos;
    while end > 0 {
        let start = end.saturating_sub(super::plan::TAIL);
        let views: Vec<&[i32]> = planes.iter().map(|p| p.as_slice()).collect();
        lossless::interleave(&views, start..end, ycocg, &mut out);
        for p in &mut planes {
            p.truncate(start);
            p.shrink_to_fit();
        }
        end = start;
    }
    out
}

/// The most bytes [`reconstruct`] holds at once for level `k`, checked against the memory
/// budget ([`crate::limits`]) before anything is allocated:
///
/// ```text
/// bytes = C · Π shape · w  +  C · Π R_k · (s + x)
/// ```
/// with `shape` the full pyramid (every channel's plane is as large whatever the level),
/// `w` its bytes per coefficient (`wide`: 8, the `i64` planes of a lossless file of
/// samples over 16 bits; else 4: `i32` planes of 8- and 16-bit samples, or `f32`), `R_k`
/// the level's extents, `s` the sample type's bytes, and `x` = 8 where the samples also
/// pass through `f64` (the `i64` lossless path).
fn check_budget(p: &Parsed, k: usize, wide: bool) -> Result<()> {
    let (h, plan) = (&p.header, &p.plan);
    let c = h.channels as u64;
    let full = plan
        .pyr
        .shape
        .iter()
        .fold(c, |n, &e| n.saturating_mul(e as u64));
    let out = plan
        .region(k)
        .iter()
        .fold(c, |n, &e| n.saturating_mul(e as u64));
    let (w, x) = if wide { (8, 8) } else { (4, 0) };
    let bytes = full
        .saturating_mul(w)
        .saturating_add(out.saturating_mul(h.sample_type.size() as u64 + x));
    crate::limits::check("decoded bytes (memory budget MRA_MAX_BYTES)", bytes)
}

pub(super) fn reconstruct(p: &Parsed, k: usize) -> Result<Raster> {
    let h = &p.header;
    let plan = &p.plan;
    let k = k.min(plan.pyr.depth());
    let lossless = h.mode == Mode::Lossless;
    let narrow = lossless && lossless::narrow(h.sample_type);
    check_budget(p, k, lossless && !narrow)?;
    let region = plan.region(k);
    if narrow {
        if let Some(samples) = lossless_narrow(p, k)? {
            return finish(p, region, samples, k);
        }
        // a value past 32 bits (no encoder's file of 8- or 16-bit samples): i64 planes
        check_budget(p, k, true)?;
    }
    if lossless {
        return finish(p, region, lossless_wide(p, k)?, k);
    }
    let mut samples = lossy_values(h, plan, k, |ch, plane| decode_channel_into(p, ch, k, plane))?;
    if k == 0 && h.mode == Mode::MaxError {
        add_residuals(p, &mut samples)?;
    }
    finish(p, region, samples, k)
}

/// A file without voids, of non-standard pyramid, decoded at level
/// `k` over the box `out` of the level's raster alone: each channel's bands decoded
/// over the code-blocks the window needs ([`band_windows`]) into buffers of their boxes
/// ([`window_decode`]; a file before code-blocks: whole bands into a plane), then only the window's support synthesized level by level
/// ([`crate::tensor::WindowPlan`]; a lossless file's integer lifting by
/// [`IntWindow`]; a `--max-error` file's residual layer added over the window,
/// [`add_residuals_window`]). The samples are those of the same box of a
/// whole decode. `None` where this does not apply (the caller then decodes whole).
pub(super) fn reconstruct_window(
    p: &Parsed,
    k: usize,
    out: &[Range<usize>],
) -> Result<Option<Raster>> {
    let (h, plan) = (&p.header, &p.plan);
    let k = k.min(plan.pyr.depth());
    if h.voids || p.window.is_none() {
        return Ok(None);
    }
    let dims: Vec<usize> = out.iter().map(|r| r.len()).collect();
    let npos: usize = dims.iter().product();
    let mut samples = if h.mode == Mode::Lossless {
        let Some(iw) = IntWindow::new(&plan.sub(k), out) else {
            return Ok(None);
        };
        if h.version.has_blocks() {
            wide_samples(h, window_decode::lossless_window(p, k, &iw)?, npos)
        } else {
            check_budget(p, k, true)?;
            lossless_window(p, k, &iw, npos)?
        }
    } else {
        let Some(wp) = crate::tensor::WindowPlan::new(&plan.sub(k), out) else {
            return Ok(None);
        };
        let planes = if h.version.has_blocks() {
            window_decode::lossy_window(p, k, &wp)?
        } else {
            // a file before code-blocks: its bands decoded whole into the plane
            check_budget(p, k, false)?;
            (0..h.channels)
                .into_par_iter()
                .map(|ch| {
                    let mut plane = vec![0f32; plan.pyr.shape.iter().product()];
                    decode_channel_into(p, ch, k, &mut plane)?;
                    Ok(wp.synthesize(&plane, &plan.pyr.shape))
                })
                .collect::<Result<Vec<_>>>()?
        };
        super::plan::to_samples(
            planes,
            npos,
            h.colour == Colour::YCoCg,
            (h.min, h.max),
            h.sample_type,
        )
    };
    if k == 0 && h.mode == Mode::MaxError {
        add_residuals_window(p, &mut samples, out)?;
    }
    let region = plan.region(k);
    let mut r = Raster::new(dims.clone(), h.channels, samples, h.kind)?;
    let meta = if k > 0 {
        p.meta.resampled(&h.dims, &region, &coarse_maps(p, k))
    } else {
        p.meta.clone()
    };
    let crop: Vec<crate::io::AxisMap> = out
        .iter()
        .map(|g| crate::io::AxisMap::crop(g.start))
        .collect();
    r.meta = meta.resampled(&region, &dims, &crop);
    Ok(Some(r))
}

/// The window `iw` (of `npos` positions) of a lossless file at level `k`: each
/// channel's bands decoded over the code-blocks the window needs ([`decode_channel`]),
/// the window's integer inverse computed from them alone ([`IntWindow::synthesize`]),
/// and taken to the sample type as a whole decode takes its planes ([`wide_samples`]).
fn lossless_window(p: &Parsed, k: usize, iw: &IntWindow, npos: usize) -> Result<Samples> {
    let plan = &p.plan;
    let planes = (0..p.header.channels)
        .into_par_iter()
        .map(|ch| {
            let q = decode_channel(p, ch, k)?;
            let coef = |pos: &[usize]| -> i64 {
                for (j, b) in plan.bands.iter().enumerate() {
                    if b.level >= 1 && b.level <= k {
                        continue;
                    }
                    if pos.iter().zip(&b.ranges).all(|(x, r)| r.contains(x)) {
                        let Some(v) = &q[j] else {
                            return 0;
                        };
                        let mut at = 0;
                        for (x, r) in pos.iter().zip(&b.ranges) {
                            at = at * r.len() + (x - r.start);
                        }
                        return v[at];
                    }
                }
                0
            };
            Ok(iw.synthesize(&coef))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(wide_samples(&p.header, planes, npos))
}

/// A lossless file decoded at level `k` in `i64` planes: every sample type (floats as
/// their mapped bit patterns or multiples of the quantum).
pub(super) fn lossless_wide(p: &Parsed, k: usize) -> Result<Samples> {
    let (h, plan) = (&p.header, &p.plan);
    let region = plan.region(k);
    let npos: usize = region.iter().product();
    let c = h.channels;
    let planes = (0..c)
        .into_par_iter()
        .map(|ch| {
            let q = decode_channel(p, ch, k)?;
            let mut plane = vec![0i64; plan.pyr.shape.iter().product()];
            for (j, b) in q.iter().enumerate() {
                if let Some(b) = b {
                    layout::scatter(&mut plane, &plan.pyr.shape, &plan.bands[j].ranges, b);
                }
            }
            lossless::inverse(&mut plane[..], &plan.pyr, k);
            let full: Vec<std::ops::Range<usize>> = region.iter().map(|&e| 0..e).collect();
            Ok(layout::gather(&plane, &plan.pyr.shape, &full))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(wide_samples(h, planes, npos))
}

/// The samples of a lossless file of header `h` from its `i64` planes of `npos`
/// values each: YCoCg-R undone, floats from their mapped bit patterns or multiples of
/// the quantum, integers clamped to the type's range.
fn wide_samples(h: &Header, mut planes: Vec<Vec<i64>>, npos: usize) -> Samples {
    let (c, ty) = (h.channels, h.sample_type);
    if h.colour == Colour::YCoCgR {
        map3(&mut planes, lossless::ycocg_r_inv);
    }
    match ty {
        SampleType::F16 | SampleType::F32 | SampleType::F64 if h.delta > 0.0 => {
            // mode 3: integer multiples of the quantum δ, exact in the sample type
            let values: Vec<f64> = (0..npos * c)
                .map(|i| planes[i % c][i / c] as f64 * h.delta)
                .collect();
            Samples::from_f64(&values, ty)
        }
        SampleType::F16 | SampleType::F32 | SampleType::F64 => {
            let w = (ty.size() * 8) as u32;
            let bits: Vec<u64> = (0..npos * c)
                .map(|i| lossless::int_to_float_bits(planes[i % c][i / c], w))
                .collect();
            match ty {
                SampleType::F16 => Samples::F16(
                    bits.iter()
                        .map(|&b| half::f16::from_bits(b as u16))
                        .collect(),
                ),
                SampleType::F32 => {
                    Samples::F32(bits.iter().map(|&b| f32::from_bits(b as u32)).collect())
                }
                _ => Samples::F64(bits.iter().map(|&b| f64::from_bits(b)).collect()),
            }
        }
        _ => {
            let values: Vec<f64> = (0..npos * c).map(|i| planes[i % c][i / c] as f64).collect();
            Samples::from_f64(&values, ty)
        }
    }
}

/// The residual layer of a `--max-error` file added to its decoded base `samples` in
/// place: each channel's `RESI` indices decoded a row at a time and every sample set to
/// `x̂ + q·s` taken to the sample type (as `Samples::from_f64` does: integers rounded and
/// clamped), the samples of a channel without one to `x̂` so taken; then, if there are
/// exceptions, every sample so taken again and the exceptions written.
fn add_residuals(p: &Parsed, samples: &mut Samples) -> Result<()> {
    let h = &p.header;
    let c = h.channels;
    let npos = samples.len() / c.max(1);
    for ch in 0..c {
        let failed =
            |e: Error| Error::format(format!("RESI of channel {ch}: {e}"), "a valid residual");
        match p.resi.get(ch).and_then(|r| r.as_ref()) {
            Some(r) if h.version.has_levels() => {
                let mut d = Decoder::new_short(&r.data);
                let coding = super::plan::coding_of(h);
                entropy::band::decode_rows(&mut d, &h.dims, None, coding, |at, q| {
                    add_row(samples, c, ch, at, q, r.step)
                })
                .map_err(failed)?;
            }
            Some(r) => {
                let q = decode_band(h, &r.data, &h.dims, &[], BandKind::Detail, None, None)
                    .map_err(failed)?;
                add_row(samples, c, ch, 0, &q[..npos.min(q.len())], r.step);
            }
            None => add_row(samples, c, ch, 0, &[], 0.0),
        }
    }
    let mut all: Vec<(usize, f64)> = Vec::new();
    for (ch, r) in p.resi.iter().enumerate() {
        if let Some(r) = r {
            for &(i, v) in &r.exceptions {
                if (i as usize) < npos {
                    all.push((i as usize * c + ch, v));
                }
            }
        }
    }
    if !all.is_empty() {
        for ch in 0..c {
            add_row(samples, c, ch, 0, &[], 0.0);
        }
        for (i, x) in all {
            set_sample(samples, i, x);
        }
    }
    Ok(())
}

/// [`add_residuals`] over the window `out` (a box of the full raster) alone: `samples`
/// holds the base of the window's positions; each channel's residual rows are decoded
/// whole (the row coder has no random access) and added where they cross the window,
/// and the exceptions inside it written, each sample taken as the whole decode takes it.
fn add_residuals_window(p: &Parsed, samples: &mut Samples, out: &[Range<usize>]) -> Result<()> {
    let h = &p.header;
    let c = h.channels;
    let w = h.dims.last().copied().unwrap_or(1).max(1);
    let nd = h.dims.len();
    let wdims: Vec<usize> = out.iter().map(|r| r.len()).collect();
    // the window position of the full raster's position `g`, if inside
    let inside = |g: usize| -> Option<usize> {
        let mut rem = g;
        let mut at = 0;
        let mut scale = 1;
        for a in (0..nd).rev() {
            let x = rem % h.dims[a];
            rem /= h.dims[a];
            if !out[a].contains(&x) {
                return None;
            }
            at += (x - out[a].start) * scale;
            scale *= wdims[a];
        }
        Some(at)
    };
    let (x0, x1) = (out[nd - 1].start, out[nd - 1].end);
    for ch in 0..c {
        let failed =
            |e: Error| Error::format(format!("RESI of channel {ch}: {e}"), "a valid residual");
        let mut add = |at: usize, q: &[i64], step: f64| {
            // `q` from position `at`, cut into rows of the last axis
            let mut t = 0;
            while t < q.len() {
                let g = at + t;
                let (x, n) = (g % w, (w - g % w).min(q.len() - t));
                let (lo, hi) = (x.max(x0), (x + n).min(x1));
                if lo < hi {
                    if let Some(wat) = inside(g - x + lo) {
                        add_row(samples, c, ch, wat, &q[t + lo - x..t + hi - x], step);
                    }
                }
                t += n;
            }
        };
        match p.resi.get(ch).and_then(|r| r.as_ref()) {
            Some(r) if h.version.has_levels() => {
                let mut d = Decoder::new_short(&r.data);
                let coding = super::plan::coding_of(h);
                entropy::band::decode_rows(&mut d, &h.dims, None, coding, |at, q| {
                    add(at, q, r.step)
                })
                .map_err(failed)?;
            }
            Some(r) => {
                let q = decode_band(h, &r.data, &h.dims, &[], BandKind::Detail, None, None)
                    .map_err(failed)?;
                let npos: usize = h.dims.iter().product();
                add(0, &q[..npos.min(q.len())], r.step);
            }
            None => add_row(samples, c, ch, 0, &[], 0.0),
        }
    }
    let npos: usize = h.dims.iter().product();
    let mut all: Vec<(usize, f64)> = Vec::new();
    for (ch, r) in p.resi.iter().enumerate() {
        if let Some(r) = r {
            for &(i, v) in &r.exceptions {
                if (i as usize) < npos {
                    if let Some(wat) = inside(i as usize) {
                        all.push((wat * c + ch, v));
                    }
                }
            }
        }
    }
    if !all.is_empty() {
        for ch in 0..c {
            add_row(samples, c, ch, 0, &[], 0.0);
        }
        for (i, x) in all {
            set_sample(samples, i, x);
        }
    }
    Ok(())
}

/// `s[(at + t)·c + ch] = x̂ + q[t]·step` taken to the sample type, for `t` over `q`; for
/// every position of channel `ch` (`x̂` alone) when `q` is empty.
pub(in crate::codec) fn add_row(
    s: &mut Samples,
    c: usize,
    ch: usize,
    at: usize,
    q: &[i64],
    step: f64,
) {
    let (lo, hi) = s.sample_type().range();
    macro_rules! go {
        ($v:expr, $conv:expr) => {{
            let conv = $conv;
            let v = $v;
            if q.is_empty() {
                for x in v.iter_mut().skip(ch).step_by(c) {
                    *x = conv(to_f64(*x));
                }
            } else {
                for (x, &qi) in v[(at * c + ch)..].iter_mut().step_by(c).zip(q) {
                    *x = conv(to_f64(*x) + qi as f64 * step);
                }
            }
        }};
    }
    fn to_f64<T: Into<f64>>(x: T) -> f64 {
        x.into()
    }
    let int = |x: f64| {
        if x.is_nan() {
            0.0
        } else {
            x.round().clamp(lo, hi)
        }
    };
    match s {
        Samples::U8(v) => go!(v, |x: f64| int(x) as u8),
        Samples::I8(v) => go!(v, |x: f64| int(x) as i8),
        Samples::U16(v) => go!(v, |x: f64| int(x) as u16),
        Samples::I16(v) => go!(v, |x: f64| int(x) as i16),
        Samples::U32(v) => go!(v, |x: f64| int(x) as u32),
        Samples::I32(v) => go!(v, |x: f64| int(x) as i32),
        Samples::F16(v) => go!(v, half::f16::from_f64),
        Samples::F32(v) => go!(v, |x: f64| x as f32),
        Samples::F64(v) => go!(v, |x: f64| x),
    }
}

/// `s[i] = x` taken to the sample type (as `Samples::from_f64` does).
pub(in crate::codec) fn set_sample(s: &mut Samples, i: usize, x: f64) {
    let ty = s.sample_type();
    let one = Samples::from_f64(&[x], ty);
    s.copy_from(i, &one, 0, 1).expect("same type, in range");
}

fn finish(p: &Parsed, region: Vec<usize>, samples: Samples, k: usize) -> Result<Raster> {
    let h = &p.header;
    let mut r = Raster::new(region.clone(), h.channels, samples, h.kind)?;
    let maps = coarse_maps(p, k);
    r.meta = if k > 0 {
        p.meta.resampled(&h.dims, &region, &maps)
    } else {
        p.meta.clone()
    };
    mark_voids(&mut r, &h.dims, &maps);
    Ok(r)
}

/// Where a scheme's coarse sample `i` sits on the fine grid of one level: at fine index
/// `2i + o`. Haar (and the lossless S-transform): the mean of fine samples `2i`, `2i+1`,
/// `o = ½`. Chaikin: fine `2i`, `2i+1` are `¾ C_i + ¼ C_{i+1}` and `¼ C_i + ¾ C_{i+1}`,
/// so `C_i` sits at `o = −½`. Cubic B-spline: fine `2i` is `⅛ C_{i−1} + ¾ C_i + ⅛ C_{i+1}`,
/// `o = 0`. The schemes with an odd-length regular row (linear, linear-wide, cubic-wide, CDF
/// 9/7) centre `C_i` on fine `2i` (`o = 0`); chaikin-wide's even row, like Chaikin's, between fine
/// `2i − 1` and `2i` (`o = −½`).
pub fn coarse_offset(scheme: Scheme) -> f64 {
    match scheme {
        Scheme::Haar => 0.5,
        Scheme::Chaikin | Scheme::ChaikinWide => -0.5,
        Scheme::Cubic | Scheme::Linear | Scheme::LinearWide | Scheme::CubicWide | Scheme::Cdf97 => {
            0.0
        }
    }
}

/// Per spatial axis, where the samples of the coarse block after `k` levels sit on the
/// full grid: each level that shortens the axis maps by `step 2`, offset
/// [`coarse_offset`] (an odd length's carried last sample is off this grid by at most
/// half a coarse cell).
fn coarse_maps(p: &Parsed, k: usize) -> Vec<crate::io::AxisMap> {
    coarse_maps_of(&p.header, &p.plan, k)
}

/// [`coarse_maps`] of a header and its plan.
pub(super) fn coarse_maps_of(h: &Header, plan: &Plan, k: usize) -> Vec<crate::io::AxisMap> {
    // the integer transforms sit where their real schemes do (the S-transform's floored
    // mean like Haar's, the 5/3 lifting's coarse samples on even samples like linear's)
    let o = coarse_offset(h.scheme);
    let pyr = &plan.pyr;
    (0..h.dims.len())
        .map(|a| {
            let mut m = crate::io::AxisMap::IDENTITY;
            if let Some(i) = pyr.spec.axes.iter().position(|&x| x == a) {
                let lens = &pyr.lengths[i];
                for l in 0..k.min(pyr.axis_levels(i)) {
                    if lens[l + 1] < lens[l] {
                        m = m.then(crate::io::AxisMap {
                            offset: o,
                            step: 2.0,
                        });
                    }
                }
            }
            m
        })
        .collect()
}

/// Decode a one-tile file read in order (a tile of a tiled file, the base of a
/// `--max-error` file): its chunks reconstructed at `opts.level`, no region.
pub(super) fn decode_untiled<R: Read>(src: R, len: u64, opts: &DecodeOptions) -> Result<Decoded> {
    let (rd, first, header) = read_head(src, len)?;
    if header.is_tiled() {
        return Err(Error::format(
            "a tiled file inside a tile",
            "a one-tile file",
        ));
    }
    let p = read_rest(rd, first, header, opts.level, opts.allow_truncated)?;
    Ok(Decoded {
        raster: reconstruct(&p, opts.level)?,
        header: p.header,
        complete: p.complete,
    })
}
