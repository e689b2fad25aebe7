//! Void samples (NaN, `meta.nodata`) through the codec: filled by pull-push before the
//! transform, their mask kept in the metadata, and marked again after decoding.

use crate::entropy::range::{Decoder, Encoder, Mix};
use crate::io::nodata::Value;
use crate::io::{Raster, RasterView, Samples, SamplesRef};
use crate::Result;
use base64::Engine as _;

// the `meta.extra` key holding the void mask of an encoded raster: `m1:` then the
// base64 of the mask range-coded by `code_mask` (the container's key, §5.1)
use crate::format::meta::VOID_RUNS;
/// The prefix of a coded mask.
const CODED: &str = "m1:";

/// The causal neighbours of sample `i` as a context: the previous position along the
/// fastest axis (W), the row before (N, NW, NE), the slice before and the previous
/// channel, each 1 when inside the raster and void. `shape` is slowest first, with the
/// channel count last.
#[inline]
fn context(mask: &[bool], i: usize, shape: &[usize]) -> usize {
    let nd = shape.len();
    let c = shape[nd - 1];
    let k = i % c;
    let pos = i / c;
    let get = |j: usize| mask[j] as usize;
    let mut ctx = 0;
    if k > 0 {
        ctx |= get(i - 1);
    }
    if nd >= 2 {
        let w = shape[nd - 2];
        let x = pos % w;
        if x > 0 {
            ctx |= get(i - c) << 1;
        }
        if nd >= 3 {
            let h = shape[nd - 3];
            let y = (pos / w) % h;
            if y > 0 {
                let n = i - c * w;
                ctx |= get(n) << 2;
                if x > 0 {
                    ctx |= get(n - c) << 3;
                }
                if x + 1 < w {
                    ctx |= get(n + c) << 4;
                }
            }
            if nd >= 4 && pos >= w * h {
                ctx |= get(i - c * w * h) << 5;
            }
        }
    }
    ctx
}

/// The void mask (one flag per sample, channels interleaved; `shape` slowest first with
/// the channel count last) range-coded with adaptive binary models in the 64 contexts of
/// its causal neighbours ([`context`]).
fn code_mask(mask: &[bool], shape: &[usize]) -> Vec<u8> {
    let mut models = [Mix::default(); 64];
    let mut enc = Encoder::new();
    for i in 0..mask.len() {
        enc.bit(&mut models[context(mask, i, shape)], mask[i]);
    }
    enc.finish_short()
}

/// Inverse of [`code_mask`] for a mask of `n` samples.
fn decode_mask(data: &[u8], n: usize, shape: &[usize]) -> Vec<bool> {
    let mut models = [Mix::default(); 64];
    let mut dec = Decoder::new_short(data);
    let mut mask = vec![false; n];
    for i in 0..n {
        mask[i] = dec.bit(&mut models[context(&mask, i, shape)]);
    }
    mask
}

/// Whether `meta` lists void samples (a filled raster's, or a decoded file's `mETA`).
pub(super) fn lists_voids(meta: &crate::io::Metadata) -> bool {
    crate::format::meta::lists_voids(meta)
}

/// `r` with its void samples ([`crate::io::nodata`]) filled by pull-push and their runs
/// kept in [`VOID_RUNS`]; `None` when no sample (or every sample) is void. With `exact`
/// (a lossless file) a sample is void only when the decoder's marker gives its bits
/// back ([`restores_exactly`]): a NaN with a payload or a sign, a signalling NaN, or a
/// NaN in a raster whose nodata value is a number, stays a sample and is coded by its
/// bits like any other. Every other sample keeps its bits.
pub(super) fn with_voids_filled(r: &RasterView<'_>, exact: bool) -> Result<Option<Raster>> {
    // integer samples are never NaN: without a nodata value there is nothing to look for
    // (and no whole-raster `f64` copy to make)
    if !r.sample_type().is_float() && r.meta.nodata.is_none() {
        return Ok(None);
    }
    let mut v = r.samples.to_f64();
    let Some(mut voids) = crate::io::nodata::Voids::find(&v, r.meta.nodata) else {
        return Ok(None);
    };
    if exact {
        let marker = voids.marker;
        for (i, m) in voids.mask.iter_mut().enumerate() {
            *m = *m && restores_exactly(&r.samples, i, marker);
        }
        if voids.count() == 0 {
            return Ok(None);
        }
    }
    if voids.count() == v.len() {
        return Ok(None);
    }
    let mut shape = r.dims.to_vec();
    shape.push(r.channels);
    voids.fill(&mut v, &shape, r.dims.len())?;
    let coded = code_mask(&voids.mask, &shape);
    // the filled values go in at the voids only: the other samples keep their bits (a
    // round trip through f64 would quieten signalling NaNs)
    let mut samples = r.samples.to_owned();
    crate::io::with_samples!(&mut samples, s => {
        for (i, _) in voids.mask.iter().enumerate().filter(|(_, &m)| m) {
            s[i] = Value::from_f64(v[i]);
        }
    });
    let mut out = Raster::new(r.dims.to_vec(), r.channels, samples, r.kind)?;
    out.meta = r.meta.clone();
    let text = format!(
        "{CODED}{}",
        base64::engine::general_purpose::STANDARD_NO_PAD.encode(coded)
    );
    out.meta.extra.insert(VOID_RUNS.into(), text);
    Ok(Some(out))
}

/// Does the decoder's void marker (`marker` in the sample type, as
/// [`crate::io::nodata::Voids::restore`] writes it) have the bits of sample `i`?
/// Always for integer samples (a void is equal to the nodata value).
fn restores_exactly(s: &SamplesRef<'_>, i: usize, marker: f64) -> bool {
    match s {
        SamplesRef::F16(v) => v[i].to_bits() == <half::f16 as Value>::from_f64(marker).to_bits(),
        SamplesRef::F32(v) => v[i].to_bits() == <f32 as Value>::from_f64(marker).to_bits(),
        SamplesRef::F64(v) => v[i].to_bits() == marker.to_bits(),
        _ => true,
    }
}

/// The mask of runs `start:length` (files written before the coded mask); `None` when
/// one is malformed or past `n`.
fn parse_runs(runs: &str, n: usize) -> Option<Vec<bool>> {
    let mut mask = vec![false; n];
    for run in runs.split_whitespace() {
        let (a, l) = run.split_once(':')?;
        let (a, l) = (a.parse::<usize>().ok()?, l.parse::<usize>().ok()?);
        let e = a.checked_add(l).filter(|&e| e <= n)?;
        mask[a..e].iter_mut().for_each(|m| *m = true);
    }
    Some(mask)
}

/// The void mask a filled raster's metadata lists ([`with_voids_filled`]; one flag per
/// sample, channels interleaved), `None` without one or when it is malformed.
pub(super) fn void_mask(r: &RasterView<'_>) -> Option<Vec<bool>> {
    let runs = r.meta.extra.get(VOID_RUNS)?;
    let n = crate::io::bytes::sample_count(r.dims, r.channels).ok()?;
    let mut shape = r.dims.to_vec();
    shape.push(r.channels);
    match runs.strip_prefix(CODED) {
        Some(b64) => base64::engine::general_purpose::STANDARD_NO_PAD
            .decode(b64)
            .ok()
            .map(|data| decode_mask(&data, n, &shape)),
        None => parse_runs(runs, n),
    }
}

/// Mark the voids listed in `meta.extra[VOID_RUNS]` on a raster decoded at level `k`
/// (an output sample is void when its whole footprint on the full grid is) and drop
/// the key. A malformed list is ignored.
pub(super) fn mark_voids(r: &mut Raster, full: &[usize], maps: &[crate::io::AxisMap]) {
    let Some(runs) = r.meta.extra.remove(VOID_RUNS) else {
        return;
    };
    let Ok(n) = crate::io::bytes::sample_count(full, r.channels) else {
        return;
    };
    let mut shape = full.to_vec();
    shape.push(r.channels);
    let mask = if let Some(b64) = runs.strip_prefix(CODED) {
        match base64::engine::general_purpose::STANDARD_NO_PAD.decode(b64) {
            Ok(data) => decode_mask(&data, n, &shape),
            Err(_) => return,
        }
    } else {
        match parse_runs(&runs, n) {
            Some(m) => m,
            None => return,
        }
    };
    let voids = crate::io::nodata::Voids {
        mask,
        marker: r.meta.nodata.unwrap_or(f64::NAN),
        range: (f64::NEG_INFINITY, f64::INFINITY),
    };
    let m = voids.footprint(&shape, &r.dims, maps);
    crate::io::with_samples!(&mut r.samples, v => voids.restore(v, &m, false));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coded_masks_invert_on_every_shape() {
        let mut seed = 7u64;
        for shape in [
            vec![1, 1],
            vec![17, 1],
            vec![9, 13, 2],
            vec![5, 7, 11, 1],
            vec![3, 4, 5, 6, 1],
        ] {
            let n: usize = shape.iter().product();
            for density in [0u64, 3, 50, 100] {
                let mask: Vec<bool> = (0..n)
                    .map(|_| {
                        crate::entropy::testing::lcg(&mut seed);
                        (seed >> 33) % 100 < density
                    })
                    .collect();
                let coded = code_mask(&mask, &shape);
                assert_eq!(decode_mask(&coded, n, &shape), mask, "{shape:?} {density}%");
            }
        }
    }

    #[test]
    fn old_run_lists_still_parse() {
        assert_eq!(
            parse_runs("1:2 4:1", 6),
            Some(vec![false, true, true, false, true, false])
        );
        assert_eq!(parse_runs("5:2", 6), None);
        assert_eq!(parse_runs("x", 6), None);
    }
}
