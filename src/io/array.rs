//! Rasters through the tensor engine: a raster becomes an f32 [`Array`] of shape
//! `dims` (one channel) or `[dims…, channels]` (channels last and not transformed), is
//! decomposed in place by [`crate::tensor::analyze`], and is stored with
//! [`super::pyramid_file`]; [`synthesize_raster`] inverts it and restores the source
//! type (integers rounded to nearest and clamped: bit-exact for integer data up to 2^24
//! whose reconstruction error stays below ½; float data to f32 precision).
//!
//! Memory: the input samples are converted once to f32 and dropped; the transform runs
//! in place. Peak ≈ input + f32 copy during the conversion, then the f32 array plus the
//! engine's per-thread scratch.

use super::pyramid_file::{self, PyramidInfo};
use super::visual::{self, Block};
use super::{Raster, Samples};
use crate::tensor::{self, Array, Order, Pyramid, PyramidSpec};
use crate::{Error, Result};

/// Shape of the engine array for a raster and the axes to transform (all spatial axes).
pub fn array_shape(dims: &[usize], channels: usize) -> (Vec<usize>, Vec<usize>) {
    let mut shape = dims.to_vec();
    if channels > 1 {
        shape.push(channels);
    }
    (shape, (0..dims.len()).collect())
}

/// Decompose `r` (consumed, so that its samples are freed early) with `spec`'s scheme,
/// boundary, levels and order over all spatial axes (`spec.axes` is replaced). Returns
/// the pyramid container (f32 coefficients, source type and metadata, pyramid keys) and
/// the plan.
pub fn analyze_raster(mut r: Raster, spec: &PyramidSpec) -> Result<(Raster, Pyramid)> {
    if r.dims.is_empty() {
        return Err(Error::parameter("dims", "[]", "at least one spatial axis"));
    }
    // the samples leave `r`, which stays as the shell the container is made from
    let samples = std::mem::replace(&mut r.samples, Samples::F32(Vec::new()));
    let source_type = samples.sample_type();
    let data = samples.to_f32();
    drop(samples);
    let (shape, axes) = array_shape(&r.dims, r.channels);
    let spec = PyramidSpec {
        axes,
        ..spec.clone()
    };
    let mut array = Array::from_shape_vec(&shape, data)?;
    let pyr = tensor::analyze(&mut array, &spec)?;
    let info = PyramidInfo {
        scheme: spec.scheme.name().into(),
        boundary: spec.boundary.name().into(),
        levels: spec.levels,
        order: spec.order.to_string(),
        axes: spec.axes.clone(),
        source_type,
        source_kind: r.kind,
    };
    // the container takes the coefficients without copying
    let container = pyramid_file::container(&r, array.into_data(), &info)?;
    Ok((container, pyr))
}

/// The spec recorded in a pyramid file.
pub fn spec_of(info: &PyramidInfo) -> Result<PyramidSpec> {
    Ok(PyramidSpec {
        scheme: info.scheme.parse()?,
        boundary: info.boundary.parse()?,
        levels: info.levels,
        order: info.order.parse()?,
        axes: info.axes.clone(),
    })
}

/// Invert [`analyze_raster`]: the container (consumed) back to the source raster.
pub fn synthesize_raster(mut container: Raster, info: &PyramidInfo) -> Result<Raster> {
    let spec = spec_of(info)?;
    // the coefficients leave the container, which stays as the shell to restore from
    let Samples::F32(data) = std::mem::replace(&mut container.samples, Samples::F32(Vec::new()))
    else {
        return Err(Error::format(
            "coefficients are not float32",
            "a pyramid written by mra analyze",
        ));
    };
    let (shape, axes) = array_shape(&container.dims, container.channels);
    if axes != spec.axes {
        return Err(Error::format(
            format!("mra.axes {:?} for dims {:?}", spec.axes, container.dims),
            "all spatial axes",
        ));
    }
    let mut array = Array::from_shape_vec(&shape, data)?;
    let pyr = Pyramid::plan(&shape, &spec)?;
    tensor::synthesize(&mut array, &pyr)?;
    pyramid_file::restore(&container, array.data(), info)
}

/// The blocks of a pyramid over the spatial axes (`ndims` of them), coarse block marked.
pub fn blocks(pyr: &Pyramid, ndims: usize) -> Vec<Block> {
    match pyr.spec.order {
        Order::NonStandard => pyr
            .subbands()
            .into_iter()
            .map(|s| Block {
                ranges: s.ranges[..ndims].to_vec(),
                coarse: s.level == 0,
            })
            .collect(),
        Order::Standard => visual::standard_blocks(&pyr.lengths),
    }
}

/// The 8-bit picture of a pyramid container (`--visual`): 2-D data whole, 3-D data at
/// slice `z` (default 0: the slice through the coarse block).
pub fn picture(container: &Raster, pyr: &Pyramid, z: Option<usize>) -> Result<Raster> {
    let Samples::F32(data) = &container.samples else {
        return Err(Error::format("coefficients are not float32", "float32"));
    };
    let nd = container.dims.len();
    let bl = blocks(pyr, nd);
    match nd {
        2 => visual::picture(data, &container.dims, container.channels, &bl),
        3 => {
            let z = z.unwrap_or(0);
            let (s, b) = visual::slice(data, &container.dims, container.channels, &bl, z)?;
            visual::picture(&s, &container.dims[1..], container.channels, &b)
        }
        _ => Err(Error::Unsupported {
            what: "picture",
            value: format!("{nd}-D data (expected 2-D or 3-D)"),
        }),
    }
}
