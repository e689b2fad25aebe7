//! `--psnr` of a one-transform file: the base step searched on the first pass's sampled
//! tiles (as the tiled file's search measures them, [`psnr_step`]), then fitted by
//! passes over the stream, each file decoded by the streamed synthesis and compared
//! with the raster a slab at a time ([`fit_psnr`]).

use super::encode_at;
use crate::codec::lossy::prepare;
use crate::codec::options::EncodeOptions;
use crate::codec::tiles;
use crate::format::{Header, Mode};
use crate::io::slab::SlabSource;
use crate::io::Raster;
use crate::{Error, Result};
use rayon::prelude::*;

/// Most passes of the whole stream [`fit_psnr`] codes.
const PSNR_PASSES: usize = 3;

/// The width of the window `[db, db + TOLERANCE]` a fitted file lands in.
const TOLERANCE: f64 = 0.05;

/// The base step of `--psnr db` (peak `peak`) measured on the sampled tiles, each
/// prepared whole with optimised indices and decoded at the candidate step: the step
/// whose summed squared error over the sample gives `10·log10(peak² / mse) ≥ db`
/// within 0.02 dB ([`tiles::search`] on `ln Δ`).
pub(super) fn psnr_step(
    sample: &[Raster],
    opts: &EncodeOptions,
    span: f64,
    peak: f64,
    db: f64,
) -> Result<f64> {
    let prepared = sample
        .par_iter()
        .map(|t| {
            let mut p = prepare(&t.view(), opts, Mode::Lossy)?;
            p.optimise();
            Ok(p)
        })
        .collect::<Result<Vec<_>>>()?;
    let count: f64 = sample.iter().map(|t| t.samples.len() as f64).sum();
    tiles::search(span, false, 0.02, |step| {
        let sse = prepared
            .par_iter()
            .zip(sample)
            .map(|(p, t)| {
                let d = p.decoded(step)?;
                Ok(squared_error(&t.samples.to_f64(), &d.samples.to_f64()))
            })
            .collect::<Result<Vec<f64>>>()?
            .iter()
            .sum::<f64>();
        Ok(psnr(peak, sse / count.max(1.0)) - db)
    })
}

/// `Σ (a − b)²` over the samples finite in both (an infinite sample is coded as 0 by
/// the lossy transform: it is left out, as `mra compare` leaves out voids).
fn squared_error(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| (x - y) * (x - y))
        .sum()
}

/// [`squared_error`] and the number of samples it sums, over the samples `voids` does
/// not flag (all of them without flags), as the whole-array `--psnr` leaves voids out.
fn valid_error(a: &[f64], b: &[f64], voids: Option<&[bool]>) -> (f64, usize) {
    match voids {
        None => (squared_error(a, b), a.len()),
        Some(f) => {
            let (mut sse, mut n) = (0.0, 0usize);
            for ((x, y), _) in a.iter().zip(b).zip(f).filter(|(_, &v)| !v) {
                if x.is_finite() && y.is_finite() {
                    sse += (x - y) * (x - y);
                }
                n += 1;
            }
            (sse, n)
        }
    }
}

/// `10·log10(peak² / mse)`, infinite at `mse = 0`.
fn psnr(peak: f64, mse: f64) -> f64 {
    if mse > 0.0 {
        10.0 * (peak * peak / mse).log10()
    } else {
        f64::INFINITY
    }
}

/// The file of `--psnr db` (peak `peak`): the whole stream coded at `step`, decoded and
/// compared with the raster; unless its PSNR `p` lands in `[db, db + 0.05]`, coded
/// again at `Δ·10^((p − db − 0.025)/20)` (the error of a step `Δ` grows as `Δ²`), at
/// most [`PSNR_PASSES`] passes. The smallest file that meets `db`, else the one of the
/// highest PSNR.
pub(super) fn fit_psnr<S: SlabSource + ?Sized>(
    src: &mut S,
    h: &mut Header,
    meta: &[u8],
    rdo: Option<f32>,
    (db, peak): (f64, f64),
    step: f64,
) -> Result<Vec<u8>> {
    let mut step = step;
    let mut met: Option<Vec<u8>> = None;
    let mut best: Option<(f64, Vec<u8>)> = None;
    for _ in 0..PSNR_PASSES {
        h.step = step;
        let bytes = encode_at(src, h, meta, rdo)?;
        let p = psnr_of(&bytes, src, peak)?;
        if p >= db && p <= db + TOLERANCE {
            return Ok(bytes);
        }
        if p >= db {
            if met.as_ref().is_none_or(|m| bytes.len() < m.len()) {
                met = Some(bytes);
            }
        } else if best.as_ref().is_none_or(|(q, _)| p > *q) {
            best = Some((p, bytes));
        }
        step *= 10f64
            .powf((p - db - TOLERANCE / 2.0) / 20.0)
            .clamp(0.25, 4.0);
    }
    Ok(met.or(best.map(|(_, b)| b)).expect("at least one pass"))
}

/// The PSNR (peak `peak`) of the one-transform file `bytes` against the raster of
/// `src`: the file decoded by the streamed synthesis, each slab compared with the same
/// rows of `src` (a file the stream does not decode, of 4 axes, decoded whole).
fn psnr_of<S: SlabSource + ?Sized>(bytes: &[u8], src: &mut S, peak: f64) -> Result<f64> {
    let shape = src.shape().clone();
    let per = shape.row_samples();
    let parsed = crate::codec::container::read_chunks(
        std::io::Cursor::new(bytes),
        bytes.len() as u64,
        0,
        false,
    )?;
    let (mut sse, mut n) = (0.0f64, 0usize);
    match super::StreamedDecoder::streaming(parsed)? {
        Ok(mut dec) => {
            let mut row = 0;
            while let Some((slab, voids)) = dec.next_slab_voids()? {
                let rows = slab.len() / per.max(1);
                if rows == 0 || row + rows > shape.dims[0] {
                    return Err(Error::format("the streamed decode", "rows of the raster"));
                }
                let a = src.read_rows(row..row + rows)?.to_f64();
                let (e, k) = valid_error(&a, &slab.to_f64(), voids.as_deref());
                sse += e;
                n += k;
                row += rows;
            }
        }
        Err(p) => {
            let voids = crate::codec::voids::listed_mask(&p.meta, &shape.dims, shape.channels);
            let d = crate::codec::decode(bytes, &Default::default())?.raster;
            let a = src.read_rows(0..shape.dims[0])?.to_f64();
            (sse, n) = valid_error(&a, &d.samples.to_f64(), voids.as_deref());
        }
    }
    Ok(psnr(peak, sse / n.max(1) as f64))
}
