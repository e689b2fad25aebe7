//! Synthesis by example (notes §9.7.4; Brosz, Samavati & Sousa): refine a base level by
//! level, `F_{k−1} = P C_k + Q D_k`, where the details `D_k` come from the example's
//! own pyramid at the same level, patch by patch, where the example's coarse
//! neighbourhood best matches the output's.
//!
//! **Lattice.** The output has `M = n·2^L` samples per axis (or `--size`), cell-centred on
//! the base's cells (output `j` at base position `(j + ½)·n/M − ½`); its lane lengths
//! `M = m_0 > m_1 > … > m_L` follow the interpolating length rule, and the base is
//! resampled (Catmull–Rom, [`super::resample`]) to the `m_L` coarse points `C_L`, which
//! span the output's first to last sample. The example is first resampled to the
//! output's cell (`example_scale` = example cell ÷ output cell), so that its level-`k`
//! details have the physical size of the output's.
//!
//! **Patches.** At level `k` the coarse grid is cut into cores of `p × p` cells
//! (default 8) with windows `q = p + 2o` (overlap `o`, default 2). A coefficient of the
//! one-level Mallat block sits in band `(hy, hx)` at band-local index `(iy, ix)`; both
//! coarse and detail indices are positions on the coarse lattice, so a patch is copied by
//! one integer shift of band-local indices from the example's block to the output's.
//!
//! **Matching** ([`super::matching`], [`super::patches`]): a window's descriptor is its shape (6 × 6 block
//! means, normalised for offset and scale), its slope direction, its curvature and its
//! steepness, all read from summed-area tables. Coarse to fine: at the coarsest level a
//! grid of at most `candidates` example windows (offset by the seed) is searched and one
//! of the `choices` best is picked by a generator seeded with (seed, level, patch); at
//! each finer level a patch's candidates are its parent's source and the 8 neighbouring
//! parents' sources, doubled and moved by up to one cell, plus a sparse grid of
//! `candidates/16` windows, and the best is kept (with `--base-scale` above the base's own,
//! the parent's source doubled as it is: whole pieces of the example, [`super::patches`]).
//! Ridges and valleys thus continue across levels and across patches. Deterministic: the
//! same bytes for any thread count.
//!
//! **Blending** ([`super::patches`]). Each sample gathers the (up to four) patches whose windows cover it, with
//! separable ramps `w` rising over `2o` cells across each border; patches taking the same
//! source shift carry the same value and count once with their weights summed, and the
//! distinct ones are blended as `Σ Wᵢ Dᵢ / √(Σ Wᵢ²)` (the variance of uncorrelated details
//! is kept, coherent neighbours are not inflated). Each band is then scaled to the RMS of
//! the example's band at the same level, `D_b ← D_b · rms(E_b)/rms(D_b)`.
//!
//! **Fidelity.** `A Q = 0`, so `A^L` of the result gives `C_L` back whatever the details;
//! when `M` is a multiple of `n`, a smooth back-projection then brings the result's
//! block means onto the base (see [`synthesize`]).
//!
//! **Defaults** (`benches/terrain_quality.py`, docs/terrain.md): 8-cell cores, 2-cell
//! overlaps, at most 16 384 candidates at the coarsest level, a pick among the 2 best.

use super::drainage::{drain, rms_step, BREACH_STEPS};
use super::finest_gain::{example_slope, fit_finest_gain, scale_details};
#[cfg(test)]
use super::finest_gain::{sub_axis, sub_block};
use super::level_gain::{level_gain, level_moments, mean_gradient2, refined_moments};
use super::patches::{level_details, Shifts};
use super::resample::{resample_add, resample_map, Map};
pub use super::seams::seam_ratio;
use super::Grid;
use crate::scheme::{max_levels, Boundary, Scheme, TwoScale};
use crate::tensor::{self, Engine, Order, Planner, Pyramid, PyramidSpec};
use crate::{Error, Result};

pub use super::options::{Details, FinestGain, SynthOptions};

/// What a synthesis did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SynthReport {
    /// Output `[rows, columns]`.
    pub dims: [usize; 2],
    /// The coarse lattice the base was resampled to.
    pub coarse: [usize; 2],
    pub levels: usize,
    /// Patches placed per level, coarsest first.
    pub patches: Vec<usize>,
    /// Mean matching distance per level, coarsest first.
    pub mean_distance: Vec<f64>,
    /// Mean |second difference| across finest patch borders ÷ elsewhere (≈ 1: no seams).
    pub seam_ratio: f64,
    /// PSNR (peak = the base's range) of the result reduced back to the base's size
    /// ([`reduce`]) against the base; `None` for [`transfer`].
    pub fidelity_psnr: Option<f64>,
    /// The gain `g₁` the finest details were multiplied by.
    pub finest_gain: f64,
    /// The example's spectral slope (the fit's target) when `g₁` was fitted.
    pub example_spectral_slope: Option<f64>,
    /// The base is trusted down to `1/base_scale` of the output (1: its own resolution);
    /// `levels` counts the synthesized levels and `fidelity_psnr` compares the result's
    /// `base_scale × base_scale` block means with the base reduced to that scale.
    pub base_scale: usize,
    /// The slope gains `g_k` of levels `K … 1`, coarsest first ([`super::level_gain`];
    /// empty at the base's own scale, where the finest gain is fitted instead).
    pub level_gains: Vec<f64>,
    /// Cells lowered by the breaching of depressions and the widening of its channels
    /// ([`super::drainage`]; with a base scale above the base's own only).
    pub drained: usize,
}

pub(super) const BOUNDARY: Boundary = Boundary::Interpolating;

fn spec(scheme: Scheme, levels: usize) -> PyramidSpec {
    PyramidSpec {
        scheme,
        boundary: BOUNDARY,
        levels,
        order: Order::NonStandard,
        axes: vec![0, 1],
    }
}

/// Lane lengths `m_0 … m_L` of an axis of `m`, or an error naming `what` when the
/// scheme's filters cannot take it `levels` levels down.
pub(super) fn lengths_down(
    scheme: Scheme,
    m: usize,
    levels: usize,
    what: &'static str,
) -> Result<Vec<usize>> {
    if max_levels(scheme, BOUNDARY, m) < levels {
        return Err(Error::parameter(
            what,
            format!("{m} samples for {levels} {scheme} levels"),
            "a side long enough for the interpolating filters at every level (see the length rule)",
        ));
    }
    let mut v = vec![m];
    for _ in 0..levels {
        v.push(TwoScale::coarse_len(scheme, BOUNDARY, *v.last().unwrap()));
    }
    Ok(v)
}

/// One level of analysis of a grid (taken by value and transformed in place): the
/// Mallat block `[C | D]` and the coarse size.
fn analyze_one(g: Grid, scheme: Scheme, planner: &Planner) -> Result<(Grid, usize, usize)> {
    let ny = TwoScale::coarse_len(scheme, BOUNDARY, g.h());
    let nx = TwoScale::coarse_len(scheme, BOUNDARY, g.w());
    let mut a = g.into_array();
    tensor::analyze_in(planner, &mut a, &spec(scheme, 1), Engine::tuned())?;
    Ok((Grid::from_array(a)?, ny, nx))
}

/// One level of reconstruction of a Mallat block, in place.
fn synthesize_one(packed: Grid, scheme: Scheme, planner: &Planner) -> Result<Grid> {
    let mut a = packed.into_array();
    let pyr = Pyramid::plan(a.shape(), &spec(scheme, 1))?;
    tensor::synthesize_in(planner, &mut a, &pyr, Engine::tuned())?;
    Grid::from_array(a)
}

/// The example's one-level blocks, finest first (`levels[k-1]` = level k).
struct ExamplePyramid {
    blocks: Vec<(Grid, usize, usize)>,
    /// Mean squared gradient of the example's grid at each level `k − 1` (`grad2[k-1]`,
    /// the slope gains' targets), when asked for.
    grad2: Vec<f64>,
    /// Mean squared gradient of the coarse part of the example's level-`k` block,
    /// `P C_k` (`coarse2[k-1]`, measured as [`level_moments`] measures the result's): the
    /// upper limit of the slope gain of level `k + 1`.
    coarse2: Vec<f64>,
}

impl ExamplePyramid {
    fn new(
        example: &Grid,
        scheme: Scheme,
        levels: usize,
        planner: &Planner,
        grad2: bool,
    ) -> Result<Self> {
        let mut blocks = Vec::with_capacity(levels);
        let mut g2 = Vec::new();
        let mut c2 = Vec::new();
        let mut g = example.clone();
        for _ in 0..levels {
            if grad2 {
                g2.push(mean_gradient2(&g, !blocks.is_empty()));
            }
            let (packed, ny, nx) = analyze_one(g, scheme, planner)?;
            if grad2 {
                let k = blocks.len() + 1;
                let ((a, _, _), _) =
                    level_moments(&packed, (ny, nx), k, (scheme, BOUNDARY), |g| {
                        synthesize_one(g, scheme, planner)
                    })?;
                c2.push(a);
            }
            g = packed.crop(ny, nx);
            blocks.push((packed, ny, nx));
        }
        Ok(ExamplePyramid {
            blocks,
            grad2: g2,
            coarse2: c2,
        })
    }
}

fn check(base: &Grid, example: &Grid, o: &SynthOptions) -> Result<()> {
    check_options(base.c(), example.c(), o)
}

/// Same channels; patch ≥ 2, overlap ≤ patch/2; 1 to 8 levels.
pub(super) fn check_options(base_c: usize, example_c: usize, o: &SynthOptions) -> Result<()> {
    if base_c != example_c {
        return Err(Error::parameter(
            "example channels",
            example_c,
            "the same number of channels as the base",
        ));
    }
    if o.patch < 2 || 2 * o.overlap > o.patch {
        return Err(Error::parameter(
            "patch/overlap",
            format!("{}/{}", o.patch, o.overlap),
            "patch ≥ 2 and overlap ≤ patch/2",
        ));
    }
    if o.levels == 0 || o.levels > 8 {
        return Err(Error::parameter("levels", o.levels, "1 to 8"));
    }
    if !(o.relief_cap.is_finite() && o.relief_cap >= 0.0) {
        return Err(Error::parameter(
            "relief cap",
            o.relief_cap,
            "a finite gain ≥ 0 (0: off)",
        ));
    }
    Ok(())
}

/// The example at the output's cell: resampled by `scale` = example cell ÷ output cell
/// (cell-centred map, Catmull–Rom, after a box pre-filter of width ⌊1/scale⌋ cells when it
/// shrinks), or itself when `scale` is 1.
pub fn example_at_scale(example: &Grid, scale: f64) -> Result<Grid> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::parameter(
            "example scale",
            scale,
            "a positive ratio of the example's cell to the output's",
        ));
    }
    if (scale - 1.0).abs() < 1e-9 {
        return Ok(example.clone());
    }
    let h = ((example.h() as f64 * scale).round() as usize).max(1);
    let w = ((example.w() as f64 * scale).round() as usize).max(1);
    if (h as u64) * (w as u64) > 1 << 28 {
        return Err(Error::LimitsExceeded {
            what: "example samples at the output's cell",
            requested: (h as u64) * (w as u64),
            limit: 1 << 28,
        });
    }
    let src = if scale < 1.0 {
        box_filter(example, (0.5 / scale).floor() as usize)
    } else {
        example.clone()
    };
    Ok(resample_map(
        &src,
        (h, Map::centred(example.h(), h)),
        (w, Map::centred(example.w(), w)),
    ))
}

/// Mean over the `(2r + 1)²` neighbourhood (indices clamped), separable.
fn box_filter(g: &Grid, r: usize) -> Grid {
    if r == 0 {
        return g.clone();
    }
    let mut out = g.clone();
    for pass in 0..2 {
        let src = out.clone();
        let n = (2 * r + 1) as f64;
        for y in 0..g.h() {
            for x in 0..g.w() {
                for k in 0..g.c() {
                    let mut s = 0.0;
                    for d in -(r as i64)..=r as i64 {
                        let (yy, xx) = if pass == 0 {
                            (y, (x as i64 + d).clamp(0, g.w() as i64 - 1) as usize)
                        } else {
                            ((y as i64 + d).clamp(0, g.h() as i64 - 1) as usize, x)
                        };
                        s += src.at(yy, xx, k);
                    }
                    *out.at_mut(y, x, k) = s / n;
                }
            }
        }
    }
    out
}

/// Refine the coarse points `coarse` (already on the lattice `ly[L] × lx[L]`) up to
/// `ly[0] × lx[0]` with the example's details (the example already at the output's cell).
fn refine(
    coarse: Grid,
    ly: &[usize],
    lx: &[usize],
    example: &Grid,
    o: &SynthOptions,
) -> Result<(Grid, SynthReport)> {
    let l = o.levels;
    let ey = lengths_down(o.scheme, example.h(), l, "example height")?;
    let ex = lengths_down(o.scheme, example.w(), l, "example width")?;
    let q = o.patch + 2 * o.overlap;
    if ey[l] < q + 4 || ex[l] < q + 4 {
        return Err(Error::parameter(
            "example size",
            format!("{}x{} (coarse {}x{} after {l} levels)", example.w(), example.h(), ex[l], ey[l]),
            "an example larger than the filter support: its coarsest grid must hold a patch window plus the detail band",
        ));
    }
    // the levels' scratch and operators, returned to the allocator when refinement ends
    // the fit's target first, while little else is held
    let target = match o.finest_gain {
        FinestGain::Fitted if o.details != Details::None => Some(example_slope(example)),
        _ => None,
    };
    let planner = Planner::new();
    let slope_gains = o.base_scale > 1 && o.details == Details::Matched;
    let mut pyr = ExamplePyramid::new(example, o.scheme, l, &planner, slope_gains)?;
    let mut t = coarse;
    let mut report = SynthReport {
        dims: [ly[0], lx[0]],
        coarse: [ly[l], lx[l]],
        levels: l,
        patches: Vec::new(),
        mean_distance: Vec::new(),
        seam_ratio: f64::NAN,
        fidelity_psnr: None,
        finest_gain: 1.0,
        example_spectral_slope: None,
        base_scale: 1,
        level_gains: Vec::new(),
        drained: 0,
    };
    let mut parent: Option<Shifts> = None;
    for k in (1..=l).rev() {
        let (mut packed, sh, md) = level_details(
            &t,
            &pyr.blocks[k - 1],
            (ly[k - 1], lx[k - 1]),
            o,
            k,
            parent.as_ref(),
        )?;
        let (n_y, n_x) = (t.h(), t.w());
        drop(t);
        // the example's block of this level is not used again
        pyr.blocks.truncate(k - 1);
        if slope_gains {
            let (m, xy) = level_moments(&packed, (n_y, n_x), k, (o.scheme, BOUNDARY), |g| {
                synthesize_one(g, o.scheme, &planner)
            })?;
            // above the finest level, the limit: the next level's coarse part no
            // steeper than the example's
            let next = match xy {
                Some((x, y)) => Some((
                    refined_moments(
                        &x,
                        &y,
                        (ly[k - 2], lx[k - 2]),
                        k - 1,
                        (o.scheme, BOUNDARY),
                        |g| synthesize_one(g, o.scheme, &planner),
                    )?,
                    pyr.coarse2[k - 2],
                )),
                None => None,
            };
            let g = level_gain((m, pyr.grad2[k - 1]), next);
            scale_details(&mut packed, (n_y, n_x), g);
            report.level_gains.push(g);
        }
        if k == 1 && o.details != Details::None && !slope_gains {
            let g = match (o.finest_gain, target) {
                (FinestGain::Fixed(g), _) => g,
                (FinestGain::Fitted, Some(target)) => {
                    report.example_spectral_slope = Some(target);
                    fit_finest_gain(&packed, (n_y, n_x), target, (o.scheme, BOUNDARY), |g| {
                        synthesize_one(g, o.scheme, &planner)
                    })?
                }
                (FinestGain::Fitted, None) => 1.0,
            };
            scale_details(&mut packed, (n_y, n_x), g);
            report.finest_gain = g;
        }
        t = synthesize_one(packed, o.scheme, &planner)?;
        report.patches.push(sh.rows * sh.cols);
        report.mean_distance.push(md);
        parent = Some(sh);
    }
    drop(planner);
    report.seam_ratio = seam_ratio(&t, 2 * o.patch);
    Ok((t, report))
}

/// Synthesize a terrain of `base × 2^L` (or `o.size`) from a smooth or coarse `base`
/// and a detailed `example` (same channels, same height units; its cell is
/// `o.example_scale` output cells).
///
/// The output lattice is cell-centred on the base's: output sample `j` lies at base
/// position `(j + ½)·n/M − ½` (the same extent, `n` cells become `M`). When `M` is a
/// multiple `f` of `n` on both axes, the result is then pulled towards the base by
/// back-projection, `F ← F + P_c (base − B F)` 3 times, with `B` the mean over each
/// base cell's `f × f` block and `P_c` the cell-centred Catmull–Rom resampling: the
/// correction is as smooth as the base, and the result's block means come within ≥ 40 dB
/// of the base (report `fidelity_psnr`; otherwise that figure is
/// the MRA reduction of [`reduce`]).
pub fn synthesize(base: &Grid, example: &Grid, o: &SynthOptions) -> Result<(Grid, SynthReport)> {
    check(base, example, o)?;
    let (base, o) = super::base_scale::trusted_base(base, o)?;
    let (base, o) = (base.as_ref(), &o);
    let l = o.levels;
    let (h, w) = match o.size {
        Some(s) => s,
        None => (
            base.h().checked_shl(l as u32).unwrap_or(usize::MAX),
            base.w().checked_shl(l as u32).unwrap_or(usize::MAX),
        ),
    };
    if (h as u64) * (w as u64) > 1 << 30 {
        return Err(Error::LimitsExceeded {
            what: "output samples",
            requested: (h as u64) * (w as u64),
            limit: 1 << 30,
        });
    }
    let ly = lengths_down(o.scheme, h, l, "output height")?;
    let lx = lengths_down(o.scheme, w, l, "output width")?;
    let coarse = resample_map(
        base,
        (ly[l], span(base.h(), h, ly[l])),
        (lx[l], span(base.w(), w, lx[l])),
    );
    // the example itself when its cell is the output's (no copy)
    let scaled: Grid;
    let example = if (o.example_scale - 1.0).abs() < 1e-9 {
        example
    } else {
        scaled = example_at_scale(example, o.example_scale)?;
        &scaled
    };
    let (mut g, mut report) = refine(coarse, &ly, &lx, example, o)?;
    report.base_scale = o.base_scale;
    let psnr = |back: &Grid| super::grid::psnr(back, base);
    let blocks = (h % base.h() == 0 && w % base.w() == 0).then(|| (h / base.h(), w / base.w()));
    report.fidelity_psnr = Some(match blocks {
        Some(f) => {
            for _ in 0..BACK_PROJECTIONS {
                back_project(&mut g, base, f);
            }
            let mut p = psnr(&block_means(&g, base.h(), base.w(), f));
            // after the back-projection, whose smooth correction would close the
            // channels again; the depth is halved (at most 4 times) while the channels
            // would take the block means below MIN_DRAINED_PSNR
            if o.base_scale > 1 && o.details == Details::Matched {
                let mut depth = BREACH_STEPS * rms_step(example);
                for _ in 0..5 {
                    let mut d = g.clone();
                    let n = drain(&mut d, depth);
                    let q = psnr(&block_means(&d, base.h(), base.w(), f));
                    if q >= MIN_DRAINED_PSNR.min(p) {
                        (g, p, report.drained) = (d, q, n);
                        break;
                    }
                    depth *= 0.5;
                }
            }
            p
        }
        None => psnr(&reduce(&g, base.h(), base.w(), o.scheme, l)?),
    });
    Ok((g, report))
}

/// The coarse lattice of `mc` points on base positions: it spans the fine lattice's
/// first to last sample, the fine lattice of `m` being cell-centred on the base's `n`.
fn span(n: usize, m: usize, mc: usize) -> Map {
    let f = Map::centred(n, m);
    let step = if mc > 1 {
        (f.at(m - 1) - f.offset) / (mc - 1) as f64
    } else {
        0.0
    };
    Map {
        offset: f.offset,
        step,
    }
}

/// The inverse of [`span`]: base sample `i` at coarse position `(i − offset)/step`.
fn span_inverse(n: usize, m: usize, mc: usize) -> Map {
    let s = span(n, m, mc);
    if s.step == 0.0 {
        return Map {
            offset: 0.0,
            step: 0.0,
        };
    }
    Map {
        offset: -s.offset / s.step,
        step: 1.0 / s.step,
    }
}

pub use super::grid::block_means;

/// The block-mean PSNR (dB) that the drainage of a result may not take it below (the
/// issue's fidelity target at the trusted scale).
const MIN_DRAINED_PSNR: f64 = 40.0;

/// Back-projection steps of [`synthesize`] (68–75 dB block-mean PSNR after 3 on the
/// bench's DEMs).
const BACK_PROJECTIONS: usize = 3;

/// One back-projection step `F ← F + P_c (base − B F)`, with `P_c` the cell-centred
/// Catmull–Rom resampling from the base's cells to the output's (a correction as smooth as
/// the base). A correction restricted to the span of `P^L` (which would leave the finest
/// levels exact) diverged on the bench's DEMs: its block means do not invert `B`.
fn back_project(g: &mut Grid, base: &Grid, f: (usize, usize)) {
    let mut r = block_means(g, base.h(), base.w(), f);
    for (v, b) in r.data_mut().iter_mut().zip(base.data()) {
        *v = b - *v;
    }
    let (my, mx) = (Map::centred(base.h(), g.h()), Map::centred(base.w(), g.w()));
    resample_add(&r, g, my, mx);
}

/// Detail transfer at the base's own size: the base is analysed `L` levels, its details
/// are dropped, and the example's matched details take their place (a blurred or
/// upscaled image gains the example's fine texture).
pub fn transfer(base: &Grid, example: &Grid, o: &SynthOptions) -> Result<(Grid, SynthReport)> {
    check(base, example, o)?;
    let l = o.levels;
    let ly = lengths_down(o.scheme, base.h(), l, "base height")?;
    let lx = lengths_down(o.scheme, base.w(), l, "base width")?;
    let (mut a, _) = base.to_array()?;
    tensor::analyze(&mut a, &spec(o.scheme, l))?;
    let packed = Grid::new(base.h(), base.w(), base.c(), a.into_data())?;
    let example = example_at_scale(example, o.example_scale)?;
    let o = SynthOptions {
        finest_gain: FinestGain::Fixed(1.0),
        ..o.clone()
    };
    refine(packed.crop(ly[l], lx[l]), &ly, &lx, &example, &o)
}

/// The result reduced back to `h × w`: `L` levels of analysis (`C_L = A^L F`), then the
/// resampling from the coarse lattice to `h × w` (the inverse of the lattice of
/// [`synthesize`]: the result's samples cell-centred on the `h × w` cells).
pub fn reduce(result: &Grid, h: usize, w: usize, scheme: Scheme, levels: usize) -> Result<Grid> {
    let ly = lengths_down(scheme, result.h(), levels, "result height")?;
    let lx = lengths_down(scheme, result.w(), levels, "result width")?;
    let (mut a, _) = result.to_array()?;
    tensor::analyze(&mut a, &spec(scheme, levels))?;
    let packed = Grid::new(result.h(), result.w(), result.c(), a.into_data())?;
    let c = packed.crop(ly[levels], lx[levels]);
    Ok(resample_map(
        &c,
        (h, span_inverse(h, result.h(), ly[levels])),
        (w, span_inverse(w, result.w(), lx[levels])),
    ))
}

/// The finest `levels` levels of a grid's MRA: `F − P^L A^L F` (the grid minus its own
/// reduction-then-reconstruction; the part that synthesis adds). The realism metrics of
/// `benches/terrain_quality.py` are taken on this part of the result and of the example.
pub fn highpass(g: &Grid, scheme: Scheme, levels: usize) -> Result<Grid> {
    let ly = lengths_down(scheme, g.h(), levels, "height")?;
    let lx = lengths_down(scheme, g.w(), levels, "width")?;
    let (mut a, _) = g.to_array()?;
    let sp = spec(scheme, levels);
    let pyr = tensor::analyze(&mut a, &sp)?;
    let packed = Grid::new(g.h(), g.w(), g.c(), a.into_data())?;
    let mut low = Grid::zeros(g.h(), g.w(), g.c());
    low.paste(&packed.crop(ly[levels], lx[levels]));
    let (mut a, _) = low.to_array()?;
    tensor::synthesize(&mut a, &pyr)?;
    let data = g.data().iter().zip(a.data()).map(|(f, l)| f - l).collect();
    Grid::new(g.h(), g.w(), g.c(), data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sub_block_reconstructs_the_first_samples_of_the_whole_block() {
        for scheme in [Scheme::Chaikin, Scheme::Cubic] {
            for (m_y, m_x, s) in [(200usize, 160usize, 64usize), (160, 161, 100), (90, 90, 64)] {
                let ly = lengths_down(scheme, m_y, 1, "h").unwrap();
                let lx = lengths_down(scheme, m_x, 1, "w").unwrap();
                let (n_y, n_x) = (ly[1], lx[1]);
                let data = (0..m_y * m_x)
                    .map(|i| ((i * 2654435761) % 1000) as f64 / 500.0 - 1.0)
                    .collect();
                let packed = Grid::new(m_y, m_x, 1, data).unwrap();
                let planner = Planner::new();
                let (ay, ax) = (
                    sub_axis(scheme, BOUNDARY, m_y, n_y, s),
                    sub_axis(scheme, BOUNDARY, m_x, n_x, s),
                );
                assert!(ay.0 >= s && ax.0 >= s);
                for coarse in [true, false] {
                    let mut whole = packed.clone();
                    for y in 0..m_y {
                        for x in 0..m_x {
                            if (y < n_y && x < n_x) != coarse {
                                *whole.at_mut(y, x, 0) = 0.0;
                            }
                        }
                    }
                    let whole = synthesize_one(whole, scheme, &planner).unwrap();
                    let sub = synthesize_one(
                        sub_block(&packed, (n_y, n_x), ay, ax, coarse),
                        scheme,
                        &planner,
                    )
                    .unwrap();
                    for y in 0..s {
                        for x in 0..s {
                            let (a, b) = (whole.at(y, x, 0), sub.at(y, x, 0));
                            assert!(
                                (a - b).abs() < 1e-9,
                                "{scheme} {m_y}x{m_x} coarse {coarse} at ({y}, {x}): {a} vs {b}"
                            );
                        }
                    }
                }
            }
        }
    }
}
