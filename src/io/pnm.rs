//! Netpbm PGM / PPM / PAM, 8- and 16-bit: read through the `image` crate, written here
//! (a text header and big-endian samples). The written subtype follows the channels:
//! PGM for gray, PPM for RGB, PAM otherwise.

use std::io::Write;
use std::path::Path;

use image::ImageFormat;

use super::slab::Shape;
use super::{Raster, SampleType, Samples};
use crate::{Error, Result};

/// Read a PNM file.
pub fn read(path: &Path) -> Result<Raster> {
    super::png::decode_with_image(path, ImageFormat::Pnm)
}

/// The header of a PGM (`P5`, gray), PPM (`P6`, RGB) or PAM (`P7`, gray+alpha or RGBA)
/// of a 2-D image of `shape`: u8 or u16 samples of 1–4 channels, else an error naming
/// what PNM takes (the same check as the whole writer's).
fn header(shape: &Shape) -> Result<String> {
    let (ty, c) = (shape.sample_type, shape.channels);
    if shape.dims.len() != 2 {
        return Err(Error::Unsupported {
            what: "PNM output",
            value: format!(
                "{}-D data (write volumes as .nrrd, .nii or .tif)",
                shape.dims.len()
            ),
        });
    }
    if !matches!(ty, SampleType::U8 | SampleType::U16) || !(1..=4).contains(&c) {
        return Err(Error::Unsupported {
            what: "PNM output",
            value: format!(
                "{c} channels of {ty} (u8 or u16 with 1-4 channels; use .tif, .exr or .nrrd)"
            ),
        });
    }
    let maxval = if ty == SampleType::U8 { 255 } else { 65535 };
    let (wd, ht) = (shape.dims[1], shape.dims[0]);
    Ok(match c {
        1 => format!("P5\n{wd} {ht}\n{maxval}\n"),
        3 => format!("P6\n{wd} {ht}\n{maxval}\n"),
        c => format!(
            "P7\nWIDTH {wd}\nHEIGHT {ht}\nDEPTH {c}\nMAXVAL {maxval}\nTUPLTYPE {}\nENDHDR\n",
            if c == 2 {
                "GRAYSCALE_ALPHA"
            } else {
                "RGB_ALPHA"
            }
        ),
    })
}

/// Samples after the header: 8-bit ones as their own bytes, wider ones big-endian a
/// piece at a time (no copy of the whole slab).
fn samples<W: Write>(w: &mut W, s: &Samples) -> Result<()> {
    if let Samples::U8(v) = s {
        w.write_all(v)?;
        return Ok(());
    }
    const PIECE: usize = 1 << 16;
    let (n, mut buf) = (s.len(), Vec::new());
    for at in (0..n).step_by(PIECE) {
        super::bytes::encode_into(s, at..(at + PIECE).min(n), true, &mut buf);
        w.write_all(&buf)?;
    }
    Ok(())
}

/// Write a 2-D u8/u16 raster as binary PGM (`P5`, gray), PPM (`P6`, RGB) or PAM (`P7`,
/// gray+alpha or RGBA); 16-bit samples big-endian with maxval 65535, as Netpbm defines.
pub fn write<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    // validates the layout (2-D, u8/u16, 1–4 channels)
    super::png::color_type(r, "PNM output")?;
    w.write_all(header(&Shape::of(r))?.as_bytes())?;
    samples(w, &r.samples)
}

/// [`write`] of an image handed over in slabs of rows (`next` gives them in order,
/// `None` at the end): the header from `shape`, then each slab's samples as they come.
/// A slab of another sample type is an error; the bytes are those of [`write`].
pub fn write_slabs<W: Write>(
    w: &mut W,
    shape: &Shape,
    next: &mut dyn FnMut() -> Result<Option<Samples>>,
) -> Result<()> {
    w.write_all(header(shape)?.as_bytes())?;
    let row = shape.dims[1] * shape.channels;
    let mut left = shape.dims[0] * row;
    while let Some(s) = next()? {
        if s.sample_type() != shape.sample_type || s.len() % row.max(1) != 0 || s.len() > left {
            return Err(Error::parameter(
                "slab",
                s.len(),
                "whole rows of the image's sample type, no more than it holds",
            ));
        }
        left -= s.len();
        samples(w, &s)?;
    }
    if left != 0 {
        return Err(Error::parameter(
            "samples missing",
            left,
            "every row of the image",
        ));
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
