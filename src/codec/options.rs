//! What the encoder and decoder are asked to do: the rate mode and the options of
//! each side, and what a decode returns.

use crate::entropy::codeblocks::Coder;
use crate::format::Header;
use crate::io::Raster;
use crate::scheme::{Boundary, Scheme};

/// How to spend bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rate {
    /// Keep the largest P percent of the (gain-weighted) details.
    Keep(f64),
    /// Zero the details whose gain-weighted magnitude is below T.
    Threshold(f64),
    /// 1..100: step `Δ = (max − min) · 2^(−Q/10)`.
    Quality(f64),
    /// Target PSNR in dB (skimage convention of `mra compare`).
    Psnr(f64),
    /// Target PSNR in dB with the peak-to-peak data range `R` of
    /// `PSNR = 10 log10(R² / MSE)` given (as `mra compare --data-range R`).
    PsnrRange(f64, f64),
    /// Target bits per position (pixel / voxel), all channels together.
    Bpp(f64),
    /// Every decoded sample within E of the source.
    MaxError(f64),
    /// Bit-exact.
    Lossless,
}

/// The layout a one-piece file is written in (formats/MRA.md §3). Tiled files are
/// format 2 whatever this says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Format {
    /// Format 3.0: every band cut into independent code-blocks (§15), coded and decoded
    /// in parallel, a region decoding only the blocks it meets. The default.
    #[default]
    Blocks,
    /// Format 2.x: one stream per band, for readers that predate format 3.
    Bands,
}

impl Format {
    /// The layout of major format version `major` (2 or 3).
    pub fn of_major(major: usize) -> crate::Result<Format> {
        match major {
            3 => Ok(Format::Blocks),
            2 => Ok(Format::Bands),
            _ => Err(crate::Error::parameter(
                "format",
                major,
                "2 (one stream per band) or 3 (code-blocks)",
            )),
        }
    }
}

/// The effort of [`EncodeOptions::default`], of `mra encode` without `--effort` and of
/// Python's `encode`: the adaptive quad coder (coder 2) on its own rate–distortion
/// choice, within issue 48's ratio target of the context coder (Kodak BD-PSNR at most
/// 0.15 dB below effort 7's); `--lossless` keeps the context coder here
/// ([`Ladder::lossless`]), so the default's lossless files are those of effort 7.
pub const DEFAULT_EFFORT: u8 = 4;

/// The efforts the encoder takes: 1 (fastest) to 9 (smallest file).
pub const EFFORTS: std::ops::RangeInclusive<u8> = 1..=9;

/// What an effort level makes the encoder do (docs/codec.md "The effort ladder").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ladder {
    /// The block coder of a code-block file (format 3.1 when not the context coder);
    /// a narrow coder ([`Coder::is_narrow`]) only for samples of 16 bits or fewer in
    /// modes lossy and lossless, whose indices fit `i32`.
    pub coder: Coder,
    /// The block coder of a `--lossless` code-block file: [`Ladder::coder`] but at
    /// efforts 4–6, where it is the context coder (coder 2's lossless files are 0.9%
    /// longer than the context coder's on Kodak and 2.5% on 16-bit photographs, over
    /// issue 48's 1%), so the default effort's lossless files are effort 7's. A
    /// `--max-error` file is coded by the context coder at every effort.
    pub lossless: Coder,
    /// Whether `--quality`, `--psnr` and `--bpp` choose the indices by
    /// rate–distortion optimisation (else deadzone quantization, reconstruction offset
    /// δ).
    pub rdo: bool,
    /// `--bpp` accepts a file within this share under the budget (`0.99`: 1% under).
    pub bpp_floor: f64,
    /// Whether `--bpp` chooses the number of levels per file (effort 9): `--levels`
    /// is then the most, and the file of [`BPP_LEVEL_CHOICES`] counts from it down with
    /// the least squared error is kept.
    pub bpp_levels: bool,
}

/// How many level counts `--bpp` tries at effort 9: `--levels` and the ones below it,
/// down to 1 (each a whole encode).
pub const BPP_LEVEL_CHOICES: usize = 5;

impl Ladder {
    /// Effort `e` (clamped to [`EFFORTS`]): 1–3 the HT coder without RDO, `--bpp`
    /// within 3% under the budget; 4–6 the adaptive coder (coder 2) on RDO indices
    /// chosen by its own costs (`block::encode_rdo`); 7–9 the context coder on RDO
    /// indices (the files of before the ladder); 9 also chooses `--bpp`'s number of
    /// levels per file.
    pub fn of(e: u8) -> Ladder {
        let e = e.clamp(*EFFORTS.start(), *EFFORTS.end());
        Ladder {
            coder: match e {
                ..=3 => Coder::Ht,
                4..=6 => Coder::Adaptive,
                _ => Coder::Context,
            },
            lossless: match e {
                ..=3 => Coder::Ht,
                _ => Coder::Context,
            },
            rdo: e >= 4,
            bpp_floor: if e <= 3 { 0.97 } else { 0.99 },
            bpp_levels: e >= 9,
        }
    }
}

/// Encoder settings.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeOptions {
    pub scheme: Scheme,
    pub boundary: Boundary,
    pub levels: usize,
    pub rate: Rate,
    /// The layout of a one-piece file.
    pub format: Format,
    /// 1..=9: speed against size ([`Ladder::of`]); [`DEFAULT_EFFORT`] by default.
    pub effort: u8,
}

impl EncodeOptions {
    /// Is the file bit-exact (`--lossless`, or `--max-error 0`)? Then every sample keeps
    /// its bits, NaN payloads included.
    pub(crate) fn keeps_bits(&self) -> bool {
        matches!(self.rate, Rate::Lossless) || self.rate == Rate::MaxError(0.0)
    }

    /// These options with one-piece files written as format 2 (what every tile of a
    /// tiled file is).
    pub fn ladder(&self) -> Ladder {
        Ladder::of(self.effort)
    }

    pub(crate) fn in_bands(&self) -> EncodeOptions {
        EncodeOptions {
            format: Format::Bands,
            ..self.clone()
        }
    }
}

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions {
            scheme: Scheme::Cdf97,
            boundary: Boundary::Symmetric,
            levels: 6,
            rate: Rate::Quality(50.0),
            format: Format::Blocks,
            effort: DEFAULT_EFFORT,
        }
    }
}

/// Decoder settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DecodeOptions {
    /// Reconstruct at 1/2^level resolution, reading only the chunks needed; a level the
    /// file does not hold (over its depth) is [`crate::Error::Level`].
    pub level: usize,
    /// Decode what a truncated file holds instead of failing.
    pub allow_truncated: bool,
    /// Decode only this box, a range per spatial axis, slowest axis first (as `dims` and
    /// every dimension list of the library: z, y, x), in full-resolution samples; at
    /// `level` k the output holds the level's samples whose cells meet it
    /// (`⌊g0·R/d⌋ .. ⌈g1·R/d⌉` on an axis of extent d and R at level k). A tiled file is
    /// read only where its tiles meet the box.
    pub region: Option<Vec<std::ops::Range<usize>>>,
}

/// A decoded file.
#[derive(Clone, Debug)]
pub struct Decoded {
    pub raster: Raster,
    pub header: Header,
    /// False when the file ended before its `MEND` chunk (only with `allow_truncated`).
    pub complete: bool,
}
