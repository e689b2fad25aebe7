//! Decoding: the chunks read, each channel's bands entropy-decoded level by level,
//! dequantized and synthesized (or the integer transform inverted), the residual layer
//! added, and the metadata and voids of the level decoded.

use super::colour::map3;
use super::container::{read_head, read_rest, Parsed};
use super::options::{DecodeOptions, Decoded};
use super::plan::Plan;
use super::plan::{band_delta, band_rows, dequantize_row, lossy_values};
use super::voids::mark_voids;
use super::{layout, lossless};
use crate::entropy::range::Decoder;
use crate::entropy::{self, BandKind, Parent};
use crate::format::header::Colour;
use crate::format::Header;
use crate::format::Mode;
use crate::io::{Raster, SampleType, Samples};
use crate::scheme::Scheme;
use crate::{Error, Result};
use rayon::prelude::*;
use std::io::Read;

/// One band's indices from its coded bytes, by the coding of the file of header `h`.
fn decode_band(
    h: &Header,
    data: &[u8],
    dims: &[usize],
    kind: BandKind,
    parent: Option<Parent>,
) -> Result<Vec<i64>> {
    if h.version.has_levels() {
        let coding = super::plan::coding_of(h);
        entropy::band::decode(&mut Decoder::new_short(data), dims, kind, parent, coding)
    } else {
        entropy::decode_band(data, dims, kind, parent)
    }
}

/// Decode one channel's bands into its coefficient indices (None = absent). A band's
/// context is its parent band (one level coarser), so the bands of one level decode
/// in parallel, level after level from the coarse block down.
fn decode_channel(p: &Parsed, c: usize, k: usize) -> Result<Vec<Option<Vec<i64>>>> {
    let plan = &p.plan;
    let nb = plan.bands.len();
    let mut q: Vec<Option<Vec<i64>>> = (0..nb).map(|_| None).collect();
    let mut levels: Vec<usize> = plan.bands.iter().map(|b| b.level).collect();
    levels.sort_unstable_by_key(|&l| (l != 0, std::cmp::Reverse(l)));
    levels.dedup();
    for level in levels {
        if k > 0 && level >= 1 && level <= k {
            continue;
        }
        let bands: Vec<usize> = (0..nb).filter(|&j| plan.bands[j].level == level).collect();
        let decoded: Vec<Result<Option<Vec<i64>>>> = bands
            .par_iter()
            .map(|&j| {
                let Some(bc) = &p.bands[c][j] else {
                    return Ok(None);
                };
                let kind = if level == 0 {
                    BandKind::Coarse
                } else {
                    BandKind::Detail
                };
                let parent = match plan.parents[j] {
                    Some(pj) => match &q[pj] {
                        Some(v) => Some(Parent {
                            data: v,
                            dims: &plan.dims[pj],
                        }),
                        None => {
                            return Err(Error::format(
                                format!("band {j} of channel {c} without its parent"),
                                "complete parents",
                            ))
                        }
                    },
                    None => None,
                };
                decode_band(&p.header, &bc.data, &plan.dims[j], kind, parent)
                    .map(Some)
                    .map_err(|e| {
                        Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
                    })
            })
            .collect();
        // the first failing band in file order, as one at a time would report it
        for (&j, v) in bands.iter().zip(decoded) {
            q[j] = v?;
        }
    }
    Ok(q)
}

/// Decode one channel's bands of a lossy file straight into its `plane` (laid out as the
/// pyramid's shape, zeroed; absent bands stay 0), dequantized as they are decoded, level
/// by level from the coarse block down, the bands of a level in parallel. Only the
/// indices of the level that is the next one's context are held (a band with children,
/// until they are decoded); a band without children is decoded a row at a time
/// ([`entropy::band::decode_rows`]) straight into the plane.
fn decode_channel_into(p: &Parsed, c: usize, k: usize, plane: &mut [f32]) -> Result<()> {
    let (h, plan) = (&p.header, &p.plan);
    let nb = plan.bands.len();
    let has_children: Vec<bool> = (0..nb).map(|j| plan.parents.contains(&Some(j))).collect();
    let mut q: Vec<Option<Vec<i64>>> = (0..nb).map(|_| None).collect();
    for (level, js) in plan.level_groups() {
        if k > 0 && level >= 1 && level <= k {
            continue;
        }
        let rows = band_rows(plan, &js, plane);
        let decoded: Vec<Result<Option<Vec<i64>>>> = js
            .par_iter()
            .zip(rows)
            .map(|(&j, mut rows)| {
                let Some(bc) = &p.bands[c][j] else {
                    return Ok(None);
                };
                let parent = match plan.parents[j] {
                    Some(pj) => match &q[pj] {
                        Some(v) => Some(Parent {
                            data: v,
                            dims: &plan.dims[pj],
                        }),
                        None => {
                            return Err(Error::format(
                                format!("band {j} of channel {c} without its parent"),
                                "complete parents",
                            ))
                        }
                    },
                    None => None,
                };
                let (step, delta) = (bc.step, band_delta(h, plan, j));
                let dims = &plan.dims[j];
                let failed = |e: Error| {
                    Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
                };
                if !h.version.has_levels() || level == 0 || has_children[j] {
                    let kind = if level == 0 {
                        BandKind::Coarse
                    } else {
                        BandKind::Detail
                    };
                    let v = decode_band(h, &bc.data, dims, kind, parent).map_err(failed)?;
                    let cols = dims.last().copied().unwrap_or(1).max(1);
                    for (r, out) in v.chunks(cols).zip(rows.iter_mut()) {
                        dequantize_row(r, step, delta, out);
                    }
                    return Ok(has_children[j].then_some(v));
                }
                let mut d = Decoder::new_short(&bc.data);
                let mut at_row = 0;
                entropy::band::decode_rows(&mut d, dims, parent, plan.coding, |_, r| {
                    dequantize_row(r, step, delta, rows[at_row]);
                    at_row += 1;
                })
                .map_err(failed)?;
                Ok(None)
            })
            .collect();
        // the first failing band in file order, as one at a time would report it
        for (&j, v) in js.iter().zip(decoded) {
            q[j] = v?;
        }
        if level > 0 {
            // the bands of the level above have no other children
            for (v, b) in q.iter_mut().zip(&plan.bands) {
                if b.level == level + 1 {
                    *v = None;
                }
            }
        }
    }
    Ok(())
}

/// The most bytes [`reconstruct`] holds at once for level `k`, checked against the memory
/// budget ([`crate::limits`]) before anything is allocated:
///
/// ```text
/// bytes = C · Π shape · w  +  C · Π R_k · (s + x)
/// ```
/// with `shape` the full pyramid (every channel's plane is as large whatever the level),
/// `w` its bytes per coefficient (8: `i64` in lossless files, 4: `f32` otherwise),
/// `R_k` the level's extents, `s` the sample type's bytes, and `x` = 8 where the
/// samples also pass through `f64` (lossless, and the residual layer of mode 2).
fn check_budget(p: &Parsed, k: usize) -> Result<()> {
    let (h, plan) = (&p.header, &p.plan);
    let c = h.channels as u64;
    let full = plan
        .pyr
        .shape
        .iter()
        .fold(c, |n, &e| n.saturating_mul(e as u64));
    let out = plan
        .region(k)
        .iter()
        .fold(c, |n, &e| n.saturating_mul(e as u64));
    let wide = h.mode == Mode::Lossless || (h.mode == Mode::MaxError && k == 0);
    let w = if h.mode == Mode::Lossless { 8 } else { 4 };
    let x = if wide { 8 } else { 0 };
    let bytes = full
        .saturating_mul(w)
        .saturating_add(out.saturating_mul(h.sample_type.size() as u64 + x));
    crate::limits::check("decoded bytes (memory budget MRA_MAX_BYTES)", bytes)
}

pub(super) fn reconstruct(p: &Parsed, k: usize) -> Result<Raster> {
    let h = &p.header;
    let plan = &p.plan;
    let k = k.min(plan.pyr.depth());
    check_budget(p, k)?;
    let region = plan.region(k);
    let npos: usize = region.iter().product();
    let c = h.channels;
    let ty = h.sample_type;
    if h.mode == Mode::Lossless {
        let planes = (0..c)
            .into_par_iter()
            .map(|ch| {
                let q = decode_channel(p, ch, k)?;
                let mut plane = vec![0i64; plan.pyr.shape.iter().product()];
                for (j, b) in q.iter().enumerate() {
                    if let Some(b) = b {
                        layout::scatter(&mut plane, &plan.pyr.shape, &plan.bands[j].ranges, b);
                    }
                }
                lossless::inverse(&mut plane, &plan.pyr, k);
                let full: Vec<std::ops::Range<usize>> = region.iter().map(|&e| 0..e).collect();
                Ok(layout::gather(&plane, &plan.pyr.shape, &full))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut planes = planes;
        if h.colour == Colour::YCoCgR {
            map3(&mut planes, lossless::ycocg_r_inv);
        }
        let samples = match ty {
            SampleType::F16 | SampleType::F32 | SampleType::F64 if h.delta > 0.0 => {
                // mode 3: integer multiples of the quantum δ, exact in the sample type
                let values: Vec<f64> = (0..npos * c)
                    .map(|i| planes[i % c][i / c] as f64 * h.delta)
                    .collect();
                Samples::from_f64(&values, ty)
            }
            SampleType::F16 | SampleType::F32 | SampleType::F64 => {
                let w = (ty.size() * 8) as u32;
                let bits: Vec<u64> = (0..npos * c)
                    .map(|i| lossless::int_to_float_bits(planes[i % c][i / c], w))
                    .collect();
                match ty {
                    SampleType::F16 => Samples::F16(
                        bits.iter()
                            .map(|&b| half::f16::from_bits(b as u16))
                            .collect(),
                    ),
                    SampleType::F32 => {
                        Samples::F32(bits.iter().map(|&b| f32::from_bits(b as u32)).collect())
                    }
                    _ => Samples::F64(bits.iter().map(|&b| f64::from_bits(b)).collect()),
                }
            }
            _ => {
                let values: Vec<f64> = (0..npos * c).map(|i| planes[i % c][i / c] as f64).collect();
                Samples::from_f64(&values, ty)
            }
        };
        return finish(p, region, samples, k);
    }
    let mut samples = lossy_values(h, plan, k, |ch, plane| decode_channel_into(p, ch, k, plane))?;
    if k == 0 && h.mode == Mode::MaxError {
        let mut values = samples.to_f64();
        for (ch, r) in p.resi.iter().enumerate() {
            let Some(r) = r else { continue };
            let q = decode_band(h, &r.data, &h.dims, BandKind::Detail, None).map_err(|e| {
                Error::format(format!("RESI of channel {ch}: {e}"), "a valid residual")
            })?;
            for i in 0..npos {
                values[i * c + ch] = samples.get_f64(i * c + ch) + q[i] as f64 * r.step;
            }
            let _ = ch;
        }
        samples = Samples::from_f64(&values, ty);
        let mut all: Vec<(usize, f64)> = Vec::new();
        for (ch, r) in p.resi.iter().enumerate() {
            if let Some(r) = r {
                for &(i, v) in &r.exceptions {
                    if (i as usize) < npos {
                        all.push((i as usize * c + ch, v));
                    }
                }
            }
        }
        if !all.is_empty() {
            let mut v = samples.to_f64();
            for (i, x) in all {
                v[i] = x;
            }
            samples = Samples::from_f64(&v, ty);
        }
    }
    finish(p, region, samples, k)
}

fn finish(p: &Parsed, region: Vec<usize>, samples: Samples, k: usize) -> Result<Raster> {
    let h = &p.header;
    let mut r = Raster::new(region.clone(), h.channels, samples, h.kind)?;
    let maps = coarse_maps(p, k);
    r.meta = if k > 0 {
        p.meta.resampled(&h.dims, &region, &maps)
    } else {
        p.meta.clone()
    };
    mark_voids(&mut r, &h.dims, &maps);
    Ok(r)
}

/// Where a scheme's coarse sample `i` sits on the fine grid of one level: at fine index
/// `2i + o`. Haar (and the lossless S-transform): the mean of fine samples `2i`, `2i+1`,
/// `o = ½`. Chaikin: fine `2i`, `2i+1` are `¾ C_i + ¼ C_{i+1}` and `¼ C_i + ¾ C_{i+1}`,
/// so `C_i` sits at `o = −½`. Cubic B-spline: fine `2i` is `⅛ C_{i−1} + ¾ C_i + ⅛ C_{i+1}`,
/// `o = 0`. The schemes with an odd-length regular row (linear, linear-wide, cubic-wide, CDF
/// 9/7) centre `C_i` on fine `2i` (`o = 0`); chaikin-wide's even row, like Chaikin's, between fine
/// `2i − 1` and `2i` (`o = −½`).
pub fn coarse_offset(scheme: Scheme) -> f64 {
    match scheme {
        Scheme::Haar => 0.5,
        Scheme::Chaikin | Scheme::ChaikinWide => -0.5,
        Scheme::Cubic | Scheme::Linear | Scheme::LinearWide | Scheme::CubicWide | Scheme::Cdf97 => {
            0.0
        }
    }
}

/// Per spatial axis, where the samples of the coarse block after `k` levels sit on the
/// full grid: each level that shortens the axis maps by `step 2`, offset
/// [`coarse_offset`] (an odd length's carried last sample is off this grid by at most
/// half a coarse cell).
fn coarse_maps(p: &Parsed, k: usize) -> Vec<crate::io::AxisMap> {
    coarse_maps_of(&p.header, &p.plan, k)
}

/// [`coarse_maps`] of a header and its plan.
pub(super) fn coarse_maps_of(h: &Header, plan: &Plan, k: usize) -> Vec<crate::io::AxisMap> {
    // the integer transforms sit where their real schemes do (the S-transform's floored
    // mean like Haar's, the 5/3 lifting's coarse samples on even samples like linear's)
    let o = coarse_offset(h.scheme);
    let pyr = &plan.pyr;
    (0..h.dims.len())
        .map(|a| {
            let mut m = crate::io::AxisMap::IDENTITY;
            if let Some(i) = pyr.spec.axes.iter().position(|&x| x == a) {
                let lens = &pyr.lengths[i];
                for l in 0..k.min(pyr.axis_levels(i)) {
                    if lens[l + 1] < lens[l] {
                        m = m.then(crate::io::AxisMap {
                            offset: o,
                            step: 2.0,
                        });
                    }
                }
            }
            m
        })
        .collect()
}

/// Decode a one-tile file read in order (a tile of a tiled file, the base of a
/// `--max-error` file): its chunks reconstructed at `opts.level`, no region.
pub(super) fn decode_untiled<R: Read>(src: R, len: u64, opts: &DecodeOptions) -> Result<Decoded> {
    let (rd, first, header) = read_head(src, len)?;
    if header.is_tiled() {
        return Err(Error::format(
            "a tiled file inside a tile",
            "a one-tile file",
        ));
    }
    let p = read_rest(rd, first, header, opts.level, opts.allow_truncated)?;
    Ok(Decoded {
        raster: reconstruct(&p, opts.level)?,
        header: p.header,
        complete: p.complete,
    })
}
