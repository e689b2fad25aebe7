//! Terrain synthesis by example (notes §9.7.4; Brosz, Samavati & Sousa, "Terrain
//! synthesis by-example"), detail transfer for images and volumes, and hillshaded pictures.
//!
//! A heightmap is an open–open tensor-product surface, so the terrain uses the
//! *interpolating* boundary of the two-scale levels: `C = A F`, `D = B F`,
//! `F = P C + Q D` along both axes. Because `A Q = 0`, whatever details are added
//! during reconstruction, analysing the result `L` levels gives back the base exactly:
//! the base's large-scale shape is kept by construction, and the example only
//! decides *which* details are added.
//!
//! ```text
//! grid.rs      Grid: h × w × channels of f64, row-major, held as the engine's Array
//! resample.rs  Catmull–Rom resampling on affine maps (base to the output lattice)
//! spectrum.rs  radially averaged power spectra, the finest octave's slope, the gain fit
//! base_scale.rs  --base-scale S: the base reduced to 1/S of the output, finer levels synthesized
//! drainage.rs  with --base-scale: depressions breached (priority flood) so valleys drain
//! synth.rs     options, the example's pyramid, the coarse-to-fine loop, back-projection
//! options.rs   SynthOptions, Details, FinestGain
//! patches.rs   one level's patches: candidate search, sources, blended detail bands
//! finest_gain.rs  the finest level's gain g₁ fitted to the example's spectral slope
//! level_gain.rs  with --base-scale: each synthesized level's gain fitted to the example's slope
//! seams.rs     the seam ratio: second differences on patch borders against elsewhere
//! matching.rs  window descriptors (shape, slope direction, curvature) from summed-area tables
//! volume.rs    the same detail transfer for 3-D volumes (cube patches, seven bands)
//! hillshade.rs Horn slope/aspect shading with an optional hypsometric colour ramp
//! raster.rs    Raster <-> Grid with units, cell size and nodata checks
//! ```

pub mod base_scale;
// `mra demo`'s rows: built with the command line only
#[cfg(feature = "cli")]
pub mod demo;
mod drainage;
mod finest_gain;
pub mod grid;
pub mod hillshade;
mod level_gain;
pub mod matching;
mod options;
mod patches;
pub mod raster;
pub mod resample;
mod seams;
pub mod spectrum;
pub mod synth;
pub mod volume;

#[cfg(feature = "cli")]
pub use demo::demo_rows;
pub use grid::Grid;
pub use hillshade::{hillshade, Shading};
pub use synth::{highpass, reduce, synthesize, transfer, FinestGain, SynthOptions, SynthReport};
pub use volume::{transfer_volume, Volume, VolumeReport};
