//! The plan of a file: its pyramid, bands, each band's parent (the context of its
//! entropy coding) and extents, all derived from the header; and the way from
//! quantized bands back to samples, shared by the decoder and the encoder's searches.

use super::colour::ycocg_inverse;
use super::{layout, lossless};
use crate::entropy::band::Coding;
use crate::entropy::codeblocks::Coder;
use crate::format::header::Colour;
use crate::format::{Header, Mode};
use crate::io::{SampleType, Samples};
use crate::quantize::{self, RHO};
use crate::tensor::{self, Array, Order, Pyramid, PyramidSpec, Subband};
use crate::Result;
use rayon::prelude::*;

/// The block coder of a file of header `h`: its coder byte in a code-block file (3.1;
/// 3.0 is coder 0), the context coder else. `Header::parse` has checked the byte.
pub(super) fn coder_of(h: &Header) -> Coder {
    if h.version.has_blocks() {
        Coder::of(h.coder).unwrap_or_default()
    } else {
        Coder::Context
    }
}

/// The coefficient coding of a file of header `h`: from format 2.3 on each band
/// chooses its magnitude classes (formats/MRA.md §9).
pub(super) fn coding_of(h: &Header) -> Coding {
    if h.version.has_chosen_coding() {
        Coding::Chosen
    } else {
        Coding::Narrow
    }
}

/// Pyramid, bands, their parents and extents for a header.
pub(super) struct Plan {
    pub(super) pyr: Pyramid,
    pub(super) bands: Vec<Subband>,
    pub(super) parents: Vec<Option<usize>>,
    pub(super) dims: Vec<Vec<usize>>,
    /// The coefficient coding (format 2.3 and later: each band's classes chosen).
    pub(super) coding: Coding,
    /// The code-block extents of each band of a format 3 file (every band cut into
    /// its own, §15; from 3.2 they shrink with coarser levels, §15.3); `None` before.
    pub(super) blocks: Option<Vec<Vec<usize>>>,
    /// The coder of every code-block (format 3.1; [`Coder::Context`] before).
    pub(super) coder: Coder,
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
        // §15.3: the coarse block's blocks are those of the coarsest detail level
        let block_extents = |h: &Header, bands: &[Subband]| -> Vec<Vec<usize>> {
            let top = bands.iter().map(|b| b.level).max().unwrap_or(0);
            bands
                .iter()
                .map(|b| h.block_extents_at(if b.level == 0 { top } else { b.level }))
                .collect()
        };
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
        let blocks = h.version.has_blocks().then(|| block_extents(h, &bands));
        Ok(Plan {
            pyr,
            bands,
            parents,
            dims,
            coding: coding_of(h),
            blocks,
            coder: coder_of(h),
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
pub(super) fn band_delta(h: &Header, plan: &Plan, j: usize) -> f64 {
    if plan.bands[j].level == 0 {
        0.0
    } else {
        h.delta
    }
}

/// Band `j`'s values from its indices `q` and its step, written where the band sits in
/// `plane` (laid out as the pyramid's shape).
pub(super) fn dequantize_into(
    h: &Header,
    plan: &Plan,
    j: usize,
    q: &[i64],
    step: f64,
    plane: &mut [f32],
) {
    let d = band_delta(h, plan, j);
    layout::rows(&plan.pyr.shape, &plan.bands[j].ranges, |off, run, at| {
        dequantize_row(&q[at..at + run], step, d, &mut plane[off..off + run]);
    });
}

/// `out[i] = sign(q)·(|q| + δ)·Δ` ([`quantize::dequantize`]) as `f32`.
#[inline]
pub(super) fn dequantize_row(q: &[i64], step: f64, delta: f64, out: &mut [f32]) {
    for (o, &x) in out.iter_mut().zip(q) {
        *o = quantize::dequantize(x, step, delta) as f32;
    }
}

/// [`dequantize_row`] of `i32` indices: the same arithmetic on the same `f64` values
/// (an `i32` converts exactly), written as selects so that the loop vectorises.
#[inline]
pub(super) fn dequantize_row_i32(q: &[i32], step: f64, delta: f64, out: &mut [f32]) {
    for (o, &x) in out.iter_mut().zip(q) {
        let a = x as f64;
        let v = (if x < 0 { a - delta } else { a + delta }) * step;
        *o = if x == 0 { 0.0 } else { v as f32 };
    }
}

/// The writer of a lossy band's decoded indices into `f32` rows: `x = sign(q)·(|q| + δ)·Δ`
/// ([`dequantize_row`]; a narrow coder's `i32` indices by [`dequantize_row_i32`], the
/// same values).
// the two closure types cannot be named in a type alias (`impl Trait`)
#[allow(clippy::type_complexity)]
pub(super) fn dequantizing_put(
    step: f64,
    delta: f64,
) -> crate::entropy::codeblocks::Put<
    impl Fn(&mut [f32], &[i64]) + Sync,
    impl Fn(&mut [f32], &[i32]) + Sync,
> {
    crate::entropy::codeblocks::Put {
        wide: move |o: &mut [f32], q: &[i64]| dequantize_row(q, step, delta, o),
        narrow: move |o: &mut [f32], q: &[i32]| dequantize_row_i32(q, step, delta, o),
    }
}

/// The rows of bands `js` in `plane` (laid out as the pyramid's shape), split into
/// disjoint slices: for each band, its rows in raster order (the band's row `r` is
/// `out[i][r]`, as long as the band's last extent). The bands of one level can so be
/// written in parallel.
pub(super) fn band_rows<'p, T>(
    plan: &Plan,
    js: &[usize],
    plane: &'p mut [T],
) -> Vec<Vec<&'p mut [T]>> {
    // (offset, length, band) of every row, in plane order
    let mut runs: Vec<(usize, usize, usize)> = Vec::new();
    for (i, &j) in js.iter().enumerate() {
        layout::rows(&plan.pyr.shape, &plan.bands[j].ranges, |off, run, _| {
            runs.push((off, run, i))
        });
    }
    runs.sort_unstable();
    let mut out: Vec<Vec<&'p mut [T]>> = js.iter().map(|_| Vec::new()).collect();
    let mut rest = plane;
    let mut at = 0;
    for (off, run, i) in runs {
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(off - at);
        let (row, tail) = tail.split_at_mut(run);
        out[i].push(row);
        rest = tail;
        at = off + run;
    }
    out
}

/// A lossy file's samples (interleaved, clamped to the source's range, before the
/// `--max-error` residuals) of the coarse block after `k` levels (k = 0: full size):
/// `fill(channel, plane)` writes the channel's dequantized bands into its zeroed plane
/// (laid out as the pyramid's shape, see [`dequantize_into`]), which is synthesized and
/// taken back from YCoCg and converted straight into the header's sample type
/// ([`to_samples`]: no whole-image `f64` copy). The decoder's way, and the encoder's
/// `--psnr` search's.
pub(super) fn lossy_values(
    h: &Header,
    plan: &Plan,
    k: usize,
    fill: impl Fn(usize, &mut [f32]) -> Result<()> + Sync,
) -> Result<Samples> {
    let region = plan.region(k);
    let npos: usize = region.iter().product();
    let c = h.channels;
    let sub = plan.sub(k);
    let planes = (0..c)
        .into_par_iter()
        .map(|ch| {
            // on huge pages where the kernel allows: the bands are written into fresh
            // pages, a fault for each 4 KB otherwise
            let mut plane: Vec<f32> = tensor::zeroed_vec(plan.pyr.shape.iter().product());
            fill(ch, &mut plane)?;
            let full: Vec<std::ops::Range<usize>> = region.iter().map(|&e| 0..e).collect();
            let small = if k == 0 {
                plane
            } else {
                layout::gather(&plane, &plan.pyr.shape, &full)
            };
            let mut a = Array::from_shape_vec(&region, small)?;
            // a volume synthesized in place (the default engine's levels of 3 or more
            // axes run out of place, through a scratch array as large as the plane,
            // which would double the decoder's memory; in place costs little time)
            let engine = if region.len() >= 3 {
                tensor::Engine::AxisByAxis
            } else {
                tensor::Engine::tuned()
            };
            tensor::synthesize_with(&mut a, &sub, engine)?;
            Ok(a.into_data())
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(to_samples(
        planes,
        npos,
        h.colour == Colour::YCoCg,
        (h.min, h.max),
        h.sample_type,
    ))
}

/// Interleaved samples of type `ty` from `planes` (`npos` values each): the first three
/// taken back from YCoCg when `ycocg` ([`ycocg_inverse`], in `f32`), every value then
/// clamped to `lo..=hi` in `f64` and converted as [`Samples::from_iter_f64`] does
/// (integers rounded half away from zero and clamped to the type, NaN → 0), in parallel
/// over blocks of positions.
///
/// The planes are consumed from their ends: the last [`TAIL`] positions converted, the
/// planes shortened and their tails given back (`shrink_to_fit`: the allocator returns
/// the pages of a large block at once), and so on to the first, so that the samples
/// and the planes are not both held whole (a volume's `f32` plane is twice its `u16`
/// samples). The output's pages, zeroed lazily, are touched as the planes shrink.
pub(super) fn to_samples(
    mut planes: Vec<Vec<f32>>,
    npos: usize,
    ycocg: bool,
    (lo, hi): (f64, f64),
    ty: SampleType,
) -> Samples {
    let c = planes.len();
    let mut out = Samples::zeros(ty, npos * c);
    let mut end = npos;
    while end > 0 {
        let start = end.saturating_sub(TAIL);
        let part: Vec<&[f32]> = planes.iter().map(|p| &p[start..end]).collect();
        convert_into(&mut out, start * c..end * c, &part, ycocg, (lo, hi));
        for p in &mut planes {
            p.truncate(start);
            p.shrink_to_fit();
        }
        end = start;
    }
    out
}

/// [`to_samples`] of planes the caller keeps (a streamed decode's slab buffers, reused
/// from slab to slab): every position of `planes` (as long as each other) converted.
pub(super) fn slab_samples(
    planes: &[&[f32]],
    ycocg: bool,
    range: (f64, f64),
    ty: SampleType,
) -> Samples {
    let n = planes.iter().map(|p| p.len()).sum();
    let mut out = Samples::zeros(ty, n);
    convert_into(&mut out, 0..n, planes, ycocg, range);
    out
}

/// Interleave `part` (one slice a channel) into `out[a..b]`, converted as [`to_samples`]
/// says.
fn convert_into(
    out: &mut Samples,
    std::ops::Range { start: a, end: b }: std::ops::Range<usize>,
    part: &[&[f32]],
    ycocg: bool,
    (lo, hi): (f64, f64),
) {
    let (tlo, thi) = out.sample_type().range();
    // (a block of its own: the macros below were the body of `to_samples`' loop)
    {
        macro_rules! fill {
            ($v:expr, $conv:expr) => {{
                let conv = $conv;
                interleave(&mut $v[a..b], part, ycocg, |x: f32| {
                    conv((x as f64).clamp(lo, hi))
                })
            }};
        }
        macro_rules! int {
            ($v:expr, $t:ty) => {
                fill!($v, |x: f64| round_to(x, tlo as i64, thi as i64) as $t)
            };
        }
        // 8- and 16-bit samples whose range is whole numbers exact in f32 (every
        // valid file's): the same clamp and rounding in f32, the same results
        // (the clamp's ends are the same numbers, and rounding an f32 value is exact)
        let in_f32 = [lo, hi]
            .iter()
            .all(|&e| e.fract() == 0.0 && e.abs() <= F32_EXACT);
        let (flo, fhi) = (lo as f32, hi as f32);
        macro_rules! small {
            ($v:expr, $t:ty) => {
                if in_f32 {
                    let (tl, th) = (tlo as i32, thi as i32);
                    interleave(&mut $v[a..b], part, ycocg, |x: f32| {
                        round_to_f32(clamp_f32(x, flo, fhi), tl, th) as $t
                    })
                } else {
                    int!($v, $t)
                }
            };
        }
        match out {
            Samples::U8(v) => small!(v, u8),
            Samples::I8(v) => small!(v, i8),
            Samples::U16(v) => small!(v, u16),
            Samples::I16(v) => small!(v, i16),
            Samples::U32(v) => int!(v, u32),
            Samples::I32(v) => int!(v, i32),
            Samples::F16(v) => fill!(v, half::f16::from_f64),
            Samples::F32(v) => fill!(v, |x: f64| x as f32),
            Samples::F64(v) => fill!(v, |x: f64| x),
        }
    }
}

/// Positions [`to_samples`] converts before it shortens the planes (4 MB of one `f32`
/// plane).
pub(super) const TAIL: usize = 1 << 20;

/// `round(x)` half away from zero, clamped to `lo..=hi`, NaN → 0: what
/// [`Samples::from_iter_f64`] makes of `x` for an integer type of range `lo..=hi` (a
/// range within ±2^53), without a call to `f64::round`: the integer part by truncation,
/// then one up or down when the fraction (exact: `x` and its integer part are within 1
/// of each other) is half or more.
#[inline(always)]
fn round_to(x: f64, lo: i64, hi: i64) -> i64 {
    const BIG: f64 = (1u64 << 53) as f64;
    let x = x.clamp(-BIG, BIG); // NaN stays NaN
    let i = x as i64; // NaN → 0
    let f = x - i as f64;
    (i + (f >= 0.5) as i64 - (f <= -0.5) as i64).clamp(lo, hi)
}

/// Whole numbers up to this magnitude are exact in `f32`.
const F32_EXACT: f64 = (1u32 << 24) as f64;

/// `x` clamped to `lo..=hi` (`lo ≤ hi`) as [`f32::clamp`] does it, NaN staying NaN:
/// two selects, without `clamp`'s check of the bounds, so that a loop of it vectorises.
#[inline(always)]
fn clamp_f32(x: f32, lo: f32, hi: f32) -> f32 {
    let x = if x < lo { lo } else { x };
    if x > hi {
        hi
    } else {
        x
    }
}

/// [`round_to`] of an `f32` value within ±2^24 (or NaN → 0) into `lo..=hi`.
#[inline(always)]
fn round_to_f32(x: f32, lo: i32, hi: i32) -> i32 {
    let i = x as i32; // NaN → 0
    let f = x - i as f32;
    (i + (f >= 0.5) as i32 - (f <= -0.5) as i32).clamp(lo, hi)
}

/// `out[i·c + ch] = conv(planes[ch][i])`, the first three planes through
/// [`ycocg_inverse`] first when `ycocg`; blocks of positions in parallel.
fn interleave<T: Send + Copy>(
    out: &mut [T],
    planes: &[&[f32]],
    ycocg: bool,
    conv: impl Fn(f32) -> T + Sync,
) {
    const BLOCK: usize = 1 << 14;
    let c = planes.len();
    if c == 0 {
        return;
    }
    out.par_chunks_mut(BLOCK * c)
        .enumerate()
        .for_each(|(b, chunk)| {
            let i0 = b * BLOCK;
            let n = chunk.len() / c;
            if c == 1 {
                for (o, &x) in chunk.iter_mut().zip(&planes[0][i0..i0 + n]) {
                    *o = conv(x);
                }
                return;
            }
            let first = if ycocg && c >= 3 { 3 } else { 0 };
            if first == 3 && c == 3 {
                // a lane of positions at a time: the colour inverse and `conv` over
                // arrays (loops the compiler vectorizes), then interleaved; the same
                // operations on each value as below
                const LANE: usize = 64;
                let z = conv(0.0);
                let mut t = [[z; LANE]; 3];
                let p = [0, 1, 2].map(|ch| &planes[ch][i0..i0 + n]);
                for (k, px) in chunk.chunks_mut(3 * LANE).enumerate() {
                    let (at, m) = (k * LANE, px.len() / 3);
                    let [y, co, cg] = p.map(|q| &q[at..at + m]);
                    let [tr, tg, tb] = &mut t;
                    // zipped, not indexed: no bounds checks, so the loop vectorises
                    let outs = tr.iter_mut().zip(tg.iter_mut()).zip(tb.iter_mut());
                    let ins = y.iter().zip(co).zip(cg);
                    for (((or, og), ob), ((&y, &co), &cg)) in outs.zip(ins) {
                        let (r, g, b) = ycocg_inverse(y, co, cg);
                        (*or, *og, *ob) = (conv(r), conv(g), conv(b));
                    }
                    let ts = tr.iter().zip(tg.iter()).zip(tb.iter());
                    for (o, ((&r, &g), &b)) in px.chunks_exact_mut(3).zip(ts) {
                        (o[0], o[1], o[2]) = (r, g, b);
                    }
                }
                return;
            }
            for (i, px) in chunk.chunks_exact_mut(c).enumerate() {
                let at = i0 + i;
                if first == 3 {
                    let (r, g, b) = ycocg_inverse(planes[0][at], planes[1][at], planes[2][at]);
                    px[0] = conv(r);
                    px[1] = conv(g);
                    px[2] = conv(b);
                }
                for (o, p) in px[first..].iter_mut().zip(&planes[first..]) {
                    *o = conv(p[at]);
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `i32` indices dequantize to the bits [`dequantize_row`] gives their `i64` values,
    /// at the extremes, around zero and at several steps and offsets.
    #[test]
    fn narrow_dequantization_is_the_wide_one() {
        let mut q: Vec<i32> = vec![0, 1, -1, 2, -2, i32::MAX, i32::MIN, i32::MIN + 1, 1 << 24];
        q.extend((0..500).map(|i: i32| i.wrapping_mul(7919).wrapping_sub(1 << 11) % 4099));
        for (step, delta) in [(1.0, 0.0), (0.37, 0.12), (1234.5, 0.5), (1e-9, 0.25)] {
            let wide: Vec<i64> = q.iter().map(|&x| x as i64).collect();
            let (mut a, mut b) = (vec![1f32; q.len()], vec![2f32; q.len()]);
            dequantize_row(&wide, step, delta, &mut a);
            dequantize_row_i32(&q, step, delta, &mut b);
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b), "step {step} delta {delta}");
        }
    }

    /// Three YCoCg planes to 8- and 16-bit samples: each sample is the inverse colour
    /// transform clamped to the range and rounded half away from zero in `f64`, for
    /// halves, values out of range, infinities and NaN, over lengths that end inside a
    /// lane and span several blocks.
    #[test]
    fn ycocg_planes_convert_as_the_f64_rule() {
        let special = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.5,
            2.5,
            254.5,
            255.5,
            256.0,
            -3.0,
            1e30,
            -1e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            127.49999,
            0.49999997,
            65535.5,
        ];
        for npos in [1usize, 63, 65, 70_001] {
            let planes: Vec<Vec<f32>> = (0..3u32)
                .map(|ch| {
                    (0..npos as u32)
                        .map(|i| {
                            let k = i.wrapping_mul(2_654_435_761).wrapping_add(ch * 97);
                            if k % 5 == 0 {
                                special[(k as usize / 5) % special.len()]
                            } else {
                                (k % 70_000) as f32 / 256.0 - 20.0
                            }
                        })
                        .collect()
                })
                .collect();
            for (ty, range) in [
                (SampleType::U8, (0.0, 255.0)),
                (SampleType::U16, (3.0, 200.0)),
            ] {
                let got = to_samples(planes.clone(), npos, true, range, ty);
                let (tlo, thi) = ty.range();
                for i in 0..npos {
                    let (r, g, b) = ycocg_inverse(planes[0][i], planes[1][i], planes[2][i]);
                    for (ch, x) in [r, g, b].into_iter().enumerate() {
                        let want =
                            round_to((x as f64).clamp(range.0, range.1), tlo as i64, thi as i64);
                        assert_eq!(
                            got.get_f64(3 * i + ch),
                            want as f64,
                            "{ty:?} {npos} {i} {ch} {x}"
                        );
                    }
                }
            }
        }
    }
}
