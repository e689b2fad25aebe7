//! Upscaling by subdivision and downscaling by the MRA's reduce-resolution filter, for
//! images, volumes, heightmaps and image sequences (notes §7.7.1–7.7.2, §9.3.3).
//!
//! **Upscale.** Along each chosen axis a lane of `n` samples becomes `m` samples of the
//! limit function `f(x) = Σ_i P_i φ(x − i)` of a subdivision rule ([`basis`]), evaluated
//! at the new cell centres ([`lane::positions`]); the tensor product over the axes is
//! the surface / volume `Σ P_ijk N_i(u) N_j(v) N_k(w)` of §7.7. The control points `P`
//! come from the samples by one of three [`Mode`]s:
//! ```text
//! control     P = samples                          plain subdivision: smooth, blurs
//! interpolate K P = samples, K_ri = φ(r − i)        f passes through the samples
//! area        K P = samples, K_ri = ∫_{r−½}^{r+½} φ(x − i) dx   the cell means of f are
//!             the samples; new samples are cell means too, so they average back exactly
//! ```
//! `K` is banded (tridiagonal for Chaikin and cubic, pentadiagonal for quartic) and is
//! solved per lane in place ([`lane::Banded`]) before evaluation. Evaluation is one
//! sparse `m × n` operator per axis ([`crate::tensor::resample_axis`]), ≤ order + 1 taps
//! per new sample, threaded over lanes; the last axis writes the input's sample type
//! directly (rounded, clamped), so a 16-bit volume never exists as a full-size f32 array.
//!
//! **Downscale.** `levels` times along each axis: the first `coarse` rows of the level's
//! analysis operator `[A; B]`, i.e. `C = A F` (REDUCE-RESOLUTION, §9).
//!
//! Measured on Kodak, CT and DEM data in `docs/upscale.md`.

mod along;
pub mod basis;
mod cells;
pub mod lane;
pub mod refine;
mod slab;

use crate::io::{DataKind, Raster, Samples};
use crate::progress::Progress;
use crate::scheme::sparse::{Csr, Triplets};
use crate::scheme::subdivide::Refinement;
use crate::scheme::{Boundary, Scheme, TwoScale};
use crate::tensor::{map_lanes, resample_axis, resample_axis_with};
use crate::{Error, Result};
use basis::Basis;
pub use lane::{Edge, Geometry, Mode};
pub use refine::Clamp;

/// Largest factor accepted along one axis.
pub const MAX_FACTOR: usize = 1 << 10;

/// How to upscale.
#[derive(Clone, Debug, PartialEq)]
pub struct Method {
    pub rule: Refinement,
    pub mode: Mode,
    pub edge: Edge,
    /// B-spline order overriding the rule's (orders above 5 have no named rule).
    pub order: Option<usize>,
    /// Area mode only: clamp overshoot and restore the cell means ([`refine`]).
    pub clamp: Clamp,
}

impl Method {
    fn basis(&self) -> Basis {
        match self.order {
            Some(k) => Basis::BSpline(k),
            None => Basis::of(self.rule),
        }
    }
}

impl Default for Method {
    /// The best measured combination (`docs/upscale.md`): Chaikin's quadratic B-spline
    /// (the dual rule, whose refined points sit at the new pixel centres), area mode,
    /// overshoot clamping blended by the weight learned one level up.
    fn default() -> Self {
        Method {
            rule: Refinement::Chaikin,
            mode: Mode::Area,
            edge: Edge::Linear,
            order: None,
            clamp: Clamp::Auto,
        }
    }
}

/// One axis to resample: array axis, new length, geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxisPlan {
    pub axis: usize,
    pub len: usize,
    pub geometry: Geometry,
}

/// The new length of a lane of `n` upscaled by `factor` with `geometry`.
pub fn scaled_len(n: usize, factor: usize, geometry: Geometry) -> usize {
    match geometry {
        Geometry::Centre => n * factor,
        Geometry::Vertex => (n - 1) * factor + 1,
    }
}

fn check(method: &Method, shape: &[usize], plans: &[AxisPlan]) -> Result<()> {
    if plans.is_empty() {
        return Err(Error::parameter("axes", "none", "at least one axis"));
    }
    if let Some(k) = method.order {
        if !(1..=basis::MAX_ORDER).contains(&k) {
            return Err(Error::parameter("B-spline order", k, "1 to 12"));
        }
    }
    let mut seen = vec![false; shape.len()];
    for p in plans {
        if p.axis >= shape.len() || seen[p.axis] {
            return Err(Error::parameter(
                "axes",
                format!("{:?}", plans.iter().map(|p| p.axis).collect::<Vec<_>>()),
                "distinct axes of the array",
            ));
        }
        seen[p.axis] = true;
        if p.len == 0 || p.len > shape[p.axis].saturating_mul(MAX_FACTOR) {
            return Err(Error::parameter(
                "output length",
                p.len,
                "between 1 and 1024 × the input length",
            ));
        }
    }
    let out: u64 = shape
        .iter()
        .enumerate()
        .map(|(a, &n)| plans.iter().find(|p| p.axis == a).map_or(n, |p| p.len) as u64)
        .try_fold(1u64, |acc, x| acc.checked_mul(x))
        .unwrap_or(u64::MAX);
    if out > crate::io::MAX_SAMPLES {
        return Err(Error::LimitsExceeded {
            what: "output samples",
            requested: out,
            limit: crate::io::MAX_SAMPLES,
        });
    }
    if method.mode == Mode::Area && plans.iter().any(|p| p.geometry == Geometry::Vertex) {
        return Err(Error::parameter(
            "mode",
            "area",
            "interpolate or control along a time axis (frames are instants, not cells)",
        ));
    }
    Ok(())
}

/// The evaluation operator of one axis (`len × n`).
pub fn axis_operator(method: &Method, n: usize, plan: &AxisPlan) -> Csr {
    let basis = method.basis();
    let (xs, w) = lane::positions(n, plan.len, plan.geometry);
    let width = if method.mode == Mode::Area { w } else { 0.0 };
    lane::eval_matrix(&basis, n, &xs, width, method.edge)
}

/// The banded systems and evaluation operators of one upscale of arrays of one shape,
/// built once (a refined upscale applies the same stage several times).
pub(crate) struct Prepared {
    shape: Vec<usize>,
    /// Per planned axis: the system turning samples into control points (none for
    /// [`Mode::Control`]).
    systems: Vec<(usize, Option<lane::Banded>)>,
    /// Evaluation operators, fastest axis first (its gathers run on the smallest array).
    ops: Vec<(usize, Csr)>,
    /// The last intermediate array of a run, reused by the next run (a refined stage
    /// runs the same upscale three times): no fresh pages, no zeroing.
    spare: std::sync::Mutex<Vec<f32>>,
}

impl Prepared {
    pub(crate) fn new(method: &Method, shape: &[usize], plans: &[AxisPlan]) -> Result<Prepared> {
        check(method, shape, plans)?;
        let basis = method.basis();
        let systems = plans
            .iter()
            .map(|p| {
                Ok((
                    p.axis,
                    lane::system(&basis, shape[p.axis], method.mode, method.edge)?,
                ))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut order = plans.to_vec();
        order.sort_by_key(|p| std::cmp::Reverse(p.axis));
        let ops = order
            .iter()
            .map(|p| (p.axis, axis_operator(method, shape[p.axis], p)))
            .collect();
        Ok(Prepared {
            shape: shape.to_vec(),
            systems,
            ops,
            spare: std::sync::Mutex::new(Vec::new()),
        })
    }

    /// The control points: every planned axis' banded system solved in place.
    pub(crate) fn prefilter(&self, data: &mut [f32]) {
        for (axis, k) in &self.systems {
            if let Some(k) = k {
                map_lanes(data, &self.shape, *axis, |lane, width| k.solve(lane, width));
            }
        }
    }

    /// The output's shape.
    pub(crate) fn out_shape(&self) -> Vec<usize> {
        let mut shape = self.shape.clone();
        for (axis, op) in &self.ops {
            shape[*axis] = op.rows();
        }
        shape
    }

    /// Prefilter then evaluate along every axis; the last axis' results go through
    /// `store`.
    pub(crate) fn run<U: Copy + Default + Send + Sync>(
        &self,
        data: Vec<f32>,
        bar: &Progress,
        store: impl Fn(f32) -> U + Sync + Send,
    ) -> (Vec<U>, Vec<usize>) {
        let shape = self.out_shape();
        let mut out = vec![U::default(); shape.iter().product()];
        self.run_into(data, bar, &mut out, store);
        (out, shape)
    }

    /// [`Prepared::run`] into `out` (of the output's size, every sample overwritten).
    pub(crate) fn run_into<U: Copy + Default + Send + Sync>(
        &self,
        data: Vec<f32>,
        bar: &Progress,
        out: &mut [U],
        store: impl Fn(f32) -> U + Sync + Send,
    ) {
        self.run_put(data, bar, out, |d: &mut U, x| *d = store(x))
    }

    /// [`Prepared::run`], every output value `x` put into its sample `d` of `out` by
    /// `put(d, x)` (`*d += x`: add the upscale to what `out` holds).
    pub(crate) fn run_put<U: Copy + Default + Send + Sync>(
        &self,
        mut data: Vec<f32>,
        bar: &Progress,
        out: &mut [U],
        put: impl Fn(&mut U, f32) + Sync + Send,
    ) {
        self.prefilter(&mut data);
        let mut shape = self.shape.clone();
        bar.inc(1);
        let last = self.ops.len() - 1;
        for (k, (axis, op)) in self.ops.iter().enumerate() {
            let mut next_shape = shape.clone();
            next_shape[*axis] = op.rows();
            if k == last {
                resample_axis_with(&data, &shape, *axis, op, out, &put);
                bar.inc(1);
                if k > 0 {
                    if let Ok(mut spare) = self.spare.lock() {
                        *spare = data;
                    }
                }
                return;
            }
            let len = next_shape.iter().product();
            let mut next = match self.spare.lock() {
                Ok(mut spare) => std::mem::take(&mut *spare),
                Err(_) => Vec::new(),
            };
            if next.len() != len {
                // (every sample is written below; zeros only to size it)
                next.clear();
                next.resize(len, 0.0);
            }
            resample_axis(&data, &shape, *axis, op, &mut next, |x| x);
            data = next;
            shape = next_shape;
            bar.inc(1);
        }
    }
}

/// Upscale (or resample) an f32 array; returns the new data and shape.
pub fn upscale_array(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    plans: &[AxisPlan],
) -> Result<(Vec<f32>, Vec<usize>)> {
    upscale_into(data, shape, method, plans, &Progress::hidden(), |x| x)
}

/// The whole pipeline, the last axis' results stored through `store`.
fn upscale_into<U: Copy + Default + Send + Sync + 'static>(
    data: Vec<f32>,
    shape: &[usize],
    method: &Method,
    plans: &[AxisPlan],
    bar: &Progress,
    store: impl Fn(f32) -> U + Sync + Send,
) -> Result<(Vec<U>, Vec<usize>)> {
    check(method, shape, plans)?;
    if data.len() != shape.iter().product::<usize>() {
        return Err(Error::parameter(
            "array data length",
            data.len(),
            "the product of the shape",
        ));
    }
    if let Some(f) = refine::factors(method, shape, plans) {
        let out = refine::upscale_refined_into(data, shape, method, &f, store)?;
        bar.inc(plans.len() as u64 + 1);
        return Ok(out);
    }
    Ok(Prepared::new(method, shape, plans)?.run(data, bar, store))
}

/// Plans for a raster: `factor` along `axes` (indices into `dims`), or explicit `size`
/// (`dims` order). `time` marks axis 0 as a time axis (vertex geometry).
pub fn plan_raster(
    dims: &[usize],
    axes: &[usize],
    factor: Option<usize>,
    size: Option<&[usize]>,
    time: bool,
) -> Result<Vec<AxisPlan>> {
    let geometry = |a: usize| {
        if time && a == 0 && dims.len() == 3 {
            Geometry::Vertex
        } else {
            Geometry::Centre
        }
    };
    match (factor, size) {
        (_, Some(size)) => {
            if size.len() != dims.len() {
                return Err(Error::parameter(
                    "size",
                    format!("{} values", size.len()),
                    "one value per spatial axis (WxH for 2-D, WxHxD for 3-D)",
                ));
            }
            Ok((0..dims.len())
                .filter(|&a| size[a] != dims[a] || axes.contains(&a))
                .map(|a| AxisPlan {
                    axis: a,
                    len: size[a],
                    geometry: geometry(a),
                })
                .collect())
        }
        (Some(f), None) => {
            if !(2..=MAX_FACTOR).contains(&f) {
                return Err(Error::parameter("factor", f, "an integer from 2 to 1024"));
            }
            axes.iter()
                .map(|&a| {
                    if a >= dims.len() {
                        return Err(Error::parameter(
                            "axes",
                            a,
                            "axes the input has (x, y for images; x, y, z or t for volumes)",
                        ));
                    }
                    Ok(AxisPlan {
                        axis: a,
                        len: scaled_len(dims[a], f, geometry(a)),
                        geometry: geometry(a),
                    })
                })
                .collect()
        }
        (None, None) => Err(Error::parameter(
            "output size",
            "none",
            "--factor F or --size WxH[xD]",
        )),
    }
}

/// Round to nearest and saturate (NaN → 0), as `Samples::from_f32` does.
macro_rules! store_int {
    ($t:ty) => {
        |x: f32| x.round() as $t
    };
}

/// The extents of the output of `plans` from a raster of extents `dims` (`dims` order).
pub fn output_dims(dims: &[usize], plans: &[AxisPlan]) -> Vec<usize> {
    (0..dims.len())
        .map(|a| {
            plans
                .iter()
                .find(|p| p.axis == a)
                .map_or(dims[a], |p| p.len)
        })
        .collect()
}

/// The memory budget of an upscale ([`crate::limits`], `MRA_MAX_BYTES`), checked by
/// [`upscale_raster`] and [`upscale_view`] before anything is allocated:
///
/// ```text
/// bytes = C · Π output_dims · (4 + s)
/// ```
/// the output's samples in f32 (the working type) plus in the stored type of `s` bytes.
pub fn check_budget(
    dims: &[usize],
    channels: usize,
    ty: crate::io::SampleType,
    plans: &[AxisPlan],
) -> Result<()> {
    let samples = output_dims(dims, plans)
        .iter()
        .try_fold(channels as u64, |acc, &d| acc.checked_mul(d as u64))
        .unwrap_or(u64::MAX);
    crate::limits::check_elems(
        "upscaled output bytes (memory budget MRA_MAX_BYTES)",
        samples,
        4 + ty.size() as u64,
    )
}

/// Upscale a raster (consumed: its samples are freed once converted to f32). Channels
/// are never resampled; the result has the input's sample type. Void samples
/// (`meta.nodata`, NaN) are filled by pull-push for the computation; an output sample
/// whose footprint is all void is void again and the others stay within the valid
/// input range ([`crate::io::nodata`]). An output over the memory budget is refused
/// first ([`check_budget`]).
pub fn upscale_raster(
    r: Raster,
    method: &Method,
    plans: &[AxisPlan],
    bar: &Progress,
) -> Result<Raster> {
    check_budget(&r.dims, r.channels, r.sample_type(), plans)?;
    let Raster {
        dims,
        channels,
        samples,
        kind,
        meta,
    } = r;
    let ty = samples.sample_type();
    let data = match samples {
        Samples::F32(v) => v,
        s => s.to_f32(),
    };
    upscale_f32(dims, channels, ty, kind, meta, data, method, plans, bar)
}

/// [`upscale_raster`] of a borrowed raster (its samples converted to f32 where they are:
/// the one copy).
pub fn upscale_view(
    r: &crate::io::RasterView<'_>,
    method: &Method,
    plans: &[AxisPlan],
    bar: &Progress,
) -> Result<Raster> {
    check_budget(r.dims, r.channels, r.sample_type(), plans)?;
    let data = r.samples.to_f32();
    let (dims, meta) = (r.dims.to_vec(), r.meta.clone());
    let ty = r.sample_type();
    upscale_f32(dims, r.channels, ty, r.kind, meta, data, method, plans, bar)
}

/// [`upscale_raster`] of samples already in f32 (`data`, stored type `ty`).
#[allow(clippy::too_many_arguments)]
fn upscale_f32(
    dims: Vec<usize>,
    channels: usize,
    ty: crate::io::SampleType,
    kind: crate::io::DataKind,
    mut meta: crate::io::Metadata,
    mut data: Vec<f32>,
    method: &Method,
    plans: &[AxisPlan],
    bar: &Progress,
) -> Result<Raster> {
    let mut shape = dims.clone();
    if channels > 1 {
        shape.push(channels);
    }
    // voids: filled for the computation, marked again where the footprint is all void
    let voids = crate::io::nodata::Voids::find(&data, meta.nodata);
    let out_void = match &voids {
        Some(v) => {
            check(method, &shape, plans)?;
            v.fill(&mut data, &shape, dims.len())?;
            let mut new_dims = dims.clone();
            for p in plans.iter().filter(|p| p.axis < dims.len()) {
                new_dims[p.axis] = p.len;
            }
            Some(v.footprint(&shape, &new_dims, &axis_maps(&dims, &new_dims, plans)))
        }
        None => None,
    };
    let p = plans;
    macro_rules! arm {
        ($variant:ident, $store:expr) => {{
            let (mut v, s) = upscale_into(data, &shape, method, p, bar, $store)?;
            if let (Some(vd), Some(m)) = (&voids, &out_void) {
                vd.restore(&mut v, m, true);
            }
            (Samples::$variant(v), s)
        }};
    }
    let (samples, new_shape) = match ty {
        crate::io::SampleType::U8 => arm!(U8, store_int!(u8)),
        crate::io::SampleType::I8 => arm!(I8, store_int!(i8)),
        crate::io::SampleType::U16 => arm!(U16, store_int!(u16)),
        crate::io::SampleType::I16 => arm!(I16, store_int!(i16)),
        crate::io::SampleType::U32 => arm!(U32, store_int!(u32)),
        crate::io::SampleType::I32 => arm!(I32, store_int!(i32)),
        crate::io::SampleType::F16 => arm!(F16, half::f16::from_f32),
        crate::io::SampleType::F32 => arm!(F32, |x: f32| x),
        crate::io::SampleType::F64 => arm!(F64, |x: f32| x as f64),
    };
    let new_dims = new_shape[..dims.len()].to_vec();
    rescale_meta(&mut meta, &dims, &new_dims, plans);
    let mut out = Raster::new(new_dims, channels, samples, kind)?;
    out.meta = meta;
    Ok(out)
}

/// The metadata of the upscaled grid: per axis, new sample `j` sits at old index
/// `x_0 + j·s` ([`lane::positions`]), applied by [`crate::io::Metadata::resampled`].
fn rescale_meta(
    meta: &mut crate::io::Metadata,
    dims: &[usize],
    new_dims: &[usize],
    plans: &[AxisPlan],
) {
    *meta = meta.resampled(dims, new_dims, &axis_maps(dims, new_dims, plans));
}

/// Per spatial axis, where the new samples sit on the old ones ([`lane::positions`]).
fn axis_maps(dims: &[usize], new_dims: &[usize], plans: &[AxisPlan]) -> Vec<crate::io::AxisMap> {
    (0..dims.len())
        .map(|a| {
            let g = plans
                .iter()
                .find(|p| p.axis == a)
                .map_or(Geometry::Centre, |p| p.geometry);
            if new_dims[a] == dims[a] {
                return crate::io::AxisMap::IDENTITY;
            }
            let (xs, s) = lane::positions(dims[a], new_dims[a], g);
            crate::io::AxisMap {
                offset: xs[0],
                step: s,
            }
        })
        .collect()
}

/// The reduce-resolution operator `A` (`coarse × m`) of one level.
///
/// With the symmetric boundary every scheme gives exactly `⌈m/2⌉` coarse samples. A scheme
/// whose regular row `a` has an even number of taps (Chaikin, chaikin-wide) is then centred on
/// the cells `[2j, 2j+1]`, at `2j + ½` as a block mean is (`C_j = Σ_t a_t F_{2j+1−L/2+t}`,
/// half-sample mirrors `F_{−1} = F_0`, `F_m = F_{m−1}`), rather than the MRA level's placement,
/// which has `⌊m/2⌋ + 1` coarse samples (the first centred at `−½`).
pub fn reduce_operator(scheme: Scheme, boundary: Boundary, m: usize) -> Csr {
    if boundary == Boundary::Symmetric && m >= 2 {
        if let Some(f) = scheme.regular().filter(|f| f.a.w.len() % 2 == 0) {
            return cell_centred(f.a.w, m);
        }
    }
    reduce_level(scheme, boundary, m)
}

/// The downscale operator: [`reduce_operator`] followed, for the quadratic B-spline schemes with
/// the symmetric boundary, by evaluating the coarse spline at the coarse cells' centres,
/// `V_j = ⅛C_{j−1} + ¾C_j + ⅛C_{j+1}` (`C_{−1} = C_0`, `C_n = C_{n−1}`).
///
/// `C = A F` are control points of the coarse B-spline, not samples of it; a picture of half the
/// size wants the samples. The product `E A` also aliases less: its response is
/// `E(2ω) A(ω)`, `E(π) = ½` at the coarse Nyquist frequency. (`docs/filters.md`: with
/// chaikin-wide this raises the downscale-then-upscale PSNR over the block mean's.)
pub fn downscale_operator(scheme: Scheme, boundary: Boundary, m: usize) -> Csr {
    let a = reduce_operator(scheme, boundary, m);
    let quadratic = matches!(scheme, Scheme::Chaikin | Scheme::ChaikinWide);
    if !(quadratic && boundary == Boundary::Symmetric && m >= 2) {
        return a;
    }
    let n = a.rows();
    let mut t = Triplets::new(n, m);
    for j in 0..n {
        let left = j.saturating_sub(1);
        let right = (j + 1).min(n - 1);
        for (r, w) in [(left, 0.125), (j, 0.75), (right, 0.125)] {
            for (c, x) in a.row(r) {
                t.add(j, c, w * x);
            }
        }
    }
    t.into_csr()
}

/// The analysis rows `A` of the scheme's level for a lane of `m`.
fn reduce_level(scheme: Scheme, boundary: Boundary, m: usize) -> Csr {
    let level = TwoScale::new(scheme, boundary, m);
    let mut t = Triplets::new(level.coarse, m);
    for r in 0..level.coarse {
        for (c, w) in level.analysis.row(r) {
            t.add(r, c, w);
        }
    }
    t.into_csr()
}

/// `C_j = Σ_t a_t F_{2j+1−L/2+t}` for `j < ⌈m/2⌉`, fine indices folded by half-sample mirrors.
fn cell_centred(a: &[f64], m: usize) -> Csr {
    let n = m.div_ceil(2);
    let half = a.len() as isize / 2;
    let fold = |mut i: isize| -> usize {
        let m = m as isize;
        loop {
            if i < 0 {
                i = -1 - i;
            } else if i >= m {
                i = 2 * m - 1 - i;
            } else {
                return i as usize;
            }
        }
    };
    let mut t = Triplets::new(n, m);
    for j in 0..n {
        for (k, &w) in a.iter().enumerate() {
            t.add(j, fold(2 * j as isize + 1 - half + k as isize), w);
        }
    }
    t.into_csr()
}

/// Downscale an f32 array `levels` times along `axes` with the scheme's `A`.
pub fn downscale_array(
    mut data: Vec<f32>,
    shape: &[usize],
    scheme: Scheme,
    boundary: Boundary,
    levels: usize,
    axes: &[usize],
) -> Result<(Vec<f32>, Vec<usize>)> {
    if levels == 0 || levels > 16 {
        return Err(Error::parameter("levels", levels, "1 to 16"));
    }
    if axes.is_empty() || axes.iter().any(|&a| a >= shape.len()) {
        return Err(Error::parameter(
            "axes",
            format!("{axes:?}"),
            "axes of the array",
        ));
    }
    let mut shape = shape.to_vec();
    for _ in 0..levels {
        for &a in axes {
            let m = shape[a];
            if m < 2 {
                return Err(Error::parameter(
                    "levels",
                    levels,
                    "few enough that every axis keeps at least one sample",
                ));
            }
            let op = downscale_operator(scheme, boundary, m);
            let mut next = shape.clone();
            next[a] = op.rows();
            let mut out = vec![0f32; next.iter().product()];
            resample_axis(&data, &shape, a, &op, &mut out, |x| x);
            data = out;
            shape = next;
        }
    }
    Ok((data, shape))
}

/// Downscale a raster over its spatial `axes`, keeping its sample type; every output
/// sample not void lies within the input's valid range `[min, max]`. The metadata
/// follows the coarse grid by [`crate::io::Metadata::rescaled`]: the same extent, cells
/// centred (spacing × `n / m` per axis, origin at the first coarse cell's centre).
pub fn downscale_raster(
    r: Raster,
    scheme: Scheme,
    boundary: Boundary,
    levels: usize,
    axes: &[usize],
) -> Result<Raster> {
    downscale_view(&r.view(), scheme, boundary, levels, axes)
}

/// [`downscale_raster`] of a borrowed raster (its samples converted to f32 where they
/// are: the one copy).
pub fn downscale_view(
    r: &crate::io::RasterView<'_>,
    scheme: Scheme,
    boundary: Boundary,
    levels: usize,
    axes: &[usize],
) -> Result<Raster> {
    let ty = r.sample_type();
    let mut shape = r.dims.to_vec();
    if r.channels > 1 {
        shape.push(r.channels);
    }
    if axes.iter().any(|&a| a >= r.dims.len()) {
        return Err(Error::parameter(
            "axes",
            format!("{axes:?}"),
            "spatial axes of the input",
        ));
    }
    let mut data = r.samples.to_f32();
    // voids never enter the filter: filled, then marked again where the footprint is
    // all void, the rest clamped into the valid range ([`crate::io::nodata`])
    let voids = crate::io::nodata::Voids::find(&data, r.meta.nodata);
    if let Some(v) = &voids {
        v.fill(&mut data, &shape, r.dims.len())?;
    }
    // without voids, the input's range bounds the output too (the filter's negative
    // lobes would otherwise dip below a flat minimum: 114 under an SRTM tile's 115 m)
    let range = match voids {
        None => data
            .iter()
            .fold(None, |acc: Option<(f32, f32)>, &x| match acc {
                None => Some((x, x)),
                Some((lo, hi)) => Some((lo.min(x), hi.max(x))),
            }),
        Some(_) => None,
    };
    let (mut out, new_shape) = downscale_array(data, &shape, scheme, boundary, levels, axes)?;
    let new_dims = new_shape[..r.dims.len()].to_vec();
    if let Some(v) = &voids {
        let maps: Vec<crate::io::AxisMap> = (r.dims.iter().zip(&new_dims))
            .map(|(&n, &m)| crate::io::AxisMap::centred(n, m))
            .collect();
        v.restore(&mut out, &v.footprint(&shape, &new_dims, &maps), true);
    }
    if let Some((lo, hi)) = range {
        for x in &mut out {
            *x = x.clamp(lo, hi);
        }
    }
    let meta = r.meta.rescaled(r.dims, &new_dims);
    let mut o = Raster::from_f32(new_dims, r.channels, &out, ty, r.kind)?;
    o.meta = meta;
    Ok(o)
}

/// Axes named by letters: `x` = fastest spatial axis, `y` the next, `z` (or `t`, time)
/// the slowest of a volume / sequence. Returns array axes and whether `t` was named.
pub fn parse_axes(s: &str, ndims: usize) -> Result<(Vec<usize>, bool)> {
    let mut axes = Vec::new();
    let mut time = false;
    for ch in s.chars().filter(|c| !matches!(c, ',' | ' ')) {
        let back = match ch.to_ascii_lowercase() {
            'x' => 0,
            'y' => 1,
            'z' => 2,
            't' => {
                time = true;
                2
            }
            _ => return Err(Error::parameter("axes", s, "letters among x, y, z, t")),
        };
        if back >= ndims {
            return Err(Error::parameter(
                "axes",
                s,
                "axes the input has (x, y for images; x, y, z or t for volumes)",
            ));
        }
        let a = ndims - 1 - back;
        if axes.contains(&a) {
            return Err(Error::parameter("axes", s, "each axis once"));
        }
        axes.push(a);
    }
    if axes.is_empty() {
        return Err(Error::parameter("axes", s, "at least one of x, y, z, t"));
    }
    Ok((axes, time))
}

/// Whether a raster's slowest axis is time (image sequences).
pub fn is_sequence(r: &Raster) -> bool {
    r.kind == DataKind::Sequence
}

/// `mra demo` rows: a generated 512² fractal terrain (8-bit scale) halved by 2×2 block
/// means, upscaled back ×2 in each mode; PSNR against the original (8-bit peak). Writes
/// the area-mode result. Built with the command line only (feature `cli`).
#[cfg(feature = "cli")]
pub fn demo_rows(out: &std::path::Path) -> Result<Vec<crate::demo::DemoRow>> {
    let n = 512;
    let img: Vec<f32> = crate::generate::terrain::diamond_square(n, n, 7, 0.6)
        .data()
        .iter()
        .map(|&v| (v * 255.0) as f32)
        .collect();
    let (low, ls) = downscale_array(
        img.clone(),
        &[n, n],
        Scheme::Haar,
        Boundary::Symmetric,
        1,
        &[0, 1],
    )?;
    let mut rows = Vec::new();
    for (name, mode) in [
        ("area", Mode::Area),
        ("interpolate", Mode::Interpolate),
        ("control", Mode::Control),
    ] {
        let m = Method {
            mode,
            ..Method::default()
        };
        let plans: Vec<AxisPlan> = (0..2)
            .map(|a| AxisPlan {
                axis: a,
                len: n,
                geometry: Geometry::Centre,
            })
            .collect();
        let t = std::time::Instant::now();
        let (up, _) = upscale_array(low.clone(), &ls, &m, &plans)?;
        let secs = t.elapsed().as_secs_f64();
        let mse = up
            .iter()
            .zip(&img)
            .map(|(a, b)| ((a.round().clamp(0.0, 255.0) - b.round()) as f64).powi(2))
            .sum::<f64>()
            / img.len() as f64;
        let output = if mode == Mode::Area {
            let p = out.join("upscale_terrain.png");
            let r = Raster::from_f32(
                vec![n, n],
                1,
                &up,
                crate::io::SampleType::U8,
                DataKind::Image,
            )?;
            crate::io::write(&p, &r)?;
            Some(p)
        } else {
            None
        };
        rows.push(crate::demo::DemoRow {
            job: format!("upscale x2 ({name})"),
            data: "fractal terrain 512^2 (8-bit) halved by 2x2 block means, Chaikin (quadratic B-spline)".into(),
            result: format!(
                "PSNR {:.2} dB vs original",
                10.0 * (255.0f64 * 255.0 / mse).log10()
            ),
            seconds: secs,
            output,
        });
    }
    Ok(rows)
}
