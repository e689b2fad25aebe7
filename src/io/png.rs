//! PNG through the `image` crate: 8- and 16-bit gray, gray+alpha, RGB and RGBA, read
//! and written at the stored bit depth. Also holds the conversion from `image`'s
//! decoded buffers used by the JPEG and PNM readers.

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::Path;

use image::{DynamicImage, ExtendedColorType, ImageEncoder, ImageFormat};

use super::{DataKind, Raster, Samples};
use crate::{Error, Result};

/// Decode `path` as `format` with `image`, allowing up to 2^33 bytes of pixels.
pub(super) fn decode_with_image(path: &Path, format: ImageFormat) -> Result<Raster> {
    let file = BufReader::new(File::open(path)?);
    let mut reader = image::ImageReader::with_format(file, format);
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(1 << 33);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| image_error(e, format))?;
    from_dynamic(img)
}

/// Map an `image` error to ours, naming the format.
pub(super) fn image_error(e: image::ImageError, format: ImageFormat) -> Error {
    match e {
        image::ImageError::IoError(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::Io(io)
        }
        image::ImageError::Limits(l) => Error::LimitsExceeded {
            what: "decoded image size",
            requested: 0,
            limit: 1 << 33,
        }
        .with_note(l.to_string()),
        image::ImageError::Unsupported(u) => Error::Unsupported {
            what: "image feature",
            value: u.to_string(),
        },
        other => Error::format(
            format!("invalid {format:?} data: {other}"),
            "a complete, valid file",
        ),
    }
}

trait WithNote {
    fn with_note(self, note: String) -> Error;
}
impl WithNote for Error {
    fn with_note(self, note: String) -> Error {
        match self {
            Error::LimitsExceeded { .. } => Error::Unsupported {
                what: "image size",
                value: note,
            },
            e => e,
        }
    }
}

/// A decoded `image` buffer as a raster (2-D, channels interleaved, exact type).
pub(super) fn from_dynamic(img: DynamicImage) -> Result<Raster> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let (channels, samples) = match img {
        DynamicImage::ImageLuma8(b) => (1, Samples::U8(b.into_raw())),
        DynamicImage::ImageLumaA8(b) => (2, Samples::U8(b.into_raw())),
        DynamicImage::ImageRgb8(b) => (3, Samples::U8(b.into_raw())),
        DynamicImage::ImageRgba8(b) => (4, Samples::U8(b.into_raw())),
        DynamicImage::ImageLuma16(b) => (1, Samples::U16(b.into_raw())),
        DynamicImage::ImageLumaA16(b) => (2, Samples::U16(b.into_raw())),
        DynamicImage::ImageRgb16(b) => (3, Samples::U16(b.into_raw())),
        DynamicImage::ImageRgba16(b) => (4, Samples::U16(b.into_raw())),
        DynamicImage::ImageRgb32F(b) => (3, Samples::F32(b.into_raw())),
        DynamicImage::ImageRgba32F(b) => (4, Samples::F32(b.into_raw())),
        other => {
            return Err(Error::Unsupported {
                what: "pixel layout",
                value: format!("{:?}", other.color()),
            })
        }
    };
    Raster::new(vec![h, w], channels, samples, DataKind::Image)
}

/// The `image` colour type for a 2-D u8/u16 raster with 1–4 channels.
pub(super) fn color_type(r: &Raster, what: &'static str) -> Result<(ExtendedColorType, Vec<u8>)> {
    if r.dims.len() != 2 {
        return Err(Error::Unsupported {
            what,
            value: format!(
                "{}-D data (write volumes as .nrrd, .nii or .tif)",
                r.dims.len()
            ),
        });
    }
    let ct = match (&r.samples, r.channels) {
        (Samples::U8(_), 1) => ExtendedColorType::L8,
        (Samples::U8(_), 2) => ExtendedColorType::La8,
        (Samples::U8(_), 3) => ExtendedColorType::Rgb8,
        (Samples::U8(_), 4) => ExtendedColorType::Rgba8,
        (Samples::U16(_), 1) => ExtendedColorType::L16,
        (Samples::U16(_), 2) => ExtendedColorType::La16,
        (Samples::U16(_), 3) => ExtendedColorType::Rgb16,
        (Samples::U16(_), 4) => ExtendedColorType::Rgba16,
        _ => {
            return Err(Error::Unsupported {
                what,
                value: format!(
                    "{} channels of {} (u8 or u16 with 1-4 channels; use .tif, .exr or .nrrd)",
                    r.channels,
                    r.sample_type()
                ),
            })
        }
    };
    let bytes = match &r.samples {
        Samples::U8(v) => v.clone(),
        Samples::U16(v) => v.iter().flat_map(|x| x.to_ne_bytes()).collect(),
        _ => unreachable!("checked above"),
    };
    Ok((ct, bytes))
}

/// Read a PNG file.
pub fn read(path: &Path) -> Result<Raster> {
    decode_with_image(path, ImageFormat::Png)
}

/// Write a 2-D u8/u16 raster with 1–4 channels as PNG.
pub fn write<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    let (ct, bytes) = color_type(r, "PNG output")?;
    let enc = image::codecs::png::PngEncoder::new(w);
    enc.write_image(&bytes, r.width() as u32, r.height() as u32, ct)
        .map_err(|e| image_error(e, ImageFormat::Png))
}
