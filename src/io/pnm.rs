//! Netpbm PGM / PPM / PAM through the `image` crate, 8- and 16-bit. The written
//! subtype follows the channels: PGM for gray, PPM for RGB, PAM otherwise.

use std::io::Write;
use std::path::Path;

use image::codecs::pnm::{PnmEncoder, PnmSubtype, SampleEncoding};
use image::{ExtendedColorType, ImageEncoder, ImageFormat};

use super::Raster;
use crate::Result;

/// Read a PNM file.
pub fn read(path: &Path) -> Result<Raster> {
    super::png::decode_with_image(path, ImageFormat::Pnm)
}

/// Write a 2-D u8/u16 raster as binary PGM (gray), PPM (RGB) or PAM (others).
pub fn write<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    let (ct, bytes) = super::png::color_type(r, "PNM output")?;
    let enc = PnmEncoder::new(w);
    let enc = match ct {
        ExtendedColorType::L8 | ExtendedColorType::L16 => {
            enc.with_subtype(PnmSubtype::Graymap(SampleEncoding::Binary))
        }
        ExtendedColorType::Rgb8 | ExtendedColorType::Rgb16 => {
            enc.with_subtype(PnmSubtype::Pixmap(SampleEncoding::Binary))
        }
        _ => enc,
    };
    enc.write_image(&bytes, r.width() as u32, r.height() as u32, ct)
        .map_err(|e| super::png::image_error(e, ImageFormat::Pnm))
}
