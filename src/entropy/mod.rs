//! Entropy coding of quantized coefficients: an adaptive binary range coder
//! ([`range`]) driven by context models (notes §9.3.2: after quantization most details
//! are zero, and zeros cluster where the picture is smooth, at every scale).
//!
//! [`band`] is the coefficient coding of format 2 (two-rate models, a wider
//! neighbourhood, rate–distortion optimised quantization in the encoder), cut into
//! independent code-blocks in format 3 ([`codeblocks`]); [`v1`] reads
//! and writes format 1. Normative: formats/MRA.md §6 and §9.

pub mod band;
pub mod block;
pub mod codeblocks;
mod golomb;
pub mod range;
pub mod v1;
mod walk;

/// Test data shared by the coders' and the codec's tests.
#[cfg(test)]
pub(crate) use walk::testing;

pub use v1::{decode_band, encode_band};

/// The parent band of a detail band: its values and extents (same number of axes).
#[derive(Clone, Copy, Debug)]
pub struct Parent<'a> {
    pub data: &'a [i64],
    pub dims: &'a [usize],
}

/// How a band is coded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BandKind {
    /// The coarsest block: median prediction, then the residuals.
    Coarse,
    /// A detail band.
    Detail,
}
