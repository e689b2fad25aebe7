//! Surfaces of the course module (notes ch. 5).
//!
//! ```text
//! raster.rs   tiny RGB canvas and PNG encoding for previews
//! ```

pub mod raster;
