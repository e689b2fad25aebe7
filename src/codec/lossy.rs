//! A lossy encode: the header, the colour transform and the pyramid computed once
//! ([`Prepared`]), then quantized and coded at any base step.

use super::colour::{channel_weights, planes_f32};
use super::levels::{quantize_box, BandInput, Choice, CodedBand};
use super::options::{EncodeOptions, Format};
use super::plan::{band_rho, dequantize_into, lossy_values, Plan};
use super::{layout, meta};
use crate::entropy::codeblocks::Coder;
use crate::format::header::Colour;
use crate::format::tag::{HEAD, MEND, META};
use crate::format::{self, put_chunk, Header, Mode};
use crate::io::slab::SlabSource;
use crate::io::{Raster, RasterView, SamplesRef};
use crate::quantize::{self, DELTA};
use crate::tensor::{self, Array};
use crate::{Error, Result};
use rayon::prelude::*;

/// The least and greatest finite sample, `(0, 0)` when there is none (integers compared
/// as they are stored, floats through `f64`).
pub(super) fn finite_range(s: SamplesRef<'_>) -> (f64, f64) {
    // integers: blocks in parallel (the least and greatest of any split are the same)
    fn ints<T: Copy + Ord + Into<f64> + Send + Sync>(v: &[T]) -> Option<(f64, f64)> {
        let (lo, hi) = v
            .par_chunks(1 << 16)
            .filter_map(|b| Some((*b.iter().min()?, *b.iter().max()?)))
            .reduce_with(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
        Some((lo.into(), hi.into()))
    }
    fn floats(it: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
        let (lo, hi) = it
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(x), hi.max(x))
            });
        (lo <= hi).then_some((lo, hi))
    }
    match s {
        SamplesRef::U8(v) => ints(v),
        SamplesRef::I8(v) => ints(v),
        SamplesRef::U16(v) => ints(v),
        SamplesRef::I16(v) => ints(v),
        SamplesRef::U32(v) => ints(v),
        SamplesRef::I32(v) => ints(v),
        SamplesRef::F16(v) => floats(v.iter().map(|x| x.to_f64())),
        SamplesRef::F32(v) => floats(v.iter().map(|&x| x as f64)),
        SamplesRef::F64(v) => floats(v.iter().copied()),
    }
    .unwrap_or((0.0, 0.0))
}

/// The transform of a lossy encode, computed once and quantized at any step.
pub(super) struct Prepared {
    pub(super) header: Header,
    pub(super) plan: Plan,
    pub(super) gains: Vec<f64>,
    pub(super) weights: Vec<f64>,
    pub(super) coeffs: Vec<Vec<f32>>,
    pub(super) meta: Vec<u8>,
    /// The multiplier of rate–distortion optimised quantization, or `None` for the
    /// dead-zone quantizer ([`quantize::quantize`] with `ρ`).
    pub(super) rdo: Option<f32>,
}

pub(super) fn header_for(
    r: &RasterView<'_>,
    opts: &EncodeOptions,
    mode: Mode,
    colour: Colour,
) -> Result<Header> {
    let shape = Frame {
        dims: r.dims,
        channels: r.channels,
        sample_type: r.sample_type(),
        kind: r.kind,
    };
    header_with(&shape, opts, mode, colour, finite_range(r.samples), r.meta)
}

/// The header of a raster of `frame` whose least and greatest finite samples are
/// `range` ([`finite_range`]), with metadata `meta` (a list of voids makes the file
/// 2.4).
pub(super) fn header_with(
    frame: &Frame<'_>,
    opts: &EncodeOptions,
    mode: Mode,
    colour: Colour,
    range: (f64, f64),
    meta: &crate::io::Metadata,
) -> Result<Header> {
    let mut header = frame.header(opts, mode, colour)?;
    (header.min, header.max) = range;
    if super::voids::lists_voids(meta) {
        // 2.4: the header says the mETA lists voids, so a file without it is refused
        header.voids = true;
        let blocks = header.version.has_blocks();
        header.version = format::Version::for_file(mode == Mode::Lossless, true, blocks)
            .with_coder(header.coder);
    }
    Ok(header)
}

/// What a header says of a raster besides its samples.
pub(super) struct Frame<'a> {
    pub(super) dims: &'a [usize],
    pub(super) channels: usize,
    pub(super) sample_type: crate::io::SampleType,
    pub(super) kind: crate::io::DataKind,
}

impl Frame<'_> {
    /// The header of a raster of this frame, its extents and channels checked; `min` and
    /// `max` are left at 0 for the caller.
    fn header(&self, opts: &EncodeOptions, mode: Mode, colour: Colour) -> Result<Header> {
        let (dims, channels) = (self.dims, self.channels);
        if dims.is_empty() || dims.len() > format::header::MAX_AXES {
            return Err(Error::parameter(
                "dims",
                format!("{dims:?}"),
                "1 to 4 spatial axes",
            ));
        }
        if dims.iter().any(|&d| d == 0 || d > u32::MAX as usize) {
            return Err(Error::parameter(
                "dims",
                format!("{dims:?}"),
                "extents from 1 to 2^32−1",
            ));
        }
        if channels == 0 || channels > format::header::MAX_CHANNELS {
            return Err(Error::parameter("channels", channels, "1 to 256"));
        }
        if opts.levels > format::header::MAX_LEVELS {
            return Err(Error::parameter("levels", opts.levels, "0 to 32"));
        }
        if !super::options::EFFORTS.contains(&opts.effort) {
            return Err(Error::parameter("effort", opts.effort, "1 to 9"));
        }
        let blocks = opts.format == Format::Blocks;
        let coder = if blocks {
            let ladder = opts.ladder();
            let asked = if mode == Mode::Lossless {
                ladder.lossless
            } else {
                ladder.coder
            };
            coder_for(asked, self.sample_type, mode)
        } else {
            Coder::Context
        };
        Ok(Header {
            version: format::Version::for_file(mode == Mode::Lossless, false, blocks)
                .with_coder(coder.id()),
            kind: self.kind,
            sample_type: self.sample_type,
            dims: dims.to_vec(),
            channels,
            colour,
            mode,
            scheme: opts.scheme,
            boundary: opts.boundary,
            levels: opts.levels,
            step: 1.0,
            delta: if mode == Mode::Lossless { 0.0 } else { DELTA },
            max_error: 0.0,
            min: 0.0,
            max: 0.0,
            tile: dims.to_vec(),
            voids: false,
            blocks: if blocks {
                super::reblock::exponents(dims.len())
            } else {
                Vec::new()
            },
            coder: coder.id(),
        })
    }
}

/// The block coder a file of samples `t` in mode `mode` gets when its effort asks for
/// `asked`: a narrow coder ([`Coder::is_narrow`], `i32` indices) only for integer
/// samples of 16 bits or fewer in modes lossy and lossless, whose indices fit (a
/// lossless band of 16-bit samples grows by a few bits; a lossy step is at least
/// 10^−7 of the range); the context coder else.
pub(super) fn coder_for(asked: Coder, t: crate::io::SampleType, mode: Mode) -> Coder {
    use crate::io::SampleType as T;
    let small = matches!(t, T::U8 | T::I8 | T::U16 | T::I16);
    if !asked.is_narrow() || (small && matches!(mode, Mode::Lossy | Mode::Lossless)) {
        asked
    } else {
        Coder::Context
    }
}

/// The colour transform of a lossy encode: YCoCg for three channels or more.
pub(super) fn lossy_colour(channels: usize) -> Colour {
    if channels >= 3 {
        Colour::YCoCg
    } else {
        Colour::None
    }
}

pub(super) fn prepare(r: &RasterView<'_>, opts: &EncodeOptions, mode: Mode) -> Result<Prepared> {
    let colour = lossy_colour(r.channels);
    let header = header_for(r, opts, mode, colour)?;
    let planes = planes_f32(r, colour);
    analysed(header, planes, meta::to_bytes(r.meta))
}

/// [`prepare`] of an integer raster without voids that `src` hands out in slabs: each
/// slab converted into the `f32` planes as it is read, so that the samples are never
/// held whole beside the planes (a 256³ u16 volume: 67 MB of planes, not 101 MB). The
/// planes, the header and so the file are those of [`prepare`] of the whole raster: the
/// conversion and the colour transform act on each position alone, and the range is the
/// least and greatest of the slabs'.
pub(super) fn prepare_slabs<S: SlabSource + ?Sized>(
    src: &mut S,
    opts: &EncodeOptions,
    mode: Mode,
) -> Result<Prepared> {
    let shape = src.shape().clone();
    let colour = lossy_colour(shape.channels);
    let frame = Frame {
        dims: &shape.dims,
        channels: shape.channels,
        sample_type: shape.sample_type,
        kind: shape.kind,
    };
    // the extents checked before the slabs are read
    frame.header(opts, mode, colour)?;
    let n = shape.positions();
    let row = n / shape.dims[0];
    // about 2^20 positions a slab
    let rows = ((1usize << 20) / row.max(1)).clamp(1, shape.dims[0]);
    let mut planes: Vec<Vec<f32>> = (0..shape.channels).map(|_| Vec::with_capacity(n)).collect();
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for r0 in (0..shape.dims[0]).step_by(rows) {
        let r1 = (r0 + rows).min(shape.dims[0]);
        let mut dims = shape.dims.clone();
        dims[0] = r1 - r0;
        let slab = Raster::new(dims, shape.channels, src.read_rows(r0..r1)?, shape.kind)?;
        let view = slab.view();
        let (lo, hi) = finite_range(view.samples);
        (min, max) = (min.min(lo), max.max(hi));
        for (plane, part) in planes.iter_mut().zip(planes_f32(&view, colour)) {
            plane.extend_from_slice(&part);
        }
    }
    let header = header_with(&frame, opts, mode, colour, (min, max), &shape.meta)?;
    analysed(header, planes, meta::to_bytes(&shape.meta))
}

/// The pyramid of each plane, analysed in place, and what a lossy encode keeps beside it.
fn analysed(header: Header, planes: Vec<Vec<f32>>, meta: Vec<u8>) -> Result<Prepared> {
    let plan = Plan::new(&header)?;
    let weights = channel_weights(header.colour, header.channels);
    let spec = plan.pyr.spec.clone();
    let dims = header.dims.clone();
    // the gains beside the analysis (they need only the plan): a thread left over by
    // the channels (three on two threads) computes them
    let (gains, coeffs) = rayon::join(
        || quantize::band_gains(&plan.pyr, &plan.bands),
        || analyse_planes(planes, &dims, &spec),
    );
    Ok(Prepared {
        header,
        plan,
        gains,
        weights,
        coeffs: coeffs?,
        meta,
        rdo: None,
    })
}

/// Each plane (extents `dims`) analysed in place by `spec`'s pyramid, the planes in
/// parallel.
fn analyse_planes(
    planes: Vec<Vec<f32>>,
    dims: &[usize],
    spec: &tensor::PyramidSpec,
) -> Result<Vec<Vec<f32>>> {
    planes
        .into_par_iter()
        .map(|p| {
            let mut a = Array::from_shape_vec(&dims, p)?;
            // a volume analysed in place: the default engine's levels of 3 or more axes
            // run through a scratch array as large as the plane (kept by the shared
            // planner), which would add a third to the encoder's memory; in place costs
            // little time (CT 256³: 1.71 against 1.66 s of CPU for a whole encode)
            let engine = if dims.len() >= 3 {
                tensor::Engine::AxisByAxis
            } else {
                tensor::Engine::tuned()
            };
            tensor::analyze_with(&mut a, spec, engine)?;
            Ok(a.into_data())
        })
        .collect()
}

impl Prepared {
    /// Quantize with rate–distortion optimisation (multiplier [`quantize::LAMBDA`]) and
    /// reconstruct at the index (`δ = 0`).
    pub(super) fn optimise(&mut self) {
        self.rdo = Some(quantize::LAMBDA);
        self.header.delta = 0.0;
    }

    /// Band `j`'s step over the base step, `1 / (G_b · w_c)`, as the file stores it.
    pub(super) fn band_ratio(&self, band: usize, channel: usize) -> f32 {
        (1.0 / (self.gains[band] * self.weights[channel])) as f32
    }

    pub(super) fn band_step(&self, step: f64, band: usize, channel: usize) -> f64 {
        step * self.band_ratio(band, channel) as f64
    }

    /// Every band of every channel quantized and coded at base step `step`; the indices
    /// of each band kept when `keep_indices` (else they are empty).
    pub(super) fn coded(&self, step: f64, keep_indices: bool) -> Vec<Vec<CodedBand>> {
        let (plan, nc) = (&self.plan, self.coeffs.len());
        match self.rdo {
            Some(lambda) => plan.code_levels_with(nc, Choice::Rdo(lambda), keep_indices, |c, j| {
                BandInput::Coefficients {
                    plane: &self.coeffs[c],
                    step: self.band_step(step, j, c),
                }
            }),
            None => plan.code_levels_with(nc, Choice::Given, keep_indices, |c, j| {
                BandInput::Quantize {
                    plane: &self.coeffs[c],
                    step: self.band_step(step, j, c),
                    rho: band_rho(plan, j),
                }
            }),
        }
    }

    /// Band `j` of channel `c` quantized at base step `step`: its indices.
    pub(super) fn quantized(&self, step: f64, j: usize, c: usize) -> Vec<i64> {
        let plan = &self.plan;
        let (s, rho) = (self.band_step(step, j, c), band_rho(plan, j));
        // read from the plane row by row (no gathered copy of the band)
        quantize_box(
            &self.coeffs[c],
            &plan.pyr.shape,
            &plan.bands[j].ranges,
            s,
            rho,
        )
    }

    /// What a decoder makes of [`Prepared::code`]`(step)`, at full size, computed from the
    /// quantized bands without coding them (the coding is lossless): the same samples.
    pub(super) fn decoded(&self, step: f64) -> Result<Raster> {
        let (h, plan) = (&self.header, &self.plan);
        // optimised indices are known only by coding them
        let coded = self.rdo.map(|_| self.coded(step, true));
        let samples = lossy_values(h, plan, 0, |c, plane| {
            let put = |j: usize, q: &[i64], plane: &mut [f32]| {
                dequantize_into(h, plan, j, q, self.band_step(step, j, c), plane)
            };
            match &coded {
                Some(cb) => {
                    for (j, b) in cb[c].iter().enumerate() {
                        put(j, &b.q, plane);
                    }
                }
                None => {
                    let qs: Vec<Vec<i64>> = (0..plan.bands.len())
                        .into_par_iter()
                        .map(|j| self.quantized(step, j, c))
                        .collect();
                    for (j, q) in qs.iter().enumerate() {
                        put(j, q, plane);
                    }
                }
            }
            Ok(())
        })?;
        Raster::new(h.dims.clone(), h.channels, samples, h.kind)
    }

    /// Every (band, channel): bands in order, the channels of each.
    pub(super) fn band_channels(&self) -> Vec<(usize, usize)> {
        let nc = self.coeffs.len();
        (0..self.plan.bands.len())
            .flat_map(|j| (0..nc).map(move |c| (j, c)))
            .collect()
    }

    /// Quantize and code at base step `step`; the whole file.
    pub(super) fn code(&self, step: f64) -> Vec<u8> {
        let coded = self.coded(step, false);
        let mut h = self.header.clone();
        h.step = step;
        let mut out = format::SIGNATURE.to_vec();
        put_chunk(&mut out, HEAD, &h.to_bytes());
        if !self.meta.is_empty() {
            put_chunk(&mut out, META, &self.meta);
        }
        self.plan
            .put_levels(&mut out, &coded, |c, j| self.band_ratio(j, c));
        put_chunk(&mut out, MEND, &[]);
        out
    }

    /// Gain-weighted magnitudes of all detail coefficients.
    pub(super) fn weighted_details(&self) -> Vec<f32> {
        let mut v = Vec::new();
        for (j, b) in self.plan.bands.iter().enumerate() {
            if b.level == 0 {
                continue;
            }
            for (c, plane) in self.coeffs.iter().enumerate() {
                let w = (self.gains[j] * self.weights[c]) as f32;
                layout::rows(&self.plan.pyr.shape, &b.ranges, |off, run, _| {
                    v.extend(plane[off..off + run].iter().map(|x| x.abs() * w));
                });
            }
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::decode::decode_untiled;
    use crate::codec::options::{DecodeOptions, Rate};
    use crate::generate::{images, phantom};
    use crate::io::SampleType;
    use crate::scheme::{Boundary, Scheme};

    /// Bands quantized block by block as they are coded ([`BandInput::Quantize`]) code
    /// to the streams of the same bands quantized whole ([`BandInput::Indices`]), with
    /// every coder of the ladder.
    #[test]
    fn bands_quantized_by_blocks_code_as_quantized_whole() {
        let r = phantom::shepp_logan(20, 36, 44)
            .to_raster(SampleType::U16)
            .unwrap();
        for effort in [1, 4, 7] {
            let opts = EncodeOptions {
                effort,
                ..EncodeOptions::default()
            };
            let p = prepare(&r.view(), &opts, Mode::Lossy).unwrap();
            let range = p.header.max - p.header.min;
            for step in [range * 1e-3, range * 0.02] {
                let by_blocks = p.coded(step, false);
                let whole = p.plan.code_levels_with(1, Choice::Given, false, |c, j| {
                    BandInput::Indices(p.quantized(step, j, c))
                });
                for (j, (a, b)) in by_blocks[0].iter().zip(&whole[0]).enumerate() {
                    assert_eq!(a.stream, b.stream, "effort {effort} step {step} band {j}");
                }
            }
        }
    }

    /// The `--psnr` search measures [`Prepared::decoded`] instead of decoding each
    /// candidate file: it must be exactly what the decoder makes of that file.
    #[test]
    fn decoded_is_what_the_decoder_makes() {
        let rasters = [
            images::zone_plate(37, 50)
                .to_raster(SampleType::U8)
                .unwrap(),
            images::gradient(20, 33, 3)
                .to_raster(SampleType::U16)
                .unwrap(),
            images::noise(17, 24, 1, 5)
                .to_raster(SampleType::F32)
                .unwrap(),
            phantom::shepp_logan(12, 10, 14)
                .to_raster(SampleType::I16)
                .unwrap(),
        ];
        for r in &rasters {
            for scheme in Scheme::ALL {
                let opts = EncodeOptions {
                    scheme,
                    boundary: Boundary::Symmetric,
                    levels: 4,
                    rate: Rate::Quality(50.0),
                    format: Default::default(),
                    effort: crate::codec::DEFAULT_EFFORT,
                };
                let p = prepare(&r.view(), &opts, Mode::Lossy).unwrap();
                let range = p.header.max - p.header.min;
                for step in [range * 1e-4, range * 0.01, range * 0.3] {
                    let coded = p.code(step);
                    let file =
                        decode_untiled(&coded[..], coded.len() as u64, &DecodeOptions::default())
                            .unwrap();
                    let ours = p.decoded(step).unwrap();
                    assert_eq!(
                        ours.samples,
                        file.raster.samples,
                        "{} {scheme:?} step {step}",
                        r.summary()
                    );
                }
            }
        }
    }
}
