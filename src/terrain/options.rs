//! The options of synthesis by example and detail transfer ([`super::synthesize`],
//! [`super::transfer`], [`super::transfer_volume`]): where the details come from, the
//! patches, the search and the gains.

use crate::scheme::Scheme;
use crate::{Error, Result};

/// Where the output's details come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Details {
    /// Patches matched by coarse neighbourhood (the method).
    Matched,
    /// The example's details copied at the same positions, without matching (a baseline).
    Copy,
    /// No details: the base refined by subdivision alone (a baseline).
    None,
}

impl std::str::FromStr for Details {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "matched" => Ok(Details::Matched),
            "copy" => Ok(Details::Copy),
            "none" => Ok(Details::None),
            _ => Err(Error::parameter("details", s, "matched, copy or none")),
        }
    }
}

/// Parameters of [`super::synthesize`] and [`super::transfer`].
#[derive(Clone, Debug, PartialEq)]
pub struct SynthOptions {
    /// Levels of refinement `L`.
    pub levels: usize,
    /// Chaikin (quadratic, the notes' choice for terrain) or cubic.
    pub scheme: Scheme,
    pub seed: u64,
    /// Output `(rows, columns)`; default base × 2^L.
    pub size: Option<(usize, usize)>,
    /// Patch core in coarse cells.
    pub patch: usize,
    /// Overlap on each side of a core, ≤ patch/2.
    pub overlap: usize,
    /// At most this many candidate windows per level.
    pub candidates: usize,
    /// Pick among this many best matches.
    pub choices: usize,
    /// Weight λ of the slope term.
    pub slope_weight: f64,
    pub details: Details,
    /// The example's cell ÷ the output's cell (the example is resampled by it first).
    pub example_scale: f64,
    /// Cap `c` of the relief gain: each patch's details are scaled by
    /// `min(c, (G_t + ε)/(G_e + ε))`, the mean coarse slope of the output's window over
    /// that of its source window (`ε` = 5 % of the example's mean), so that flat ground
    /// (sea, plains) gets no mountain detail; 0 turns it off.
    pub relief_cap: f64,
    /// Gain `g₁` of the finest details, `F = P C₁ + g₁ Q D₁` ([`super::synthesize`] only;
    /// [`super::transfer`] keeps `g₁ = 1`).
    pub finest_gain: FinestGain,
    /// The base is trusted down to `1/S` of the output's resolution and every finer level
    /// is synthesized ([`super::base_scale`]); 1 keeps the base at its own resolution.
    pub base_scale: usize,
}

/// How the finest details' gain `g₁` is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FinestGain {
    /// Fitted so that the result's spectral slope over the finest octave is the
    /// example's ([`super::spectrum`]), within [`super::spectrum::GAIN_RANGE`].
    Fitted,
    /// A fixed gain (1: the finest band at the example's RMS, as matched).
    Fixed(f64),
}

impl std::str::FromStr for FinestGain {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        if s == "fit" {
            return Ok(FinestGain::Fitted);
        }
        match s.parse::<f64>() {
            Ok(g) if g.is_finite() && (0.0..=8.0).contains(&g) => Ok(FinestGain::Fixed(g)),
            _ => Err(Error::parameter(
                "finest gain",
                s,
                "fit, or a gain from 0 to 8",
            )),
        }
    }
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            levels: 2,
            scheme: Scheme::Chaikin,
            seed: 1,
            size: None,
            patch: 8,
            overlap: 2,
            candidates: 16384,
            choices: 2,
            slope_weight: 1.0,
            details: Details::Matched,
            example_scale: 1.0,
            relief_cap: 0.0,
            finest_gain: FinestGain::Fitted,
            base_scale: 1,
        }
    }
}
