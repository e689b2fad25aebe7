//! One transform at any size: a format 3.0 file written from a raster that is never
//! whole in memory. The rows of the raster (a line of an image, a plane of a volume)
//! are read a slab at a time and pushed through the streamed pyramid
//! ([`crate::tensor::stream`]); each band row is quantized as it comes (the dead-zone
//! quantizer, `q = sign(c)·⌊|c|/Δ_b + ρ⌋`, `Δ_b = Δ / (G_b·w_c)`), and as soon as a stripe
//! of a band one code-block tall is complete, and its parent band holds the rows of the
//! stripe's parent boxes, the stripe's blocks are coded (in parallel, streams in block
//! order) and only their bytes are kept. The file is the one [`super::lossy::Prepared::code`]
//! writes of the whole raster at the same base step (the same header, transform,
//! indices and streams: tested), so every 3.0 reader reads it unchanged.
//!
//! Memory: the stream's few rows per level, the quantized rows of each band's open
//! stripe (and of a parent's rows until its children's stripes are coded), and the
//! coded blocks. The base step comes from a first pass ([`super::tiles::first_pass`]):
//! the range, and for `--keep`, `--bpp` and `--psnr` a sample of tiles of the default
//! grid; `--bpp` then codes the whole stream once or a few times to land on its budget
//! ([`fit_bpp`]), `--psnr` to land on its target ([`psnr::fit_psnr`]).
//! Rate–distortion optimised indices: a child is coded with its parent's final indices
//! as context, so a parent band's indices are chosen a stripe at a time as soon as the
//! stripe is complete, coded without its own parent ([`Coder::settled`]); waiting for
//! the parent's own parent would hold a band's values until its coarsest ancestor's
//! stripe is done (half a 16384² image).

use super::colour::{channel_weights, planes_f32};
use super::levels::{round_index, CodedBand};
use super::lossy::{header_with, lossy_colour, Frame};
use super::options::{EncodeOptions, Format, Rate};
use super::plan::{band_rho, Plan};
use super::rate::{check_rate, quality_step};
use super::{meta, tiles};
use crate::entropy::band::Coding;
use crate::entropy::codeblocks::{self, box_dims, extract, parent_box, Grid};
use crate::entropy::BandKind;
use crate::format::bands::blocks_payload;
use crate::format::tag::{HEAD, MEND, META};
use crate::format::{self, put_chunk, Header, Mode};
use crate::io::slab::{Shape, SlabSource};
use crate::io::Raster;
use crate::quantize::{self, RHO};
use crate::tensor::stream::{BandRow, StreamPlan};
use crate::{Error, Result};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::ops::Range;

mod decode;
mod lift;
mod lossless;
mod max_error;
mod psnr;
mod voids;
pub use decode::{decodes_streamed, StreamedDecoder};

/// Whether [`encode_streamed`] writes the file of these options and raster: a format
/// 3.0 file of samples of any type, of 2 to 4 axes and at least one level, at a rate
/// mode that sets one base step (`--quality`, `--keep`, `--threshold`, `--bpp`,
/// `--psnr`), or lossless on 8- or 16-bit samples ([`lossless::streams`]: the integer
/// transform streamed). Float samples are coded as the whole-array encoder codes them
/// (the same finite range in the header, non-finite samples 0 in the planes, the
/// context coder, no lossless file tried). Voids (NaN samples, samples equal to the
/// nodata value) are filled and their mask listed as the whole-array encoder lists it
/// ([`voids`]). `--max-error` above the lossless range (E ≥ 1 on integers, any E > 0 on
/// floats) is a streamed base and its residual layer ([`max_error`]). A raster whose
/// metadata already lists voids stays tiled above the one-piece limit.
pub fn covers(shape: &Shape, opts: &EncodeOptions) -> bool {
    opts.format == Format::Blocks
        && !super::voids::lists_voids(&shape.meta)
        && (2..=4).contains(&shape.dims.len())
        && opts.levels > 0
        && (matches!(
            opts.rate,
            Rate::Quality(_)
                | Rate::Keep(_)
                | Rate::Threshold(_)
                | Rate::Bpp(_)
                | Rate::Psnr(_)
                | Rate::PsnrRange(..)
        ) || lossy_max_error(shape, opts)
            || lossless::streams(shape, opts))
}

/// Whether the options ask for `--max-error E` above the lossless range of the samples
/// (E ≥ 1 on integers, E > 0 on floats: a base and a residual layer, [`max_error`]).
fn lossy_max_error(shape: &Shape, opts: &EncodeOptions) -> bool {
    match opts.rate {
        Rate::MaxError(e) => {
            super::max_error::is_exact(e, shape.sample_type).is_ok_and(|exact| !exact)
        }
        _ => false,
    }
}

/// Tiles of the first pass measured by the `--bpp` search (of the ⌈n/64⌉-th tiles).
const BPP_SAMPLE: usize = 16;

/// The one-transform file of the raster `src` hands out in slabs (module doc), written
/// into `out`; returns the bytes written. An error for the options [`covers`] refuses.
/// A raster that can hold voids (float samples, a nodata value) is read through
/// [`voids::FilledSlabs`]: its voids filled, their mask in the metadata.
pub fn encode_streamed<S: SlabSource + ?Sized, W: std::io::Write>(
    src: &mut S,
    opts: &EncodeOptions,
    out: &mut W,
) -> Result<u64> {
    check_rate(opts.rate)?;
    let shape = src.shape().clone();
    if !covers(&shape, opts) {
        return Err(Error::parameter(
            "rate",
            format!("{:?}", opts.rate),
            "a one-transform file at --quality, --keep, --threshold, --bpp, --psnr, --max-error or 8/16-bit --lossless",
        ));
    }
    if voids::may_hold(&shape) {
        encode_void_free(&mut voids::FilledSlabs::new(src), opts, out)
    } else {
        encode_void_free(src, opts, out)
    }
}

/// [`encode_streamed`] of a raster without voids (or with them filled and listed in the
/// metadata by the end of the first pass).
fn encode_void_free<S: SlabSource + ?Sized, W: std::io::Write>(
    src: &mut S,
    opts: &EncodeOptions,
    out: &mut W,
) -> Result<u64> {
    if lossless::streams(src.shape(), opts) {
        return lossless::encode(src, opts, out);
    }
    if let Rate::MaxError(e) = opts.rate {
        return max_error::encode(src, opts, e, out);
    }
    let sampled = matches!(
        opts.rate,
        Rate::Keep(_) | Rate::Bpp(_) | Rate::Psnr(_) | Rate::PsnrRange(..)
    );
    let first = tiles::first_pass(src, sampled)?;
    // after the first pass: the metadata lists the voids it found
    let shape = src.shape().clone();
    let (range, sample) = (first.range, first.sample);
    let span = (range.1 - range.0).max(1e-30);
    let step = match opts.rate {
        Rate::Quality(q) => quality_step(q, span),
        Rate::Threshold(t) => t / (1.0 - RHO),
        Rate::Keep(k) => tiles::sampled_keep_step(&sample, opts, k, span)?,
        Rate::Bpp(_) | Rate::Psnr(_) | Rate::PsnrRange(..) => 0.0,
        _ => unreachable!("refused by covers"),
    };
    let colour = lossy_colour(shape.channels);
    let frame = Frame {
        dims: &shape.dims,
        channels: shape.channels,
        sample_type: shape.sample_type,
        kind: shape.kind,
    };
    let mut header = header_with(&frame, opts, Mode::Lossy, colour, range, &shape.meta)?;
    header.step = step;
    let rdo = rdo_of(opts);
    if rdo.is_some() {
        // reconstruction at the index, as the whole-array encoder's optimised files
        header.delta = 0.0;
    }
    let meta = meta::to_bytes(&shape.meta);
    let bytes = match opts.rate {
        Rate::Bpp(b) => {
            let (step, slope) = bpp_step(sample, opts, span, b)?;
            fit_bpp(src, &mut header, &meta, rdo, b, step, slope)?
        }
        Rate::Psnr(db) | Rate::PsnrRange(db, _) => {
            let peak = match opts.rate {
                Rate::PsnrRange(_, p) => p,
                _ => first.peak,
            };
            let step = psnr::psnr_step(&sample, opts, span, peak, db)?;
            drop(sample);
            psnr::fit_psnr(src, &mut header, &meta, rdo, (db, peak), step)?
        }
        _ => encode_at(src, &header, &meta, rdo)?,
    };
    out.write_all(&bytes)?;
    Ok(bytes.len() as u64)
}

/// The multiplier of the rate–distortion optimised indices of the rate mode (those the
/// whole-array encoder optimises: `--quality`, `--bpp`, `--psnr`, at an effort that
/// optimises, [`super::options::Ladder::rdo`]), given to the detail bands ([`Coder`]).
fn rdo_of(opts: &EncodeOptions) -> Option<f32> {
    let optimises = matches!(
        opts.rate,
        Rate::Quality(_) | Rate::Bpp(_) | Rate::Psnr(_) | Rate::PsnrRange(..)
    );
    (optimises && opts.ladder().rdo).then_some(quantize::LAMBDA)
}

/// Most passes of the whole stream [`fit_bpp`] codes.
const BPP_PASSES: usize = 4;

/// The file of `--bpp b` (at most `b` bits per position, within 0.5% under it when the
/// passes allow): the whole stream coded at the sampled tiles' step `step` (their bits
/// per position `r(Δ)` differ from the raster's, each tile its own small pyramid), then
/// at the secant step on `ln r` against `ln Δ` aimed at `0.998·b` (the first secant's
/// slope `slope = d ln r / d ln Δ` measured on the sample), at most [`BPP_PASSES`]
/// passes; the met file nearest `b` when none lands in `[0.995·b, b]`, the smallest
/// when none meets `b`.
fn fit_bpp<S: SlabSource + ?Sized>(
    src: &mut S,
    h: &mut Header,
    meta: &[u8],
    rdo: Option<f32>,
    b: f64,
    step: f64,
    slope: f64,
) -> Result<Vec<u8>> {
    let positions = h.dims.iter().product::<usize>().max(1) as f64;
    let aim = (0.998 * b).ln();
    let mut x = step.ln();
    let mut last: Option<(f64, f64)> = None;
    let mut met: Option<Vec<u8>> = None;
    let mut unmet: Option<Vec<u8>> = None;
    for _ in 0..BPP_PASSES {
        h.step = x.exp();
        let bytes = encode_at(src, h, meta, rdo)?;
        let r = bytes.len() as f64 * 8.0 / positions;
        if r <= b && r >= 0.995 * b {
            return Ok(bytes);
        }
        let y = r.ln();
        let g = match last {
            Some((x0, y0)) if (x - x0).abs() > 1e-9 && y != y0 => (y - y0) / (x - x0),
            _ => slope,
        };
        last = Some((x, y));
        if r <= b {
            if met.as_ref().is_none_or(|m| bytes.len() > m.len()) {
                met = Some(bytes);
            }
        } else if unmet.as_ref().is_none_or(|u| bytes.len() < u.len()) {
            unmet = Some(bytes);
        }
        // bits fall as the step grows: a slope that is not negative is noise
        let g = if g < -1e-3 { g } else { slope };
        x += ((aim - y) / g).clamp(-0.7, 0.7);
    }
    Ok(met.or(unmet).expect("at least one pass"))
}

/// The base step of `--bpp b` measured on (every ⌈n/[`BPP_SAMPLE`]⌉-th of) the sampled
/// tiles, each coded as the stream codes the raster ([`encode_at`]): the search of the
/// tiled files ([`tiles::search`]) on their bits per position `r(Δ)`, and the slope
/// `d ln r / d ln Δ` there (from `Δ` and `1.1·Δ`) for [`fit_bpp`].
fn bpp_step(
    mut sample: Vec<Raster>,
    opts: &EncodeOptions,
    span: f64,
    b: f64,
) -> Result<(f64, f64)> {
    let every = sample.len().div_ceil(BPP_SAMPLE).max(1);
    sample = sample.into_iter().step_by(every).collect();
    let positions: f64 = sample.iter().map(|t| t.positions() as f64).sum();
    let rdo = rdo_of(opts);
    let heads = sample
        .iter()
        .map(|t| {
            let frame = Frame {
                dims: &t.dims,
                channels: t.channels,
                sample_type: t.sample_type(),
                kind: t.kind,
            };
            let colour = lossy_colour(t.channels);
            let mut h = header_with(&frame, opts, Mode::Lossy, colour, (0.0, 0.0), &t.meta)?;
            h.delta = if rdo.is_some() { 0.0 } else { h.delta };
            Ok(h)
        })
        .collect::<Result<Vec<Header>>>()?;
    let bits = |step: f64| -> Result<f64> {
        let bytes = sample
            .par_iter()
            .zip(&heads)
            .map(|(t, h)| {
                let mut h = h.clone();
                h.step = step;
                let mut src = crate::io::slab::MemorySlabs::new(t);
                Ok(encode_at(&mut src, &h, &[], rdo)?.len())
            })
            .collect::<Result<Vec<usize>>>()?;
        let bytes: usize = bytes.iter().sum();
        Ok((bytes as f64 * 8.0 / positions.max(1.0)).max(1e-9))
    };
    let step = tiles::search(span, true, -(0.99f64.ln()), |step| {
        Ok(b.ln() - bits(step)?.ln())
    })?;
    let slope = (bits(step * 1.1)?.ln() - bits(step)?.ln()) / 1.1f64.ln();
    // a flat sample (all its indices 0 at both steps) says nothing: a typical slope
    let slope = if slope < -0.05 { slope } else { -0.8 };
    Ok((step, slope))
}

/// The file of header `h` (its base step set) of the raster of `src`, with `mETA`
/// bytes `meta`: the raster streamed through the pyramid a slab at a time. With `rdo`
/// (a multiplier λ) the detail bands get rate–distortion optimised indices (those with
/// children chosen before they are coded, [`Coder::settled`]) and the coarse band is
/// rounded; without, every band is dead-zone quantized.
pub(super) fn encode_at<S: SlabSource + ?Sized>(
    src: &mut S,
    h: &Header,
    meta: &[u8],
    rdo: Option<f32>,
) -> Result<Vec<u8>> {
    let plan = Plan::new(h)?;
    let sp = StreamPlan::new(&h.dims, &plan.pyr.spec)?;
    if sp.bands() != plan.bands.as_slice() {
        return Err(Error::parameter(
            "levels",
            h.levels,
            "a pyramid the stream lays out as the file does",
        ));
    }
    let gains = quantize::band_gains(&plan.pyr, &plan.bands);
    let weights = channel_weights(h.colour, h.channels);
    let ratio = |j: usize, c: usize| (1.0 / (gains[j] * weights[c])) as f32;
    let nc = h.channels;
    let mut coders: Vec<Coder> = (0..nc)
        .map(|c| {
            let steps = (0..plan.bands.len())
                .map(|j| h.step * ratio(j, c) as f64)
                .collect();
            Coder::new(&plan, steps, rdo)
        })
        .collect();
    {
        let mut analyses: Vec<_> = coders
            .iter_mut()
            .map(|k| sp.analysis(move |row: BandRow<f32>| k.take(row)))
            .collect();
        let d0 = h.dims[0];
        let row_len = sp.row_len();
        // about 2^20 positions a slab
        let rows = ((1usize << 20) / row_len.max(1)).clamp(1, d0);
        let shape = src.shape().clone();
        for r0 in (0..d0).step_by(rows) {
            let r1 = (r0 + rows).min(d0);
            let mut dims = shape.dims.clone();
            dims[0] = r1 - r0;
            let slab = Raster::new(dims, nc, src.read_rows(r0..r1)?, shape.kind)?;
            let planes = planes_f32(&slab.view(), h.colour);
            drop(slab);
            for r in 0..r1 - r0 {
                for (a, p) in analyses.iter_mut().zip(&planes) {
                    a.push(&p[r * row_len..(r + 1) * row_len])?;
                }
            }
        }
        for a in analyses {
            let _sink = a.finish()?;
        }
    }
    let mut coded: Vec<Vec<CodedBand>> = Vec::with_capacity(nc);
    for k in coders {
        coded.push(k.finish()?);
    }
    let mut out = format::SIGNATURE.to_vec();
    put_chunk(&mut out, HEAD, &h.to_bytes());
    if !meta.is_empty() {
        put_chunk(&mut out, META, meta);
    }
    plan.put_levels(&mut out, &coded, |c, j| ratio(j, c));
    put_chunk(&mut out, MEND, &[]);
    Ok(out)
}

/// One band of one channel while it streams: its quantized rows not yet let go, which
/// of its stripes are coded, and the coded blocks.
struct BandState {
    grid: Grid,
    /// rows a stripe holds (the block extent on axis 0)
    tall: usize,
    rows: BTreeMap<usize, Vec<i32>>,
    /// the values over the step of the rows not yet let go (bands whose indices are
    /// optimised as they are coded, or settled a stripe at a time)
    values: BTreeMap<usize, Vec<f32>>,
    /// rows received per stripe
    got: Vec<usize>,
    coded: Vec<bool>,
    streams: Vec<Vec<u8>>,
}

impl BandState {
    fn stripes(&self) -> usize {
        self.got.len()
    }

    /// The rows of stripe `s`.
    fn stripe_rows(&self, s: usize) -> Range<usize> {
        s * self.tall..((s + 1) * self.tall).min(self.grid.dims[0])
    }

    /// The values over the step of box `b` of the band (its rows held), raster order.
    fn gather_values(&self, b: &[Range<usize>]) -> Vec<f32> {
        let n: usize = b.iter().map(|r| r.len()).product();
        let mut out = Vec::with_capacity(n);
        for y in b[0].clone() {
            out.extend(extract(&self.values[&y], &self.grid.dims[1..], &b[1..]));
        }
        out
    }

    /// The indices of box `b` of the band (its rows held), raster order.
    fn gather(&self, b: &[Range<usize>]) -> Vec<i64> {
        let n: usize = b.iter().map(|r| r.len()).product();
        let mut out = Vec::with_capacity(n);
        for y in b[0].clone() {
            let row = &self.rows[&y];
            out.extend(
                extract(row, &self.grid.dims[1..], &b[1..])
                    .into_iter()
                    .map(i64::from),
            );
        }
        out
    }
}

/// The bands of one channel as their rows stream in ([`BandState`]).
struct Coder<'p> {
    plan: &'p Plan,
    /// each band's step `Δ_b`
    steps: Vec<f64>,
    bands: Vec<BandState>,
    /// each band's child (the band whose parent it is)
    children: Vec<Option<usize>>,
    /// the multiplier of optimised indices (detail bands), see [`encode_at`]
    rdo: Option<f32>,
    err: Option<Error>,
}

impl<'p> Coder<'p> {
    fn new(plan: &'p Plan, steps: Vec<f64>, rdo: Option<f32>) -> Coder<'p> {
        let bands = (0..plan.bands.len())
            .map(|j| {
                let grid = plan.grid(j).expect("a format 3 plan has code-blocks");
                let tall = grid.block[0];
                let n = if grid.is_empty() { 0 } else { grid.counts[0] };
                BandState {
                    tall,
                    rows: BTreeMap::new(),
                    values: BTreeMap::new(),
                    got: vec![0; n],
                    coded: vec![false; n],
                    streams: vec![Vec::new(); grid.len()],
                    grid,
                }
            })
            .collect();
        let mut children = vec![None; plan.bands.len()];
        for (j, p) in plan.parents.iter().enumerate() {
            if let Some(p) = *p {
                children[p] = Some(j);
            }
        }
        Coder {
            plan,
            steps,
            bands,
            children,
            rdo,
            err: None,
        }
    }

    /// The sink of the stream: quantize a band row, keep it, and code what it completes.
    fn take(&mut self, row: BandRow<f32>) {
        if self.err.is_some() {
            return;
        }
        if let Err(e) = self.take_row(row) {
            self.err = Some(e);
        }
    }

    fn take_row(&mut self, row: BandRow<f32>) -> Result<()> {
        let j = row.band;
        if self.bands[j].grid.is_empty() {
            return Ok(());
        }
        let (s, rho) = (self.steps[j], band_rho(self.plan, j));
        if self.optimised(j) || self.settled(j) {
            let v = row.data.iter().map(|&x| (x as f64 / s) as f32).collect();
            self.bands[j].values.insert(row.row, v);
        } else {
            let rounded = self.rdo.is_some();
            let q = row
                .data
                .iter()
                .map(|&x| {
                    let q = if rounded {
                        round_index((x as f64 / s) as f32)
                    } else {
                        quantize::quantize(x as f64, s, rho)
                    };
                    i32::try_from(q).map_err(|_| {
                        Error::parameter("step", s, "a step whose indices fit 32 bits")
                    })
                })
                .collect::<Result<Vec<i32>>>()?;
            self.bands[j].rows.insert(row.row, q);
        }
        self.landed(j, row.row)
    }

    /// Row `y` of band `j` is held (its indices, or its values for a band whose indices
    /// are chosen later): code the stripes it completes, its own and its child's.
    fn landed(&mut self, j: usize, y: usize) -> Result<()> {
        let stripe = y / self.bands[j].tall;
        let settled = self.settled(j);
        let b = &mut self.bands[j];
        b.got[stripe] += 1;
        let held = if !settled {
            y..y + 1
        } else if b.got[stripe] == b.stripe_rows(stripe).len() {
            self.settle(j, stripe)?
        } else {
            return Ok(());
        };
        self.try_code(j, stripe)?;
        if let Some(k) = self.children[j] {
            // the child's stripes whose parent boxes hold these rows
            let ch = &self.bands[k];
            let last = self.bands[j].grid.dims[0] - 1;
            let hi = if held.end > last {
                ch.grid.dims[0]
            } else {
                (2 * held.end).min(ch.grid.dims[0])
            };
            let lo = (2 * held.start).min(hi);
            if lo < hi {
                for t in lo / ch.tall..=(hi - 1) / ch.tall {
                    self.try_code(k, t)?;
                }
            }
        }
        Ok(())
    }

    /// Whether band `j`'s indices are optimised a stripe at a time before it is coded:
    /// a detail band with children, when the rate mode optimises. Its children are
    /// coded with its final indices as context (as the whole-array encoder codes
    /// them), so they cannot wait for its own parent's stripe (a chain up to the
    /// coarsest band): its indices are chosen as the whole-array encoder chooses them
    /// (`(|v| − a)² + λ·bits(a)` least among `round(|v|)`, `round(|v|) − 1`, 0, the bits
    /// those of the context coder's adaptive models as it codes the block), the block
    /// coded without its parent, and those indices are then coded with their parent as
    /// any rounded band's.
    fn settled(&self, j: usize) -> bool {
        self.rdo.is_some() && self.plan.bands[j].level > 0 && self.children[j].is_some()
    }

    /// Choose the indices of stripe `s` of band `j` (complete, [`Coder::settled`]) from
    /// its values, block by block in parallel; its values go, its rows are kept as
    /// indices. Returns the stripe's rows.
    fn settle(&mut self, j: usize, s: usize) -> Result<Range<usize>> {
        let lambda = self.rdo.unwrap_or(quantize::LAMBDA);
        let coding: Coding = self.plan.coding;
        let b = &self.bands[j];
        let g = &b.grid;
        let per: usize = g.counts[1..].iter().product();
        let rows = b.stripe_rows(s);
        let coder = self.plan.coder;
        let qs: Vec<Vec<i64>> = (s * per..(s + 1) * per)
            .into_par_iter()
            .map(|i| {
                let bx = g.bounds(i);
                let d = box_dims(&bx);
                let v = b.gather_values(&bx);
                codeblocks::encode_one_rdo(coder, &v, &d, None, lambda, coding, true).1
            })
            .collect();
        let row_len: usize = g.dims[1..].iter().product();
        let mut sdims = g.dims.clone();
        sdims[0] = rows.len();
        let mut stripe = vec![0i64; rows.len() * row_len];
        for (k, q) in qs.into_iter().enumerate() {
            let mut bx = g.bounds(s * per + k);
            bx[0] = bx[0].start - rows.start..bx[0].end - rows.start;
            crate::entropy::codeblocks::insert(&mut stripe, &sdims, &bx, &q);
        }
        let step = self.steps[j];
        let b = &mut self.bands[j];
        for (k, y) in rows.clone().enumerate() {
            let row = stripe[k * row_len..(k + 1) * row_len]
                .iter()
                .map(|&q| {
                    i32::try_from(q).map_err(|_| {
                        Error::parameter("step", step, "a step whose indices fit 32 bits")
                    })
                })
                .collect::<Result<Vec<i32>>>()?;
            b.values.remove(&y);
            b.rows.insert(y, row);
        }
        Ok(rows)
    }

    /// Whether band `j`'s indices are optimised as its blocks are coded: a detail band
    /// without children, when the rate mode optimises.
    fn optimised(&self, j: usize) -> bool {
        self.rdo.is_some() && self.plan.bands[j].level > 0 && self.children[j].is_none()
    }

    /// The parent band of `j` and the rows of it that stripe `s` of `j` reads (the
    /// parent boxes of its blocks), when it has one.
    fn parent_rows(&self, j: usize, s: usize) -> Option<(usize, Range<usize>)> {
        if self.plan.bands[j].level == 0 {
            return None;
        }
        let p = self.plan.parents[j]?;
        let pd = &self.bands[p].grid.dims;
        if pd.len() != self.bands[j].grid.dims.len() || pd.contains(&0) {
            return None;
        }
        let r = self.bands[j].stripe_rows(s);
        let pb = parent_box(&[r], &pd[..1]);
        Some((p, pb[0].clone()))
    }

    /// Code stripe `s` of band `j` when all its rows and its parent rows are there.
    fn try_code(&mut self, j: usize, s: usize) -> Result<()> {
        let b = &self.bands[j];
        if s >= b.stripes() || b.coded[s] || b.got[s] < b.stripe_rows(s).len() {
            return Ok(());
        }
        let parent = self.parent_rows(j, s);
        if let Some((p, rows)) = &parent {
            let pb = &self.bands[*p];
            if rows.clone().any(|y| !pb.rows.contains_key(&y)) {
                return Ok(());
            }
        }
        let parent = parent.map(|(p, _)| p);
        self.code_stripe(j, s, parent);
        self.prune(j);
        if let Some(p) = parent {
            self.prune(p);
        }
        Ok(())
    }

    /// Code the blocks of stripe `s` of band `j` (parent band `parent`) in parallel.
    fn code_stripe(&mut self, j: usize, s: usize, parent: Option<usize>) {
        let b = &self.bands[j];
        let g = &b.grid;
        let per: usize = g.counts[1..].iter().product();
        let kind = if self.plan.bands[j].level == 0 {
            BandKind::Coarse
        } else {
            BandKind::Detail
        };
        let coding: Coding = self.plan.coding;
        let pb = parent.map(|p| &self.bands[p]);
        let lambda = self.rdo.filter(|_| self.optimised(j));
        let coder = self.plan.coder;
        let streams: Vec<Vec<u8>> = (s * per..(s + 1) * per)
            .into_par_iter()
            .map(|i| {
                let bx = g.bounds(i);
                let d = box_dims(&bx);
                let par = pb.map(|pb| {
                    let pbox = parent_box(&bx, &pb.grid.dims);
                    (pb.gather(&pbox), box_dims(&pbox))
                });
                // as codeblocks::encode_blocks(_rdo_by) codes a block
                match lambda {
                    Some(lambda) => {
                        let v = b.gather_values(&bx);
                        let (st, _) = codeblocks::encode_one_rdo(
                            coder,
                            &v,
                            &d,
                            par.as_ref(),
                            lambda,
                            coding,
                            false,
                        );
                        st
                    }
                    None => codeblocks::encode_one(
                        coder,
                        &b.gather(&bx),
                        &d,
                        kind,
                        par.as_ref(),
                        coding,
                    ),
                }
            })
            .collect();
        let b = &mut self.bands[j];
        for (k, st) in streams.into_iter().enumerate() {
            b.streams[s * per + k] = st;
        }
        b.coded[s] = true;
    }

    /// Let go of the rows of band `j` no stripe left to code reads: its own coded
    /// stripes' rows that no uncoded stripe of its child reads as parent rows.
    fn prune(&mut self, j: usize) {
        let child = self.children[j];
        let waiting: Vec<Range<usize>> = match child {
            Some(k) => (0..self.bands[k].stripes())
                .filter(|&t| !self.bands[k].coded[t])
                .filter_map(|t| self.parent_rows(k, t).map(|(_, r)| r))
                .collect(),
            None => Vec::new(),
        };
        let b = &mut self.bands[j];
        let tall = b.tall;
        let coded = &b.coded;
        b.rows
            .retain(|&y, _| !coded[y / tall] || waiting.iter().any(|r| r.contains(&y)));
        b.values.retain(|&y, _| !coded[y / tall]);
    }

    /// The coded bands of the channel, once every row has streamed through.
    fn finish(self) -> Result<Vec<CodedBand>> {
        if let Some(e) = self.err {
            return Err(e);
        }
        self.bands
            .into_iter()
            .map(|b| {
                if b.coded.contains(&false) {
                    return Err(Error::parameter(
                        "raster",
                        "a band",
                        "every stripe of code-blocks complete at the end of the stream",
                    ));
                }
                Ok(CodedBand {
                    q: Vec::new(),
                    stream: blocks_payload(&b.streams),
                })
            })
            .collect()
    }
}
