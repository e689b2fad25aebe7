//! Code lengths of the HT-style coder's default codes ([`super::ht::Tables::standard`]):
//! placeholder flat codes until `cargo bench --bench coder -- train-ht` writes the
//! trained ones.

/// The joint (ternary) quad alphabet.
pub const JOINT: bool = true;

/// Quad code lengths per class, then the run context.
#[rustfmt::skip]
pub const QUAD: [[u8; 81]; 13] = [[7; 81]; 13];

/// Magnitude code lengths per class.
#[rustfmt::skip]
pub const MAGNITUDE: [[u8; 16]; 26] = [[4; 16]; 26];
