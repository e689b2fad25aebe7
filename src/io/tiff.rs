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
use std::ops::Range;
use std::path::Path;

use tiff::decoder::{ifd::Value, Decoder, DecodingResult, Limits};
use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;
use tiff::ColorType;

use super::slab::{Shape, SlabSource};
use super::{DataKind, GeoTag, GeoValue, Metadata, Raster, SampleType, Samples, GEOTIFF_TAGS};
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
        // the decoder's buffers are capped at the budget ([`open_head`])
        tiff::TiffError::LimitsExceeded => Error::format(
            "a TIFF decoder buffer over the memory budget (MRA_MAX_BYTES)",
            "strips and tiles within the budget",
        ),
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
    if ndims == 2 {
        georeferenced(meta);
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

/// Units, height unit, origin and directions from the GeoKeys ([`super::geokeys`]),
/// where mra's own keys did not already give them.
fn georeferenced(meta: &mut Metadata) {
    let Some(g) = super::geokeys::georeference(&meta.geotiff) else {
        return;
    };
    if meta.units.is_none() {
        meta.units = g.units;
    }
    if let Some(h) = g.height_units {
        meta.extra.entry("elevation_units".into()).or_insert(h);
    }
    if meta.origin.is_none() && meta.directions.is_none() {
        if let (Some(o), Some(d)) = (g.origin, g.directions) {
            meta.origin = Some(o.to_vec());
            meta.directions = Some(d.iter().map(|v| v.to_vec()).collect());
        }
    }
}

fn rational(v: Option<Value>) -> Option<f64> {
    match v? {
        Value::Rational(n, d) if d != 0 => Some(n as f64 / d as f64),
        _ => None,
    }
}

/// What the first page of a TIFF says, before its samples are read.
struct Head {
    w: u32,
    h: u32,
    ct: ColorType,
    channels: usize,
    meta: Metadata,
    own: Option<String>,
    xres: Option<f64>,
    yres: Option<f64>,
}

/// Open a TIFF and read its first page's tags, checking the declared size against the
/// file (before anything is allocated).
fn open_head(path: &Path) -> Result<(Decoder<BufReader<File>>, Head)> {
    let file_len = std::fs::metadata(path)?.len();
    let budget = crate::limits::Limits::from_env()?;
    let mut dec = Decoder::new(BufReader::new(File::open(path)?)).map_err(tiff_error)?;
    let mut limits = Limits::default();
    // the crate's own buffers stay within the budget too (usize: a 32-bit target caps it)
    let most = usize::try_from(budget.max_bytes).unwrap_or(usize::MAX);
    limits.decoding_buffer_size = most;
    limits.intermediate_buffer_size = most;
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
    Ok((
        dec,
        Head {
            w,
            h,
            ct,
            channels,
            meta,
            own,
            xres,
            yres,
        },
    ))
}

/// The kind of a TIFF of `pages` pages (a single float gray page or a GeoTIFF is a
/// heightmap).
fn kind_of(pages: usize, meta: &Metadata, float: bool, channels: usize) -> DataKind {
    if pages > 1 {
        DataKind::Volume
    } else if meta.geotiff.is_empty() && !(float && channels == 1) {
        DataKind::Image
    } else {
        DataKind::Heightmap
    }
}

/// Read a TIFF file: one page → 2-D image, several equal pages → volume `[D, H, W]`.
pub fn read(path: &Path) -> Result<Raster> {
    let (mut dec, head) = open_head(path)?;
    let Head {
        w,
        h,
        ct,
        channels,
        mut meta,
        own,
        xres,
        yres,
    } = head;

    let mut acc: Option<Samples> = None;
    let mut pages = 0usize;
    // pages may share their strips: the stack, not the file, bounds what they inflate
    // to. Before page p is read: the p pages held, the page as decoded and, from the
    // second page on, its copy appended to the stack, `(p + 1 + [p > 0]) · page` bytes
    let page_bytes = (w as u64 * h as u64 * channels as u64 * ct.bit_depth() as u64).div_ceil(8);
    loop {
        crate::limits::check_elems(
            "TIFF stack bytes (memory budget MRA_MAX_BYTES)",
            pages as u64 + 1 + u64::from(pages > 0),
            page_bytes,
        )?;
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
    let kind = kind_of(pages, &meta, samples.sample_type().is_float(), channels);
    let dims = if pages == 1 {
        vec![h as usize, w as usize]
    } else {
        vec![pages, h as usize, w as usize]
    };
    interpret(&mut meta, own, dims.len(), xres, yres);
    let mut r = Raster::new(dims, channels, samples, kind)?;
    r.meta = meta;
    Ok(r)
}

/// A TIFF read a slab of rows (one page) or pages (a stack) at a time: strips and tiles
/// are decoded only where the slab lies.
pub struct TiffSlabs {
    dec: Decoder<BufReader<File>>,
    shape: Shape,
    pages: usize,
}

/// A TIFF as a source of slabs: the raster [`read`] would give, read by strips, tiles
/// or pages.
pub fn open_slabs(path: &Path) -> Result<TiffSlabs> {
    let (mut dec, head) = open_head(path)?;
    let mut pages = 1;
    while dec.more_images() {
        dec.next_image().map_err(tiff_error)?;
        let (w2, h2) = dec.dimensions().map_err(tiff_error)?;
        let ct2 = dec.colortype().map_err(tiff_error)?;
        if (w2, h2) != (head.w, head.h) || ct2 != head.ct {
            break;
        }
        pages += 1;
    }
    dec.seek_to_image(0).map_err(tiff_error)?;
    // the sample type as the first chunk decodes
    let mut first = None;
    append(&mut first, dec.read_chunk(0).map_err(tiff_error)?)?;
    let ty = first.expect("one chunk").sample_type();
    let mut meta = head.meta;
    let (w, h) = (head.w as usize, head.h as usize);
    let dims = if pages == 1 {
        vec![h, w]
    } else {
        vec![pages, h, w]
    };
    interpret(&mut meta, head.own, dims.len(), head.xres, head.yres);
    let kind = kind_of(pages, &meta, ty.is_float(), head.channels);
    Ok(TiffSlabs {
        dec,
        shape: Shape {
            dims,
            channels: head.channels,
            sample_type: ty,
            kind,
            meta,
        },
        pages,
    })
}

impl TiffSlabs {
    /// Rows `rows` of the one page: the strips or tile rows holding them, decoded and cut.
    fn page_rows(&mut self, rows: Range<usize>) -> Result<Samples> {
        let (h, w) = (self.shape.dims[0], self.shape.dims[1]);
        let c = self.shape.channels;
        let (cw, ch) = self.dec.chunk_dimensions();
        let (cw, ch) = (cw as usize, ch.max(1) as usize);
        let across = match self.dec.get_chunk_type() {
            tiff::decoder::ChunkType::Strip => 1,
            tiff::decoder::ChunkType::Tile => w.div_ceil(cw.max(1)),
        };
        let (b0, b1) = (rows.start / ch, rows.end.div_ceil(ch));
        let band_rows = (b1 * ch).min(h) - b0 * ch;
        let mut band = Samples::zeros(self.shape.sample_type, band_rows * w * c);
        for b in b0..b1 {
            for x in 0..across {
                let i = b * across + x;
                let (dw, dh) = self.dec.chunk_data_dimensions(i as u32);
                let (dw, dh) = (dw as usize, dh as usize);
                let mut chunk = None;
                append(
                    &mut chunk,
                    self.dec.read_chunk(i as u32).map_err(tiff_error)?,
                )?;
                let chunk = chunk.expect("one chunk");
                if chunk.len() != dw * dh * c || (b - b0) * ch + dh > band_rows {
                    return Err(Error::format(
                        format!("TIFF chunk {i} of {} samples for {dw}x{dh}", chunk.len()),
                        "chunks of the image's layout",
                    ));
                }
                // rows of the chunk into the band
                for y in 0..dh {
                    let to = ((b - b0) * ch + y) * w * c + x * cw * c;
                    band.copy_from(to, &chunk, y * dw * c, dw * c)?;
                }
            }
        }
        let skip = (rows.start - b0 * ch) * w * c;
        Ok(band.range(skip..skip + rows.len() * w * c))
    }
}

impl SlabSource for TiffSlabs {
    fn shape(&self) -> &Shape {
        &self.shape
    }

    fn read_rows(&mut self, rows: Range<usize>) -> Result<Samples> {
        if rows.start >= rows.end || rows.end > self.shape.dims[0] {
            return Err(Error::parameter(
                "rows",
                format!("{}..{} of {}", rows.start, rows.end, self.shape.dims[0]),
                "a non-empty range within the slowest axis",
            ));
        }
        if self.pages == 1 {
            return self.page_rows(rows);
        }
        let mut acc = None;
        for z in rows {
            self.dec.seek_to_image(z).map_err(tiff_error)?;
            append(&mut acc, self.dec.read_image().map_err(tiff_error)?)?;
        }
        let s = acc.expect("a page");
        if s.sample_type() != self.shape.sample_type {
            return Err(Error::Unsupported {
                what: "TIFF stack",
                value: "pages with different sample types".into(),
            });
        }
        Ok(s)
    }
}

/// The text of [`MRA_TAG`]: mra's `mra.` lines (empty when there is nothing to say).
fn own_lines(meta: &Metadata) -> String {
    let mut lines: Vec<String> = Vec::new();
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    if let Some(s) = &meta.spacing {
        lines.push(format!("mra.spacing={}", join(s)));
    }
    if let Some(o) = &meta.origin {
        lines.push(format!("mra.origin={}", join(o)));
    }
    if let Some(u) = &meta.units {
        lines.push(format!("mra.units={u}"));
    }
    if let Some(n) = meta.nodata {
        lines.push(format!("mra.nodata={n}"));
    }
    if let Some(sp) = &meta.space {
        lines.push(format!("mra.space={sp}"));
    }
    if let Some(d) = &meta.directions {
        for (f, v) in d.iter().enumerate() {
            lines.push(format!("mra.direction.{f}={}", join(v)));
        }
    }
    for (k, v) in &meta.extra {
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

/// ImageDescription, mra's own tag, the GeoTIFF tags and (gray + alpha) ExtraSamples.
fn put_tags<W: Write + Seek, K: tiff::encoder::TiffKind>(
    e: &mut tiff::encoder::DirectoryEncoder<'_, W, K>,
    desc: &str,
    own: &str,
    meta: &Metadata,
    channels: usize,
) -> Result<()> {
    if !desc.is_empty() {
        e.write_tag(Tag::ImageDescription, desc)
            .map_err(tiff_error)?;
    }
    if !own.is_empty() {
        e.write_tag(Tag::Unknown(MRA_TAG), own)
            .map_err(tiff_error)?;
    }
    for g in &meta.geotiff {
        match &g.value {
            GeoValue::Shorts(v) => e.write_tag(Tag::Unknown(g.tag), &v[..]),
            GeoValue::Doubles(v) => e.write_tag(Tag::Unknown(g.tag), &v[..]),
            GeoValue::Ascii(s) => e.write_tag(Tag::Unknown(g.tag), s.as_str()),
        }
        .map_err(tiff_error)?;
    }
    if channels == 2 {
        // ExtraSamples = 2 (unassociated alpha) for the second of the two samples
        e.write_tag(Tag::ExtraSamples, &[2u16][..])
            .map_err(tiff_error)?;
    }
    Ok(())
}

/// Write a raster handed over in slabs (`next` gives the rows of the slowest axis in
/// order, `None` at the end) as [`write`] writes it uncompressed: a volume page by page,
/// an image strip by strip (strips of about 1 MiB), so memory holds a slab.
pub fn write_slabs<W: Write + Seek>(
    w: &mut W,
    shape: &Shape,
    next: &mut dyn FnMut() -> Result<Option<Samples>>,
) -> Result<()> {
    if shape.dims.len() < 2 || shape.dims.len() > 3 {
        return Err(Error::Unsupported {
            what: "TIFF output",
            value: format!("{}-D data (expected 2-D or 3-D)", shape.dims.len()),
        });
    }
    use colortype as c;
    use SampleType as T;
    macro_rules! go {
        ($c:ty, $var:ident, $inner:ty) => {{
            fn get(s: &Samples) -> Option<&[$inner]> {
                match s {
                    Samples::$var(v) => Some(v),
                    _ => None,
                }
            }
            slabs_as::<_, $c>(w, shape, next, get)
        }};
    }
    match (shape.sample_type, shape.channels) {
        (T::U8, 1) => go!(c::Gray8, U8, u8),
        (T::I8, 1) => go!(c::GrayI8, I8, i8),
        (T::U16, 1) => go!(c::Gray16, U16, u16),
        (T::I16, 1) => go!(c::GrayI16, I16, i16),
        (T::U32, 1) => go!(c::Gray32, U32, u32),
        (T::I32, 1) => go!(c::GrayI32, I32, i32),
        (T::F32, 1) => go!(c::Gray32Float, F32, f32),
        (T::F64, 1) => go!(c::Gray64Float, F64, f64),
        (T::U8, 2) => go!(GrayA8, U8, u8),
        (T::U16, 2) => go!(GrayA16, U16, u16),
        (T::F32, 2) => go!(GrayA32Float, F32, f32),
        (T::U8, 3) => go!(c::RGB8, U8, u8),
        (T::U16, 3) => go!(c::RGB16, U16, u16),
        (T::U32, 3) => go!(c::RGB32, U32, u32),
        (T::F32, 3) => go!(c::RGB32Float, F32, f32),
        (T::F64, 3) => go!(c::RGB64Float, F64, f64),
        (T::U8, 4) => go!(c::RGBA8, U8, u8),
        (T::U16, 4) => go!(c::RGBA16, U16, u16),
        (T::U32, 4) => go!(c::RGBA32, U32, u32),
        (T::F32, 4) => go!(c::RGBA32Float, F32, f32),
        (T::F64, 4) => go!(c::RGBA64Float, F64, f64),
        _ => Err(Error::Unsupported {
            what: "TIFF output",
            value: format!(
                "{} channels of {} (expected gray of any type, or RGB/RGBA of u8, u16, u32, f32, f64; f16 → .exr)",
                shape.channels, shape.sample_type
            ),
        }),
    }
}

fn slabs_as<W, C>(
    w: &mut W,
    shape: &Shape,
    next: &mut dyn FnMut() -> Result<Option<Samples>>,
    get: fn(&Samples) -> Option<&[C::Inner]>,
) -> Result<()>
where
    W: Write + Seek,
    C: colortype::ColorType,
    C::Inner: Copy,
    [C::Inner]: tiff::encoder::TiffValue,
{
    let nd = shape.dims.len();
    let (width, height) = (shape.dims[nd - 1], shape.dims[nd - 2]);
    let row = width * shape.channels;
    let page = row * height;
    let desc = shape
        .meta
        .description
        .as_deref()
        .map(ascii)
        .unwrap_or_default();
    let own = ascii(&own_lines(&shape.meta));
    let mut enc = TiffEncoder::new(w).map_err(tiff_error)?;
    let wrong = |s: &Samples| {
        Error::format(
            format!("a slab of {} {} samples", s.len(), s.sample_type()),
            "whole rows of the raster's sample type",
        )
    };
    if nd == 3 {
        let mut pages = 0;
        while let Some(s) = next()? {
            let v = get(&s)
                .filter(|v| v.len() % page == 0)
                .ok_or_else(|| wrong(&s))?;
            for p in v.chunks(page) {
                let mut img = enc
                    .new_image::<C>(width as u32, height as u32)
                    .map_err(tiff_error)?;
                put_tags(img.encoder(), &desc, &own, &shape.meta, shape.channels)?;
                img.write_data(p).map_err(tiff_error)?;
                pages += 1;
            }
        }
        if pages != shape.dims[0] {
            return Err(Error::format(
                format!("{pages} pages written of {}", shape.dims[0]),
                "every page of the volume",
            ));
        }
        return Ok(());
    }
    let mut img = enc
        .new_image::<C>(width as u32, height as u32)
        .map_err(tiff_error)?;
    put_tags(img.encoder(), &desc, &own, &shape.meta, shape.channels)?;
    let bytes = (row * std::mem::size_of::<C::Inner>()).max(1);
    let rows_per_strip = ((1usize << 20) / bytes).clamp(1, height);
    img.rows_per_strip(rows_per_strip as u32)
        .map_err(tiff_error)?;
    let strip = rows_per_strip * row;
    let mut carry: Vec<C::Inner> = Vec::with_capacity(strip);
    let mut rows = 0;
    while let Some(s) = next()? {
        let v = get(&s)
            .filter(|v| v.len() % row == 0)
            .ok_or_else(|| wrong(&s))?;
        rows += v.len() / row;
        let mut v = v;
        while !v.is_empty() {
            let take = (strip - carry.len()).min(v.len());
            carry.extend_from_slice(&v[..take]);
            v = &v[take..];
            if carry.len() == strip {
                img.write_strip(&carry).map_err(tiff_error)?;
                carry.clear();
            }
        }
    }
    if rows != height {
        return Err(Error::format(
            format!("{rows} rows written of {height}"),
            "every row of the image",
        ));
    }
    if !carry.is_empty() {
        img.write_strip(&carry).map_err(tiff_error)?;
    }
    img.finish().map_err(tiff_error)?;
    Ok(())
}

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
    let own = ascii(&own_lines(&r.meta));
    let mut enc = TiffEncoder::new(w).map_err(tiff_error)?;
    if compress {
        enc = enc.with_compression(tiff::encoder::Compression::Deflate(
            tiff::encoder::DeflateLevel::Fast,
        ));
    }
    for chunk in data.chunks(page.max(1)) {
        let mut img = enc.new_image::<C>(width, height).map_err(tiff_error)?;
        put_tags(img.encoder(), &desc, &own, &r.meta, r.channels)?;
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
