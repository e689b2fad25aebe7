//! Detail transfer for volumes (notes §9.7.4 carried to three axes): the base volume is
//! analysed `L` levels with the open–open (interpolating) tensor-product MRA, its
//! details are dropped, and the example's details take their place, cube patch by cube
//! patch, where the example's coarse neighbourhood best matches the base's. The same
//! rules as the 2-D [`super::synth`]:
//!
//! * one-level Mallat block: coarse `C` in the corner `n_z × n_y × n_x`, seven detail
//!   bands `(h_z, h_y, h_x) ≠ (0, 0, 0)`; a detail `j` lies between coarse `j` and `j + 1`,
//!   so a patch is copied by one integer shift of band-local indices;
//! * feature of a `q³` window (`q = p + 2o`), sampled every other voxel: heights
//!   normalised for offset and scale, plus the mean gradient magnitude; distance
//!   `patches::distance_below` (cut short once it exceeds the k-th best); the best `choices` of at most `candidates` windows,
//!   one picked by a generator seeded with (seed, level, patch);
//! * separable ramps over `2o` voxels, blend `Σ wᵢDᵢ / √Σwᵢ²`, then each band scaled to
//!   the example's band RMS at that level (matched details only);
//! * `F_{k−1} = P C_k + Q D_k`; since `A Q = 0`, analysing the result `L` levels gives
//!   the base's coarse points back exactly.

use rayon::prelude::*;

use super::patches::{mix, origins, pick_match, ramp};
use super::synth::{check_options, lengths_down, Details, SynthOptions, BOUNDARY};
use crate::scheme::{Scheme, TwoScale};
use crate::tensor::{self, Array, Order, Pyramid, PyramidSpec};
use crate::{Error, Result};

/// A volume: `dims = [depth, rows, columns]`, `c` channels, row-major, channel fastest;
/// held as the engine's [`Array`] (shape `[d, h, w]`, or `[d, h, w, c]` when `c > 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    dims: [usize; 3],
    values: Array<f64>,
}

/// The engine's shape of a volume: `[d, h, w]` or `[d, h, w, c]`.
fn shape(dims: [usize; 3], c: usize) -> Vec<usize> {
    let mut s = dims.to_vec();
    if c > 1 {
        s.push(c);
    }
    s
}

impl Volume {
    pub fn new(dims: [usize; 3], c: usize, data: Vec<f64>) -> Result<Volume> {
        let n = dims.iter().product::<usize>() * c;
        if n == 0 || data.len() != n {
            return Err(Error::parameter(
                "volume samples",
                format!("{} for {dims:?} × {c} channels", data.len()),
                "depth × rows × columns × channels samples, non-empty",
            ));
        }
        Ok(Volume {
            dims,
            values: Array::from_shape_vec(&shape(dims, c), data)?,
        })
    }

    fn zeros(dims: [usize; 3], c: usize) -> Volume {
        Volume {
            dims,
            values: Array::zeros(&shape(dims, c)),
        }
    }

    /// `[depth, rows, columns]`.
    #[inline]
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Channels.
    #[inline]
    pub fn c(&self) -> usize {
        self.values.shape().get(3).copied().unwrap_or(1)
    }

    super::grid::samples_access!();

    /// The engine's array, borrowed.
    pub fn array(&self) -> &Array<f64> {
        &self.values
    }

    fn idx(&self, p: [usize; 3]) -> usize {
        ((p[0] * self.dims[1] + p[1]) * self.dims[2] + p[2]) * self.c()
    }

    /// Mean over channels at `p`, with each index clamped into the volume.
    fn mean_clamped(&self, p: [i64; 3]) -> f64 {
        let q = [0, 1, 2].map(|a| p[a].clamp(0, self.dims[a] as i64 - 1) as usize);
        let i = self.idx(q);
        let c = self.c();
        self.data()[i..i + c].iter().sum::<f64>() / c as f64
    }

    /// The corner `n` of the volume.
    fn crop(&self, n: [usize; 3]) -> Volume {
        let c = self.c();
        let mut out = Volume::zeros(n, c);
        for z in 0..n[0] {
            for y in 0..n[1] {
                let (s, d) = (self.idx([z, y, 0]), out.idx([z, y, 0]));
                out.data_mut()[d..d + n[2] * c].copy_from_slice(&self.data()[s..s + n[2] * c]);
            }
        }
        out
    }

    /// Copy `src` into the corner.
    fn paste(&mut self, src: &Volume) {
        let c = self.c();
        for z in 0..src.dims[0] {
            for y in 0..src.dims[1] {
                let (s, d) = (src.idx([z, y, 0]), self.idx([z, y, 0]));
                let n = src.dims[2] * c;
                self.data_mut()[d..d + n].copy_from_slice(&src.data()[s..s + n]);
            }
        }
    }

    /// The engine's array (a copy): `[d, h, w]` or `[d, h, w, c]`.
    fn to_array(&self) -> Result<Array<f64>> {
        Ok(self.values.clone())
    }
}

/// What a volume transfer did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VolumeReport {
    /// Output `[depth, rows, columns]` (the base's).
    pub dims: [usize; 3],
    /// The coarse lattice after `L` levels.
    pub coarse: [usize; 3],
    pub levels: usize,
    /// Patches placed per level, coarsest first.
    pub patches: Vec<usize>,
    /// Mean matching distance per level, coarsest first.
    pub mean_distance: Vec<f64>,
    /// Mean |second difference| across finest patch borders ÷ elsewhere (≈ 1: no seams).
    pub seam_ratio: f64,
}

fn spec3(scheme: Scheme, levels: usize) -> PyramidSpec {
    PyramidSpec {
        scheme,
        boundary: BOUNDARY,
        levels,
        order: Order::NonStandard,
        axes: vec![0, 1, 2],
    }
}

/// One level of analysis: the Mallat block and its coarse size.
fn analyze_one(v: &Volume, scheme: Scheme) -> Result<(Volume, [usize; 3])> {
    let mut a = v.to_array()?;
    tensor::analyze(&mut a, &spec3(scheme, 1))?;
    let n = v.dims().map(|m| TwoScale::coarse_len(scheme, BOUNDARY, m));
    Ok((Volume::new(v.dims(), v.c(), a.into_data())?, n))
}

fn synthesize_one(packed: Volume, scheme: Scheme) -> Result<Volume> {
    let (dims, c) = (packed.dims(), packed.c());
    let mut a = packed.to_array()?;
    let pyr = Pyramid::plan(a.shape(), &spec3(scheme, 1))?;
    tensor::synthesize(&mut a, &pyr)?;
    Volume::new(dims, c, a.into_data())
}

/// Feature of the `q³` window at `o` (indices clamped), sampled every other voxel:
/// z-scored heights, then the mean gradient magnitude.
fn feature(v: &Volume, o: [i64; 3], q: usize, out: &mut Vec<f32>) {
    out.clear();
    let mut vals = Vec::new();
    let mut slope = 0.0;
    for dz in (0..q as i64).step_by(2) {
        for dy in (0..q as i64).step_by(2) {
            for dx in (0..q as i64).step_by(2) {
                let p = [o[0] + dz, o[1] + dy, o[2] + dx];
                vals.push(v.mean_clamped(p));
                let mut g2 = 0.0;
                for a in 0..3 {
                    let (mut lo, mut hi) = (p, p);
                    lo[a] -= 1;
                    hi[a] += 1;
                    let g = 0.5 * (v.mean_clamped(hi) - v.mean_clamped(lo));
                    g2 += g * g;
                }
                slope += g2.sqrt();
            }
        }
    }
    let n = vals.len() as f64;
    let mean = vals.iter().sum::<f64>() / n;
    let sd = (vals.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    let inv = if sd > 1e-12 * (1.0 + mean.abs()) {
        1.0 / sd
    } else {
        0.0
    };
    out.extend(vals.iter().map(|x| ((x - mean) * inv) as f32));
    out.push((slope / n) as f32);
}

/// The seven detail bands as (high z, high y, high x).
fn bands() -> impl Iterator<Item = [bool; 3]> {
    (1..8).map(|b| [b & 4 != 0, b & 2 != 0, b & 1 != 0])
}

/// The details of one level: the Mallat block of `m` whose coarse part is `t`, the number
/// of patches and the mean matching distance.
fn level_details(
    t: &Volume,
    (e, ne): &(Volume, [usize; 3]),
    m: [usize; 3],
    o: &SynthOptions,
    level: usize,
) -> Result<(Volume, usize, f64)> {
    let (n, c) = (t.dims(), t.c());
    let (p, ov) = (o.patch, o.overlap);
    let q = p + 2 * ov;
    let count = window_counts(e, *ne, p, ov, level)?;
    let cands = candidate_grid(count, o, level);
    let back = |p: [usize; 3]| p.map(|v| v as i64 - ov as i64);
    let feats: Vec<Vec<f32>> = if o.details == Details::Matched {
        let ce = e.crop(*ne);
        cands
            .par_iter()
            .map(|&cp| {
                let mut f = Vec::new();
                feature(&ce, back(cp), q, &mut f);
                f
            })
            .collect()
    } else {
        Vec::new()
    };
    let os = n.map(|v| origins(v, p));
    let (oy, ox) = (&os[1], &os[2]);
    let patches: Vec<[usize; 3]> = os[0]
        .iter()
        .flat_map(|&z| {
            oy.iter()
                .flat_map(move |&y| ox.iter().map(move |&x| [z, y, x]))
        })
        .collect();
    let chosen: Vec<([usize; 3], f64)> = patches
        .par_iter()
        .enumerate()
        .map(|(idx, &tp)| match o.details {
            Details::Matched => {
                let mut f = Vec::new();
                feature(t, back(tp), q, &mut f);
                let (ci, d) = pick_match(&f, &feats, o, level, idx);
                (cands[ci], d)
            }
            _ => ([0, 1, 2].map(|a| ov + tp[a] % count[a]), 0.0),
        })
        .collect();
    let mean_d = chosen.iter().map(|c| c.1).sum::<f64>() / chosen.len().max(1) as f64;
    let mut acc = Volume::zeros(m, c);
    if o.details != Details::None {
        let sources: Vec<[usize; 3]> = chosen.iter().map(|c| c.0).collect();
        blend(&mut acc, n, (e, *ne), (&patches, &sources), (p, ov));
        if o.details == Details::Matched {
            match_band_rms(&mut acc, n, e, *ne);
        }
    }
    acc.paste(t);
    Ok((acc, patches.len(), mean_d))
}

/// Window origins per axis in the example's level block (coarse part `ne`): windows of
/// `p + 2·ov` inside the coarse grid and the detail bands; an error when not one fits.
fn window_counts(
    e: &Volume,
    ne: [usize; 3],
    p: usize,
    ov: usize,
    level: usize,
) -> Result<[usize; 3]> {
    let mut count = [0usize; 3];
    for a in 0..3 {
        let hi = ne[a].min(e.dims()[a] - ne[a]) as i64 - (p + ov) as i64;
        if hi < ov as i64 {
            return Err(Error::parameter(
                "example",
                format!("{:?} coefficients at level {level}", e.dims()),
                "an example whose coarse grid holds at least one patch window at every level",
            ));
        }
        count[a] = (hi - ov as i64 + 1) as usize;
    }
    Ok(count)
}

/// At most `o.candidates` core origins on a cubic stride offset by the seed.
fn candidate_grid(count: [usize; 3], o: &SynthOptions, level: usize) -> Vec<[usize; 3]> {
    let ov = o.overlap;
    let total: usize = count.iter().product();
    let stride = ((total as f64 / o.candidates.max(1) as f64).cbrt().ceil() as usize).max(1);
    let mut rng = mix(o.seed, level, usize::MAX);
    let off = [0, 1, 2].map(|a| ((rng.next_u64() % stride as u64) as usize).min(count[a] - 1));
    let mut cands = Vec::new();
    for z in (off[0]..count[0]).step_by(stride) {
        for y in (off[1]..count[1]).step_by(stride) {
            for x in (off[2]..count[2]).step_by(stride) {
                cands.push([z + ov, y + ov, x + ov]);
            }
        }
    }
    cands
}

/// Accumulate every patch's seven detail bands from its source core `cp` in the example
/// block `e` (coarse part `ne`) with separable ramps `w`, then divide by `√Σw²`.
fn blend(
    acc: &mut Volume,
    n: [usize; 3],
    (e, ne): (&Volume, [usize; 3]),
    (patches, sources): (&[[usize; 3]], &[[usize; 3]]),
    (p, ov): (usize, usize),
) {
    let (m, c) = (acc.dims(), acc.c());
    let d = [0, 1, 2].map(|a| m[a] - n[a]);
    let de = [0, 1, 2].map(|a| e.dims()[a] - ne[a]);
    let mut w2 = vec![0.0f64; m.iter().product()];
    for (&tp, &cp) in patches.iter().zip(sources) {
        let first = [0, 1, 2].map(|a| tp[a] == 0);
        let last = [0, 1, 2].map(|a| tp[a] + p >= n[a]);
        for hb in bands() {
            // per axis: (output index, example index, weight) of every covered sample
            let axis = |a: usize| -> Vec<(usize, usize, f64)> {
                let len = if hb[a] { d[a] } else { n[a] };
                let elen = if hb[a] { de[a] } else { ne[a] };
                (tp[a].saturating_sub(ov)..(tp[a] + p + ov).min(len))
                    .filter_map(|i| {
                        let w = ramp(i, tp[a], p, ov, first[a], last[a]);
                        let j =
                            ((i + cp[a]) as i64 - tp[a] as i64).clamp(0, elen as i64 - 1) as usize;
                        let (po, pe) = if hb[a] { (n[a] + i, ne[a] + j) } else { (i, j) };
                        (w > 0.0).then_some((po, pe, w))
                    })
                    .collect()
            };
            let (az, ay, ax) = (axis(0), axis(1), axis(2));
            for &(oz, ez, wz) in &az {
                for &(oy, ey, wy) in &ay {
                    for &(ox, ex, wx) in &ax {
                        let w = wz * wy * wx;
                        let (io, ie) = (acc.idx([oz, oy, ox]), e.idx([ez, ey, ex]));
                        for k in 0..c {
                            acc.data_mut()[io + k] += w * e.data()[ie + k];
                        }
                        w2[io / c] += w * w;
                    }
                }
            }
        }
    }
    for (i, &s) in w2.iter().enumerate() {
        if s > 0.0 {
            let inv = 1.0 / s.sqrt();
            acc.data_mut()[i * c..(i + 1) * c]
                .iter_mut()
                .for_each(|v| *v *= inv);
        }
    }
}

/// Index ranges of band `hb` of a block of `dims` whose coarse part is `n`.
fn band_ranges(hb: [bool; 3], dims: [usize; 3], n: [usize; 3]) -> [std::ops::Range<usize>; 3] {
    [0, 1, 2].map(|a| if hb[a] { n[a]..dims[a] } else { 0..n[a] })
}

fn band_rms(v: &Volume, r: &[std::ops::Range<usize>; 3]) -> f64 {
    let (mut s, mut k) = (0.0, 0usize);
    for z in r[0].clone() {
        for y in r[1].clone() {
            let i = v.idx([z, y, r[2].start]);
            let row = &v.data()[i..i + r[2].len() * v.c()];
            s += row.iter().map(|x| x * x).sum::<f64>();
            k += row.len();
        }
    }
    (s / k.max(1) as f64).sqrt()
}

/// Each detail band scaled to the example's band RMS: `D_b ← D_b · rms(E_b)/rms(D_b)`.
fn match_band_rms(acc: &mut Volume, n: [usize; 3], e: &Volume, ne: [usize; 3]) {
    for hb in bands() {
        let r = band_ranges(hb, acc.dims(), n);
        let (have, want) = (
            band_rms(acc, &r),
            band_rms(e, &band_ranges(hb, e.dims(), ne)),
        );
        if have > 0.0 {
            let f = want / have;
            for z in r[0].clone() {
                for y in r[1].clone() {
                    let i = acc.idx([z, y, r[2].start]);
                    let len = r[2].len() * acc.c();
                    acc.data_mut()[i..i + len].iter_mut().for_each(|v| *v *= f);
                }
            }
        }
    }
}

/// Mean |second difference| of channel means across the lines `period·j − 1 ± 1` of
/// every axis ÷ the same elsewhere (the volume form of [`super::synth::seam_ratio`]).
pub fn seam_ratio(v: &Volume, period: usize) -> f64 {
    let mut seams = super::seams::SeamTally::new(period);
    let [dz, dy, dx] = v.dims();
    for z in 1..dz.saturating_sub(1) {
        for y in 1..dy.saturating_sub(1) {
            for x in 1..dx.saturating_sub(1) {
                let p = [z as i64, y as i64, x as i64];
                let h = v.mean_clamped(p);
                for a in 0..3 {
                    let (mut lo, mut hi) = (p, p);
                    lo[a] -= 1;
                    hi[a] += 1;
                    let s = (v.mean_clamped(hi) - 2.0 * h + v.mean_clamped(lo)).abs();
                    seams.add(p[a] as usize, s);
                }
            }
        }
    }
    seams.ratio()
}

/// Detail transfer for a volume: `base` keeps its size and its coarse points `A^L F`;
/// its finest `L` levels of details are replaced by the example's matched details.
pub fn transfer_volume(
    base: &Volume,
    example: &Volume,
    o: &SynthOptions,
) -> Result<(Volume, VolumeReport)> {
    check_options(base.c(), example.c(), o)?;
    let l = o.levels;
    const NAMES: [(&str, &str); 3] = [
        ("base depth", "example depth"),
        ("base height", "example height"),
        ("base width", "example width"),
    ];
    let q = o.patch + 2 * o.overlap;
    let mut lb = Vec::new();
    let mut le = Vec::new();
    for (a, names) in NAMES.iter().enumerate() {
        lb.push(lengths_down(o.scheme, base.dims()[a], l, names.0)?);
        let e = lengths_down(o.scheme, example.dims()[a], l, names.1)?;
        if e[l] < q + 4 {
            return Err(Error::parameter(
                "example size",
                format!("{:?} (coarse {} along axis {a} after {l} levels)", example.dims(), e[l]),
                "an example larger than the filter support: its coarsest grid must hold a patch window plus the detail band",
            ));
        }
        le.push(e);
    }
    let mut blocks = Vec::with_capacity(l);
    let mut g = example.clone();
    for _ in 0..l {
        let (packed, n) = analyze_one(&g, o.scheme)?;
        g = packed.crop(n);
        blocks.push((packed, n));
    }
    let mut a = base.to_array()?;
    tensor::analyze(&mut a, &spec3(o.scheme, l))?;
    let packed = Volume::new(base.dims(), base.c(), a.into_data())?;
    let coarse = [0, 1, 2].map(|a| lb[a][l]);
    let mut t = packed.crop(coarse);
    let mut report = VolumeReport {
        dims: base.dims(),
        coarse,
        levels: l,
        patches: Vec::new(),
        mean_distance: Vec::new(),
        seam_ratio: f64::NAN,
    };
    for k in (1..=l).rev() {
        let m = [0, 1, 2].map(|a| lb[a][k - 1]);
        let (block, np, md) = level_details(&t, &blocks[k - 1], m, o, k)?;
        t = synthesize_one(block, o.scheme)?;
        report.patches.push(np);
        report.mean_distance.push(md);
    }
    report.seam_ratio = seam_ratio(&t, 2 * o.patch);
    Ok((t, report))
}

/// The coarse points `A^L F` of a volume (the part a transfer keeps), as a volume.
pub fn coarse_points(v: &Volume, scheme: Scheme, levels: usize) -> Result<Volume> {
    let n: Vec<Vec<usize>> = (0..3)
        .map(|a| lengths_down(scheme, v.dims()[a], levels, "volume side"))
        .collect::<Result<_>>()?;
    let mut a = v.to_array()?;
    tensor::analyze(&mut a, &spec3(scheme, levels))?;
    let packed = Volume::new(v.dims(), v.c(), a.into_data())?;
    Ok(packed.crop([n[0][levels], n[1][levels], n[2][levels]]))
}
