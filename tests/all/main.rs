//! The integration tests, one module per area, linked into a single test binary: one
//! link of the library instead of one per file (`cargo test --release --test all <filter>`
//! runs a part, e.g. `cli::` or `codec::`).

mod common;

mod architecture;
mod array;
mod block_coder;
mod cli;
mod cli_words;
mod codeblocks;
mod codeblocks_default;
mod codec;
mod codec_bpp;
mod codec_rate;
mod container;
mod curve;
mod effort;
mod filters;
mod format_spec;
mod ht_coder;
mod hyperpatch;
mod inputs_outputs;
mod io;
mod kernel_tables;
mod level_blocks;
mod library_rules;
mod mesh;
mod metadata;
mod metrics;
mod nodata;
mod rans_coder;
mod raster_view;
mod region;
mod robust;
mod scheme;
mod serve;
mod simd_parity;
mod solid;
mod solid_cli;
mod stdio;
mod stream;
mod streamed;
mod streamed_float;
mod streamed_lossless;
mod streamed_max_error;
mod subdivide;
mod surface;
mod tensor;
mod terrain;
mod terrain_landforms;
mod tiles;
mod tiles_stream;
mod upscale;
mod upscale_edges;
mod upscale_refine;
