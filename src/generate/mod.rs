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
use crate::tensor::Array;
use crate::{Error, Result};

pub mod images;
pub mod phantom;
pub mod rng;
pub mod terrain;

/// Generated values in [0, 1]: the engine's array ([`Array`]) of shape `dims` then
/// `channels` (the last axis, also when 1: channels interleaved last), and what the
/// samples are.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub values: Array<f64>,
    pub kind: DataKind,
}

impl Field {
    /// `data` (row-major, channels last) over `dims` × `channels`; every size at least 1
    /// and `data` as long as their product (the generators' own sizes).
    pub(crate) fn new(dims: &[usize], channels: usize, data: Vec<f64>, kind: DataKind) -> Field {
        let shape: Vec<usize> = dims.iter().copied().chain([channels]).collect();
        let values = Array::from_shape_vec(&shape, data)
            .expect("a generator makes a value per sample of its sizes");
        Field { values, kind }
    }

    /// Spatial extent, slowest axis first: `[H, W]` or `[D, H, W]`.
    pub fn dims(&self) -> &[usize] {
        let s = self.values.shape();
        &s[..s.len() - 1]
    }

    /// Values per position.
    pub fn channels(&self) -> usize {
        self.values.shape()[self.values.ndim() - 1]
    }

    /// The values, row-major, channels last.
    pub fn data(&self) -> &[f64] {
        self.values.data()
    }

    /// Scale to `ty`: integer types map [0, 1] to [0, type max] (rounded), floats keep
    /// the values.
    pub fn to_raster(&self, ty: SampleType) -> Result<Raster> {
        let scale = if ty.is_float() { 1.0 } else { ty.range().1 };
        let v: Vec<f64> = self.data().iter().map(|&x| x * scale).collect();
        Raster::new(
            self.dims().to_vec(),
            self.channels(),
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
    if channels == 0 {
        return Err(Error::parameter("channels", channels, "at least 1"));
    }
    crate::io::bytes::sample_count(dims, channels)?;
    let (h, w) = (dims[dims.len() - 2], dims[dims.len() - 1]);
    Ok(match kind {
        Kind::ZonePlate => images::zone_plate(h, w),
        Kind::Gradient => images::gradient(h, w, channels),
        Kind::Edges => images::edges(h, w),
        Kind::Strokes => images::strokes(h, w, seed),
        Kind::Noise => images::noise(h, w, channels, seed),
        Kind::Phantom => phantom::shepp_logan(dims[0], h, w),
        Kind::Terrain => terrain::diamond_square(h, w, seed, 0.55),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_is_deterministic_and_in_unit_range() {
        for kind in Kind::ALL {
            let dims = if kind == Kind::Phantom {
                vec![9, 10, 11]
            } else {
                vec![33, 40]
            };
            let a = generate(kind, &dims, 1, 5).unwrap();
            let b = generate(kind, &dims, 1, 5).unwrap();
            assert_eq!(a, b, "{}", kind.name());
            assert_eq!(a.data().len(), dims.iter().product::<usize>());
            assert!(
                a.data().iter().all(|v| (0.0..=1.0).contains(v)),
                "{}",
                kind.name()
            );
        }
    }

    #[test]
    fn seeds_change_the_random_kinds() {
        for kind in [Kind::Strokes, Kind::Noise, Kind::Terrain] {
            let a = generate(kind, &[64, 64], 1, 1).unwrap();
            let b = generate(kind, &[64, 64], 1, 2).unwrap();
            assert_ne!(a.data(), b.data(), "{}", kind.name());
        }
    }

    #[test]
    fn zone_plate_is_symmetric_with_peak_at_centre() {
        let f = images::zone_plate(31, 31);
        let at = |y: usize, x: usize| f.data()[y * 31 + x];
        assert!((at(15, 15) - 1.0).abs() < 1e-12);
        for y in 0..31 {
            for x in 0..31 {
                assert!((at(y, x) - at(30 - y, x)).abs() < 1e-12);
                assert!((at(y, x) - at(y, 30 - x)).abs() < 1e-12);
                assert!((at(y, x) - at(x, y)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn gradient_ramps_span_zero_to_one() {
        let f = images::gradient(5, 9, 3);
        assert_eq!(f.data()[0..3], [0.0, 0.0, 0.0]);
        let last = f.data().len() - 3;
        assert_eq!(f.data()[last..], [1.0, 1.0, 1.0]);
        // channel 0 depends on x only
        assert_eq!(f.data()[(2 * 9 + 4) * 3], 0.5);
    }

    #[test]
    fn phantom_has_air_skull_and_brain() {
        let n = 33;
        let f = phantom::shepp_logan(n, n, n);
        let at = |z: usize, y: usize, x: usize| f.data()[(z * n + y) * n + x];
        assert_eq!(at(0, 0, 0), 0.0, "corner is air");
        assert!((at(16, 16, 16) - 0.2).abs() < 1e-12, "centre is brain");
        assert!(f.data().contains(&1.0), "skull");
        let int = f.to_raster(SampleType::U16).unwrap();
        assert_eq!(int.samples.min_max(), Some((0.0, 65535.0)));
    }

    #[test]
    fn terrain_is_normalised_and_rough() {
        let f = terrain::diamond_square(65, 65, 3, 0.55);
        let lo = f.data().iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = f.data().iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        assert_eq!((lo, hi), (0.0, 1.0));
        // neighbours differ less than far-apart samples on average (spatial correlation)
        let near: f64 = (0..64)
            .map(|x| (f.data()[x] - f.data()[x + 1]).abs())
            .sum::<f64>()
            / 64.0;
        let far: f64 = (0..32)
            .map(|x| (f.data()[x] - f.data()[x + 32]).abs())
            .sum::<f64>()
            / 32.0;
        assert!(near < far, "near {near} far {far}");
    }

    #[test]
    fn bad_sizes_are_parameter_errors() {
        assert!(generate(Kind::Phantom, &[8, 8], 1, 1).is_err());
        assert!(generate(Kind::ZonePlate, &[1, 8], 1, 1).is_err());
        assert!(generate(Kind::Noise, &[1 << 20, 1 << 20], 64, 1).is_err());
    }
}
