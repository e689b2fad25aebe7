//! `--max-error E` over the one-piece limit as one transform: the lossy base streamed
//! as any one-transform file ([`super::encode_at`], rate–distortion optimised indices,
//! `δ = 0`), then its residual layer (formats/MRA.md §11: per channel a `RESI` chunk, the
//! residual `q = round((x − x̂)/s)` to the *decoded* base `x̂` coded as one band of the
//! raster's extents, and the samples still outside the bound listed as exceptions)
//! made in one more pass: the base decoded by the streamed synthesis
//! ([`super::StreamedDecoder`]) slab by slab beside a second read of the same rows of the
//! source, each channel's residual rows coded as they come ([`RowEncoder`]). The file is
//! a 3.x file of mode 2 that every reader of the whole-array `--max-error` file reads;
//! its bytes differ from the whole-array file's (the stream chooses the base's
//! optimised indices a stripe at a time).
//!
//! The base step is a multiple of the residual's step `s` (`2⌊E⌋ + 1` on integers,
//! `2E(1 − 10⁻⁹)` on floats) as in the whole-array encoder, which codes a base at each
//! of its two multiples and keeps the shorter file; here each base costs a pass of the
//! transform and one of the decode, so only [`STREAMED_STEPS`] are tried.
//!
//! Memory: the stream's (one base's coded bytes, read back once to be decoded), the
//! decoded slab and the source's same rows, the coded residual streams and the
//! exceptions; the whole raster is never held.

use super::super::lossy::{header_with, lossy_colour, Frame};
use super::super::max_error::{exceptions, residual_index, residual_step};
use super::super::options::EncodeOptions;
use super::super::{container, meta, plan, tiles};
use super::{encode_at, StreamedDecoder};
use crate::entropy::band::RowEncoder;
use crate::format::bands::residual_payload;
use crate::format::tag::{MEND, RESI};
use crate::format::{put_chunk, Mode, MAX_CHUNK};
use crate::io::slab::SlabSource;
use crate::quantize;
use crate::{Error, Result};
use rayon::prelude::*;

/// The multiples of the residual's step tried as the streamed base's step (the whole
/// encoder's first: on the corpus volumes and DEMs it alone spends fewer bits than the
/// dead-zone base at the residual's step; the shorter file is kept).
const STREAMED_STEPS: [f64; 1] = [1.2];

/// The `--max-error e` file (a bound the whole-array rule finds lossy) of the raster
/// `src` hands out in slabs, written into `out`; returns the bytes written. Voids (a
/// source that fills them and lists their mask by the end of its first pass,
/// [`super::voids`]) take no residual and no exceptions, as in the whole-array file.
pub(super) fn encode<S: SlabSource + ?Sized, W: std::io::Write>(
    src: &mut S,
    opts: &EncodeOptions,
    e: f64,
    out: &mut W,
) -> Result<u64> {
    let first = tiles::first_pass(src, false)?;
    // the metadata after the first pass: it lists the voids a filling source found
    let shape = src.shape().clone();
    let frame = Frame {
        dims: &shape.dims,
        channels: shape.channels,
        sample_type: shape.sample_type,
        kind: shape.kind,
    };
    let colour = lossy_colour(shape.channels);
    let mut h = header_with(
        &frame,
        opts,
        Mode::MaxError,
        colour,
        first.range,
        &shape.meta,
    )?;
    h.max_error = e;
    h.delta = 0.0;
    let meta = meta::to_bytes(&shape.meta);
    let s = residual_step(e, shape.sample_type);
    let mut best: Option<(Vec<u8>, Vec<Vec<u8>>, usize)> = None;
    for m in STREAMED_STEPS {
        h.step = s.max(2.0 * e) * m;
        let base = encode_at(src, &h, &meta, Some(quantize::LAMBDA))?;
        let layer = residual_layer(src, &base, e)?;
        let len = base.len() + layer.iter().map(|p| p.len() + 12).sum::<usize>();
        if best.as_ref().is_none_or(|b| len < b.2) {
            best = Some((base, layer, len));
        }
        crate::tuning::release_freed();
    }
    let (base, layer, len) = best.expect("STREAMED_STEPS is not empty");
    // the base without its MEND, then the RESI chunks and MEND
    out.write_all(&base[..base.len() - 12])?;
    drop(base);
    for pl in &layer {
        let mut chunk = Vec::with_capacity(pl.len() + 12);
        put_chunk(&mut chunk, RESI, pl);
        out.write_all(&chunk)?;
    }
    let mut end = Vec::new();
    put_chunk(&mut end, MEND, &[]);
    out.write_all(&end)?;
    Ok(len as u64)
}

/// The `RESI` payloads (one per channel) of the residual of the raster of `src` to the
/// decoded base file `base` (a `--max-error` header and no `RESI` chunk), bound `e`.
fn residual_layer<S: SlabSource + ?Sized>(
    src: &mut S,
    base: &[u8],
    e: f64,
) -> Result<Vec<Vec<u8>>> {
    let shape = src.shape().clone();
    let (c, ty) = (shape.channels, shape.sample_type);
    let s = residual_step(e, ty);
    // the base alone: its header commits to RESI chunks that are not there yet
    let p = container::read_chunks(base, base.len() as u64, 0, true)?;
    let coding = plan::coding_of(&p.header);
    let mut dec = StreamedDecoder::of(p)?;
    let row_len: usize = shape.dims[1..].iter().product();
    let mut coders: Vec<RowEncoder> = (0..c)
        .map(|_| RowEncoder::new(&shape.dims, coding))
        .collect();
    let mut exc: Vec<Vec<(u64, f64)>> = vec![Vec::new(); c];
    let mut r0 = 0;
    while let Some((slab, voids)) = dec.next_slab_voids()? {
        let n = slab.len() / (row_len * c).max(1);
        if n == 0 || r0 + n > shape.dims[0] {
            return Err(Error::parameter(
                "base",
                format!("a slab of {n} rows at row {r0}"),
                "the base decoded in slabs of the raster's rows",
            ));
        }
        let mut dims = shape.dims.clone();
        dims[0] = n;
        let r = shape.raster(dims, src.read_rows(r0..r0 + n)?)?;
        let view = r.view();
        let at = (r0 * row_len) as u64;
        coders
            .par_iter_mut()
            .zip(exc.par_iter_mut())
            .enumerate()
            .for_each(|(k, (coder, exc))| {
                let cols = coder.cols();
                let mut row = vec![0i64; cols];
                for g in 0..n * row_len / cols {
                    for (t, q) in row.iter_mut().enumerate() {
                        let at = (g * cols + t) * c + k;
                        *q = residual_index(&view, &slab, at, s, voids.as_deref());
                    }
                    coder.push(&row);
                }
                exc.extend(
                    exceptions(&view, &slab, k, s, e, voids.as_deref())
                        .into_iter()
                        .map(|(i, x)| (i + at, x)),
                );
            });
        r0 += n;
    }
    if r0 != shape.dims[0] {
        return Err(Error::parameter(
            "base",
            format!("{r0} of {} rows decoded", shape.dims[0]),
            "the raster's rows",
        ));
    }
    coders
        .into_iter()
        .zip(exc)
        .enumerate()
        .map(|(k, (coder, exc))| {
            let pl = residual_payload(k, s, &exc, &coder.finish());
            if pl.len() as u64 > MAX_CHUNK {
                return Err(Error::parameter(
                    "max-error",
                    e,
                    "a residual layer of at most 2^30 bytes a channel (a larger bound, or --tile)",
                ));
            }
            Ok(pl)
        })
        .collect()
}
