//! The `HEAD` chunk: what the data is and how it was coded (formats/MRA.md §4).

use super::{Cursor, Version};
use crate::io::{DataKind, SampleType};
use crate::scheme::{Boundary, Scheme};
use crate::{Error, FormatError, Result};

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
    /// The format version (its capabilities: [`Version`]).
    pub version: Version,
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
    /// Format 3.0: the code-block extents, `2^x[k]` on axis `k` of every band (the
    /// `HEAD`'s last `N` bytes, §15); empty before 3.0.
    pub blocks: Vec<u8>,
    /// Format 3.1: the id of the block coder of every code-block (the `HEAD`'s last
    /// byte, §15.1, one of [`CODERS`]); 0 (today's context coder) before 3.1.
    pub coder: u8,
}

/// The block coders of format 3.1 by id (formats/MRA.md §15.1): 0 the adaptive context
/// coder of §9 (every 3.0 file's), 1 the HT-style coder of §15.2, 2 the adaptive quad
/// coder of §15.4 (format 3.2). A reader rejects any other id, and an id its file's
/// version does not have ([`Version::has_coder`]). `entropy::codeblocks::Coder` holds the coders under these ids.
pub const CODERS: [&str; 3] = ["context", "ht", "adaptive"];

/// The name of block coder `id` ([`CODERS`]); `None` for an id no reader knows.
pub fn coder_name(id: u8) -> Option<&'static str> {
    CODERS.get(id as usize).copied()
}

/// Format 3.2's floor on a code-block exponent of a raster of 1 or 2 axes (§15.3):
/// blocks shrink from the third level to 32 samples a side, not below.
pub const BLOCK_FLOOR_2D: u8 = 5;
/// Format 3.2's floor on a code-block exponent of a raster of 3 or 4 axes (§15.3):
/// blocks shrink from the second level to 16 samples a side.
pub const BLOCK_FLOOR_3D: u8 = 4;

pub const MAX_AXES: usize = 4;
pub const MAX_CHANNELS: usize = 256;
pub const MAX_LEVELS: usize = 32;

/// The mode byte: lossless files whose float samples are coded as integer multiples of
/// the quantum δ > 0 get their own code (3, `scaled`), which readers before it reject
/// instead of reading the integers as float bit patterns.
pub fn mode_code(m: Mode, scaled: bool) -> u8 {
    match m {
        Mode::Lossless if scaled => 3,
        m => m as u8,
    }
}

/// The mode of a mode byte and whether it is the scaled lossless code (3).
pub fn mode_of(code: u8) -> Option<(Mode, bool)> {
    Some(match code {
        0 => (Mode::Lossy, false),
        1 => (Mode::Lossless, false),
        2 => (Mode::MaxError, false),
        3 => (Mode::Lossless, true),
        _ => return None,
    })
}

/// The name of a mode byte's meaning (formats/MRA.md §4.1).
pub fn mode_name(m: Mode, scaled: bool) -> &'static str {
    match (m, scaled) {
        (Mode::Lossy, _) => "lossy",
        (Mode::Lossless, false) => "lossless",
        (Mode::Lossless, true) => "lossless-scaled",
        (Mode::MaxError, _) => "max-error",
    }
}

impl Mode {
    pub const ALL: [Mode; 3] = [Mode::Lossy, Mode::Lossless, Mode::MaxError];
}

impl Colour {
    pub const ALL: [Colour; 3] = [Colour::None, Colour::YCoCg, Colour::YCoCgR];

    /// The colour byte.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The colour transform of a colour byte.
    pub fn of(code: u8) -> Option<Colour> {
        Colour::ALL.into_iter().find(|c| c.code() == code)
    }

    pub fn name(self) -> &'static str {
        match self {
            Colour::None => "none",
            Colour::YCoCg => "ycocg",
            Colour::YCoCgR => "ycocg-r",
        }
    }
}

/// The data kinds in code order.
pub const KINDS: [DataKind; 4] = [
    DataKind::Image,
    DataKind::Volume,
    DataKind::Heightmap,
    DataKind::Sequence,
];

/// The kind byte.
pub fn kind_code(k: DataKind) -> u8 {
    KINDS
        .iter()
        .position(|&x| x == k)
        .expect("every kind has a code") as u8
}

/// The data kind of a kind byte.
pub fn kind_of(code: u8) -> Option<DataKind> {
    KINDS.get(code as usize).copied()
}

/// The name of a data kind.
pub fn kind_name(k: DataKind) -> &'static str {
    match k {
        DataKind::Image => "image",
        DataKind::Volume => "volume",
        DataKind::Heightmap => "heightmap",
        DataKind::Sequence => "sequence",
    }
}

/// The sample types in code order: `SampleType::ALL` lists them in that order
/// (`format_spec::spec_tables_match_the_code` checks the codes against the spec).
pub const TYPES: [SampleType; 9] = SampleType::ALL;

/// The sample-type byte.
pub fn sample_type_code(t: SampleType) -> u8 {
    TYPES
        .iter()
        .position(|&x| x == t)
        .expect("every type has a code") as u8
}

/// The sample type of a sample-type byte.
pub fn sample_type_of(code: u8) -> Option<SampleType> {
    TYPES.get(code as usize).copied()
}

/// The scheme byte.
pub fn scheme_code(s: Scheme) -> u8 {
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

/// The scheme of a scheme byte.
pub fn scheme_of(code: u8) -> Option<Scheme> {
    Scheme::ALL.into_iter().find(|&s| scheme_code(s) == code)
}

/// The boundary byte.
pub fn boundary_code(b: Boundary) -> u8 {
    match b {
        Boundary::Interpolating => 0,
        Boundary::Periodic => 1,
        Boundary::Symmetric => 2,
    }
}

/// The boundary of a boundary byte.
pub fn boundary_of(code: u8) -> Option<Boundary> {
    Boundary::ALL
        .into_iter()
        .find(|&b| boundary_code(b) == code)
}

fn bad(what: String, expected: &'static str) -> Error {
    FormatError::invalid(what, expected)
}

impl Header {
    /// Number of samples the header declares (checked for overflow).
    pub fn samples(&self) -> Result<u64> {
        let mut n = self.channels as u64;
        for &d in &self.dims {
            n = n.checked_mul(d as u64).ok_or_else(|| {
                FormatError::budget("sample count", u64::MAX, crate::io::MAX_SAMPLES)
            })?;
        }
        Ok(n)
    }

    /// Whether the file is split into more than one tile (format 2.1, formats/MRA.md §14).
    pub fn is_tiled(&self) -> bool {
        self.tile != self.dims
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = vec![self.version.major, self.version.minor, kind_code(self.kind)];
        b.push(sample_type_code(self.sample_type));
        b.push(self.dims.len() as u8);
        for &d in &self.dims {
            b.extend_from_slice(&(d as u32).to_le_bytes());
        }
        b.extend_from_slice(&(self.channels as u16).to_le_bytes());
        b.push(self.colour.code());
        b.push(mode_code(self.mode, self.delta > 0.0));
        b.push(scheme_code(self.scheme));
        b.push(boundary_code(self.boundary));
        b.push(self.levels as u8);
        for v in [self.step, self.delta, self.max_error, self.min, self.max] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for &t in &self.tile {
            b.extend_from_slice(&(t as u32).to_le_bytes());
        }
        if self.version.has_head_flags() {
            b.push(self.voids as u8);
        }
        if self.version.has_blocks() {
            b.extend_from_slice(&self.blocks);
        }
        if self.version.has_coder_choice() {
            b.push(self.coder);
        }
        b
    }

    /// The code-block extents of a format 3.0 file (`2^x[k]` per axis), empty before:
    /// the finest level's ([`Header::block_extents_at`] gives every level's).
    pub fn block_extents(&self) -> Vec<usize> {
        self.blocks.iter().map(|&x| 1usize << x.min(31)).collect()
    }

    /// The code-block extents of the bands of level `level` (1 the finest detail level;
    /// the coarse block counts as the coarsest detail level, 0 as 1), formats/MRA.md
    /// §15.3: from format 3.2, `2^max(min(x, f), x − max(0, level − s))` on an axis of
    /// `HEAD` exponent `x`: for 1 or 2 axes `(f, s)` = ([`BLOCK_FLOOR_2D`], 2) (the two
    /// finest levels at `2^x`), for more ([`BLOCK_FLOOR_3D`], 1); before 3.2, `2^x` at
    /// every level. Empty before 3.0.
    pub fn block_extents_at(&self, level: usize) -> Vec<usize> {
        if !self.version.has_level_blocks() {
            return self.block_extents();
        }
        let (f, s) = if self.blocks.len() <= 2 {
            (BLOCK_FLOOR_2D, 2)
        } else {
            (BLOCK_FLOOR_3D, 1)
        };
        let shrink = level.saturating_sub(s).min(31) as u8;
        self.blocks
            .iter()
            .map(|&x| {
                let x = x.min(31);
                1usize << x.min(f).max(x.saturating_sub(shrink))
            })
            .collect()
    }

    /// Parse and validate a `HEAD` payload.
    pub fn parse(payload: &[u8]) -> Result<Header> {
        let mut c = Cursor::new(payload, "HEAD");
        let version = Version::new(c.u8()?, c.u8()?).check()?;
        let k = c.u8()?;
        let kind = kind_of(k).ok_or_else(|| {
            bad(
                format!("data kind {k}"),
                "0 image, 1 volume, 2 heightmap, 3 sequence",
            )
        })?;
        let t = c.u8()? as usize;
        let sample_type = sample_type_of(t as u8).ok_or_else(|| {
            bad(
                format!("sample type code {t}"),
                "0..8 (u8 i8 u16 i16 u32 i32 f16 f32 f64)",
            )
        })?;
        let dims = extents(&mut c)?;
        let channels = c.u16()? as usize;
        if channels == 0 || channels > MAX_CHANNELS {
            return Err(bad(format!("{channels} channels"), "1 to 256 channels"));
        }
        let k = c.u8()?;
        let colour = Colour::of(k).ok_or_else(|| {
            bad(
                format!("colour transform {k}"),
                "0 none, 1 YCoCg, 2 YCoCg-R",
            )
        })?;
        if colour != Colour::None && channels < 3 {
            return Err(bad(
                format!("colour transform on {channels} channels"),
                "3 or more channels",
            ));
        }
        let code = c.u8()?;
        let (mode, _) = mode_of(code).ok_or_else(|| {
            bad(
                format!("mode {code}"),
                "0 lossy, 1 lossless, 2 max-error, 3 lossless scaled floats",
            )
        })?;
        let k = c.u8()?;
        let scheme = scheme_of(k).ok_or_else(|| {
            bad(
                format!("scheme {k}"),
                "0 haar, 1 chaikin, 2 cubic, 3 linear, 4 chaikin-wide, 5 cubic-wide, 6 cdf97, 7 linear-wide",
            )
        })?;
        let k = c.u8()?;
        let boundary = boundary_of(k).ok_or_else(|| {
            bad(
                format!("boundary {k}"),
                "0 interpolating, 1 periodic, 2 symmetric",
            )
        })?;
        let levels = c.u8()? as usize;
        if levels > MAX_LEVELS {
            return Err(bad(format!("{levels} levels"), "at most 32 levels"));
        }
        let [step, delta, max_error, min, max] = reals(&mut c, mode, code, sample_type)?;
        let tile = tiles(&mut c, version, &dims)?;
        let voids = if version.has_head_flags() {
            match c.u8()? {
                f @ 0..=1 => f == 1,
                f => return Err(bad(format!("HEAD flags {f:#04x}"), "bit 0 alone (voids)")),
            }
        } else {
            false
        };
        let blocks = if version.has_blocks() {
            block_exponents(&mut c, dims.len())?
        } else {
            Vec::new()
        };
        let coder = if version.has_coder_choice() {
            let id = c.u8()?;
            if coder_name(id).is_none() || !version.has_coder(id) {
                return Err(bad(
                    format!("block coder {id} in a {version} file"),
                    "0 context, 1 ht (3.1 and later), 2 adaptive (3.2 and later) (formats/MRA.md §15.1)",
                ));
            }
            id
        } else {
            0
        };
        Ok(Header {
            version,
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
            blocks,
            coder,
        })
    }
}

/// The code-block exponents of a 3.0 `HEAD`: one byte per axis, each at most 31.
fn block_exponents(c: &mut Cursor, nd: usize) -> Result<Vec<u8>> {
    let x = c.take(nd)?.to_vec();
    if let Some(&e) = x.iter().find(|&&e| e > 31) {
        return Err(bad(
            format!("code-block extent 2^{e}"),
            "block extents 2^0 to 2^31",
        ));
    }
    Ok(x)
}

/// The axis count and extents of `HEAD`: 1 to 4 axes, each extent ≥ 1.
fn extents(c: &mut Cursor) -> Result<Vec<usize>> {
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
    Ok(dims)
}

/// The five reals of `HEAD` (base step, δ, error bound, min, max), checked: a positive
/// finite step, finite values with `min ≤ max` and a bound ≥ 0, and the δ of the
/// lossless modes (mode 1: 0; mode 3: float samples, δ the quantum, a power of two).
fn reals(c: &mut Cursor, mode: Mode, code: u8, sample_type: SampleType) -> Result<[f64; 5]> {
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
    if mode == Mode::Lossless {
        let quantum = delta > 0.0 && delta.log2().fract() == 0.0 && sample_type.is_float();
        if (code == 3) != quantum || (code == 1 && delta != 0.0) {
            return Err(bad(
                format!("lossless mode {code} with δ {delta} on {sample_type:?} samples"),
                "mode 1 with δ = 0, or mode 3 with float samples and δ a power of two",
            ));
        }
    }
    Ok([step, delta, max_error, min, max])
}

/// The tile extents of `HEAD` for a raster of `dims`, checked: the raster's own (one
/// tile), or from 1 to each axis extent in a version with tiles.
fn tiles(c: &mut Cursor, version: Version, dims: &[usize]) -> Result<Vec<usize>> {
    let nd = dims.len();
    let mut tile = Vec::with_capacity(nd);
    for _ in 0..nd {
        tile.push(c.u32()? as usize);
    }
    if tile != dims {
        if !version.has_tiles() {
            return Err(Error::Unsupported {
                what: "tile grid",
                value: format!(
                    "tiles {tile:?} of {dims:?} in a {version} file (tiles need 2.1 to 2.x)"
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
    Ok(tile)
}
