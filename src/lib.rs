//! # mra — multiresolution analysis for images, volumes, heightmaps and curves
//!
//! One idea runs through the crate: a banded two-scale operator (the notes' A, B, P, Q,
//! each written as start block + regular rows + end block) applied along any axis of any
//! array. On it stand the codec, the upscaler, terrain synthesis and the course module.
//!
//! The module map, lowest layer first. A module may use the modules of a lower layer, and
//! those of its own layer only where `tests/architecture.rs` lists the pair; the test reads
//! the layers from this table and checks it against `src/`.
//!
//! ```text
//! layer  module            job
//! 0      src/error.rs      Error with kind(): Parameter, Format, Unsupported, LimitsExceeded, Io
//! 0      src/fsutil.rs     temporary outputs renamed into place, removed on failure or signal
//! 0      src/tuning.rs     every environment variable and tuning constant, read in one place
//! 0      src/progress.rs   progress reports of long work
//! 0      src/limits.rs     the memory budget a declared size must fit before allocation
//! 1      src/scheme/       1D schemes (Haar, Chaikin, cubic B-spline, CDF), boundary modes
//! 1      src/kernel/       row kernels: scalar, AVX2, AVX-512, one table chosen per plan
//! 2      src/tensor/       N-d arrays, transforms along any axis, pyramids, the rayon helpers
//! 3      src/io/           images, volumes, heightmaps, point lists (one file per format)
//! 3      src/metrics.rs    MSE, PSNR, SSIM
//! 3      src/generate/     the test rasters and volumes of `mra generate`
//! 3      src/demo.rs       the demo table's rows and the generated data they run on
//! 4      src/format/       the .mra file grammar: versions, chunk tags, payload parsers, CRCs
//! 5      src/quantize/     quantizers and rate–distortion choices
//! 5      src/entropy/      the coefficient coders
//! 5      src/codec/        encode and decode of .mra files (one file per job)
//! 6      src/upscale/      upscaling by the pyramid's details
//! 6      src/terrain/      terrain synthesis by example, rendering
//! 6      src/denoise.rs    wavelet denoising
//! 6      src/style.rs      curve style transfer
//! 6      src/curve/        Bézier, B-spline (de Boor), NURBS, knot insertion
//! 6      src/surface/      patches, Coons, revolution, sweep, blends
//! 6      src/mesh/         half-edge meshes, I/O, topology, subdivision surfaces
//! 6      src/solid/        implicit solids, CSG, ray casting, polygonisation
//! 6      src/points.rs     point lists as text (one point per line)
//! 7      src/serve/        `mra serve`: IIIF Image API 3.0 and a deep-zoom viewer (feature `serve`)
//! 8      src/cli/          the `mra` command line, a thin shell over the above
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

pub use error::{Error, ErrorKind, FormatError, Result};
