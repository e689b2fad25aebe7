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
    context_of(|j| mask[j], i, shape)
}

/// [`context`] with the flag of sample `j` read by `get` (a mask held in part: the
/// flags [`lookback`] before `i` and those after).
#[inline(always)]
fn context_of(get: impl Fn(usize) -> bool, i: usize, shape: &[usize]) -> usize {
    let nd = shape.len();
    let c = shape[nd - 1];
    let k = i % c;
    let pos = i / c;
    let get = |j: usize| get(j) as usize;
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

/// How far back [`context`] reads from sample `i` (the most of its neighbours' offsets):
/// the slice before (4 or more entries in `shape`), else the row before and a position.
fn lookback(shape: &[usize]) -> usize {
    let nd = shape.len();
    let c = shape[nd - 1];
    let mut back = c.max(1);
    if nd >= 3 {
        back = back.max(c * shape[nd - 2] + c);
    }
    if nd >= 4 {
        back = back.max(c * shape[nd - 2] * shape[nd - 3]);
    }
    back
}

/// [`code_mask`] a few rows at a time: the flags handed to [`MaskCoder::push`] in raster
/// order give the bytes `code_mask` gives of the whole mask, while only the last
/// [`lookback`] flags are held. Leading clear flags are counted, and coded (0 in context
/// 0, as their neighbours are clear too) only when a void comes.
pub(super) struct MaskCoder {
    shape: Vec<usize>,
    keep: usize,
    models: [Mix; 64],
    enc: Encoder,
    /// flags from sample `base` on: the last `keep` coded ones, then those being coded
    held: Vec<bool>,
    base: usize,
    /// flags received
    next: usize,
    voids: usize,
}

impl MaskCoder {
    /// The coder of a mask of `shape` (slowest first, the channel count last).
    pub(super) fn new(shape: &[usize]) -> MaskCoder {
        MaskCoder {
            shape: shape.to_vec(),
            keep: lookback(shape),
            models: [Mix::default(); 64],
            enc: Encoder::new(),
            held: Vec::new(),
            base: 0,
            next: 0,
            voids: 0,
        }
    }

    /// Code the next `flags` (the samples after those pushed before, raster order).
    pub(super) fn push(&mut self, flags: &[bool]) {
        let voids = flags.iter().filter(|&&f| f).count();
        if self.voids == 0 {
            if voids == 0 {
                self.next += flags.len();
                return;
            }
            // the clear flags so far, each in context 0
            for _ in 0..self.next {
                self.enc.bit(&mut self.models[0], false);
            }
            let h = self.keep.min(self.next);
            self.held = vec![false; h];
            self.base = self.next - h;
        }
        self.voids += voids;
        self.held.extend_from_slice(flags);
        let (held, base, shape) = (&self.held, self.base, &self.shape);
        for i in self.next..self.next + flags.len() {
            let ctx = context_of(|j| held[j - base], i, shape);
            self.enc.bit(&mut self.models[ctx], held[i - base]);
        }
        self.next += flags.len();
        let drop = self.held.len().saturating_sub(self.keep);
        self.held.drain(..drop);
        self.base += drop;
    }

    /// Void flags pushed so far.
    pub(super) fn voids(&self) -> usize {
        self.voids
    }

    /// The coded mask as [`VOID_RUNS`] holds it (`m1:` and base64); `None` when no
    /// flag was set.
    pub(super) fn finish(self) -> Option<String> {
        (self.voids > 0).then(|| coded_text(&self.enc.finish_short()))
    }
}

/// [`decode_mask`] a few rows at a time ([`MaskCoder`]'s inverse).
pub(super) struct MaskDecoder<'a> {
    shape: Vec<usize>,
    keep: usize,
    models: [Mix; 64],
    dec: Decoder<'a>,
    held: Vec<bool>,
    base: usize,
    next: usize,
}

impl<'a> MaskDecoder<'a> {
    /// The decoder of the coded mask `data` of `shape` ([`coded_bytes`]).
    pub(super) fn new(data: &'a [u8], shape: &[usize]) -> MaskDecoder<'a> {
        MaskDecoder {
            shape: shape.to_vec(),
            keep: lookback(shape),
            models: [Mix::default(); 64],
            dec: Decoder::new_short(data),
            held: Vec::new(),
            base: 0,
            next: 0,
        }
    }

    /// The next `n` flags (raster order).
    pub(super) fn next_flags(&mut self, n: usize) -> Vec<bool> {
        let start = self.held.len();
        self.held.reserve(n);
        for i in self.next..self.next + n {
            let (held, base) = (&self.held, self.base);
            let ctx = context_of(|j| held[j - base], i, &self.shape);
            let bit = self.dec.bit(&mut self.models[ctx]);
            self.held.push(bit);
        }
        self.next += n;
        let out = self.held[start..].to_vec();
        let drop = self.held.len().saturating_sub(self.keep);
        self.held.drain(..drop);
        self.base += drop;
        out
    }
}

/// The `VOID_RUNS` text of a coded mask.
fn coded_text(coded: &[u8]) -> String {
    format!(
        "{CODED}{}",
        base64::engine::general_purpose::STANDARD_NO_PAD.encode(coded)
    )
}

/// The bytes of the coded mask `meta` lists (`m1:` and base64); `None` without one, for
/// a run list, and when the base64 is malformed.
pub(super) fn coded_bytes(meta: &crate::io::Metadata) -> Option<Vec<u8>> {
    let b64 = meta.extra.get(VOID_RUNS)?.strip_prefix(CODED)?;
    base64::engine::general_purpose::STANDARD_NO_PAD
        .decode(b64)
        .ok()
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
    out.meta.extra.insert(VOID_RUNS.into(), coded_text(&coded));
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
    listed_mask(r.meta, r.dims, r.channels)
}

/// The void mask `meta` lists for a raster of `dims` × `channels` ([`void_mask`]).
pub(super) fn listed_mask(
    meta: &crate::io::Metadata,
    dims: &[usize],
    channels: usize,
) -> Option<Vec<bool>> {
    let runs = meta.extra.get(VOID_RUNS)?;
    let n = crate::io::bytes::sample_count(dims, channels).ok()?;
    let mut shape = dims.to_vec();
    shape.push(channels);
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
    fn masks_coded_rows_at_a_time_are_the_whole_masks() {
        let mut seed = 11u64;
        for shape in [
            vec![40, 1],
            vec![9, 13, 2],
            vec![6, 7, 5, 1],
            vec![3, 4, 5, 6, 2],
        ] {
            let n: usize = shape.iter().product();
            let row = n / shape[0];
            for density in [0u64, 2, 40] {
                // voids only after the first rows too (the clear prefix counted)
                let mask: Vec<bool> = (0..n)
                    .map(|i| {
                        crate::entropy::testing::lcg(&mut seed);
                        i >= 2 * row && (seed >> 33) % 100 < density
                    })
                    .collect();
                let whole = code_mask(&mask, &shape);
                for rows in [1, 2, 5] {
                    let mut c = MaskCoder::new(&shape);
                    for chunk in mask.chunks(rows * row) {
                        c.push(chunk);
                    }
                    let text = c.finish();
                    if !mask.contains(&true) {
                        assert_eq!(text, None);
                        continue;
                    }
                    assert_eq!(text.as_deref(), Some(coded_text(&whole).as_str()));
                    let mut d = MaskDecoder::new(&whole, &shape);
                    let back: Vec<bool> = mask
                        .chunks(rows * row)
                        .flat_map(|ch| d.next_flags(ch.len()))
                        .collect();
                    assert_eq!(back, mask, "{shape:?} {density}% {rows} rows");
                }
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
