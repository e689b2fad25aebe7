//! JPEG, read only, through the `image` crate (8-bit gray or RGB).

use std::path::Path;

use super::Raster;
use crate::Result;

/// Read a JPEG file.
pub fn read(path: &Path) -> Result<Raster> {
    super::png::decode_with_image(path, image::ImageFormat::Jpeg)
}
