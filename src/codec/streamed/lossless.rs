//! `--lossless` as one transform at any size: the integer 5/3 pyramid streamed a few
//! rows per level at a time ([`super::lift`]), each band's stripes of code-blocks coded
//! as they complete (the stripes of [`super::Coder`], the indices the transform's
//! values, the file's block coder). The file is the whole-array lossless encoder's
//! ([`crate::codec::encode`] of the same raster: the same header, transform values,
//! blocks and bytes; tested), so every 3.x reader reads it; it decodes streamed too
//! ([`decode`]).

use super::lift::LiftPlan;
use super::Coder;
use crate::codec::levels::CodedBand;
use crate::codec::lossy::{header_with, Frame};
use crate::codec::options::{EncodeOptions, Format, Rate};
use crate::codec::plan::Plan;
use crate::codec::{lossless, max_error, meta, tiles};
use crate::format::header::Colour;
use crate::format::tag::{HEAD, MEND, META};
use crate::format::{self, put_chunk, Mode};
use crate::io::slab::{Shape, SlabSource};
use crate::io::Samples;
use crate::{Error, Result};
use rayon::prelude::*;

pub(super) mod decode;

/// Whether the options and raster make a lossless file the stream writes: `--lossless`
/// (or a `--max-error` bound that keeps every sample exact) on 8- or 16-bit integer
/// samples ([`lossless::narrow`]: every transform value fits the coder's `i32` rows).
/// The rest of [`super::covers`] (no voids, 2–4 axes, format 3) holds too.
pub(super) fn streams(shape: &Shape, opts: &EncodeOptions) -> bool {
    let exact = match opts.rate {
        Rate::Lossless => true,
        Rate::MaxError(e) => max_error::is_exact(e, shape.sample_type).unwrap_or(false),
        _ => false,
    };
    exact && lossless::narrow(shape.sample_type) && opts.format == Format::Blocks
}

impl Coder<'_> {
    /// Row `y` of band `j`, integer values that are the indices (a lossless file): held
    /// as `i32`, and the stripes it completes coded.
    fn take_indices(&mut self, j: usize, y: usize, data: &[i64]) {
        if self.err.is_some() || self.bands[j].grid.is_empty() {
            return;
        }
        let q = data
            .iter()
            .map(|&v| i32::try_from(v))
            .collect::<std::result::Result<Vec<i32>, _>>();
        let r = match q {
            Ok(q) => {
                self.bands[j].rows.insert(y, q);
                self.landed(j, y)
            }
            Err(_) => Err(Error::parameter(
                "raster",
                "a transform value past 32 bits",
                "8- or 16-bit samples whose lossless transform fits 32 bits",
            )),
        };
        if let Err(e) = r {
            self.err = Some(e);
        }
    }
}

/// The lossless file of the raster `src` hands out in slabs (module doc), written into
/// `out`; returns the bytes written.
pub(super) fn encode<S: SlabSource + ?Sized, W: std::io::Write>(
    src: &mut S,
    opts: &EncodeOptions,
    out: &mut W,
) -> Result<u64> {
    let shape = src.shape().clone();
    let (range, _) = tiles::first_pass(src, false)?;
    let nc = shape.channels;
    let colour = if nc >= 3 {
        Colour::YCoCgR
    } else {
        Colour::None
    };
    let frame = Frame {
        dims: &shape.dims,
        channels: nc,
        sample_type: shape.sample_type,
        kind: shape.kind,
    };
    let header = header_with(
        &frame,
        &crate::codec::encode::lossless_options(opts),
        Mode::Lossless,
        colour,
        range,
        &shape.meta,
    )?;
    let plan = Plan::new(&header)?;
    let lp = LiftPlan::new(&plan.pyr, &plan.bands)?;
    let mut coders: Vec<Coder> = (0..nc)
        .map(|_| Coder::new(&plan, vec![1.0; plan.bands.len()], None))
        .collect();
    {
        let mut analyses: Vec<_> = coders
            .iter_mut()
            .map(|k| lp.analysis(move |j, y, d: &[i64]| k.take_indices(j, y, d)))
            .collect();
        let d0 = shape.dims[0];
        let row_len = lp.row_len();
        // about 2^20 positions a slab
        let rows = ((1usize << 20) / row_len.max(1)).clamp(1, d0);
        for r0 in (0..d0).step_by(rows) {
            let r1 = (r0 + rows).min(d0);
            let planes = planes_i64(&src.read_rows(r0..r1)?, nc, colour == Colour::YCoCgR)?;
            // the channels' transforms in parallel (each one's stripes too)
            analyses
                .par_iter_mut()
                .zip(planes)
                .map(|(a, p)| {
                    for row in p.chunks(row_len.max(1)) {
                        a.push(row.to_vec())?;
                    }
                    Ok(())
                })
                .collect::<Result<()>>()?;
        }
        for a in analyses {
            let _sink = a.finish()?;
        }
    }
    let coded = coders
        .into_iter()
        .map(|k| k.finish())
        .collect::<Result<Vec<Vec<CodedBand>>>>()?;
    let mut bytes = format::SIGNATURE.to_vec();
    put_chunk(&mut bytes, HEAD, &header.to_bytes());
    let meta = meta::to_bytes(&shape.meta);
    if !meta.is_empty() {
        put_chunk(&mut bytes, META, &meta);
    }
    plan.put_levels(&mut bytes, &coded, |_, _| 1.0);
    put_chunk(&mut bytes, MEND, &[]);
    out.write_all(&bytes)?;
    Ok(bytes.len() as u64)
}

/// The channel planes of interleaved 8- or 16-bit samples `s` (`c` channels) as
/// integers, the first three through YCoCg-R when `ycocg` (as the whole-array encoder
/// maps them).
fn planes_i64(s: &Samples, c: usize, ycocg: bool) -> Result<Vec<Vec<i64>>> {
    fn split<T: Copy + Into<i64>>(v: &[T], c: usize, ycocg: bool) -> Vec<Vec<i64>> {
        let n = v.len() / c.max(1);
        let mut planes: Vec<Vec<i64>> = (0..c).map(|_| Vec::with_capacity(n)).collect();
        for px in v.chunks_exact(c) {
            let first = if ycocg {
                let (y, co, cg) = lossless::ycocg_r(px[0].into(), px[1].into(), px[2].into());
                planes[0].push(y);
                planes[1].push(co);
                planes[2].push(cg);
                3
            } else {
                0
            };
            for (p, &x) in planes[first..].iter_mut().zip(&px[first..]) {
                p.push(x.into());
            }
        }
        planes
    }
    Ok(match s {
        Samples::U8(v) => split(v, c, ycocg),
        Samples::I8(v) => split(v, c, ycocg),
        Samples::U16(v) => split(v, c, ycocg),
        Samples::I16(v) => split(v, c, ycocg),
        other => {
            return Err(Error::parameter(
                "sample type",
                other.sample_type(),
                "8- or 16-bit integer samples for a streamed lossless file",
            ))
        }
    })
}
