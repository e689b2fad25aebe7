//! TIFF through the `tiff` crate: every integer and float sample type, gray / RGB /
//! RGBA, a stack of equal pages as a volume (ImageJ hyperstacks included, with their
//! `spacing=` and `unit=`), GeoTIFF tags kept verbatim and rewritten on output.
//!
//! mra's own metadata travels in a private ASCII tag ([`MRA_TAG`], 65000) as
//! `mra.KEY=VALUE` lines (`mra.spacing=3,2.1484375,2.1484375`, `mra.units=mm`,
//! `mra.nodata=-32768`, and every key of [`Metadata::extra`](super::Metadata) as
//! `mra.extra.KEY=VALUE`), so that ImageDescription stays exactly the text it was (a
//! tifffile JSON or an ImageJ header remains readable by those tools). `mra.` lines in
//! an ImageDescription (older mra output) are still read.

use std::fs::File;
use std::io::{BufReader, Seek, Write};
use std::path::Path;

use tiff::decoder::{ifd::Value, Decoder, DecodingResult, Limits};
use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;
use tiff::ColorType;

use super::{DataKind, GeoTag, GeoValue, Metadata, Raster, Samples, GEOTIFF_TAGS};
use crate::{Error, Result};

/// The private tag holding mra's `mra.KEY=VALUE` lines (in the reusable private range
/// 65000–65535 of TIFF 6.0).
pub const MRA_TAG: u16 = 65000;

/// Deflate output can be at most ~1032× smaller than its input: a declared image larger
/// than this multiple of the file size cannot be real.
const MAX_RATIO: u64 = 1100;

fn tiff_error(e: tiff::TiffError) -> Error {
    match e {
        tiff::TiffError::IoError(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::Io(io)
        }
        tiff::TiffError::IoError(_) => Error::format("TIFF data ends early", "a complete file"),
        tiff::TiffError::UnsupportedError(u) => Error::Unsupported {
            what: "TIFF feature",
            value: u.to_string(),
        },
        tiff::TiffError::LimitsExceeded => Error::LimitsExceeded {
            what: "TIFF image bytes",
            requested: 0,
            limit: 1 << 33,
        },
        other => Error::format(format!("invalid TIFF: {other}"), "a valid TIFF file"),
    }
}

fn channels_of(ct: ColorType) -> Result<usize> {
    Ok(match ct {
        ColorType::Gray(_) => 1,
        ColorType::GrayA(_) => 2,
        ColorType::RGB(_) => 3,
        ColorType::RGBA(_) => 4,
        ColorType::Multiband { num_samples, .. } => num_samples as usize,
        other => {
            return Err(Error::Unsupported {
                what: "TIFF colour type",
                value: format!("{other:?} (expected gray, gray+alpha, RGB or RGBA)"),
            })
        }
    })
}

/// Append one decoded page to the accumulated samples (same type required).
fn append(acc: &mut Option<Samples>, page: DecodingResult) -> Result<()> {
    macro_rules! push {
        ($var:ident, $v:expr) => {{
            match acc {
                None => *acc = Some(Samples::$var($v)),
                Some(Samples::$var(a)) => a.extend_from_slice(&$v),
                Some(_) => {
                    return Err(Error::Unsupported {
                        what: "TIFF stack",
                        value: "pages with different sample types".into(),
                    })
                }
            }
        }};
    }
    match page {
        DecodingResult::U8(v) => push!(U8, v),
        DecodingResult::I8(v) => push!(I8, v),
        DecodingResult::U16(v) => push!(U16, v),
        DecodingResult::I16(v) => push!(I16, v),
        DecodingResult::U32(v) => push!(U32, v),
        DecodingResult::I32(v) => push!(I32, v),
        DecodingResult::F16(v) => push!(F16, v),
        DecodingResult::F32(v) => push!(F32, v),
        DecodingResult::F64(v) => push!(F64, v),
        DecodingResult::U64(_) | DecodingResult::I64(_) => {
            return Err(Error::Unsupported {
                what: "sample type",
                value: "64-bit integer TIFF".into(),
            })
        }
    }
    Ok(())
}

fn geo_value(v: Value) -> Option<GeoValue> {
    match v {
        Value::Ascii(s) => Some(GeoValue::Ascii(s)),
        Value::Double(d) => Some(GeoValue::Doubles(vec![d])),
        Value::Short(s) => Some(GeoValue::Shorts(vec![s])),
        Value::List(items) => {
            if items.iter().all(|x| matches!(x, Value::Short(_))) {
                Some(GeoValue::Shorts(
                    items
                        .into_iter()
                        .filter_map(|x| match x {
                            Value::Short(s) => Some(s),
                            _ => None,
                        })
                        .collect(),
                ))
            } else {
                let d: Vec<f64> = items
                    .into_iter()
                    .filter_map(|x| match x {
                        Value::Double(d) => Some(d),
                        Value::Float(f) => Some(f as f64),
                        _ => None,
                    })
                    .collect();
                Some(GeoValue::Doubles(d))
            }
        }
        Value::Float(f) => Some(GeoValue::Doubles(vec![f as f64])),
        _ => None,
    }
}

fn parse_list(s: &str) -> Option<Vec<f64>> {
    s.split(',').map(|t| t.trim().parse().ok()).collect()
}

/// Fill spacing/units/nodata/extra from the description, resolution and GeoTIFF tags.
/// One `mra.KEY=VALUE` line into `meta`; false when the line is not one.
fn mra_line(meta: &mut Metadata, line: &str) -> bool {
    let Some(rest) = line.strip_prefix("mra.") else {
        return false;
    };
    if let Some((k, v)) = rest.split_once('=') {
        match k {
            "spacing" => meta.spacing = parse_list(v),
            "origin" => meta.origin = parse_list(v),
            "units" => meta.units = Some(v.to_string()),
            "nodata" => meta.nodata = v.parse().ok(),
            _ => {
                if let Some(key) = k.strip_prefix("extra.") {
                    meta.extra.insert(key.to_string(), v.to_string());
                } else if let Some(f) = k.strip_prefix("direction.") {
                    if let (Ok(f), Some(d)) = (f.parse::<usize>(), parse_list(v)) {
                        let dirs = meta.directions.get_or_insert_with(Vec::new);
                        if dirs.len() == f {
                            dirs.push(d);
                        }
                    }
                } else if k == "space" {
                    meta.space = Some(v.to_string());
                }
            }
        }
    }
    true
}

fn interpret(
    meta: &mut Metadata,
    own: Option<String>,
    ndims: usize,
    xres: Option<f64>,
    yres: Option<f64>,
) {
    let mut imagej_spacing = None;
    for line in own.as_deref().unwrap_or("").lines() {
        mra_line(meta, line);
    }
    if let Some(desc) = meta.description.clone() {
        let mut kept = Vec::new();
        for line in desc.lines() {
            if line.starts_with("mra.") {
                if own.is_none() {
                    mra_line(meta, line);
                }
                continue;
            }
            if let Some(v) = line.strip_prefix("spacing=") {
                imagej_spacing = v.trim().parse::<f64>().ok();
            }
            if let Some(v) = line.strip_prefix("unit=") {
                if meta.units.is_none() {
                    meta.units = Some(v.trim().to_string());
                }
            }
            kept.push(line);
        }
        meta.description = if kept.iter().all(|l| l.trim().is_empty()) {
            None
        } else {
            Some(kept.join("\n"))
        };
    }
    for g in &meta.geotiff {
        match (&g.tag, &g.value) {
            (33550, GeoValue::Doubles(d)) if d.len() >= 2 && meta.spacing.is_none() => {
                meta.spacing = Some(vec![d[1], d[0]]);
            }
            (42113, GeoValue::Ascii(s)) if meta.nodata.is_none() => {
                meta.nodata = s.trim().trim_end_matches('\0').parse().ok();
            }
            _ => {}
        }
    }
    if meta.spacing.is_none() {
        if let (Some(xr), Some(yr)) = (xres, yres) {
            let is_imagej = meta
                .description
                .as_deref()
                .is_some_and(|d| d.starts_with("ImageJ="));
            if is_imagej && xr > 0.0 && yr > 0.0 {
                let mut s = vec![1.0 / yr, 1.0 / xr];
                if ndims == 3 {
                    s.insert(0, imagej_spacing.unwrap_or(1.0));
                }
                meta.spacing = Some(s);
            }
        }
    }
}

fn rational(v: Option<Value>) -> Option<f64> {
    match v? {
        Value::Rational(n, d) if d != 0 => Some(n as f64 / d as f64),
        _ => None,
    }
}

/// Read a TIFF file: one page → 2-D image, several equal pages → volume `[D, H, W]`.
pub fn read(path: &Path) -> Result<Raster> {
    let file_len = std::fs::metadata(path)?.len();
    let mut dec = Decoder::new(BufReader::new(File::open(path)?)).map_err(tiff_error)?;
    let mut limits = Limits::default();
    limits.decoding_buffer_size = 1 << 33;
    limits.intermediate_buffer_size = 1 << 33;
    limits.ifd_value_size = 64 << 20;
    dec = dec.with_limits(limits);

    let (w, h) = dec.dimensions().map_err(tiff_error)?;
    let ct = dec.colortype().map_err(tiff_error)?;
    let channels = channels_of(ct)?;
    let planar = dec
        .find_tag_unsigned::<u16>(Tag::PlanarConfiguration)
        .ok()
        .flatten()
        .unwrap_or(1);
    if planar == 2 && channels > 1 {
        return Err(Error::Unsupported {
            what: "TIFF layout",
            value: "planar (separate) channels; expected interleaved (chunky) samples".into(),
        });
    }
    let bits = ct.bit_depth() as u64;
    let compression = dec
        .find_tag_unsigned::<u16>(Tag::Compression)
        .ok()
        .flatten()
        .unwrap_or(1);
    let page_bytes = (w as u64)
        .checked_mul(h as u64)
        .and_then(|n| n.checked_mul(channels as u64 * bits.max(1)))
        .map(|b| b.div_ceil(8))
        .ok_or_else(|| Error::format("TIFF dimensions overflow", "sizes that fit in memory"))?;
    let cap = if compression == 1 {
        file_len
    } else {
        file_len.saturating_mul(MAX_RATIO)
    };
    if page_bytes > cap {
        return Err(Error::format(
            format!("TIFF header declares {w}x{h}x{channels} samples ({page_bytes} bytes) but the file holds {file_len} bytes"),
            "a data size that fits the file",
        ));
    }

    let mut meta = Metadata {
        description: dec
            .find_tag(Tag::ImageDescription)
            .ok()
            .flatten()
            .and_then(|v| v.into_string().ok())
            .map(|s| s.trim_end_matches('\0').to_string()),
        ..Default::default()
    };
    for tag in GEOTIFF_TAGS {
        if let Ok(Some(v)) = dec.find_tag(Tag::Unknown(tag)) {
            if let Some(value) = geo_value(v) {
                meta.geotiff.push(GeoTag { tag, value });
            }
        }
    }
    let own = dec
        .find_tag(Tag::Unknown(MRA_TAG))
        .ok()
        .flatten()
        .and_then(|v| v.into_string().ok())
        .map(|s| s.trim_end_matches('\0').to_string());
    let xres = rational(dec.find_tag(Tag::XResolution).ok().flatten());
    let yres = rational(dec.find_tag(Tag::YResolution).ok().flatten());

    let mut acc: Option<Samples> = None;
    let mut pages = 0usize;
    loop {
        append(&mut acc, dec.read_image().map_err(tiff_error)?)?;
        pages += 1;
        if !dec.more_images() {
            break;
        }
        dec.next_image().map_err(tiff_error)?;
        let (w2, h2) = dec.dimensions().map_err(tiff_error)?;
        let ct2 = dec.colortype().map_err(tiff_error)?;
        if (w2, h2) != (w, h) || ct2 != ct {
            // a thumbnail or a reduced-resolution page: keep the stack read so far
            break;
        }
    }
    let samples = acc.expect("at least one page");
    let (dims, kind) = if pages == 1 {
        let kind =
            if meta.geotiff.is_empty() && !(samples.sample_type().is_float() && channels == 1) {
                DataKind::Image
            } else {
                DataKind::Heightmap
            };
        (vec![h as usize, w as usize], kind)
    } else {
        (vec![pages, h as usize, w as usize], DataKind::Volume)
    };
    interpret(&mut meta, own, dims.len(), xres, yres);
    let mut r = Raster::new(dims, channels, samples, kind)?;
    r.meta = meta;
    Ok(r)
}

/// The text of [`MRA_TAG`]: mra's `mra.` lines (empty when there is nothing to say).
fn own_lines(r: &Raster) -> String {
    let mut lines: Vec<String> = Vec::new();
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    if let Some(s) = &r.meta.spacing {
        lines.push(format!("mra.spacing={}", join(s)));
    }
    if let Some(o) = &r.meta.origin {
        lines.push(format!("mra.origin={}", join(o)));
    }
    if let Some(u) = &r.meta.units {
        lines.push(format!("mra.units={u}"));
    }
    if let Some(n) = r.meta.nodata {
        lines.push(format!("mra.nodata={n}"));
    }
    if let Some(sp) = &r.meta.space {
        lines.push(format!("mra.space={sp}"));
    }
    if let Some(d) = &r.meta.directions {
        for (f, v) in d.iter().enumerate() {
            lines.push(format!("mra.direction.{f}={}", join(v)));
        }
    }
    for (k, v) in &r.meta.extra {
        lines.push(format!("mra.extra.{k}={}", v.replace('\n', " ")));
    }
    lines.join("\n")
}

/// ASCII tags hold 7-bit text: other characters are written as `?`.
fn ascii(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii() && c != '\0' { c } else { '?' })
        .collect()
}

/// Gray + alpha colour types (the `tiff` crate has none): two samples, the second an
/// unassociated alpha (ExtraSamples = 2, written in [`write_pages`]).
macro_rules! gray_alpha {
    ($name:ident, $inner:ty, $bits:expr, $fmt:ident) => {
        struct $name;
        impl colortype::ColorType for $name {
            type Inner = $inner;
            const TIFF_VALUE: tiff::tags::PhotometricInterpretation =
                tiff::tags::PhotometricInterpretation::BlackIsZero;
            const BITS_PER_SAMPLE: &'static [u16] = &[$bits, $bits];
            const SAMPLE_FORMAT: &'static [tiff::tags::SampleFormat] = &[
                tiff::tags::SampleFormat::$fmt,
                tiff::tags::SampleFormat::$fmt,
            ];
            fn horizontal_predict(row: &[Self::Inner], result: &mut Vec<Self::Inner>) {
                result.extend_from_slice(row);
            }
        }
    };
}
gray_alpha!(GrayA8, u8, 8, Uint);
gray_alpha!(GrayA16, u16, 16, Uint);
gray_alpha!(GrayA32Float, f32, 32, IEEEFP);

/// Write one page per `[H, W]` slice, with ImageDescription and GeoTIFF tags on each.
fn write_pages<W, C>(w: &mut W, r: &Raster, data: &[C::Inner], compress: bool) -> Result<()>
where
    W: Write + Seek,
    C: colortype::ColorType,
    [C::Inner]: tiff::encoder::TiffValue,
{
    let (width, height) = (r.width() as u32, r.height() as u32);
    let page = r.width() * r.height() * r.channels;
    let desc = r.meta.description.as_deref().map(ascii).unwrap_or_default();
    let own = ascii(&own_lines(r));
    let mut enc = TiffEncoder::new(w).map_err(tiff_error)?;
    if compress {
        enc = enc.with_compression(tiff::encoder::Compression::Deflate(
            tiff::encoder::DeflateLevel::Fast,
        ));
    }
    for chunk in data.chunks(page.max(1)) {
        let mut img = enc.new_image::<C>(width, height).map_err(tiff_error)?;
        if !desc.is_empty() {
            img.encoder()
                .write_tag(Tag::ImageDescription, desc.as_str())
                .map_err(tiff_error)?;
        }
        if !own.is_empty() {
            img.encoder()
                .write_tag(Tag::Unknown(MRA_TAG), own.as_str())
                .map_err(tiff_error)?;
        }
        for g in &r.meta.geotiff {
            let e = img.encoder();
            match &g.value {
                GeoValue::Shorts(v) => e.write_tag(Tag::Unknown(g.tag), &v[..]),
                GeoValue::Doubles(v) => e.write_tag(Tag::Unknown(g.tag), &v[..]),
                GeoValue::Ascii(s) => e.write_tag(Tag::Unknown(g.tag), s.as_str()),
            }
            .map_err(tiff_error)?;
        }
        if r.channels == 2 {
            // ExtraSamples = 2 (unassociated alpha) for the second of the two samples
            img.encoder()
                .write_tag(Tag::ExtraSamples, &[2u16][..])
                .map_err(tiff_error)?;
        }
        img.write_data(chunk).map_err(tiff_error)?;
    }
    Ok(())
}

/// Write a 2-D raster as one TIFF page or a 3-D raster as a page stack. Gray, RGB and
/// RGBA of u8, i8, u16, i16, u32, i32, f32, f64 (RGB/RGBA unsigned or float only;
/// gray+alpha u8, u16, f32).
/// With `compress`, strips are Deflate-compressed (fast level).
pub fn write<W: Write + Seek>(w: &mut W, r: &Raster, compress: bool) -> Result<()> {
    if r.dims.len() < 2 || r.dims.len() > 3 {
        return Err(Error::Unsupported {
            what: "TIFF output",
            value: format!("{}-D data (expected 2-D or 3-D)", r.dims.len()),
        });
    }
    use colortype as c;
    use Samples as S;
    match (&r.samples, r.channels) {
        (S::U8(v), 1) => write_pages::<_, c::Gray8>(w, r, v, compress),
        (S::I8(v), 1) => write_pages::<_, c::GrayI8>(w, r, v, compress),
        (S::U16(v), 1) => write_pages::<_, c::Gray16>(w, r, v, compress),
        (S::I16(v), 1) => write_pages::<_, c::GrayI16>(w, r, v, compress),
        (S::U32(v), 1) => write_pages::<_, c::Gray32>(w, r, v, compress),
        (S::I32(v), 1) => write_pages::<_, c::GrayI32>(w, r, v, compress),
        (S::F32(v), 1) => write_pages::<_, c::Gray32Float>(w, r, v, compress),
        (S::F64(v), 1) => write_pages::<_, c::Gray64Float>(w, r, v, compress),
        (S::U8(v), 2) => write_pages::<_, GrayA8>(w, r, v, compress),
        (S::U16(v), 2) => write_pages::<_, GrayA16>(w, r, v, compress),
        (S::F32(v), 2) => write_pages::<_, GrayA32Float>(w, r, v, compress),
        (S::U8(v), 3) => write_pages::<_, c::RGB8>(w, r, v, compress),
        (S::U16(v), 3) => write_pages::<_, c::RGB16>(w, r, v, compress),
        (S::U32(v), 3) => write_pages::<_, c::RGB32>(w, r, v, compress),
        (S::F32(v), 3) => write_pages::<_, c::RGB32Float>(w, r, v, compress),
        (S::F64(v), 3) => write_pages::<_, c::RGB64Float>(w, r, v, compress),
        (S::U8(v), 4) => write_pages::<_, c::RGBA8>(w, r, v, compress),
        (S::U16(v), 4) => write_pages::<_, c::RGBA16>(w, r, v, compress),
        (S::U32(v), 4) => write_pages::<_, c::RGBA32>(w, r, v, compress),
        (S::F32(v), 4) => write_pages::<_, c::RGBA32Float>(w, r, v, compress),
        (S::F64(v), 4) => write_pages::<_, c::RGBA64Float>(w, r, v, compress),
        _ => Err(Error::Unsupported {
            what: "TIFF output",
            value: format!(
                "{} channels of {} (expected gray of any type, or RGB/RGBA of u8, u16, u32, f32, f64; f16 → .exr)",
                r.channels,
                r.sample_type()
            ),
        }),
    }
}
