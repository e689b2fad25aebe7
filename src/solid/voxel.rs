//! Sampling an implicit model on a regular grid: the input of marching cubes and of
//! `mra solid voxelize` (a volume for the codec and upscaler).

use super::field::Node;
use crate::io::{DataKind, Raster, SampleType};
use crate::{Error, Result};
use rayon::prelude::*;

/// A model sampled on `dims` points (`x` fastest) spanning its bounds plus a margin of one
/// cell on every side, so the surface is closed inside the grid.
#[derive(Clone, Debug)]
pub struct Sampled {
    pub values: Vec<f32>,
    pub dims: [usize; 3],
    pub spacing: [f64; 3],
    pub origin: [f64; 3],
}

impl Sampled {
    /// The grid view used by [`super::mc::polygonize`].
    pub fn grid(&self) -> super::mc::Grid<'_> {
        super::mc::Grid {
            values: &self.values,
            dims: self.dims,
            spacing: self.spacing,
            origin: self.origin,
        }
    }
}

/// Largest number of samples [`sample`] accepts.
pub const MAX_SAMPLES: usize = 1 << 30;

/// Sample `F` with `n` cells along the longest side of the model's bounds (cubic cells).
pub fn sample(node: &Node, n: usize) -> Result<Sampled> {
    if n < 2 {
        return Err(Error::parameter("resolution", n, "at least 2"));
    }
    let (lo, hi) = node
        .bounds()
        .ok_or_else(|| Error::format("the solid is unbounded", "a bounded solid to sample"))?;
    let ext = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
    if ext.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::format(
            "the solid's bounds are empty",
            "a non-empty solid",
        ));
    }
    let h = ext / n as f64;
    let mut dims = [0usize; 3];
    let mut origin = [0.0; 3];
    for i in 0..3 {
        let cells = ((hi[i] - lo[i]) / h).ceil() as usize + 2;
        dims[i] = cells + 1;
        let centre = 0.5 * (lo[i] + hi[i]);
        origin[i] = centre - 0.5 * cells as f64 * h;
    }
    let total = dims[0] * dims[1] * dims[2];
    if total > MAX_SAMPLES {
        return Err(Error::LimitsExceeded {
            what: "grid samples",
            requested: total as u64,
            limit: MAX_SAMPLES as u64,
        });
    }
    let [nx, ny, _] = dims;
    let mut values = vec![0f32; total];
    values
        .par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, plane)| {
            let z = origin[2] + k as f64 * h;
            for j in 0..ny {
                let y = origin[1] + j as f64 * h;
                for i in 0..nx {
                    let x = origin[0] + i as f64 * h;
                    plane[j * nx + i] = node.eval([x, y, z]) as f32;
                }
            }
        });
    Ok(Sampled {
        values,
        dims,
        spacing: [h; 3],
        origin,
    })
}

/// What [`to_raster`] stores per voxel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelMode {
    /// `F` as float32.
    Field,
    /// 255 inside, 0 outside, as uint8.
    Occupancy,
}

/// A volume raster (`[nz, ny, nx]`, spacing and origin in the metadata) of a sampled model.
pub fn to_raster(s: &Sampled, mode: VoxelMode) -> Result<Raster> {
    let dims = vec![s.dims[2], s.dims[1], s.dims[0]];
    let mut r = match mode {
        VoxelMode::Field => {
            Raster::from_f32(dims, 1, &s.values, SampleType::F32, DataKind::Volume)?
        }
        VoxelMode::Occupancy => {
            let occ: Vec<f32> = s
                .values
                .iter()
                .map(|&v| if v > 0.0 { 255.0 } else { 0.0 })
                .collect();
            Raster::from_f32(dims, 1, &occ, SampleType::U8, DataKind::Volume)?
        }
    };
    r.meta.spacing = Some(vec![s.spacing[2], s.spacing[1], s.spacing[0]]);
    r.meta.origin = Some(s.origin.to_vec());
    Ok(r)
}
