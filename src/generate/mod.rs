//! Deterministic generators of test data: the embedded default data and the core test
//! data. Every generator returns values in [0, 1] ([`Field`]); [`Field::to_raster`]
//! scales them to a sample type (integers: × type max, rounded; floats unchanged).
//! The same kind, size and seed give the same samples on every platform (integer
//! random numbers from SplitMix64, no platform maths beyond IEEE `+ − × ÷ sqrt`, and
//! `sin`/`cos` only in the zone plate).
//!
//! ```text
//! images.rs   zone plate, gradients, edges, text-like strokes, noise
//! phantom.rs  3D Shepp–Logan-style CT phantom (ellipsoids)
//! terrain.rs  fractal terrain by diamond-square
//! rng.rs      SplitMix64
//! ```

use crate::io::{DataKind, Raster, SampleType, Samples};
use crate::{Error, Result};

pub mod images;
pub mod phantom;
pub mod rng;
pub mod terrain;

/// Generated values in [0, 1] over a row-major grid, channels interleaved last.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub dims: Vec<usize>,
    pub channels: usize,
    pub data: Vec<f64>,
    pub kind: DataKind,
}

impl Field {
    /// Scale to `ty`: integer types map [0, 1] to [0, type max] (rounded), floats keep
    /// the values.
    pub fn to_raster(&self, ty: SampleType) -> Result<Raster> {
        let scale = if ty.is_float() { 1.0 } else { ty.range().1 };
        let v: Vec<f64> = self.data.iter().map(|&x| x * scale).collect();
        Raster::new(
            self.dims.clone(),
            self.channels,
            Samples::from_f64(&v, ty),
            self.kind,
        )
    }
}

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    ZonePlate,
    Gradient,
    Edges,
    Strokes,
    Noise,
    Phantom,
    Terrain,
}

impl Kind {
    pub const ALL: [Kind; 7] = [
        Kind::ZonePlate,
        Kind::Gradient,
        Kind::Edges,
        Kind::Strokes,
        Kind::Noise,
        Kind::Phantom,
        Kind::Terrain,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kind::ZonePlate => "zone-plate",
            Kind::Gradient => "gradient",
            Kind::Edges => "edges",
            Kind::Strokes => "strokes",
            Kind::Noise => "noise",
            Kind::Phantom => "phantom",
            Kind::Terrain => "terrain",
        }
    }

    /// Default spatial dims (slowest first).
    pub fn default_dims(self) -> Vec<usize> {
        match self {
            Kind::Phantom => vec![64, 64, 64],
            Kind::Terrain => vec![257, 257],
            _ => vec![256, 256],
        }
    }

    /// Default stored type.
    pub fn default_type(self) -> SampleType {
        match self {
            Kind::Phantom | Kind::Terrain => SampleType::U16,
            _ => SampleType::U8,
        }
    }
}

/// Generate `kind` over `dims` (2-D `[H, W]`, or 3-D `[D, H, W]` for the phantom) with
/// `channels` (gradient and noise only; others are gray) from `seed`.
pub fn generate(kind: Kind, dims: &[usize], channels: usize, seed: u64) -> Result<Field> {
    let want = if kind == Kind::Phantom { 3 } else { 2 };
    if dims.len() != want || dims.iter().any(|&d| d < 2) {
        return Err(Error::parameter(
            "size",
            format!("{dims:?}"),
            if want == 3 {
                "three sides ≥ 2 for the phantom (e.g. 64 or 64x64x64)"
            } else {
                "two sides ≥ 2 (e.g. 256 or 320x200)"
            },
        ));
    }
    crate::io::bytes::sample_count(dims, channels.max(1))?;
    let (h, w) = (dims[dims.len() - 2], dims[dims.len() - 1]);
    Ok(match kind {
        Kind::ZonePlate => images::zone_plate(h, w),
        Kind::Gradient => images::gradient(h, w, channels.max(1)),
        Kind::Edges => images::edges(h, w),
        Kind::Strokes => images::strokes(h, w, seed),
        Kind::Noise => images::noise(h, w, channels.max(1), seed),
        Kind::Phantom => phantom::shepp_logan(dims[0], h, w),
        Kind::Terrain => terrain::diamond_square(h, w, seed, 0.55),
    })
}
