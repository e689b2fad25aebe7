//! Encoding one tile: the file of the rate mode (lossy at a step, with a residual layer
//! for `--max-error`, or the integer transform of `--lossless`).

use super::colour::map3;
use super::levels::{BandInput, Choice};
use super::lossy::header_for;
use super::options::{EncodeOptions, Rate};
use super::plan::Plan;
use super::{layout, lossless, max_error, meta, rate};
use crate::format::header::Colour;
use crate::format::tag::{HEAD, MEND, META};
use crate::format::{self, put_chunk, Mode};
use crate::io::slab::SlabSource;
use crate::io::{RasterView, SampleType, SamplesRef};
use crate::scheme::{Boundary, Scheme};
use crate::Result;
use rayon::prelude::*;

/// The file of one tile (a whole raster or one tile of a tiled file) whose voids are
/// already filled: the rate mode's coding.
pub(super) fn encode_filled(r: &RasterView<'_>, opts: &EncodeOptions) -> Result<Vec<u8>> {
    match opts.rate {
        Rate::Lossless => encode_lossless(r, opts),
        Rate::MaxError(e) => {
            if max_error::is_exact(e, r.sample_type())? {
                encode_lossless(r, opts)
            } else {
                max_error::encode_max_error(r, opts, e)
            }
        }
        rate => rate::encode_lossy(r, opts, rate, &|| encode_lossless(r, opts)),
    }
}

/// The file of a whole raster that `src` hands out in slabs, for the rate modes that need
/// nothing of the samples but their transform (`--quality`, `--keep`, `--threshold`,
/// `--bpp`) on integer samples without a nodata value (no voids to fill): the bytes of
/// [`encode_filled`], with the samples read a slab at a time into the transform's planes
/// ([`super::lossy::prepare_slabs`]), so that they are never held whole beside them.
/// `--bpp` near the lossless cost and `--quality 100` read them again, whole, for the
/// lossless file.
/// `None` for the other rate modes and samples, which need the raster whole.
pub(super) fn encode_slabs<S: SlabSource + ?Sized>(
    src: &mut S,
    opts: &EncodeOptions,
) -> Result<Option<Vec<u8>>> {
    let shape = src.shape();
    let transform_only = matches!(
        opts.rate,
        Rate::Quality(_) | Rate::Keep(_) | Rate::Threshold(_) | Rate::Bpp(_)
    );
    if !transform_only || shape.sample_type.is_float() || shape.meta.nodata.is_some() {
        return Ok(None);
    }
    let p = super::lossy::prepare_slabs(src, opts, Mode::Lossy)?;
    let src = std::cell::RefCell::new(src);
    let lossless = || {
        let mut src = src.borrow_mut();
        let shape = src.shape().clone();
        let r = shape.raster(shape.dims.clone(), src.read_rows(0..shape.dims[0])?)?;
        encode_lossless(&r.view(), opts)
    };
    rate::encode_prepared(p, opts.rate, None, &lossless).map(Some)
}

fn lossless_int(x: f64, t: SampleType) -> i64 {
    let _ = t;
    x as i64
}

fn encode_lossless(r: &RasterView<'_>, opts: &EncodeOptions) -> Result<Vec<u8>> {
    let ty = r.sample_type();
    let colour = if r.channels >= 3 && !ty.is_float() {
        Colour::YCoCgR
    } else {
        Colour::None
    };
    let mut o = opts.clone();
    o.scheme = Scheme::Linear;
    o.boundary = Boundary::Symmetric;
    let mut header = header_for(r, &o, Mode::Lossless, colour)?;
    let c = r.channels;
    let n = r.positions();
    // float samples that are all multiples of a power of two are coded as the integers
    let quantum = if ty.is_float() {
        lossless::float_quantum((0..n * c).map(|i| r.samples.get_f64(i)))
    } else {
        None
    };
    if let Some(q) = quantum {
        header.delta = q;
    }
    let plan = Plan::new(&header)?;
    let mut planes = vec![vec![0i64; n]; c];
    for i in 0..n {
        for (k, p) in planes.iter_mut().enumerate() {
            p[i] = match (r.samples, quantum) {
                (s, Some(q)) => (s.get_f64(i * c + k) / q) as i64,
                (SamplesRef::F16(v), None) => {
                    lossless::float_bits_to_int(v[i * c + k].to_bits() as u64, 16)
                }
                (SamplesRef::F32(v), None) => {
                    lossless::float_bits_to_int(v[i * c + k].to_bits() as u64, 32)
                }
                (SamplesRef::F64(v), None) => {
                    lossless::float_bits_to_int(v[i * c + k].to_bits(), 64)
                }
                (s, None) => lossless_int(s.get_f64(i * c + k), ty),
            };
        }
    }
    if colour == Colour::YCoCgR {
        map3(&mut planes, lossless::ycocg_r);
    }
    planes
        .par_iter_mut()
        .for_each(|p| lossless::forward(p, &plan.pyr));
    let coded = plan.code_levels(c, Choice::Given, |k, j| {
        BandInput::Indices(layout::gather(
            &planes[k],
            &plan.pyr.shape,
            &plan.bands[j].ranges,
        ))
    });
    drop(planes);
    let mut out = format::SIGNATURE.to_vec();
    put_chunk(&mut out, HEAD, &header.to_bytes());
    let m = meta::to_bytes(r.meta);
    if !m.is_empty() {
        put_chunk(&mut out, META, &m);
    }
    plan.put_levels(&mut out, &coded, |_, _| 1.0);
    put_chunk(&mut out, MEND, &[]);
    Ok(out)
}
