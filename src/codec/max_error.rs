//! `--max-error E`: every decoded sample within E of the source, as a lossy base plus
//! a spatial residual layer (one `RESI` chunk per channel).

use super::decode::decode_untiled;
use super::lossy::{prepare, prepare_slabs, Prepared};
use super::options::{DecodeOptions, EncodeOptions};
use super::voids::void_mask;
use crate::entropy::band;
use crate::format::bands::residual_payload;
use crate::format::tag::{MEND, RESI};
use crate::format::{put_chunk, Mode};
use crate::io::slab::SlabSource;
use crate::io::{RasterView, SampleType, Samples};
use crate::{Error, Result};
use rayon::prelude::*;

/// The largest bound accepted: the coarsest step coded is `RDO_STEPS`' last × `2E`
/// (`5E`), which must stay a finite `f64` for the file to decode.
const MAX_BOUND: f64 = f64::MAX / 8.0;

/// Whether bound `e` on samples of type `t` keeps every sample exact (0, or under 1 on
/// integer samples), so that the file is lossless; an error for a bound that is not
/// finite, ≥ 0 and at most [`MAX_BOUND`].
pub(super) fn is_exact(e: f64, t: SampleType) -> Result<bool> {
    if !(0.0..=MAX_BOUND).contains(&e) {
        // exponent form for the huge values this refuses (1e308 has 309 digits)
        let shown = if e.abs() >= 1e15 {
            format!("{e:e}")
        } else {
            e.to_string()
        };
        return Err(Error::parameter(
            "max-error",
            shown,
            "a bound ≥ 0 and ≤ 2.2e307; larger ones overflow the coded steps",
        ));
    }
    Ok(e == 0.0 || (!t.is_float() && e < 1.0))
}

/// Step of the residual layer for bound `e` on samples of type `t`.
pub(super) fn residual_step(e: f64, t: SampleType) -> f64 {
    if t.is_float() {
        2.0 * e * (1.0 - 1e-9)
    } else {
        2.0 * e.floor() + 1.0
    }
}

/// A `--max-error` file for a bound `e` that [`is_exact`] found lossy: the lossy base
/// with rate–distortion optimised indices at a step [`RDO_STEPS`] times the residual's
/// (`2E`, or `2⌊E⌋ + 1` on integer samples), the shortest file of those steps, then per
/// channel the residual to the decoded base quantized with [`residual_step`] and the
/// samples still outside the bound listed as exceptions.
pub(super) fn encode_max_error(
    r: &RasterView<'_>,
    opts: &EncodeOptions,
    e: f64,
) -> Result<Vec<u8>> {
    let bases = bases(prepare(r, opts, Mode::MaxError)?, e, r.sample_type());
    let voids = void_mask(r);
    shortest(bases, |base| with_residual(r, base, e, voids.as_deref()))
}

/// [`encode_max_error`] of integer samples without voids that `src` hands out in
/// slabs: the transform's planes filled a slab at a time
/// ([`super::lossy::prepare_slabs`]) and dropped once the bases are coded, then for
/// each base the samples read whole for its residual once the base is decoded. The same
/// bytes; the samples are never held beside the planes of the transform or of a base's
/// decode.
pub(super) fn encode_max_error_slabs<S: SlabSource + ?Sized>(
    src: &mut S,
    opts: &EncodeOptions,
    e: f64,
) -> Result<Vec<u8>> {
    let ty = src.shape().sample_type;
    let bases = bases(prepare_slabs(src, opts, Mode::MaxError)?, e, ty);
    let shape = src.shape().clone();
    shortest(bases, |base| {
        // the base decoded before the samples are read (its planes are the peak), the
        // samples read again for each base
        let dec = decode_base(&base)?;
        let r = shape.raster(shape.dims.clone(), src.read_rows(0..shape.dims[0])?)?;
        residual_file(&r.view(), base, dec, e, None)
    })
}

/// The base files of `p` at every step of [`RDO_STEPS`] (its indices rate–distortion
/// optimised, λ = 0.1, δ = 0); `p` is dropped once they are coded.
fn bases(mut p: Prepared, e: f64, ty: SampleType) -> Vec<Vec<u8>> {
    p.header.max_error = e;
    // the base's indices are chosen by rate–distortion optimisation (λ = 0.1, δ = 0) at
    // steps coarser than the residual's cell (2E, or 2⌊E⌋ + 1 on integers) by the
    // factors of RDO_STEPS, and the shortest file is kept: the residual corrects what
    // the base leaves, so a coarser base spending fewer bits wins, the more so at small
    // E (figures in docs/codec.md)
    let step = residual_step(e, ty).max(2.0 * e);
    p.optimise();
    let bases = RDO_STEPS.iter().map(|m| p.code(step * m)).collect();
    drop(p);
    crate::tuning::release_freed();
    bases
}

/// The shortest of the files `file(base)` makes of `bases` (the first of equal ones),
/// each base handed over (and so freed) as its turn comes.
fn shortest(
    bases: Vec<Vec<u8>>,
    mut file: impl FnMut(Vec<u8>) -> Result<Vec<u8>>,
) -> Result<Vec<u8>> {
    let mut best: Option<Vec<u8>> = None;
    for base in bases {
        let f = file(base)?;
        crate::tuning::release_freed();
        match &best {
            Some(b) if f.len() >= b.len() => {}
            _ => best = Some(f),
        }
    }
    Ok(best.expect("RDO_STEPS is not empty"))
}

/// The base steps over the residual's step tried with rate–distortion optimised indices.
/// On every corpus volume and DEM at every bound the 1.2 step alone spends fewer bits
/// than dead-zone indices at the residual's step; the coarser one wins at small bounds.
const RDO_STEPS: [f64; 2] = [1.2, 2.5];

/// A base file decoded alone (its header commits to the `RESI` chunks that follow it).
fn decode_base(base: &[u8]) -> Result<Samples> {
    Ok(decode_untiled(
        base,
        base.len() as u64,
        &DecodeOptions {
            level: 0,
            allow_truncated: true,
            ..Default::default()
        },
    )?
    .raster
    .samples)
}

/// The file of `base` (a base coded with `r`'s `--max-error` header) and the residual
/// layer of bound `e` that brings `r` back within it.
fn with_residual(
    r: &RasterView<'_>,
    base: Vec<u8>,
    e: f64,
    voids: Option<&[bool]>,
) -> Result<Vec<u8>> {
    let dec = decode_base(&base)?;
    residual_file(r, base, dec, e, voids)
}

/// The file of `base` followed, per channel, by the `RESI` chunk of the residual of
/// `r` to the decoded base `dec` (step [`residual_step`]) and its exceptions. Each
/// channel's indices are computed a row at a time as they are coded
/// ([`band::encode_stream_rows`]), never held whole.
fn residual_file(
    r: &RasterView<'_>,
    base: Vec<u8>,
    dec: Samples,
    e: f64,
    voids: Option<&[bool]>,
) -> Result<Vec<u8>> {
    let c = r.channels;
    let s = residual_step(e, r.sample_type());
    let coding = super::plan::coding_of(&crate::codec::header_of(&base)?);
    let cols = r.dims.last().copied().unwrap_or(1).max(1);
    let chunks: Vec<Vec<u8>> = (0..c)
        .into_par_iter()
        .map(|k| {
            let exc = exceptions(r, &dec, k, s, e, voids);
            let coded = band::encode_stream_rows(r.dims, None, coding, |g, out| {
                for (t, o) in out.iter_mut().enumerate() {
                    *o = residual_index(r, &dec, (g * cols + t) * c + k, s, voids);
                }
            });
            residual_payload(k, s, &exc, &coded)
        })
        .collect();
    drop(dec);
    let mut out = base;
    out.truncate(out.len() - 12); // drop MEND
    for ch in chunks {
        put_chunk(&mut out, RESI, &ch);
    }
    put_chunk(&mut out, MEND, &[]);
    Ok(out)
}

/// The residual index `round((x − x̂)/s)` of sample `i` (channels interleaved) over
/// the decoded base `dec`: 0 for a void sample (`voids`, filled before the transform
/// and marked again after decoding: the decoded base holds the void marker there, and
/// coding the distance from it to the fill cost the N22W160 tile an index of about 3000
/// at each of its 4279 voids) and for a sample that is not finite.
#[inline]
pub(super) fn residual_index(
    r: &RasterView<'_>,
    dec: &Samples,
    i: usize,
    s: f64,
    voids: Option<&[bool]>,
) -> i64 {
    if voids.is_some_and(|m| m[i]) {
        return 0;
    }
    let x = r.samples.get_f64(i);
    let xh = dec.get_f64(i);
    let d = if x.is_finite() { x - xh } else { 0.0 };
    (d / s).round() as i64
}

/// Channel `k`'s samples (index, value) that the residual layer over the decoded base
/// `dec` leaves outside the bound `e`: `x̂ + q·s` taken to the sample type (as
/// `Samples::from_f64` does) further than `e` from `x` (NaN for NaN is within). Void
/// samples are no exceptions.
pub(super) fn exceptions(
    r: &RasterView<'_>,
    dec: &Samples,
    k: usize,
    s: f64,
    e: f64,
    voids: Option<&[bool]>,
) -> Vec<(u64, f64)> {
    let (c, n) = (r.channels, r.positions());
    let ty = r.sample_type();
    let mut exc = Vec::new();
    for i in 0..n {
        let at = i * c + k;
        if voids.is_some_and(|m| m[at]) {
            continue;
        }
        let q = residual_index(r, dec, at, s, voids);
        let y = as_type(dec.get_f64(at) + q as f64 * s, ty);
        let x = r.samples.get_f64(at);
        // NaN differences are outside the bound, except NaN for NaN
        let within = (x - y).abs() <= e || (x.is_nan() && y.is_nan());
        if !within {
            exc.push((i as u64, x));
        }
    }
    exc
}

/// `x` taken to the sample type `ty` and back to `f64`: integers rounded half away from
/// zero and clamped to the type (NaN → 0), floats rounded to the type (what
/// `Samples::from_f64` then `get_f64` make of it).
#[inline]
fn as_type(x: f64, ty: SampleType) -> f64 {
    match ty {
        SampleType::F16 => half::f16::from_f64(x).to_f64(),
        SampleType::F32 => x as f32 as f64,
        SampleType::F64 => x,
        _ if x.is_nan() => 0.0,
        _ => {
            let (lo, hi) = ty.range();
            x.round().clamp(lo, hi)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::options::Rate;
    use crate::io::{DataKind, Raster};
    use crate::scheme::{Boundary, Scheme};

    /// Channel `k`'s residual indices over `dec` and its exceptions.
    fn residual(
        r: &RasterView<'_>,
        dec: &Samples,
        k: usize,
        s: f64,
        e: f64,
        voids: Option<&[bool]>,
    ) -> (Vec<i64>, Vec<(u64, f64)>) {
        let c = r.channels;
        let q = (0..r.positions())
            .map(|i| residual_index(r, dec, i * c + k, s, voids))
            .collect();
        (q, exceptions(r, dec, k, s, e, voids))
    }

    /// The file of `p`'s base at `step` and its residual layer.
    fn file_at(r: &RasterView<'_>, p: &Prepared, e: f64, step: f64) -> Vec<u8> {
        with_residual(r, p.code(step), e, None).unwrap()
    }

    /// A DEM-like raster: sea at exactly 0 on most of it, rough land in one corner.
    fn island(h: usize, w: usize) -> Raster {
        let mut s = 9u64;
        let v: Vec<f64> = (0..h * w)
            .map(|i| {
                let (y, x) = ((i / w) as f64, (i % w) as f64);
                let d = ((y - 20.0).powi(2) + (x - 24.0).powi(2)).sqrt();
                if d > 14.0 {
                    return 0.0;
                }
                crate::entropy::testing::lcg(&mut s);
                (14.0 - d) * 40.0 + ((s >> 40) % 60) as f64
            })
            .collect();
        Raster::new(
            vec![h, w],
            1,
            Samples::from_f64(&v, SampleType::I16),
            DataKind::Heightmap,
        )
        .unwrap()
    }

    /// The residual of a void sample is 0 and it is no exception, whatever the decoded
    /// base holds there (the void marker, NaN); elsewhere the index brings the sample
    /// within the bound, and a NaN base outside the voids is an exception.
    #[test]
    fn voids_have_no_residual_and_no_exceptions() {
        let src = [10.0f32, 50.0, 20.0, 7.0, -3.0];
        let dec = Samples::F32(vec![f32::NAN, -32768.0, 31.0, f32::NAN, -3.5]);
        let r = Raster::new(vec![5], 1, Samples::F32(src.to_vec()), DataKind::Image).unwrap();
        let voids = [true, true, false, false, false];
        let (e, s) = (2.0, residual_step(2.0, SampleType::F32));
        let (q, exc) = residual(&r.view(), &dec, 0, s, e, Some(&voids));
        assert_eq!(&q[..2], &[0, 0]);
        assert_eq!(q[2], ((20.0 - 31.0) / s).round() as i64);
        assert_ne!(q[2], 0);
        assert!((31.0 + q[2] as f64 * s - 20.0).abs() <= e);
        assert_eq!(q[4], 0);
        assert_eq!(exc, vec![(3, 7.0)]);
        // without the mask the voids are coded: a large index, an exception
        let (q, exc) = residual(&r.view(), &dec, 0, s, e, None);
        assert!(q[1] > 5000, "{q:?}");
        assert_eq!(exc, vec![(0, 10.0), (3, 7.0)]);
    }

    /// The encoder keeps the shortest of the optimised bases at the steps it tries, each
    /// holding the bound on every sample, and on a raster of flat sea and rough land it
    /// is shorter than the dead-zone base at the residual's step.
    #[test]
    fn the_shorter_base_is_kept_and_the_bound_holds() {
        let r = island(64, 80);
        for e in [2.0, 5.0] {
            let opts = EncodeOptions {
                scheme: Scheme::Cdf97,
                boundary: Boundary::Symmetric,
                levels: 6,
                rate: Rate::MaxError(e),
                format: Default::default(),
                effort: crate::codec::DEFAULT_EFFORT,
            };
            let s = residual_step(e, SampleType::I16);
            let mut p = prepare(&r.view(), &opts, Mode::MaxError).unwrap();
            p.header.max_error = e;
            let dead_zone = file_at(&r.view(), &p, e, s);
            p.optimise();
            let tried: Vec<Vec<u8>> = RDO_STEPS
                .iter()
                .map(|m| file_at(&r.view(), &p, e, s * m))
                .collect();
            let optimised = tried.iter().map(|f| f.len()).min().unwrap();
            let kept = encode_max_error(&r.view(), &opts, e).unwrap();
            assert_eq!(kept.len(), optimised, "E = {e}");
            assert!(
                optimised < dead_zone.len(),
                "E = {e}: {optimised} vs {}",
                dead_zone.len()
            );
            for file in tried.iter().chain([&dead_zone, &kept]) {
                let d = decode_untiled(&file[..], file.len() as u64, &DecodeOptions::default())
                    .unwrap()
                    .raster;
                for i in 0..r.positions() {
                    let (a, b) = (r.samples.get_f64(i), d.samples.get_f64(i));
                    assert!((a - b).abs() <= e, "E = {e}: sample {i} {a} → {b}");
                }
            }
        }
    }
}
