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
//! the range, and for `--keep` and `--bpp` a sample of tiles of the default grid.
//! Rate–distortion optimised indices need a parent's final indices before a child is
//! coded, which would hold a band's values until its coarsest ancestor's stripe is
//! done (half a 16384² image); the stream quantizes without it.

use super::colour::{channel_weights, planes_f32};
use super::levels::CodedBand;
use super::lossy::{header_with, lossy_colour, prepare, Frame};
use super::options::{EncodeOptions, Format, Rate};
use super::plan::{band_rho, Plan};
use super::rate::{check_rate, keep_step, quality_step};
use super::{meta, tiles};
use crate::entropy::band::{self, Coding};
use crate::entropy::codeblocks::{box_dims, extract, parent_box, Grid};
use crate::entropy::{BandKind, Parent};
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

/// Whether [`encode_streamed`] writes the file of these options and raster: a format
/// 3.0 file of integer samples without a nodata value (no voids to fill), of 2 to 4
/// axes and at least one level, at a rate mode that sets one base step
/// (`--quality`, `--keep`, `--threshold`, `--bpp`). `--lossless` and `--max-error`
/// (the integer transform, a residual of the whole raster) and `--psnr` stay tiled
/// above the one-piece limit.
pub fn covers(shape: &Shape, opts: &EncodeOptions) -> bool {
    opts.format == Format::Blocks
        && !shape.sample_type.is_float()
        && shape.meta.nodata.is_none()
        && !super::voids::lists_voids(&shape.meta)
        && (2..=4).contains(&shape.dims.len())
        && opts.levels > 0
        && matches!(
            opts.rate,
            Rate::Quality(_) | Rate::Keep(_) | Rate::Threshold(_) | Rate::Bpp(_)
        )
}

/// Tiles of the first pass measured by the `--bpp` search (of the ⌈n/64⌉-th tiles).
const BPP_SAMPLE: usize = 16;

/// The one-transform file of the raster `src` hands out in slabs (module doc), written
/// into `out`; returns the bytes written. An error for the options [`covers`] refuses.
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
            "a one-transform file of integer samples at --quality, --keep, --threshold or --bpp",
        ));
    }
    let sampled = matches!(opts.rate, Rate::Keep(_) | Rate::Bpp(_));
    let (range, sample) = tiles::first_pass(src, sampled)?;
    let span = (range.1 - range.0).max(1e-30);
    let step = match opts.rate {
        Rate::Quality(q) => quality_step(q, span),
        Rate::Threshold(t) => t / (1.0 - RHO),
        Rate::Keep(k) => {
            let mut w: Vec<f32> = sample
                .par_iter()
                .map(|t| Ok(prepare(&t.view(), opts, Mode::Lossy)?.weighted_details()))
                .collect::<Result<Vec<_>>>()?
                .concat();
            keep_step(&mut w, k, span)
        }
        Rate::Bpp(b) => bpp_step(sample, opts, span, b)?,
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
    let bytes = encode_at(src, &header, &meta::to_bytes(&shape.meta))?;
    out.write_all(&bytes)?;
    Ok(bytes.len() as u64)
}

/// The base step of `--bpp b`: the search of the tiled files ([`tiles::search`]) on the
/// bits per position of one-piece files of (every ⌈n/[`BPP_SAMPLE`]⌉-th of) the sampled
/// tiles, coded as the stream codes them.
fn bpp_step(mut sample: Vec<Raster>, opts: &EncodeOptions, span: f64, b: f64) -> Result<f64> {
    let every = sample.len().div_ceil(BPP_SAMPLE).max(1);
    sample = sample.into_iter().step_by(every).collect();
    let positions: f64 = sample.iter().map(|t| t.positions() as f64).sum();
    let prepared = sample
        .into_par_iter()
        .map(|t| prepare(&t.view(), opts, Mode::Lossy))
        .collect::<Result<Vec<_>>>()?;
    tiles::search(span, true, -(0.99f64.ln()), |step| {
        let bytes: usize = prepared.par_iter().map(|p| p.code(step).len()).sum();
        Ok(b.ln() - (bytes as f64 * 8.0 / positions.max(1.0)).ln())
    })
}

/// The file of header `h` (its base step set) of the raster of `src`, with `mETA`
/// bytes `meta`: the raster streamed through the pyramid a slab at a time.
pub(super) fn encode_at<S: SlabSource + ?Sized>(
    src: &mut S,
    h: &Header,
    meta: &[u8],
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
            Coder::new(&plan, steps)
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

    /// The values of box `b` of the band (its rows held), raster order.
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
    err: Option<Error>,
}

impl<'p> Coder<'p> {
    fn new(plan: &'p Plan, steps: Vec<f64>) -> Coder<'p> {
        let bands = (0..plan.bands.len())
            .map(|j| {
                let grid = plan.grid(j).expect("a format 3 plan has code-blocks");
                let tall = grid.block[0];
                let n = if grid.is_empty() { 0 } else { grid.counts[0] };
                BandState {
                    tall,
                    rows: BTreeMap::new(),
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
        let q = row
            .data
            .iter()
            .map(|&x| {
                i32::try_from(quantize::quantize(x as f64, s, rho)).map_err(|_| {
                    Error::parameter("step", s, "a step whose indices fit 32 bits")
                })
            })
            .collect::<Result<Vec<i32>>>()?;
        let b = &mut self.bands[j];
        let stripe = row.row / b.tall;
        b.rows.insert(row.row, q);
        b.got[stripe] += 1;
        self.try_code(j, stripe)?;
        if let Some(k) = self.children[j] {
            // the child's stripes whose parent boxes hold this row
            let ch = &self.bands[k];
            let last = self.bands[j].grid.dims[0] - 1;
            let hi = if row.row == last {
                ch.grid.dims[0]
            } else {
                (2 * row.row + 2).min(ch.grid.dims[0])
            };
            let lo = (2 * row.row).min(hi);
            if lo < hi {
                for t in lo / ch.tall..=(hi - 1) / ch.tall {
                    self.try_code(k, t)?;
                }
            }
        }
        Ok(())
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
        let streams: Vec<Vec<u8>> = (s * per..(s + 1) * per)
            .into_par_iter()
            .map(|i| {
                let bx = g.bounds(i);
                let d = box_dims(&bx);
                let v = b.gather(&bx);
                let par = pb.map(|pb| {
                    let pbox = parent_box(&bx, &pb.grid.dims);
                    (pb.gather(&pbox), box_dims(&pbox))
                });
                let pp = par.as_ref().map(|(data, dims)| Parent { data, dims });
                band::encode_stream(&v, &d, kind, pp, coding)
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
