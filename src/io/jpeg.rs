//! JPEG through the `image` crate: read 8-bit gray or RGB, write baseline JPEG.

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

/// Quality of written JPEG files unless told (`mra convert --quality`).
pub const DEFAULT_QUALITY: u8 = 90;

/// Write an 8-bit gray or RGB image as baseline JPEG at `quality` (1–100, libjpeg's
/// scale). Other sample types and channel counts are refused (JPEG holds 8-bit gray or
/// RGB only): convert with `--dtype-out u8` first.
pub fn write<W: std::io::Write>(w: &mut W, r: &Raster, quality: u8) -> Result<()> {
    use image::ExtendedColorType as C;
    if !(1..=100).contains(&quality) {
        return Err(crate::Error::parameter("JPEG quality", quality, "1 to 100"));
    }
    let (ct, bytes) = super::png::color_type(r, "JPEG output")?;
    if !matches!(ct, C::L8 | C::Rgb8) {
        return Err(crate::Error::Unsupported {
            what: "JPEG output",
            value: format!(
                "{} channel(s) of {} (expected 8-bit gray or RGB)",
                r.channels,
                r.sample_type().name()
            ),
        });
    }
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(w, quality);
    image::ImageEncoder::write_image(enc, &bytes, r.width() as u32, r.height() as u32, ct)
        .map_err(|e| super::png::image_error(e, image::ImageFormat::Jpeg))
}
