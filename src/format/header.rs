//! The `HEAD` chunk: what the data is and how it was coded (formats/MRA.md §4).

use super::{Cursor, LATEST_MINOR, MAJOR, MINOR_VOIDS, OLDEST_MAJOR};
use crate::io::{DataKind, SampleType};
use crate::scheme::{Boundary, Scheme};
use crate::{Error, Result};

/// How the coefficients were produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Real-valued transform, dead-zone quantization.
    Lossy = 0,
    /// Integer S-transform (reversible Haar), exact.
    Lossless = 1,
    /// Lossy base plus a spatial residual layer bounding every sample's error.
    MaxError = 2,
}

/// Colour transform applied to channels 0..3 before the spatial transform.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colour {
    None = 0,
    /// YCoCg-R lifting in real arithmetic (lossy modes).
    YCoCg = 1,
    /// YCoCg-R lifting in integers (lossless).
    YCoCgR = 2,
}

/// Everything the `HEAD` chunk holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub major: u8,
    pub minor: u8,
    pub kind: DataKind,
    pub sample_type: SampleType,
    /// Spatial extents, slowest first (1 to 4 axes).
    pub dims: Vec<usize>,
    pub channels: usize,
    pub colour: Colour,
    pub mode: Mode,
    /// Scheme of the real-valued transform (ignored when `mode` is lossless).
    pub scheme: Scheme,
    pub boundary: Boundary,
    /// Requested levels (each axis does what its length allows).
    pub levels: usize,
    /// The base quantizer step Δ (informative; every band carries its own step).
    pub step: f64,
    /// Reconstruction offset δ of detail bands.
    pub delta: f64,
    /// The guaranteed bound of mode MaxError, else 0.
    pub max_error: f64,
    /// Smallest and largest source sample (finite values); decoded values are clamped.
    pub min: f64,
    pub max: f64,
    /// Tile extents (equal to `dims`: one tile).
    pub tile: Vec<usize>,
    /// Whether the `mETA` lists void samples (`extra.nodata.voids`): bit 0 of the flags
    /// byte of 2.4 and later (false before). A reader refuses a file that says so and
    /// has no such list.
    pub voids: bool,
}

pub const MAX_AXES: usize = 4;
pub const MAX_CHANNELS: usize = 256;
pub const MAX_LEVELS: usize = 32;

/// The mode byte: lossless files whose float samples are coded as integer multiples of
/// the quantum δ > 0 get their own code (3), which readers before it reject instead of
/// reading the integers as float bit patterns.
fn mode_code(m: Mode, delta: f64) -> u8 {
    match m {
        Mode::Lossless if delta > 0.0 => 3,
        m => m as u8,
    }
}

fn kind_code(k: DataKind) -> u8 {
    match k {
        DataKind::Image => 0,
        DataKind::Volume => 1,
        DataKind::Heightmap => 2,
        DataKind::Sequence => 3,
    }
}

const TYPES: [SampleType; 9] = [
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

fn scheme_code(s: Scheme) -> u8 {
    match s {
        Scheme::Haar => 0,
        Scheme::Chaikin => 1,
        Scheme::Cubic => 2,
        Scheme::Linear => 3,
        Scheme::ChaikinWide => 4,
        Scheme::CubicWide => 5,
        Scheme::Cdf97 => 6,
        Scheme::LinearWide => 7,
    }
}

fn boundary_code(b: Boundary) -> u8 {
    match b {
        Boundary::Interpolating => 0,
        Boundary::Periodic => 1,
        Boundary::Symmetric => 2,
    }
}

fn bad(what: String, expected: &'static str) -> Error {
    Error::format(what, expected)
}

impl Header {
    /// Number of samples the header declares (checked for overflow).
    pub fn samples(&self) -> Result<u64> {
        let mut n = self.channels as u64;
        for &d in &self.dims {
            n = n.checked_mul(d as u64).ok_or(Error::LimitsExceeded {
                what: "sample count",
                requested: u64::MAX,
                limit: crate::io::MAX_SAMPLES,
            })?;
        }
        Ok(n)
    }

    /// Whether the file is split into more than one tile (format 2.1, formats/MRA.md §14).
    pub fn is_tiled(&self) -> bool {
        self.tile != self.dims
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = vec![self.major, self.minor, kind_code(self.kind)];
        b.push(TYPES.iter().position(|&t| t == self.sample_type).unwrap() as u8);
        b.push(self.dims.len() as u8);
        for &d in &self.dims {
            b.extend_from_slice(&(d as u32).to_le_bytes());
        }
        b.extend_from_slice(&(self.channels as u16).to_le_bytes());
        b.push(self.colour as u8);
        b.push(mode_code(self.mode, self.delta));
        b.push(scheme_code(self.scheme));
        b.push(boundary_code(self.boundary));
        b.push(self.levels as u8);
        for v in [self.step, self.delta, self.max_error, self.min, self.max] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for &t in &self.tile {
            b.extend_from_slice(&(t as u32).to_le_bytes());
        }
        if self.has_flags() {
            b.push(self.voids as u8);
        }
        b
    }

    /// Whether `HEAD` ends with the flags byte (2.4 and later).
    fn has_flags(&self) -> bool {
        self.major == MAJOR && self.minor >= MINOR_VOIDS
    }

    /// Parse and validate a `HEAD` payload.
    pub fn parse(payload: &[u8]) -> Result<Header> {
        let mut c = Cursor::new(payload, "HEAD");
        let major = c.u8()?;
        let minor = c.u8()?;
        if !(OLDEST_MAJOR..=MAJOR).contains(&major) {
            return Err(Error::Unsupported {
                what: "format version",
                value: format!(
                    "{major}.{minor} (this reader implements {OLDEST_MAJOR}.x to {MAJOR}.x)"
                ),
            });
        }
        if major == MAJOR && minor > LATEST_MINOR {
            return Err(Error::Unsupported {
                what: "format version",
                value: format!(
                    "{major}.{minor} (this reader implements {MAJOR}.0 to {MAJOR}.{LATEST_MINOR})"
                ),
            });
        }
        let kind = match c.u8()? {
            0 => DataKind::Image,
            1 => DataKind::Volume,
            2 => DataKind::Heightmap,
            3 => DataKind::Sequence,
            k => {
                return Err(bad(
                    format!("data kind {k}"),
                    "0 image, 1 volume, 2 heightmap, 3 sequence",
                ))
            }
        };
        let t = c.u8()? as usize;
        let sample_type = *TYPES.get(t).ok_or_else(|| {
            bad(
                format!("sample type code {t}"),
                "0..8 (u8 i8 u16 i16 u32 i32 f16 f32 f64)",
            )
        })?;
        let nd = c.u8()? as usize;
        if nd == 0 || nd > MAX_AXES {
            return Err(bad(format!("{nd} axes"), "1 to 4 axes"));
        }
        let mut dims = Vec::with_capacity(nd);
        for _ in 0..nd {
            let d = c.u32()? as usize;
            if d == 0 {
                return Err(bad("an axis of extent 0".into(), "extents ≥ 1"));
            }
            dims.push(d);
        }
        let channels = c.u16()? as usize;
        if channels == 0 || channels > MAX_CHANNELS {
            return Err(bad(format!("{channels} channels"), "1 to 256 channels"));
        }
        let colour = match c.u8()? {
            0 => Colour::None,
            1 => Colour::YCoCg,
            2 => Colour::YCoCgR,
            k => {
                return Err(bad(
                    format!("colour transform {k}"),
                    "0 none, 1 YCoCg, 2 YCoCg-R",
                ))
            }
        };
        if colour != Colour::None && channels < 3 {
            return Err(bad(
                format!("colour transform on {channels} channels"),
                "3 or more channels",
            ));
        }
        let code = c.u8()?;
        let mode = match code {
            0 => Mode::Lossy,
            1 | 3 => Mode::Lossless,
            2 => Mode::MaxError,
            k => {
                return Err(bad(
                    format!("mode {k}"),
                    "0 lossy, 1 lossless, 2 max-error, 3 lossless scaled floats",
                ))
            }
        };
        let scheme =
            match c.u8()? {
                0 => Scheme::Haar,
                1 => Scheme::Chaikin,
                2 => Scheme::Cubic,
                3 => Scheme::Linear,
                4 => Scheme::ChaikinWide,
                5 => Scheme::CubicWide,
                6 => Scheme::Cdf97,
            7 => Scheme::LinearWide,
                k => return Err(bad(
                    format!("scheme {k}"),
                    "0 haar, 1 chaikin, 2 cubic, 3 linear, 4 chaikin-wide, 5 cubic-wide, 6 cdf97, 7 linear-wide",
                )),
            };
        let boundary = match c.u8()? {
            0 => Boundary::Interpolating,
            1 => Boundary::Periodic,
            2 => Boundary::Symmetric,
            k => {
                return Err(bad(
                    format!("boundary {k}"),
                    "0 interpolating, 1 periodic, 2 symmetric",
                ))
            }
        };
        let levels = c.u8()? as usize;
        if levels > MAX_LEVELS {
            return Err(bad(format!("{levels} levels"), "at most 32 levels"));
        }
        let step = c.f64()?;
        if !(step > 0.0 && step.is_finite()) {
            // every band's step is this one times its ratio
            return Err(bad(format!("base step Δ {step}"), "a positive finite step"));
        }
        let delta = c.f64()?;
        let max_error = c.f64()?;
        let min = c.f64()?;
        let max = c.f64()?;
        if !(min.is_finite()
            && max.is_finite()
            && min <= max
            && delta.is_finite()
            && max_error.is_finite()
            && max_error >= 0.0)
        {
            return Err(bad(
                format!("range {min}..{max}, δ {delta}, bound {max_error}"),
                "finite values with min ≤ max",
            ));
        }
        // mode 3: float samples, δ the quantum (a power of two); mode 1: δ = 0
        if mode == Mode::Lossless {
            let quantum = delta > 0.0 && delta.log2().fract() == 0.0 && sample_type.is_float();
            if (code == 3) != quantum || (code == 1 && delta != 0.0) {
                return Err(bad(
                    format!("lossless mode {code} with δ {delta} on {sample_type:?} samples"),
                    "mode 1 with δ = 0, or mode 3 with float samples and δ a power of two",
                ));
            }
        }
        let mut tile = Vec::with_capacity(nd);
        for _ in 0..nd {
            tile.push(c.u32()? as usize);
        }
        if tile != dims {
            if major < 2 || minor < 1 {
                return Err(Error::Unsupported {
                    what: "tile grid",
                    value: format!(
                        "tiles {tile:?} of {dims:?} in a {major}.{minor} file (tiles need 2.1)"
                    ),
                });
            }
            if let Some(k) = (0..nd).find(|&k| tile[k] == 0 || tile[k] > dims[k]) {
                return Err(bad(
                    format!("tile extent {} on axis {k} of extent {}", tile[k], dims[k]),
                    "tile extents from 1 to the axis extent",
                ));
            }
        }
        let voids = if major == MAJOR && minor >= MINOR_VOIDS {
            match c.u8()? {
                f @ 0..=1 => f == 1,
                f => return Err(bad(format!("HEAD flags {f:#04x}"), "bit 0 alone (voids)")),
            }
        } else {
            false
        };
        Ok(Header {
            major,
            minor,
            kind,
            sample_type,
            dims,
            channels,
            colour,
            mode,
            scheme,
            boundary,
            levels,
            step,
            delta,
            max_error,
            min,
            max,
            tile,
            voids,
        })
    }
}
