//! JPEG, read only, through the `image` crate (8-bit gray or RGB).

use std::path::Path;

use super::Raster;
use crate::Result;

/// Read a JPEG file.
pub fn read(path: &Path) -> Result<Raster> {
    super::png::decode_with_image(path, image::ImageFormat::Jpeg)
}

/// The size and channels a JPEG's frame header declares, checked against the file's
/// length and the memory budget, without decoding the image.
pub fn read_header(path: &Path) -> Result<super::png::Header> {
    super::png::read_header(path, image::ImageFormat::Jpeg)
}
