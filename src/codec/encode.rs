//! Encoding one tile: the file of the rate mode (lossy at a step, with a residual layer
//! for `--max-error`, or the integer transform of `--lossless`).

use super::colour::map3;
use super::levels::{BandInput, Choice, CodedBand};
use super::lossy::{finite_range, header_for, header_with, Frame};
use super::options::{EncodeOptions, Rate};
use super::plan::Plan;
use super::{layout, lossless, max_error, meta, rate};
use crate::entropy::{band, codeblocks, BandKind, Parent};
use crate::format::bands::blocks_payload;
use crate::format::header::Colour;
use crate::format::tag::{HEAD, MEND, META};
use crate::format::{self, put_chunk, Header, Mode};
use crate::io::slab::{MemorySlabs, SlabSource};
use crate::io::{RasterView, SampleType, Samples, SamplesRef};
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

/// The file of a whole raster that `src` hands out in slabs, for integer samples
/// without a nodata value (no voids to fill): the bytes of [`encode_filled`], with the
/// samples read a slab at a time, so that they are never held whole beside the
/// transform's planes. `--quality`, `--keep`, `--threshold` and `--bpp` read them into
/// the `f32` planes ([`super::lossy::prepare_slabs`]; `--bpp` near the lossless cost and
/// `--quality 100` read them again for the lossless file); `--lossless` into `i32`
/// planes ([`encode_lossless_src`]); `--max-error` into the `f32` planes, and again
/// whole for the residual once the planes are dropped
/// ([`max_error::encode_max_error_slabs`]).
/// `None` for the other rate modes and samples, which need the raster whole.
pub(super) fn encode_slabs<S: SlabSource + ?Sized>(
    src: &mut S,
    opts: &EncodeOptions,
) -> Result<Option<Vec<u8>>> {
    let shape = src.shape();
    let ty = shape.sample_type;
    if ty.is_float() || shape.meta.nodata.is_some() {
        return Ok(None);
    }
    match opts.rate {
        // effort 9's `--bpp` measures each candidate's error against the samples
        Rate::Bpp(_) if opts.ladder().bpp_levels => return Ok(None),
        Rate::Quality(_) | Rate::Keep(_) | Rate::Threshold(_) | Rate::Bpp(_) => {}
        Rate::Lossless => return encode_lossless_src(src, opts).map(Some),
        Rate::MaxError(e) if max_error::is_exact(e, ty)? => {
            return encode_lossless_src(src, opts).map(Some)
        }
        Rate::MaxError(e) => return max_error::encode_max_error_slabs(src, opts, e).map(Some),
        _ => return Ok(None),
    }
    let p = super::lossy::prepare_slabs(src, opts, Mode::Lossy)?;
    let src = std::cell::RefCell::new(src);
    let lossless = || encode_lossless_src(&mut **src.borrow_mut(), opts);
    rate::encode_prepared(p, opts.rate, opts.ladder(), None, &lossless).map(Some)
}

fn lossless_int(x: f64, t: SampleType) -> i64 {
    let _ = t;
    x as i64
}

/// The options of a `--lossless` file: the 5/3 lifting, whole-sample symmetric ends.
pub(super) fn lossless_options(opts: &EncodeOptions) -> EncodeOptions {
    let mut o = opts.clone();
    o.scheme = Scheme::Linear;
    o.boundary = Boundary::Symmetric;
    o
}

/// The `--lossless` file of a raster: [`encode_lossless_narrow`] where the sample type
/// allows it, else (or when a value does not fit 32 bits) [`encode_lossless_wide`].
pub(super) fn encode_lossless(r: &RasterView<'_>, opts: &EncodeOptions) -> Result<Vec<u8>> {
    if lossless::narrow(r.sample_type()) {
        if let Some(file) = encode_lossless_narrow(&mut MemorySlabs::of_view(*r), opts)? {
            return Ok(file);
        }
    }
    encode_lossless_wide(r, opts)
}

/// [`encode_lossless`] of the raster `src` hands out (integer samples without a nodata
/// value: no voids to fill): read a slab at a time into `i32` planes where the sample
/// type allows it, else read whole.
pub(super) fn encode_lossless_src<S: SlabSource + ?Sized>(
    src: &mut S,
    opts: &EncodeOptions,
) -> Result<Vec<u8>> {
    let shape = src.shape().clone();
    if lossless::narrow(shape.sample_type) {
        if let Some(file) = encode_lossless_narrow(src, opts)? {
            return Ok(file);
        }
    }
    let r = shape.raster(shape.dims.clone(), src.read_rows(0..shape.dims[0])?)?;
    encode_lossless_wide(&r.view(), opts)
}

/// The `--lossless` file of 8- or 16-bit integer samples ([`lossless::narrow`]) that
/// `src` hands out in slabs, with the transform in `i32` planes: the samples read a slab
/// at a time (about 2^20 positions) into the planes, never held whole; each band coded
/// from the plane ([`code_plane`]). The bytes of [`encode_lossless_wide`]: the same
/// header, and the same transform values (computed in `i64` a lane at a time, stored
/// only when they fit); `None` when one does not fit 32 bits.
fn encode_lossless_narrow<S: SlabSource + ?Sized>(
    src: &mut S,
    opts: &EncodeOptions,
) -> Result<Option<Vec<u8>>> {
    let shape = src.shape().clone();
    let c = shape.channels;
    let colour = if c >= 3 { Colour::YCoCgR } else { Colour::None };
    let frame = Frame {
        dims: &shape.dims,
        channels: c,
        sample_type: shape.sample_type,
        kind: shape.kind,
    };
    let n = shape.positions();
    let d0 = shape.dims[0];
    let rows = ((1usize << 20) / (n / d0).max(1)).clamp(1, d0);
    let mut planes: Vec<Vec<i32>> = (0..c).map(|_| Vec::with_capacity(n)).collect();
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for r0 in (0..d0).step_by(rows) {
        let slab = src.read_rows(r0..(r0 + rows).min(d0))?;
        let (lo, hi) = finite_range(slab.view());
        (min, max) = (min.min(lo), max.max(hi));
        let ycocg = colour == Colour::YCoCgR;
        match &slab {
            Samples::U8(v) => push_planes(&v[..], ycocg, &mut planes),
            Samples::I8(v) => push_planes(&v[..], ycocg, &mut planes),
            Samples::U16(v) => push_planes(&v[..], ycocg, &mut planes),
            Samples::I16(v) => push_planes(&v[..], ycocg, &mut planes),
            _ => return Ok(None),
        }
    }
    let header = header_with(
        &frame,
        &lossless_options(opts),
        Mode::Lossless,
        colour,
        (min, max),
        &shape.meta,
    )?;
    let plan = Plan::new(&header)?;
    let fits = planes
        .par_iter_mut()
        .map(|p| lossless::forward(&mut p[..], &plan.pyr))
        .collect::<Vec<bool>>();
    if fits.contains(&false) {
        return Ok(None);
    }
    let coded: Vec<Vec<CodedBand>> = planes
        .into_par_iter()
        .map(|p| code_plane(&plan, p))
        .collect();
    Ok(Some(lossless_file(
        &header,
        &plan,
        &coded,
        &meta::to_bytes(&shape.meta),
    )))
}

/// Append the samples `v` (positions of `c = planes.len()` interleaved channels) to
/// the planes, the first three through YCoCg-R when `ycocg`.
fn push_planes<T: Copy + Into<i64>>(v: &[T], ycocg: bool, planes: &mut [Vec<i32>]) {
    let c = planes.len();
    if c == 1 {
        planes[0].extend(v.iter().map(|&x| x.into() as i32));
        return;
    }
    for px in v.chunks_exact(c) {
        let first = if ycocg {
            let (y, co, cg) = lossless::ycocg_r(px[0].into(), px[1].into(), px[2].into());
            // 8 and 16-bit samples: at most 17 bits
            planes[0].push(y as i32);
            planes[1].push(co as i32);
            planes[2].push(cg as i32);
            3
        } else {
            0
        };
        for (p, &x) in planes[first..].iter_mut().zip(&px[first..]) {
            p.push(x.into() as i32);
        }
    }
}

/// The bands of an integer plane (laid out as the pyramid's shape, after
/// [`lossless::forward`]) coded as given indices (as [`Plan::code_levels`] codes them:
/// the same streams). Each band's stream depends only on its indices and its parent's,
/// so the bands are coded from the finest level to the coarse block, straight from the
/// plane a row at a time ([`band::encode_stream_rows`]), a parent copied to `i64` while
/// its child is coded; after each group (the bands of a level high along the slowest
/// axis, then the others) the plane is cut to the end of the bands left, so that a
/// volume's plane halves once the finest level's upper half is coded.
fn code_plane(plan: &Plan, mut plane: Vec<i32>) -> Vec<CodedBand> {
    let shape = &plan.pyr.shape;
    let nb = plan.bands.len();
    let ends: Vec<usize> = (0..nb)
        .map(|j| {
            let mut end = 0;
            layout::rows(shape, &plan.bands[j].ranges, |off, run, _| {
                end = end.max(off + run)
            });
            end
        })
        .collect();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (_, js) in plan.level_groups().into_iter().rev() {
        let (upper, lower): (Vec<usize>, Vec<usize>) = js
            .iter()
            .partition(|&&j| plan.bands[j].high.first() == Some(&true));
        groups.extend([upper, lower].into_iter().filter(|g| !g.is_empty()));
    }
    let mut streams: Vec<Vec<u8>> = vec![Vec::new(); nb];
    for (i, group) in groups.iter().enumerate() {
        let coded: Vec<Vec<u8>> = group
            .par_iter()
            .map(|&j| code_plane_band(plan, &plane, j))
            .collect();
        for (&j, s) in group.iter().zip(coded) {
            streams[j] = s;
        }
        let keep = groups[i + 1..]
            .iter()
            .flatten()
            .map(|&j| ends[j])
            .max()
            .unwrap_or(0);
        if keep < plane.len() {
            plane.truncate(keep);
            plane.shrink_to_fit();
        }
    }
    streams
        .into_iter()
        .map(|stream| CodedBand {
            q: Vec::new(),
            stream,
        })
        .collect()
}

/// Band `j` of an integer plane coded as given indices (see [`code_plane`]).
fn code_plane_band(plan: &Plan, plane: &[i32], j: usize) -> Vec<u8> {
    let shape = &plan.pyr.shape;
    let dims = &plan.dims[j];
    let wide = |ranges: &[std::ops::Range<usize>]| {
        let mut out = Vec::with_capacity(ranges.iter().map(|r| r.len()).product());
        layout::rows(shape, ranges, |off, run, _| {
            out.extend(plane[off..off + run].iter().map(|&v| v as i64))
        });
        out
    };
    let ranges = &plan.bands[j].ranges;
    if plan.bands[j].level == 0 || dims.contains(&0) {
        let kind = if plan.bands[j].level == 0 {
            BandKind::Coarse
        } else {
            BandKind::Detail
        };
        return plan.code_indices(&wide(ranges), j, kind, None);
    }
    let pq = plan.parents[j].map(|p| wide(&plan.bands[p].ranges));
    let parent = plan.parents[j].zip(pq.as_deref()).map(|(p, data)| Parent {
        data,
        dims: &plan.dims[p],
    });
    if let Some(g) = plan.grid(j) {
        let blocks = codeblocks::encode_blocks_by(
            &g,
            BandKind::Detail,
            parent,
            plan.coding,
            plan.coder,
            |b| {
                layout::gather(plane, shape, &plan.in_plane(j, b))
                    .into_iter()
                    .map(i64::from)
                    .collect()
            },
        );
        return blocks_payload(&blocks);
    }
    let offs = plan.row_offsets(j);
    let cols = dims.last().copied().unwrap_or(1);
    band::encode_stream_rows(dims, parent, plan.coding, |g, out| {
        for (o, &v) in out.iter_mut().zip(&plane[offs[g]..offs[g] + cols]) {
            *o = v as i64;
        }
    })
}

/// The bytes of a `--lossless` file: signature, `HEAD`, `mETA` (when `meta` is not
/// empty), the `LEVL` chunks of `coded` and `MEND`.
fn lossless_file(header: &Header, plan: &Plan, coded: &[Vec<CodedBand>], meta: &[u8]) -> Vec<u8> {
    let mut out = format::SIGNATURE.to_vec();
    put_chunk(&mut out, HEAD, &header.to_bytes());
    if !meta.is_empty() {
        put_chunk(&mut out, META, meta);
    }
    plan.put_levels(&mut out, coded, |_, _| 1.0);
    put_chunk(&mut out, MEND, &[]);
    out
}

/// The `--lossless` file of any raster, with the transform in `i64` planes (floats
/// mapped to integers: see [`lossless`]).
fn encode_lossless_wide(r: &RasterView<'_>, opts: &EncodeOptions) -> Result<Vec<u8>> {
    let ty = r.sample_type();
    let colour = if r.channels >= 3 && !ty.is_float() {
        Colour::YCoCgR
    } else {
        Colour::None
    };
    let o = lossless_options(opts);
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
    planes.par_iter_mut().for_each(|p| {
        lossless::forward(&mut p[..], &plan.pyr);
    });
    let coded = plan.code_levels(c, Choice::Given, |k, j| {
        BandInput::Indices(layout::gather(
            &planes[k],
            &plan.pyr.shape,
            &plan.bands[j].ranges,
        ))
    });
    drop(planes);
    Ok(lossless_file(
        &header,
        &plan,
        &coded,
        &meta::to_bytes(r.meta),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{DataKind, Raster};

    /// A raster of `ty` over its whole range: smooth, noisy, and its extremes.
    fn raster(dims: &[usize], c: usize, ty: SampleType, seed: u64) -> Raster {
        let (lo, hi) = ty.range();
        let n: usize = dims.iter().product::<usize>() * c;
        let mut s = seed;
        let v: Vec<f64> = (0..n)
            .map(|i| {
                crate::entropy::testing::lcg(&mut s);
                let t = (i as f64 * 0.013).sin() * 0.4 + 0.5 + ((s >> 40) % 64) as f64 / 640.0;
                match i % 97 {
                    0 => lo,
                    1 => hi,
                    _ => lo + t * (hi - lo),
                }
            })
            .collect();
        let kind = if dims.len() >= 3 {
            DataKind::Volume
        } else {
            DataKind::Image
        };
        let mut r = Raster::new(dims.to_vec(), c, Samples::from_f64(&v, ty), kind).unwrap();
        r.meta.description = Some("narrow".into());
        r
    }

    /// The `i32` planes read in slabs write the bytes of the `i64` planes, for every
    /// narrow sample type, colour and shape (over 2^20 positions: several slabs).
    #[test]
    fn narrow_planes_write_the_file_of_wide_ones() {
        let cases: [(&[usize], usize, SampleType); 6] = [
            (&[33, 47], 3, SampleType::U8),
            (&[40, 31], 1, SampleType::I8),
            (&[9, 20, 17], 1, SampleType::U16),
            (&[12, 13], 2, SampleType::I16),
            (&[3, 4, 5, 6], 1, SampleType::U16),
            (&[3, 700, 520], 1, SampleType::U8),
        ];
        for (dims, c, ty) in cases {
            let r = raster(dims, c, ty, dims.len() as u64);
            let opts = EncodeOptions {
                scheme: Scheme::Cdf97,
                boundary: Boundary::Periodic,
                levels: 5,
                rate: Rate::Lossless,
                format: Default::default(),
                effort: crate::codec::DEFAULT_EFFORT,
            };
            let wide = encode_lossless_wide(&r.view(), &opts).unwrap();
            let narrow = encode_lossless_narrow(&mut MemorySlabs::new(&r), &opts)
                .unwrap()
                .expect("16-bit values fit");
            assert!(narrow == wide, "{dims:?} {c} {ty}");
            assert!(encode_lossless(&r.view(), &opts).unwrap() == wide);
        }
    }

    /// A lossless file of narrow samples decodes in `i32` planes to the samples of the
    /// `i64` planes at every level.
    #[test]
    fn narrow_planes_decode_the_samples_of_wide_ones() {
        let cases: [(&[usize], usize, SampleType); 4] = [
            (&[33, 47], 3, SampleType::U8),
            (&[40, 31], 1, SampleType::I8),
            (&[9, 20, 17], 1, SampleType::U16),
            (&[12, 13], 2, SampleType::I16),
        ];
        for (dims, c, ty) in cases {
            let r = raster(dims, c, ty, 3);
            let opts = EncodeOptions {
                scheme: Scheme::Linear,
                boundary: Boundary::Symmetric,
                levels: 4,
                rate: Rate::Lossless,
                format: Default::default(),
                effort: crate::codec::DEFAULT_EFFORT,
            };
            let file = crate::codec::encode(&r, &opts).unwrap();
            for k in 0..3 {
                let p =
                    crate::codec::container::read_chunks(&file[..], file.len() as u64, k, false)
                        .unwrap();
                let narrow = super::super::decode::lossless_narrow(&p, k)
                    .unwrap()
                    .expect("16-bit values fit");
                assert_eq!(
                    narrow,
                    super::super::decode::lossless_wide(&p, k).unwrap(),
                    "{dims:?} {ty} level {k}"
                );
                if k == 0 {
                    assert_eq!(narrow, r.samples);
                }
            }
        }
    }
}
