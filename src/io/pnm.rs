//! Netpbm PGM / PPM / PAM, 8- and 16-bit: read through the `image` crate, written here
//! (a text header and big-endian samples). The written subtype follows the channels:
//! PGM for gray, PPM for RGB, PAM otherwise.

use std::io::Write;
use std::path::Path;

use image::ImageFormat;

use super::{Raster, SampleType};
use crate::Result;

/// Read a PNM file.
pub fn read(path: &Path) -> Result<Raster> {
    super::png::decode_with_image(path, ImageFormat::Pnm)
}

/// Write a 2-D u8/u16 raster as binary PGM (`P5`, gray), PPM (`P6`, RGB) or PAM (`P7`,
/// gray+alpha or RGBA); 16-bit samples big-endian with maxval 65535, as Netpbm defines.
pub fn write<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    // validates the layout (2-D, u8/u16, 1–4 channels)
    super::png::color_type(r, "PNM output")?;
    let maxval = if r.sample_type() == SampleType::U8 {
        255
    } else {
        65535
    };
    let (wd, ht) = (r.width(), r.height());
    let header =
        match r.channels {
            1 => format!("P5\n{wd} {ht}\n{maxval}\n"),
            3 => format!("P6\n{wd} {ht}\n{maxval}\n"),
            c => {
                format!(
            "P7\nWIDTH {wd}\nHEIGHT {ht}\nDEPTH {c}\nMAXVAL {maxval}\nTUPLTYPE {}\nENDHDR\n",
            if c == 2 { "GRAYSCALE_ALPHA" } else { "RGB_ALPHA" }
        )
            }
        };
    w.write_all(header.as_bytes())?;
    w.write_all(&super::bytes::encode(&r.samples, true))?;
    Ok(())
}
