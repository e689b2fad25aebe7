//! Rasters in and out: images, volumes and heightmaps, keeping the exact sample type.
//!
//! A [`Raster`] is a row-major block of samples over `dims` spatial axes (`[H, W]` for
//! images and heightmaps, `[D, H, W]` for volumes, the first axis slowest) with
//! `channels` samples interleaved per position (the last, fastest axis). The samples keep
//! the type the file stored ([`Samples`]); [`Raster::to_f32`] / [`Raster::from_f32`]
//! convert for the transforms, rounding and clamping on the way back.
//!
//! Formats are recognised by their content (magic bytes) first and by extension second;
//! a file whose content contradicts its extension is an error ([`Format::detect`]).
//! One file per format:
//!
//! ```text
//! png.rs    PNG (8/16-bit, gray, gray+alpha, RGB, RGBA)        via `image`
//! jpeg.rs   JPEG, read only (8-bit gray, RGB)                   via `image`
//! pnm.rs    PGM / PPM / PAM (8/16-bit)                          via `image`
//! tiff.rs   TIFF: all integer and float types, page stacks, GeoTIFF tags, ImageJ spacing
//! exr.rs    OpenEXR, half / float / uint per channel            via `exr`
//! nrrd.rs   NRRD raw / gzip / ascii, both byte orders, detached .nhdr
//! nifti.rs  NIfTI-1 .nii / .nii.gz (348-byte header, affine)
//! dicom.rs  DICOM files and series (uncompressed), rescale applied, spacing kept
//! dicom_scan.rs  finding DICOM files by their preamble (built without the feature too)
//! slices.rs a folder of 2D slices (TIFF / PNG) as one volume
//! hgt.rs    SRTM .hgt (big-endian i16, void −32768 kept as nodata)
//! asc.rs    ESRI ASCII grid
//! geokeys.rs  GeoTIFF units and position from the GeoKeys, as GDAL reads them
//! geometry.rs  where samples sit after a resample or crop ([`Metadata::resampled`])
//! nodata.rs  void samples (NaN, `meta.nodata`) kept out of every filter
//! raw.rs    headerless raw (.raw with dims/dtype/endian, .r16, .r32)
//! slab.rs   a raster's shape, sources and sinks of slabs of rows
//! stream.rs  the files read and written a slab at a time (raw, raw NRRD, TIFF)
//! bytes.rs  endian decoding, size checks before allocation, atomic writes
//! array.rs  rasters through the tensor engine (analyze / synthesize / pictures)
//! pyramid_file.rs  the float32 TIFF / NRRD a pyramid is stored in, with its keys
//! visual.rs  8-bit pictures of pyramids, each block contrast-stretched
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use crate::{Error, Result};

pub use geometry::AxisMap;
pub use view::{RasterView, SamplesRef};

pub mod array;
pub mod asc;
pub mod bytes;
#[cfg(feature = "dicom")]
pub mod dicom;
/// DICOM without the `dicom` feature: files and series are recognised, then refused.
#[cfg(not(feature = "dicom"))]
pub mod dicom {
    use super::Raster;
    use crate::{Error, Result};
    use std::path::Path;

    fn not_built(path: &Path) -> Error {
        Error::Unsupported {
            what: "DICOM input in a build without the `dicom` feature",
            value: path.display().to_string(),
        }
    }
    pub fn read_file(path: &Path) -> Result<Raster> {
        Err(not_built(path))
    }
    pub fn read_series(dir: &Path, _uneven_ok: bool) -> Result<Raster> {
        Err(not_built(dir))
    }
    pub use super::dicom_scan::{dicom_files, is_dicom};
}
mod dicom_scan;
pub mod exr;
pub mod geokeys;
pub mod geometry;
pub mod hgt;
pub mod jpeg;
pub mod nifti;
pub mod nodata;
pub mod nrrd;
pub mod png;
pub mod pnm;
pub mod pyramid_file;
pub mod raw;
pub mod slab;
pub mod slices;
pub mod stream;
pub mod tiff;
pub mod view;
pub mod visual;

/// The largest number of samples a reader accepts (2^34, 64 GiB of f32): a declared size
/// beyond this is reported as [`Error::LimitsExceeded`] before anything is allocated.
pub const MAX_SAMPLES: u64 = 1 << 34;

/// The stored type of one sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SampleType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F16,
    F32,
    F64,
}

impl SampleType {
    /// Every sample type, integers by size then floats.
    pub const ALL: [SampleType; 9] = [
        SampleType::U8,
        SampleType::I8,
        SampleType::U16,
        SampleType::I16,
        SampleType::U32,
        SampleType::I32,
        SampleType::F16,
        SampleType::F32,
        SampleType::F64,
    ];

    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            SampleType::U8 | SampleType::I8 => 1,
            SampleType::U16 | SampleType::I16 | SampleType::F16 => 2,
            SampleType::U32 | SampleType::I32 | SampleType::F32 => 4,
            SampleType::F64 => 8,
        }
    }

    /// Short name as used on the command line (`u8`, `i16`, `f32`, …).
    pub fn name(self) -> &'static str {
        match self {
            SampleType::U8 => "u8",
            SampleType::I8 => "i8",
            SampleType::U16 => "u16",
            SampleType::I16 => "i16",
            SampleType::U32 => "u32",
            SampleType::I32 => "i32",
            SampleType::F16 => "f16",
            SampleType::F32 => "f32",
            SampleType::F64 => "f64",
        }
    }

    /// Parse a short name (`u8`, `i8`, `u16`, `i16`, `u32`, `i32`, `f16`, `f32`, `f64`).
    pub fn parse(s: &str) -> Result<Self> {
        Ok(match s.to_ascii_lowercase().as_str() {
            "u8" | "uint8" => SampleType::U8,
            "i8" | "int8" => SampleType::I8,
            "u16" | "uint16" => SampleType::U16,
            "i16" | "int16" => SampleType::I16,
            "u32" | "uint32" => SampleType::U32,
            "i32" | "int32" => SampleType::I32,
            "f16" | "float16" | "half" => SampleType::F16,
            "f32" | "float32" | "float" => SampleType::F32,
            "f64" | "float64" | "double" => SampleType::F64,
            _ => {
                return Err(Error::parameter(
                    "sample type",
                    s,
                    "one of u8, i8, u16, i16, u32, i32, f16, f32, f64",
                ))
            }
        })
    }

    pub fn is_float(self) -> bool {
        matches!(self, SampleType::F16 | SampleType::F32 | SampleType::F64)
    }

    /// `(min, max)` of an integer type; `(-1, 1)` for floats (scikit-image's `dtype_range`).
    pub fn range(self) -> (f64, f64) {
        match self {
            SampleType::U8 => (0.0, u8::MAX as f64),
            SampleType::I8 => (i8::MIN as f64, i8::MAX as f64),
            SampleType::U16 => (0.0, u16::MAX as f64),
            SampleType::I16 => (i16::MIN as f64, i16::MAX as f64),
            SampleType::U32 => (0.0, u32::MAX as f64),
            SampleType::I32 => (i32::MIN as f64, i32::MAX as f64),
            SampleType::F16 | SampleType::F32 | SampleType::F64 => (-1.0, 1.0),
        }
    }
}

impl std::fmt::Display for SampleType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The samples of a raster, in the exact type the file stored.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    U8(Vec<u8>),
    I8(Vec<i8>),
    U16(Vec<u16>),
    I16(Vec<i16>),
    U32(Vec<u32>),
    I32(Vec<i32>),
    F16(Vec<half::f16>),
    F32(Vec<f32>),
    F64(Vec<f64>),
}

/// Apply `$body` to the vector inside any [`Samples`] variant, bound as `$v`.
macro_rules! with_samples {
    ($s:expr, $v:ident => $body:expr) => {
        match $s {
            Samples::U8($v) => $body,
            Samples::I8($v) => $body,
            Samples::U16($v) => $body,
            Samples::I16($v) => $body,
            Samples::U32($v) => $body,
            Samples::I32($v) => $body,
            Samples::F16($v) => $body,
            Samples::F32($v) => $body,
            Samples::F64($v) => $body,
        }
    };
}
#[allow(unused_imports)]
pub(crate) use with_samples;

/// Round to nearest (ties away from zero) and clamp into `[lo, hi]`; NaN becomes 0.
fn quantize(x: f64, lo: f64, hi: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        x.round().clamp(lo, hi)
    }
}

impl Samples {
    #[inline]
    pub fn len(&self) -> usize {
        self.view().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    #[inline]
    pub fn sample_type(&self) -> SampleType {
        self.view().sample_type()
    }

    /// Sample `i` as f64 (exact for every stored type).
    #[inline]
    pub fn get_f64(&self, i: usize) -> f64 {
        self.view().get_f64(i)
    }

    /// All samples as f32 (exact for u8, i8, u16, i16, f16, f32; rounded for the rest).
    pub fn to_f32(&self) -> Vec<f32> {
        self.view().to_f32()
    }

    /// All samples as f64 (exact).
    pub fn to_f64(&self) -> Vec<f64> {
        self.view().to_f64()
    }

    /// Convert f32 values to `ty`: integers are rounded to nearest and clamped to the
    /// type's range (NaN → 0); floats are cast.
    pub fn from_f32(data: &[f32], ty: SampleType) -> Samples {
        Self::from_iter_f64(data.iter().map(|&x| x as f64), data.len(), ty)
    }

    /// Convert f64 values to `ty` as [`Samples::from_f32`] does.
    pub fn from_f64(data: &[f64], ty: SampleType) -> Samples {
        Self::from_iter_f64(data.iter().copied(), data.len(), ty)
    }

    /// Convert `n` f64 values to `ty` as [`Samples::from_f32`] does, from an iterator
    /// (no intermediate buffer).
    pub(crate) fn from_iter_f64(
        it: impl Iterator<Item = f64>,
        n: usize,
        ty: SampleType,
    ) -> Samples {
        let (lo, hi) = ty.range();
        macro_rules! ints {
            ($t:ty, $var:ident) => {{
                let mut v: Vec<$t> = Vec::with_capacity(n);
                v.extend(it.map(|x| quantize(x, lo, hi) as $t));
                Samples::$var(v)
            }};
        }
        match ty {
            SampleType::U8 => ints!(u8, U8),
            SampleType::I8 => ints!(i8, I8),
            SampleType::U16 => ints!(u16, U16),
            SampleType::I16 => ints!(i16, I16),
            SampleType::U32 => ints!(u32, U32),
            SampleType::I32 => ints!(i32, I32),
            SampleType::F16 => Samples::F16(it.map(half::f16::from_f64).collect()),
            SampleType::F32 => Samples::F32(it.map(|x| x as f32).collect()),
            SampleType::F64 => Samples::F64(it.collect()),
        }
    }

    /// `n` zero samples of type `t`.
    pub fn zeros(t: SampleType, n: usize) -> Samples {
        match t {
            SampleType::U8 => Samples::U8(vec![0; n]),
            SampleType::I8 => Samples::I8(vec![0; n]),
            SampleType::U16 => Samples::U16(vec![0; n]),
            SampleType::I16 => Samples::I16(vec![0; n]),
            SampleType::U32 => Samples::U32(vec![0; n]),
            SampleType::I32 => Samples::I32(vec![0; n]),
            SampleType::F16 => Samples::F16(vec![half::f16::ZERO; n]),
            SampleType::F32 => Samples::F32(vec![0.0; n]),
            SampleType::F64 => Samples::F64(vec![0.0; n]),
        }
    }

    /// The samples `r` (a copy).
    pub fn range(&self, r: std::ops::Range<usize>) -> Samples {
        self.view().range(r)
    }

    /// Copy `n` samples of `src` from `from` to `to` (same sample type, both in range).
    pub fn copy_from(&mut self, to: usize, src: &Samples, from: usize, n: usize) -> Result<()> {
        macro_rules! pair {
            ($($var:ident),*) => {
                match (self, src) {
                    $((Samples::$var(d), Samples::$var(s)) if to + n <= d.len() && from + n <= s.len() => {
                        d[to..to + n].copy_from_slice(&s[from..from + n])
                    })*
                    (d, s) => {
                        return Err(Error::format(
                            format!("{n} {} samples from {from} of {} into {to} of {} {}", s.sample_type(), s.len(), d.len(), d.sample_type()),
                            "samples of one type within both buffers",
                        ))
                    }
                }
            };
        }
        pair!(U8, I8, U16, I16, U32, I32, F16, F32, F64);
        Ok(())
    }

    /// `(min, max)` over all samples, ignoring NaN; `None` when empty or all NaN.
    pub fn min_max(&self) -> Option<(f64, f64)> {
        self.view().min_max()
    }
}

/// What the samples describe; decides defaults such as the analysed axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataKind {
    Image,
    Volume,
    Heightmap,
    Sequence,
}

/// One GeoTIFF tag kept verbatim so that rewriting a TIFF preserves georeferencing.
#[derive(Clone, Debug, PartialEq)]
pub struct GeoTag {
    /// 33550 ModelPixelScale, 33922 ModelTiepoint, 34264 ModelTransformation,
    /// 34735 GeoKeyDirectory, 34736 GeoDoubleParams, 34737 GeoAsciiParams,
    /// 42112 GDAL_METADATA, 42113 GDAL_NODATA.
    pub tag: u16,
    pub value: GeoValue,
}

/// The stored value of a [`GeoTag`].
#[derive(Clone, Debug, PartialEq)]
pub enum GeoValue {
    Shorts(Vec<u16>),
    Doubles(Vec<f64>),
    Ascii(String),
}

/// The tags [`GeoTag`] keeps.
pub const GEOTIFF_TAGS: [u16; 8] = [33550, 33922, 34264, 34735, 34736, 34737, 42112, 42113];

/// What the file says about where the samples are, beyond their values.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metadata {
    /// Distance between sample centres along each spatial axis, in `dims` order.
    pub spacing: Option<Vec<f64>>,
    /// World position of the first sample, in the file's world axis order (x, y, z).
    pub origin: Option<Vec<f64>>,
    /// Unit of spacing and origin (e.g. "mm", "m").
    pub units: Option<String>,
    /// Value that marks a missing sample (SRTM void −32768, ASCII grid NODATA_value).
    pub nodata: Option<f64>,
    /// GeoTIFF tags, verbatim.
    pub geotiff: Vec<GeoTag>,
    /// NRRD `space` (e.g. "left-posterior-superior").
    pub space: Option<String>,
    /// NRRD `space directions`, one world vector per spatial file axis (fastest first).
    pub directions: Option<Vec<Vec<f64>>>,
    /// NIfTI voxel-to-world affine (rows of the 3×4 matrix; index order i = x fastest).
    pub affine: Option<[[f64; 4]; 3]>,
    /// Free text (TIFF ImageDescription, NRRD content).
    pub description: Option<String>,
    /// Key/value pairs: NRRD `key:=value`, DICOM essentials, NIfTI scaling, mra's own keys.
    pub extra: BTreeMap<String, String>,
}

/// Samples over a row-major grid, channels interleaved last.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    /// Spatial extent, slowest axis first: `[H, W]` or `[D, H, W]`.
    pub dims: Vec<usize>,
    /// Samples per position (1 gray, 2 gray+alpha, 3 RGB, 4 RGBA, …).
    pub channels: usize,
    pub samples: Samples,
    pub kind: DataKind,
    pub meta: Metadata,
}

impl Raster {
    /// A raster with default metadata; errors when a size is 0 or the sample count does
    /// not match.
    pub fn new(
        dims: Vec<usize>,
        channels: usize,
        samples: Samples,
        kind: DataKind,
    ) -> Result<Self> {
        RasterView::new(&dims, channels, samples.view(), kind, &Metadata::default())?;
        Ok(Raster {
            dims,
            channels,
            samples,
            kind,
            meta: Metadata::default(),
        })
    }

    pub fn sample_type(&self) -> SampleType {
        self.samples.sample_type()
    }

    /// Number of spatial positions (product of `dims`).
    pub fn positions(&self) -> usize {
        self.dims.iter().product()
    }

    /// Width (fastest spatial axis).
    pub fn width(&self) -> usize {
        *self.dims.last().unwrap_or(&1)
    }

    /// Height (second fastest spatial axis), 1 for 1-D data.
    pub fn height(&self) -> usize {
        if self.dims.len() >= 2 {
            self.dims[self.dims.len() - 2]
        } else {
            1
        }
    }

    /// Depth (number of slices), 1 for 2-D data.
    pub fn depth(&self) -> usize {
        if self.dims.len() >= 3 {
            self.dims[..self.dims.len() - 2].iter().product()
        } else {
            1
        }
    }

    pub fn to_f32(&self) -> Vec<f32> {
        self.samples.to_f32()
    }

    pub fn to_f64(&self) -> Vec<f64> {
        self.samples.to_f64()
    }

    /// A raster of type `ty` from f32 values (rounded and clamped for integer types).
    pub fn from_f32(
        dims: Vec<usize>,
        channels: usize,
        data: &[f32],
        ty: SampleType,
        kind: DataKind,
    ) -> Result<Self> {
        Raster::new(dims, channels, Samples::from_f32(data, ty), kind)
    }

    /// A short description: `768x512 RGB u8 image`.
    pub fn summary(&self) -> String {
        summary(&self.dims, self.channels, self.sample_type(), self.kind)
    }
}

/// A short description of a raster: `768x512 RGB u8 image`.
pub fn summary(dims: &[usize], channels: usize, ty: SampleType, kind: DataKind) -> String {
    let dims: Vec<String> = dims.iter().rev().map(|d| d.to_string()).collect();
    let ch = match channels {
        1 => "gray".to_string(),
        2 => "gray+alpha".to_string(),
        3 => "RGB".to_string(),
        4 => "RGBA".to_string(),
        c => format!("{c}-channel"),
    };
    let kind = match kind {
        DataKind::Image => "image",
        DataKind::Volume => "volume",
        DataKind::Heightmap => "heightmap",
        DataKind::Sequence => "sequence",
    };
    format!("{} {} {} {}", dims.join("x"), ch, ty, kind)
}

/// A file format known to this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Jpeg,
    Tiff,
    Pnm,
    Exr,
    Nrrd,
    Nifti,
    Dicom,
    /// A folder holding one DICOM series.
    DicomSeries,
    /// A folder of 2D slices (TIFF or PNG), read in name order.
    SliceFolder,
    Hgt,
    Asc,
    R16,
    R32,
    Raw,
}

impl Format {
    pub fn name(self) -> &'static str {
        match self {
            Format::Png => "PNG",
            Format::Jpeg => "JPEG",
            Format::Tiff => "TIFF",
            Format::Pnm => "PNM",
            Format::Exr => "OpenEXR",
            Format::Nrrd => "NRRD",
            Format::Nifti => "NIfTI-1",
            Format::Dicom => "DICOM",
            Format::DicomSeries => "DICOM series",
            Format::SliceFolder => "slice folder",
            Format::Hgt => "SRTM HGT",
            Format::Asc => "ESRI ASCII grid",
            Format::R16 => "raw 16-bit heightmap",
            Format::R32 => "raw 32-bit float heightmap",
            Format::Raw => "raw",
        }
    }

    /// The format an extension names (case-insensitive; `.nii.gz` counts as NIfTI).
    pub fn from_extension(path: &Path) -> Option<Format> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        if name.ends_with(".nii.gz") {
            return Some(Format::Nifti);
        }
        let ext = name.rsplit_once('.')?.1;
        Some(match ext {
            "png" => Format::Png,
            "jpg" | "jpeg" => Format::Jpeg,
            "tif" | "tiff" => Format::Tiff,
            "pgm" | "ppm" | "pbm" | "pnm" | "pam" => Format::Pnm,
            "exr" => Format::Exr,
            "nrrd" | "nhdr" => Format::Nrrd,
            "nii" => Format::Nifti,
            "dcm" | "dicom" => Format::Dicom,
            "hgt" => Format::Hgt,
            "asc" => Format::Asc,
            "r16" => Format::R16,
            "r32" => Format::R32,
            "raw" | "bin" => Format::Raw,
            _ => return None,
        })
    }

    /// The format the first bytes of a file announce, if any (`None` for headerless data).
    pub fn sniff(head: &[u8]) -> Option<Format> {
        // DICOM first: its 128-byte preamble is free for application use and may itself
        // look like another format (a TIFF header, for dual-format files); the `DICM`
        // magic at offset 128 decides.
        if head.len() >= 132 && &head[128..132] == b"DICM" {
            return Some(Format::Dicom);
        }
        if head.starts_with(b"\x89PNG\r\n\x1a\n") {
            return Some(Format::Png);
        }
        if head.starts_with(&[0xFF, 0xD8, 0xFF]) {
            return Some(Format::Jpeg);
        }
        if head.starts_with(b"II*\0")
            || head.starts_with(b"MM\0*")
            || head.starts_with(b"II+\0")
            || head.starts_with(b"MM\0+")
        {
            return Some(Format::Tiff);
        }
        if head.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            return Some(Format::Exr);
        }
        if head.starts_with(b"NRRD000") {
            return Some(Format::Nrrd);
        }
        if head.len() >= 348
            && (&head[344..348] == b"n+1\0" || &head[344..348] == b"ni1\0")
            && (head[0..4] == 348i32.to_le_bytes() || head[0..4] == 348i32.to_be_bytes())
        {
            return Some(Format::Nifti);
        }
        if head.len() >= 3
            && head[0] == b'P'
            && (b'1'..=b'7').contains(&head[1])
            && head[2].is_ascii_whitespace()
        {
            return Some(Format::Pnm);
        }
        let text = String::from_utf8_lossy(&head[..head.len().min(16)]).to_ascii_lowercase();
        if text.trim_start().starts_with("ncols") || text.trim_start().starts_with("nrows") {
            return Some(Format::Asc);
        }
        None
    }

    /// Decide the format of `path`: folders are DICOM series or slice folders; files by
    /// magic bytes, then by extension; content and extension must agree.
    pub fn detect(path: &Path) -> Result<Format> {
        let md = std::fs::metadata(path)?;
        if md.is_dir() {
            return slices::classify_folder(path);
        }
        let mut head = [0u8; 352];
        let n = bytes::read_head(path, &mut head)?;
        let head = &head[..n];
        let by_ext = Format::from_extension(path);
        let gz = head.starts_with(&[0x1f, 0x8b]);
        let by_magic = if gz && by_ext == Some(Format::Nifti) {
            Some(Format::Nifti)
        } else {
            Format::sniff(head)
        };
        match (by_magic, by_ext) {
            (Some(m), Some(e)) if m != e => Err(Error::format(
                format!(
                    "content is {} but the extension says {}",
                    m.name(),
                    e.name()
                ),
                "content and extension to agree",
            )),
            (Some(m), _) => Ok(m),
            (None, Some(e @ (Format::Hgt | Format::R16 | Format::R32 | Format::Raw))) => Ok(e),
            (None, Some(e)) => Err(Error::format(
                format!("not a {} file (no {} signature)", e.name(), e.name()),
                "a file whose content matches its extension",
            )),
            (None, None) if gz => Err(Error::Unsupported {
                what: "gzip-compressed file",
                value: "only .nii.gz and gzip-encoded NRRD are read".into(),
            }),
            (None, None) => Err(Error::format(
                "unrecognised file format",
                "PNG, JPEG, TIFF, PNM, EXR, NRRD, NIfTI, DICOM, HGT, ASC, R16, R32 or RAW",
            )),
        }
    }
}

/// How to read headerless data (`.raw`, and `.r16` / `.r32` of non-square size).
#[derive(Clone, Debug, PartialEq)]
pub struct RawSpec {
    /// Spatial dims, slowest first (`[D, H, W]`); the CLI's `WxHxD` reversed.
    pub dims: Vec<usize>,
    pub sample_type: SampleType,
    pub big_endian: bool,
}

/// Options for [`read_with`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadOptions {
    pub raw: Option<RawSpec>,
    /// Accept a DICOM series whose slice positions are unevenly spaced or repeated
    /// (a missing or duplicated slice); the slice step is then their mean.
    pub uneven_slices: bool,
}

/// Options for [`write_with`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WriteOptions {
    /// Compress where the format allows a choice (NRRD gzip encoding, TIFF Deflate;
    /// NIfTI `.nii.gz` is chosen by the name instead).
    pub compress: bool,
}

/// Read any supported file or folder.
pub fn read(path: &Path) -> Result<Raster> {
    read_with(path, &ReadOptions::default())
}

/// Read with options (raw layout for headerless files).
pub fn read_with(path: &Path, opts: &ReadOptions) -> Result<Raster> {
    let format = Format::detect(path)?;
    match format {
        Format::Png => png::read(path),
        Format::Jpeg => jpeg::read(path),
        Format::Pnm => pnm::read(path),
        Format::Tiff => tiff::read(path),
        Format::Exr => exr::read(path),
        Format::Nrrd => nrrd::read(path),
        Format::Nifti => nifti::read(path),
        Format::Dicom => dicom::read_file(path),
        Format::DicomSeries => dicom::read_series(path, opts.uneven_slices),
        Format::SliceFolder => slices::read(path),
        Format::Hgt => hgt::read(path),
        Format::Asc => asc::read(path),
        Format::R16 => raw::read_r16(path, opts.raw.as_ref()),
        Format::R32 => raw::read_r32(path, opts.raw.as_ref()),
        Format::Raw => match &opts.raw {
            Some(spec) => raw::read(path, spec),
            None => Err(Error::parameter(
                "raw layout",
                "none given",
                "--dims WxH[xD] and --dtype for a headerless .raw file",
            )),
        },
    }
}

/// Write `r` in the format the extension of `path` names; the file appears only when
/// complete (written to a temporary file in the same folder, then renamed).
pub fn write(path: &Path, r: &Raster) -> Result<()> {
    write_with(path, r, &WriteOptions::default())
}

/// [`write()`] with options.
pub fn write_with(path: &Path, r: &Raster, opts: &WriteOptions) -> Result<()> {
    let format = Format::from_extension(path).ok_or_else(|| {
        Error::parameter(
            "output extension",
            path.display(),
            "one of .png .jpg .tif .pgm .ppm .pam .exr .nrrd .nhdr .nii .nii.gz .hgt .asc .r16 .r32 .raw",
        )
    })?;
    let n = bytes::sample_count(&r.dims, r.channels)?;
    if n != r.samples.len() {
        return Err(Error::format(
            format!(
                "{} samples for dims {:?} × {} channels",
                r.samples.len(),
                r.dims,
                r.channels
            ),
            "dims × channels samples",
        ));
    }
    match format {
        Format::Png => bytes::atomic_write(path, |w| png::write(w, r)),
        Format::Pnm => bytes::atomic_write(path, |w| pnm::write(w, r)),
        Format::Tiff => bytes::atomic_write(path, |w| tiff::write(w, r, opts.compress)),
        Format::Exr => bytes::atomic_write(path, |w| exr::write(w, r)),
        Format::Nrrd => nrrd::write_path(path, r, opts.compress),
        Format::Nifti => nifti::write_path(path, r),
        Format::Hgt => bytes::atomic_write(path, |w| hgt::write(w, r)),
        Format::Asc => bytes::atomic_write(path, |w| asc::write(w, r)),
        Format::R16 => bytes::atomic_write(path, |w| raw::write_r16(w, r)),
        Format::R32 => bytes::atomic_write(path, |w| raw::write_r32(w, r)),
        Format::Raw => bytes::atomic_write(path, |w| raw::write(w, r, false)),
        Format::Jpeg => bytes::atomic_write(path, |w| jpeg::write(w, r, jpeg::DEFAULT_QUALITY)),
        Format::Dicom | Format::DicomSeries | Format::SliceFolder => Err(Error::Unsupported {
            what: "output format",
            value: format!("{} is read only", format.name()),
        }),
    }
}
