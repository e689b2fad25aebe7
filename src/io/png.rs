//! PNG through the `image` crate: 8- and 16-bit gray, gray+alpha, RGB and RGBA, read
//! and written at the stored bit depth. Also holds the conversion from `image`'s
//! decoded buffers used by the JPEG and PNM readers.

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::Path;

use image::{DynamicImage, ExtendedColorType, ImageDecoder, ImageEncoder, ImageFormat};

use super::{DataKind, Raster, Samples};
use crate::{Error, Result};

/// The most decoded bytes one byte of a file can hold, by format: the bound a header's
/// declared size must meet before anything is allocated.
///
/// ```text
/// PNG   1032   deflate's largest expansion (258-byte matches coded in 2 bits)
/// PNM      8   one bit per sample (P1/P4 bitmaps) decoded to one byte
/// JPEG  4096   every 8×8 block codes at least one bit: one byte covers at most 512 pixels
///              (1536 bytes of RGB); the margin allows for arithmetic coding
/// ```
fn max_expansion(format: ImageFormat) -> u64 {
    match format {
        ImageFormat::Png => 1032,
        ImageFormat::Pnm => 8,
        _ => 4096,
    }
}

/// What the header of an `image`-read file declares, read without decoding the pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    pub width: u32,
    pub height: u32,
    pub channels: u8,
    /// Bytes of the decoded pixels.
    pub decoded_bytes: u64,
}

/// Open `path` as `format` and read its header; the declared size is checked against the
/// file's length ([`max_expansion`]) and the memory budget ([`crate::limits`]) before the
/// decoder is returned, so no pixel buffer is sized by an unchecked header.
fn open_checked(path: &Path, format: ImageFormat) -> Result<(Header, impl ImageDecoder)> {
    let budget = crate::limits::Limits::from_env()?;
    let file = File::open(path)?;
    let len = file.metadata()?.len();
    let mut reader = image::ImageReader::with_format(BufReader::new(file), format);
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(budget.max_bytes);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(|e| image_error(e, format))?;
    let (width, height) = decoder.dimensions();
    let header = Header {
        width,
        height,
        channels: decoder.color_type().channel_count(),
        decoded_bytes: decoder.total_bytes(),
    };
    let most = len.saturating_mul(max_expansion(format)).max(1 << 16);
    if header.decoded_bytes > most {
        return Err(Error::format(
            format!(
                "header declares {width}×{height} pixels ({} bytes decoded) but a {len}-byte {format:?} file holds at most {most}",
                header.decoded_bytes
            ),
            "a size the file can hold",
        ));
    }
    budget.check(
        "decoded image bytes (memory budget MRA_MAX_BYTES)",
        header.decoded_bytes,
    )?;
    if format == ImageFormat::Jpeg {
        jpeg_end_check(path, len)?;
    }
    Ok((header, decoder))
}

/// A JPEG ends with its end-of-image marker `FF D9`; a file cut short has none in its last
/// kilobyte (entropy-coded data never holds `FF D9`, it stuffs `FF` as `FF 00`), and the
/// decoder would fill the missing blocks with grey instead of failing.
fn jpeg_end_check(path: &Path, len: u64) -> Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let tail = len.min(1024);
    let mut f = File::open(path)?;
    f.seek(SeekFrom::Start(len - tail))?;
    let mut buf = Vec::with_capacity(tail as usize);
    f.take(tail).read_to_end(&mut buf)?;
    if buf.windows(2).any(|w| w == [0xFF, 0xD9]) {
        Ok(())
    } else {
        Err(Error::format(
            format!("JPEG data ends after {len} bytes without an end-of-image marker"),
            "a complete JPEG file ending with FF D9",
        ))
    }
}

/// The header of a PNG, JPEG or PNM file (size and channels), checked as for a read,
/// without decoding the pixels.
pub fn read_header(path: &Path, format: ImageFormat) -> Result<Header> {
    open_checked(path, format).map(|(h, _)| h)
}

/// Decode `path` as `format` with `image`, after [`open_checked`].
pub(super) fn decode_with_image(path: &Path, format: ImageFormat) -> Result<Raster> {
    let (_, decoder) = open_checked(path, format)?;
    let img = DynamicImage::from_decoder(decoder).map_err(|e| image_error(e, format))?;
    from_dynamic(img)
}

/// Map an `image` error to ours, naming the format.
pub(super) fn image_error(e: image::ImageError, format: ImageFormat) -> Error {
    match e {
        image::ImageError::IoError(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::Io(io)
        }
        image::ImageError::Limits(l) => Error::Unsupported {
            what: "image size",
            value: l.to_string(),
        },
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
