//! Multilevel pyramids over chosen axes of an array, stored in place ("Mallat layout"):
//! after a level along axis `k` the lane `[F_0 … F_{m−1}]` holds `[C | D]`, so the
//! coarse block sits at the origin and the detail blocks around it.
//!
//! - **Standard order**: all levels along the first axis, then all along the next, …
//! - **Non-standard (Mallat) order**: one level along every axis, then recurse on the
//!   coarse block. An axis whose lanes can no longer be reduced ([`max_levels`]) stops
//!   while the others go on.

use super::array::Array;
use super::boxes::{strided, strided_mut};
use super::cascade::{self, Way};
use super::fused::{fused_level, fused_level_strided, AxisOp, Writes};
use super::par::{for_each_task, SharedMut};
use super::transform::transform_axis_with;
use super::workspace::{self, Planner};
use crate::scheme::{max_levels, Boundary, Sample, Scheme, TwoScale};
use crate::tuning::EngineChoice;
use crate::{Error, Result};

/// The order in which levels and axes are visited.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    Standard,
    NonStandard,
}

impl std::str::FromStr for Order {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "standard" => Ok(Order::Standard),
            "non-standard" | "nonstandard" | "mallat" => Ok(Order::NonStandard),
            _ => Err(Error::parameter("order", s, "standard or non-standard")),
        }
    }
}

impl std::fmt::Display for Order {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Order::Standard => "standard",
            Order::NonStandard => "non-standard",
        })
    }
}

/// What to compute.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PyramidSpec {
    pub scheme: Scheme,
    pub boundary: Boundary,
    /// Requested levels; each axis does at most what its length allows.
    pub levels: usize,
    pub order: Order,
    /// The axes to transform (e.g. `[0, 1]` for an image `[H, W, C]`: channels untouched).
    pub axes: Vec<usize>,
}

/// A planned (or computed) pyramid: the spec, the array shape and every axis' lane
/// lengths level by level (`lengths[a][0]` = full length).
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Pyramid {
    pub spec: PyramidSpec,
    pub shape: Vec<usize>,
    pub lengths: Vec<Vec<usize>>,
}

/// One block of coefficients: `ranges[k]` along every array axis.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Subband {
    /// 0 for the coarsest block, else the level (1 = finest) the details belong to.
    pub level: usize,
    /// For each transformed axis: `true` = high-pass (details) along it.
    pub high: Vec<bool>,
    pub ranges: Vec<std::ops::Range<usize>>,
}

impl Pyramid {
    /// Plan a pyramid for an array of `shape`.
    pub fn plan(shape: &[usize], spec: &PyramidSpec) -> Result<Self> {
        let mut seen = vec![false; shape.len()];
        for &a in &spec.axes {
            if a >= shape.len() || seen[a] {
                return Err(Error::parameter(
                    "axes",
                    format!("{:?}", spec.axes),
                    "distinct axes of the array",
                ));
            }
            seen[a] = true;
        }
        let lengths = spec
            .axes
            .iter()
            .map(|&a| {
                let l = spec
                    .levels
                    .min(max_levels(spec.scheme, spec.boundary, shape[a]));
                let mut v = vec![shape[a]];
                for _ in 0..l {
                    v.push(TwoScale::coarse_len(
                        spec.scheme,
                        spec.boundary,
                        *v.last().unwrap(),
                    ));
                }
                v
            })
            .collect();
        Ok(Pyramid {
            spec: spec.clone(),
            shape: shape.to_vec(),
            lengths,
        })
    }

    /// Levels actually done along transformed axis number `i` (index into `spec.axes`).
    pub fn axis_levels(&self, i: usize) -> usize {
        self.lengths[i].len() - 1
    }
    /// The deepest level over all axes.
    pub fn depth(&self) -> usize {
        (0..self.lengths.len())
            .map(|i| self.axis_levels(i))
            .max()
            .unwrap_or(0)
    }

    /// The steps of the forward transform in order: (axis index into spec.axes, level, region).
    fn steps(&self) -> Vec<(usize, usize, Vec<usize>)> {
        let mut steps = Vec::new();
        let mut region = self.shape.clone();
        match self.spec.order {
            Order::Standard => {
                for (i, &a) in self.spec.axes.iter().enumerate() {
                    for l in 0..self.axis_levels(i) {
                        region[a] = self.lengths[i][l];
                        steps.push((i, l, region.clone()));
                    }
                    region[a] = self.shape[a];
                }
            }
            Order::NonStandard => {
                for l in 0..self.depth() {
                    let before = region.clone();
                    for (i, &a) in self.spec.axes.iter().enumerate() {
                        if l < self.axis_levels(i) {
                            steps.push((i, l, before.clone()));
                            region[a] = self.lengths[i][l + 1];
                        }
                    }
                }
            }
        }
        steps
    }

    /// The region a non-standard level `l` starts from (the coarse block of level `l−1`).
    pub fn region_before(&self, l: usize) -> Vec<usize> {
        let mut r = self.shape.clone();
        for m in 0..l {
            for (i, &a) in self.spec.axes.iter().enumerate() {
                if m < self.axis_levels(i) {
                    r[a] = self.lengths[i][m + 1];
                }
            }
        }
        r
    }

    /// The subbands of a non-standard pyramid, coarsest block first, then level by
    /// level from the coarsest details to the finest. (For the standard order the
    /// blocks are the products of every axis' own bands; use [`Pyramid::lengths`].)
    pub fn subbands(&self) -> Vec<Subband> {
        let nd = self.shape.len();
        let depth = self.depth();
        // region before level l
        let mut regions = vec![self.shape.clone()];
        for l in 0..depth {
            let mut r = regions[l].clone();
            for (i, &a) in self.spec.axes.iter().enumerate() {
                if l < self.axis_levels(i) {
                    r[a] = self.lengths[i][l + 1];
                }
            }
            regions.push(r);
        }
        let mut out = vec![Subband {
            level: 0,
            high: vec![false; self.spec.axes.len()],
            ranges: (0..nd).map(|k| 0..regions[depth][k]).collect(),
        }];
        for l in (0..depth).rev() {
            let active: Vec<usize> = (0..self.spec.axes.len())
                .filter(|&i| l < self.axis_levels(i))
                .collect();
            for mask in 1u32..(1 << active.len()) {
                let mut high = vec![false; self.spec.axes.len()];
                let mut ranges: Vec<_> = (0..nd).map(|k| 0..regions[l][k]).collect();
                for (bit, &i) in active.iter().enumerate() {
                    let a = self.spec.axes[i];
                    if mask >> bit & 1 == 1 {
                        high[i] = true;
                        ranges[a] = regions[l + 1][a]..regions[l][a];
                    } else {
                        ranges[a] = 0..regions[l + 1][a];
                    }
                }
                out.push(Subband {
                    level: l + 1,
                    high,
                    ranges,
                });
            }
        }
        out
    }
}

/// Decompose `array` in place; returns the plan needed to invert it. The engine of
/// [`Engine::tuned`], the operators and scratch of [`Planner::shared`].
pub fn analyze<T: Sample>(array: &mut Array<T>, spec: &PyramidSpec) -> Result<Pyramid> {
    analyze_with(array, spec, Engine::tuned())
}

/// Invert [`analyze`] in place.
pub fn synthesize<T: Sample>(array: &mut Array<T>, pyr: &Pyramid) -> Result<()> {
    synthesize_with(array, pyr, Engine::tuned())
}

/// How the levels of a pyramid are computed. Both give the same bits: every output
/// sample is the same sums in the same order (axes in increasing order within a level,
/// in both directions; the operators of different axes commute).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// Non-standard pyramids over the leading axes run as one cascade over all levels
    /// (every sample read and written once for the whole pyramid, see `cascade.rs`);
    /// where that does not apply, [`Engine::FusedLevels`]. The default.
    Fused,
    /// Non-standard levels over the leading axes run fused and out of place, level by
    /// level (one read and one write of every sample per level, the array plus one
    /// scratch array of memory; a level inside the array first copies its box compactly
    /// into the scratch); other levels go axis by axis.
    FusedLevels,
    /// Every level axis by axis, in place.
    AxisByAxis,
    /// [`Engine::Fused`] with the cascade split into exactly this many parts (at least
    /// one), volumes included, whatever its halos cost: what `MRA_ENGINE=cascade` runs
    /// (a part per thread), and how the tests reach every cut of the cascade. The same
    /// bits as every engine.
    CascadeParts(usize),
}

impl Default for Engine {
    /// [`Engine::Fused`].
    fn default() -> Self {
        Engine::Fused
    }
}

impl Engine {
    /// The engine `tuning` asks for (`MRA_ENGINE`: `levels`, `axis`, or `cascade` for
    /// [`Engine::CascadeParts`] with a part per thread), [`Engine::Fused`] otherwise.
    pub fn tuned() -> Engine {
        match crate::tuning::get().engine {
            EngineChoice::Fused => Engine::Fused,
            EngineChoice::Levels => Engine::FusedLevels,
            EngineChoice::Axis => Engine::AxisByAxis,
            EngineChoice::Cascade => Engine::CascadeParts(rayon::current_num_threads()),
        }
    }
}

/// [`analyze`] with a chosen [`Engine`].
pub fn analyze_with<T: Sample>(
    array: &mut Array<T>,
    spec: &PyramidSpec,
    engine: Engine,
) -> Result<Pyramid> {
    analyze_in(Planner::shared(), array, spec, engine)
}

/// [`analyze_with`] with the operators and scratch of `planner`.
pub fn analyze_in<T: Sample>(
    planner: &Planner,
    array: &mut Array<T>,
    spec: &PyramidSpec,
    engine: Engine,
) -> Result<Pyramid> {
    let pyr = Pyramid::plan(array.shape(), spec)?;
    run(planner, array, &pyr, Way::Analysis, engine);
    Ok(pyr)
}

/// [`synthesize`] with a chosen [`Engine`].
pub fn synthesize_with<T: Sample>(
    array: &mut Array<T>,
    pyr: &Pyramid,
    engine: Engine,
) -> Result<()> {
    synthesize_in(Planner::shared(), array, pyr, engine)
}

/// [`synthesize_with`] with the operators and scratch of `planner`.
pub fn synthesize_in<T: Sample>(
    planner: &Planner,
    array: &mut Array<T>,
    pyr: &Pyramid,
    engine: Engine,
) -> Result<()> {
    if array.shape() != pyr.shape.as_slice() {
        return Err(Error::parameter(
            "array shape",
            format!("{:?}", array.shape()),
            "the shape the pyramid was computed for",
        ));
    }
    run(planner, array, pyr, Way::Synthesis, engine);
    Ok(())
}

/// The levels of `pyr` in the direction asked. With [`Engine::Fused`], a non-standard
/// level whose axes are the leading axes of the array (an image `[H, W, C]`, a volume `[D, H, W]`) runs fused and
/// out of place ([`fused_level`]); any other step goes axis by axis in place.
fn run<T: Sample>(
    planner: &Planner,
    array: &mut Array<T>,
    pyr: &Pyramid,
    dir: Way,
    engine: Engine,
) {
    let shape = array.shape().to_vec();
    let spec = &pyr.spec;
    let k = planner.kernels();
    let ops = |i: usize, l: usize| planner.level_ops(spec.scheme, spec.boundary, pyr.lengths[i][l]);
    let step = |data: &mut [T], i: usize, l: usize, region: &[usize]| {
        let o = ops(i, l);
        let op = match dir {
            Way::Analysis => &o.two_scale.analysis,
            Way::Synthesis => &o.two_scale.synthesis,
        };
        transform_axis_with(k, data, &shape, region, spec.axes[i], op);
    };
    if spec.order == Order::Standard {
        let mut steps = pyr.steps();
        if dir == Way::Synthesis {
            steps.reverse();
        }
        for (i, l, region) in steps {
            step(array.data_mut(), i, l, &region);
        }
        return;
    }
    let mut levels: Vec<usize> = (0..pyr.depth()).collect();
    if dir == Way::Synthesis {
        levels.reverse();
    }
    let fused_k = fused_axes(pyr, &shape, engine);
    // every level fused over the same axes and inside the array: the cascade may run
    // them all in one sweep
    let cascadable = fused_k.len() >= 2
        && fused_k.iter().all(|&k| k.is_some() && k == fused_k[0])
        && (1..pyr.depth()).all(|l| pyr.region_before(l) != shape);
    let parts = match engine {
        Engine::Fused => Some((rayon::current_num_threads(), false)),
        Engine::CascadeParts(p) => Some((p, true)),
        _ => None,
    };
    if let (true, Some((parts, forced))) = (cascadable, parts) {
        if cascade(
            planner,
            array,
            pyr,
            dir,
            fused_k[0].unwrap_or(0),
            parts,
            forced,
        ) {
            return;
        }
    }
    let mut scratch: Option<Vec<T>> = None;
    for l in levels {
        let region = pyr.region_before(l);
        let Some(k) = fused_k[l] else {
            let mut order: Vec<usize> = (0..spec.axes.len())
                .filter(|&i| l < pyr.axis_levels(i))
                .collect();
            // increasing axis order in both directions (as the fused path computes)
            order.sort_by_key(|&i| spec.axes[i]);
            for i in order {
                // every axis of a level sees the whole region (coarse and detail blocks)
                step(array.data_mut(), i, l, &region);
            }
            continue;
        };
        let buf = scratch.get_or_insert_with(|| planner.take_scratch(array.len()));
        fused_step(planner, array, pyr, dir, l, k, buf);
    }
    if let Some(s) = scratch {
        planner.give_scratch(s);
    }
}

/// How each level of `pyr` runs: `Some(k)`, fused over its `k` leading axes (the
/// active axes are exactly `0..k` and the rest of the array is whole), or `None`, axis
/// by axis.
fn fused_axes(pyr: &Pyramid, shape: &[usize], engine: Engine) -> Vec<Option<usize>> {
    let spec = &pyr.spec;
    (0..pyr.depth())
        .map(|l| {
            let region = pyr.region_before(l);
            let active: Vec<usize> = (0..spec.axes.len())
                .filter(|&i| l < pyr.axis_levels(i))
                .collect();
            let k = active.len();
            let fusable = engine != Engine::AxisByAxis
                && k > 0
                && (0..k).all(|d| active.iter().any(|&i| spec.axes[i] == d))
                && (k..shape.len()).all(|d| region[d] == shape[d]);
            fusable.then_some(k)
        })
        .collect()
}

/// Level `l` of `pyr` fused over the `k` leading axes, with the scratch `buf` (the
/// array's length): out of place and swapped in when the level covers the array, else
/// through a compact copy of its box.
fn fused_step<T: Sample>(
    planner: &Planner,
    array: &mut Array<T>,
    pyr: &Pyramid,
    dir: Way,
    l: usize,
    k: usize,
    buf: &mut Vec<T>,
) {
    let shape = array.shape().to_vec();
    let spec = &pyr.spec;
    let region = pyr.region_before(l);
    let mut by_axis = vec![usize::MAX; shape.len()];
    for i in (0..spec.axes.len()).filter(|&i| l < pyr.axis_levels(i)) {
        by_axis[spec.axes[i]] = i;
    }
    let level_ops: Vec<_> = (0..k)
        .map(|d| planner.level_ops(spec.scheme, spec.boundary, pyr.lengths[by_axis[d]][l]))
        .collect();
    let axis_ops: Vec<AxisOp> = level_ops.iter().map(|o| axis_op(o, dir)).collect();
    let strides = array.strides();
    let st = &strides[..k];
    let e: usize = shape[k..].iter().product();
    let writes = match dir {
        Way::Analysis => Writes::StreamLarge,
        Way::Synthesis => Writes::Cached,
    };
    let box_ = &region[..k];
    if region == shape {
        fused_level(array.data(), buf, st, box_, e, &axis_ops, writes);
        array.swap_data(buf);
        return;
    }
    // A level inside the array: its box copied compactly to the end of the scratch
    // (the level's one read of the box from memory), then the level from that copy,
    // in the caches, back into the box. The box's lines come back to the caches
    // with the copy, so the level's stores find them there (faster than levels that
    // alternate between the array and the scratch, reading each box from memory and
    // copying its details back).
    let cst: Vec<usize> = super::array::strides(box_).iter().map(|s| s * e).collect();
    let at = compact_at(buf, cst[0] * box_[0]);
    copy_region(array.data(), st, &mut buf[at..], &cst, box_, e);
    fused_level_strided(
        strided(&buf[at..], &cst),
        strided_mut(array.data_mut(), st),
        box_,
        e,
        &axis_ops,
        writes,
    );
}

/// One axis' operator of a level in the direction asked.
fn axis_op(o: &workspace::LevelOps, dir: Way) -> AxisOp<'_> {
    match dir {
        Way::Analysis => AxisOp {
            op: &o.two_scale.analysis,
            plan: &o.analysis,
            order: &o.analysis_order,
            parts: &o.analysis_parts,
        },
        Way::Synthesis => AxisOp {
            op: &o.two_scale.synthesis,
            plan: &o.synthesis,
            order: &o.synthesis_order,
            parts: &o.synthesis_parts,
        },
    }
}

/// All levels of a non-standard pyramid fused over the leading `k` axes as one cascade
/// ([`cascade::Plan`]), into the scratch array which then becomes the array's data;
/// `false` (nothing done) when the cascade does not apply.
fn cascade<T: Sample>(
    planner: &Planner,
    array: &mut Array<T>,
    pyr: &Pyramid,
    dir: Way,
    k: usize,
    parts: usize,
    forced: bool,
) -> bool {
    let shape = array.shape().to_vec();
    let spec = &pyr.spec;
    let depth = pyr.depth();
    if k < 2 || depth < 2 {
        return false;
    }
    let mut by_axis = vec![usize::MAX; shape.len()];
    for (i, &a) in spec.axes.iter().enumerate() {
        by_axis[a] = i;
    }
    let level_ops: Vec<Vec<_>> = (0..depth)
        .map(|l| {
            (0..k)
                .map(|d| {
                    let m = pyr.lengths[by_axis[d]][l];
                    planner.level_ops(spec.scheme, spec.boundary, m)
                })
                .collect()
        })
        .collect();
    let ops: Vec<Vec<AxisOp>> = level_ops
        .iter()
        .map(|lv| lv.iter().map(|o| axis_op(o, dir)).collect())
        .collect();
    let regions: Vec<Vec<usize>> = (0..=depth)
        .map(|l| {
            if l < depth {
                pyr.region_before(l)[..k].to_vec()
            } else {
                (0..k).map(|d| pyr.lengths[by_axis[d]][depth]).collect()
            }
        })
        .collect();
    let e: usize = shape[k..].iter().product();
    let Some(plan) = cascade::Plan::new(dir, regions, &ops, e, parts, forced) else {
        return false;
    };
    let strides = array.strides();
    let mut buf = planner.take_scratch(array.len());
    plan.run(array.data(), &mut buf, &strides[..k]);
    array.swap_data(&mut buf);
    planner.give_scratch(buf);
    true
}

/// Copy the box `[0, region)` (leading axes; elements of `e` samples) from `src`
/// (strides `src_st`) to `dst` (strides `dst_st`), lines shared among the pool's threads.
fn copy_region<T: Sample>(
    src: &[T],
    src_st: &[usize],
    dst: &mut [T],
    dst_st: &[usize],
    region: &[usize],
    e: usize,
) {
    let k = region.len();
    let run = region[k - 1] * e;
    let lines: usize = region[..k - 1].iter().product();
    let start = |line: usize, strides: &[usize]| {
        let (mut at, mut rem) = (0, line);
        for j in (0..k - 1).rev() {
            at += (rem % region[j]) * strides[j];
            rem /= region[j];
        }
        at
    };
    assert!(lines == 0 || start(lines - 1, src_st) + run <= src.len());
    assert!(lines == 0 || start(lines - 1, dst_st) + run <= dst.len());
    let per = (COPY_TASK / run.max(1)).max(1);
    let dptr = SharedMut(dst.as_mut_ptr());
    for_each_task(
        lines.div_ceil(per),
        per * run,
        || (),
        |t, _| {
            let p = dptr;
            for line in t * per..((t + 1) * per).min(lines) {
                let (at, to) = (start(line, src_st), start(line, dst_st));
                // SAFETY: lines of the box are disjoint runs inside `dst` (nested strides,
                // checked by the caller's level plan and the bound above); each task owns
                // its lines.
                unsafe {
                    std::ptr::copy_nonoverlapping(src.as_ptr().add(at), p.0.add(to), run);
                }
            }
        },
    );
}

/// Where a compact box of `n` samples starts in `buf`: at its end, on a cache line
/// (256³ cubic, 1–2% faster than 16 bytes past one).
fn compact_at<T>(buf: &[T], n: usize) -> usize {
    let size = std::mem::size_of::<T>().max(1);
    let at = buf.len() - n;
    let mis = (buf.as_ptr() as usize + at * size) % 64;
    if mis.is_multiple_of(size) && at >= mis / size {
        at - mis / size
    } else {
        at
    }
}

/// Samples copied per task by [`copy_region`].
const COPY_TASK: usize = 1 << 16;
