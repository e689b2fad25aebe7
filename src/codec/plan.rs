//! The plan of a file: its pyramid, bands, each band's parent (the context of its
//! entropy coding) and extents, all derived from the header; and the way from
//! quantized bands back to samples, shared by the decoder and the encoder's searches.

use super::colour::{map3, ycocg_inverse};
use super::{layout, lossless};
use crate::format::header::Colour;
use crate::format::{Header, Mode};
use crate::io::Samples;
use crate::quantize::{self, RHO};
use crate::tensor::{self, Array, Order, Pyramid, PyramidSpec, Subband};
use crate::Result;
use rayon::prelude::*;
use std::borrow::Cow;

/// Pyramid, bands, their parents and extents for a header.
pub(super) struct Plan {
    pub(super) pyr: Pyramid,
    pub(super) bands: Vec<Subband>,
    pub(super) parents: Vec<Option<usize>>,
    pub(super) dims: Vec<Vec<usize>>,
}

impl Plan {
    pub(super) fn new(h: &Header) -> Result<Plan> {
        let pyr = if h.mode == Mode::Lossless {
            if !lossless::supports(h.scheme) {
                return Err(crate::Error::Unsupported {
                    what: "lossless scheme",
                    value: h.scheme.name().to_string(),
                });
            }
            lossless::plan(&h.dims, h.levels, h.scheme)
        } else {
            let spec = PyramidSpec {
                scheme: h.scheme,
                boundary: h.boundary,
                levels: h.levels,
                order: Order::NonStandard,
                axes: (0..h.dims.len()).collect(),
            };
            Pyramid::plan(&h.dims, &spec)?
        };
        let bands = pyr.subbands();
        let parents = bands
            .iter()
            .map(|b| {
                if b.level == 0 {
                    return None;
                }
                bands
                    .iter()
                    .position(|p| p.level == b.level + 1 && p.high == b.high)
            })
            .collect();
        let dims = bands
            .iter()
            .map(|b| b.ranges.iter().map(|r| r.len()).collect())
            .collect();
        Ok(Plan {
            pyr,
            bands,
            parents,
            dims,
        })
    }

    /// Extents of the coarse block left after `k` levels (k = 0: full size).
    pub(super) fn region(&self, k: usize) -> Vec<usize> {
        let mut r = self.pyr.shape.clone();
        for (i, &a) in self.pyr.spec.axes.iter().enumerate() {
            r[a] = self.pyr.lengths[i][k.min(self.pyr.axis_levels(i))];
        }
        r
    }

    /// The pyramid of the coarse block after `k` levels.
    pub(super) fn sub(&self, k: usize) -> Pyramid {
        let p = &self.pyr;
        Pyramid {
            spec: PyramidSpec {
                levels: p.spec.levels.saturating_sub(k),
                ..p.spec.clone()
            },
            shape: self.region(k),
            lengths: (0..p.lengths.len())
                .map(|i| p.lengths[i][k.min(p.axis_levels(i))..].to_vec())
                .collect(),
        }
    }
}

/// Quantization dead zone of band `j` (plain rounding for the coarse block).
pub(super) fn band_rho(plan: &Plan, j: usize) -> f64 {
    if plan.bands[j].level == 0 {
        0.5
    } else {
        RHO
    }
}

/// Dequantization offset of band `j` (none for the coarse block).
fn band_delta(h: &Header, plan: &Plan, j: usize) -> f64 {
    if plan.bands[j].level == 0 {
        0.0
    } else {
        h.delta
    }
}

/// Band `j`'s values from its indices `q` and its step, written where the band sits in
/// `plane` (laid out as the pyramid's shape).
fn dequantize_into(h: &Header, plan: &Plan, j: usize, q: &[i64], step: f64, plane: &mut [f32]) {
    let d = band_delta(h, plan, j);
    layout::rows(&plan.pyr.shape, &plan.bands[j].ranges, |off, run, at| {
        for (o, &x) in plane[off..off + run].iter_mut().zip(&q[at..at + run]) {
            *o = quantize::dequantize(x, step, d) as f32;
        }
    });
}

/// One band handed to [`lossy_values`]: its indices and its step.
pub(super) type BandIndices<'a> = Option<(Cow<'a, [i64]>, f64)>;

/// A lossy file's samples (interleaved, clamped to the source's range, before the
/// `--max-error` residuals) of the coarse block after `k` levels (k = 0: full size):
/// per channel, its bands' indices and steps (`bands(channel)[band]`, None = absent)
/// dequantized in place into the channel's plane (no copy of each band), synthesized
/// and taken back from YCoCg, converted straight into the header's sample type
/// ([`Samples::from_iter_f64`]: no whole-image `f64` copy). The decoder's way, and the
/// encoder's `--psnr` search's.
pub(super) fn lossy_values<'a>(
    h: &Header,
    plan: &Plan,
    k: usize,
    bands: impl Fn(usize) -> Result<Vec<BandIndices<'a>>> + Sync,
) -> Result<Samples> {
    let region = plan.region(k);
    let npos: usize = region.iter().product();
    let c = h.channels;
    let sub = plan.sub(k);
    let mut planes = (0..c)
        .into_par_iter()
        .map(|ch| {
            let q = bands(ch)?;
            let mut plane = vec![0f32; plan.pyr.shape.iter().product()];
            for (j, v) in q.into_iter().enumerate() {
                if let Some((v, step)) = v {
                    dequantize_into(h, plan, j, &v, step, &mut plane);
                }
            }
            let full: Vec<std::ops::Range<usize>> = region.iter().map(|&e| 0..e).collect();
            let small = if k == 0 {
                plane
            } else {
                layout::gather(&plane, &plan.pyr.shape, &full)
            };
            let mut a = Array::from_shape_vec(&region, small)?;
            tensor::synthesize(&mut a, &sub)?;
            Ok(a.into_data())
        })
        .collect::<Result<Vec<_>>>()?;
    if h.colour == Colour::YCoCg {
        map3(&mut planes, ycocg_inverse);
    }
    let (lo, hi) = (h.min, h.max);
    if c == 1 {
        // one plane: its values in order (no division per sample)
        let it = planes[0].iter().map(|&x| (x as f64).clamp(lo, hi));
        return Ok(Samples::from_iter_f64(it, npos, h.sample_type));
    }
    let it = (0..npos * c).map(|i| (planes[i % c][i / c] as f64).clamp(lo, hi));
    Ok(Samples::from_iter_f64(it, npos * c, h.sample_type))
}
