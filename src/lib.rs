//! # mra — multiresolution analysis for images, volumes, heightmaps and curves
//!
//! One idea runs through the crate: a banded two-scale operator (the notes' A, B, P, Q,
//! each written as start block + regular rows + end block) applied along any axis of any
//! array. On it stand the codec, the upscaler, terrain synthesis and the course module.
//!
//! ```text
//! src/error.rs        Error with kind(): Parameter, Format, Unsupported, LimitsExceeded, Io
//! src/scheme/         1D schemes (Haar, Chaikin, cubic B-spline), boundary modes, subdivision
//! src/tensor/         N-d arrays, transforms along any axis, pyramids; par.rs holds the rayon code
//! src/io/             images, volumes, heightmaps, point lists (one file per format)
//! src/metrics.rs      MSE, PSNR, SSIM
//! src/curve/          Bézier, B-spline (de Boor), NURBS, knot insertion
//! src/surface/        patches, Coons, revolution, sweep, blends
//! src/mesh/           half-edge meshes, I/O, topology, subdivision surfaces
//! src/solid/          implicit solids, CSG, ray casting, polygonisation
//! src/cli/            the `mra` command line, a thin shell over the above
//! src/serve/          `mra serve`: IIIF Image API 3.0 and a deep-zoom viewer (feature `serve`)
//! ```
//!
//! Data flows one way: read → array → transform → (quantize → code → container) → back.

#[cfg(feature = "cli")]
pub mod cli;
pub mod codec;
pub mod curve;
pub mod demo;
pub mod denoise;
pub mod entropy;
pub mod error;
pub mod format;
pub mod fsutil;
pub mod generate;
pub mod io;
// the kernels are the tensor engine's inner loops: public only to the tests and benches
// (feature `testing`), which check every CPU level's build against the plain loops
#[cfg(feature = "testing")]
pub mod kernel;
#[cfg(not(feature = "testing"))]
mod kernel;
pub mod limits;
#[cfg(feature = "geometry")]
pub mod mesh;
pub mod metrics;
pub mod points;
pub mod progress;
pub mod quantize;
pub mod scheme;
#[cfg(feature = "serve")]
pub mod serve;
#[cfg(feature = "geometry")]
pub mod solid;
pub mod style;
#[cfg(feature = "geometry")]
pub mod surface;
pub mod tensor;
pub mod terrain;
pub mod tuning;
pub mod upscale;

pub use error::{Error, ErrorKind, Result};
