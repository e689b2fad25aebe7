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
    // 8-bit samples are their own bytes; wider ones go big-endian a piece at a time (no
    // copy of the whole raster)
    if let super::Samples::U8(v) = &r.samples {
        w.write_all(v)?;
        return Ok(());
    }
    const PIECE: usize = 1 << 16;
    let (n, mut buf) = (r.samples.len(), Vec::new());
    for at in (0..n).step_by(PIECE) {
        super::bytes::encode_into(&r.samples, at..(at + PIECE).min(n), true, &mut buf);
        w.write_all(&buf)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{DataKind, Samples};

    /// The samples follow the header as they are (8-bit) or big-endian (16-bit), also
    /// past the first piece of 2^16 samples.
    #[test]
    fn samples_follow_the_header_big_endian() {
        let (w, h, c) = (200usize, 150usize, 3usize);
        let n = w * h * c;
        let wide: Vec<u16> = (0..n)
            .map(|i| (i as u32).wrapping_mul(40_503) as u16)
            .collect();
        let narrow: Vec<u8> = wide.iter().map(|&x| (x >> 5) as u8).collect();
        for (samples, maxval) in [
            (Samples::U16(wide.clone()), 65535),
            (Samples::U8(narrow), 255),
        ] {
            let want: Vec<u8> = match &samples {
                Samples::U16(v) => v.iter().flat_map(|x| x.to_be_bytes()).collect(),
                Samples::U8(v) => v.clone(),
                _ => unreachable!(),
            };
            let r = Raster::new(vec![h, w], c, samples, DataKind::Image).unwrap();
            let mut out = Vec::new();
            write(&mut out, &r).unwrap();
            let head = format!("P6\n{w} {h}\n{maxval}\n");
            assert_eq!(&out[..head.len()], head.as_bytes());
            assert_eq!(out[head.len()..], want[..], "maxval {maxval}");
        }
    }
}
