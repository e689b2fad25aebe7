//! The codec: raster → colour transform → pyramid (notes §9.3) → per-band dead-zone
//! quantization weighted by synthesis gain ([`crate::quantize`]) → context-modelled
//! range coding ([`crate::entropy`]) → `.mra` chunks ([`crate::format`]), and back.
//!
//! Rate modes ([`Rate`]): keep P% of details, threshold, quality, target PSNR, target
//! bits per position (a search on the step), guaranteed maximum error (lossy base plus
//! a spatial residual layer quantized with step `2E`), and lossless (integer 5/3
//! lifting, integer YCoCg-R).
//!
//! One file per job: [`Rate`] and the options in `options`; the colour transform in
//! `colour`; the pyramid and bands of a header in `plan`; the lossy transform coded at
//! a step in `lossy`; the step of each rate mode and its search in `rate`; the residual
//! layer in `max_error`; the integer transforms in [`lossless`]; voids in `voids`; the
//! chunks in `container`; [`encode`] and [`decode`] in their files; [`info`] and
//! [`frames`] beside them.

mod block_file;
mod colour;
mod container;
mod decode;
mod indexed_read;
// `mra demo`'s rows: built with the command line only
#[cfg(feature = "cli")]
pub mod demo;
mod encode;
mod frames;
mod info;
mod int_window;
pub mod layout;
mod levels;
pub mod lossless;
mod lossy;
mod max_error;
mod opened;
mod sparse_read;
pub use crate::format::meta;
mod options;
mod plan;
mod rate;
mod read;
mod reblock;
mod streamed;
mod support;
pub mod tiles;
mod voids;
mod window_decode;
mod write;

pub use crate::format::body::ChunkInfo;
pub use decode::coarse_offset;
pub use frames::frames;
pub use info::{depth_of, info, kind_name, Info};
pub use opened::Opened;
pub use options::{
    DecodeOptions, Decoded, EncodeOptions, Format, Ladder, Rate, DEFAULT_EFFORT, EFFORTS,
};
pub use rate::keep_psnr;
pub use read::{
    decode, decode_file, decode_file_slabs, decode_seek, decode_stream, header_of, header_of_file,
    SlabDecode, SlabDecoder,
};
pub use reblock::to_blocks;
pub use streamed::{decodes_streamed, encode_streamed, StreamedDecoder};
pub use tiles::{default_tile, level_extents};
pub use write::{
    default_layout, encode, encode_stream, encode_tiled, encode_tiled_view, encode_view, streams,
};
