//! One-dimensional multiresolution schemes (§9) and subdivision (§7).
//!
//! A [`TwoScale`] level maps a lane of `m` fine elements to `n` coarse elements and
//! `m − n` details (`C = A F`, `D = B F`) and back (`F = P C + Q D`), for any length
//! `m ≥ 1` and any element width (scalars, points, whole rows).

/// A scheme module's `REGULAR` (its filters `A`, `B`, `P`, `Q` placed at the first taps
/// `[a, b, p, q]`, as the module's comment shows) and `OPEN` (interpolating ends: the
/// open B-spline `open_ends::$spline` (`$name`) as `P`, with the module's derived start
/// blocks `A_START`, `B_START`, `Q_START` and its `MIN_INTERPOLATING`). Defined before
/// the scheme modules, which see it by textual scope.
macro_rules! regular_and_open {
    ([$a:expr, $b:expr, $p:expr, $q:expr], $spline:ident, $name:literal) => {
        /// The regular filters placed as in the comment above.
        pub const REGULAR: RegularFilters = RegularFilters {
            a: Taps { w: &A, first: $a },
            b: Taps { w: &B, first: $b },
            p: Taps { w: &P, first: $p },
            q: Taps { w: &Q, first: $q },
        };

        #[doc = concat!("Interpolating ends: the open ", $name, " B-spline `P` with derived start blocks.")]
        pub const OPEN: OpenEnds = OpenEnds {
            spline: &open_ends::$spline,
            a: &A,
            b: &B,
            q: &Q,
            a_start: A_START,
            b_start: B_START,
            q_start: Q_START,
            min_len: MIN_INTERPOLATING,
        };
    };
}

pub mod cdf97;
pub mod chaikin;
pub mod chaikin_wide;
pub mod cubic;
pub mod cubic_wide;
pub mod haar;
pub mod lane;
pub mod linear;
pub mod linear_wide;
pub mod open_ends;
pub mod regular;
pub mod sample;
pub mod sparse;
pub mod subdivide;
mod two_scale;

pub use lane::{analyze_lane, synthesize_lane, LanePyramid};
pub use sample::{Build, Sample};
pub use two_scale::{lane_levels, max_levels, narrow_of, LevelKind, TwoScale};

use crate::Error;
use std::fmt;
use std::str::FromStr;

/// The multiresolution scheme: which B-spline's reverse subdivision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// Order-1 B-splines: averages and half-differences (§9.2).
    Haar,
    /// Quadratic B-spline (Chaikin), width-4 local filters (§9.5.1, §9.6).
    Chaikin,
    /// Cubic B-spline, width-7 local filters (§9.5.1).
    Cubic,
    /// Linear B-spline subdivision with the CDF 5/3 analysis (JPEG 2000's reversible pair).
    Linear,
    /// Linear B-spline subdivision with the window-9 least-squares analysis (CDF 9/3, bior2.4).
    #[serde(rename = "linear-wide")]
    LinearWide,
    /// Chaikin subdivision with the window-12 local least-squares analysis.
    #[serde(rename = "chaikin-wide")]
    ChaikinWide,
    /// Cubic B-spline subdivision with a window-19 least-squares analysis, 4 zeros at π.
    #[serde(rename = "cubic-wide")]
    CubicWide,
    /// CDF 9/7, the reference wavelet (not a B-spline synthesis).
    Cdf97,
}

/// What happens at the two ends of a lane.
///
/// ```text
/// interpolating   |F0 F1 F2 …        open ends, C_0 = F_0 and C_last = F_last (multiple knots)
/// periodic     … F6 F7 |F0 F1 … F7| F0 F1 …   closed curves, tileable data
/// symmetric    … F1 F0 |F0 F1 … | F7 F6 …     mirror extension of the regular filters
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Boundary {
    Interpolating,
    Periodic,
    Symmetric,
}

impl Scheme {
    pub const ALL: [Scheme; 8] = [
        Scheme::Haar,
        Scheme::Chaikin,
        Scheme::Cubic,
        Scheme::Linear,
        Scheme::LinearWide,
        Scheme::ChaikinWide,
        Scheme::CubicWide,
        Scheme::Cdf97,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Haar => "haar",
            Scheme::Chaikin => "chaikin",
            Scheme::Cubic => "cubic",
            Scheme::Linear => "linear",
            Scheme::LinearWide => "linear-wide",
            Scheme::ChaikinWide => "chaikin-wide",
            Scheme::CubicWide => "cubic-wide",
            Scheme::Cdf97 => "cdf97",
        }
    }
    /// The regular (interior) filters; `None` for Haar, whose rows are its own blocks.
    pub fn regular(self) -> Option<&'static regular::RegularFilters> {
        match self {
            Scheme::Haar => None,
            Scheme::Chaikin => Some(&chaikin::REGULAR),
            Scheme::Cubic => Some(&cubic::REGULAR),
            Scheme::Linear => Some(&linear::REGULAR),
            Scheme::LinearWide => Some(&linear_wide::REGULAR),
            Scheme::ChaikinWide => Some(&chaikin_wide::REGULAR),
            Scheme::CubicWide => Some(&cubic_wide::REGULAR),
            Scheme::Cdf97 => Some(&cdf97::REGULAR),
        }
    }

    /// Whether the synthesis `P` is B-spline subdivision (every scheme but CDF 9/7).
    pub fn is_bspline(self) -> bool {
        self != Scheme::Cdf97
    }
}

impl Boundary {
    pub const ALL: [Boundary; 3] = [
        Boundary::Interpolating,
        Boundary::Periodic,
        Boundary::Symmetric,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Boundary::Interpolating => "interpolating",
            Boundary::Periodic => "periodic",
            Boundary::Symmetric => "symmetric",
        }
    }
}

impl fmt::Display for Scheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
impl fmt::Display for Boundary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Scheme {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s.to_ascii_lowercase().as_str() {
            "haar" => Ok(Scheme::Haar),
            "chaikin" | "quadratic" => Ok(Scheme::Chaikin),
            "cubic" => Ok(Scheme::Cubic),
            "linear" | "cdf53" | "5/3" | "bior2.2" => Ok(Scheme::Linear),
            "linear-wide" | "cdf93" | "9/3" | "bior2.4" => Ok(Scheme::LinearWide),
            "chaikin-wide" | "quadratic-wide" => Ok(Scheme::ChaikinWide),
            "cubic-wide" => Ok(Scheme::CubicWide),
            "cdf97" | "9/7" | "bior4.4" => Ok(Scheme::Cdf97),
            _ => Err(Error::parameter(
                "scheme",
                s,
                "haar, chaikin, cubic, linear, linear-wide, chaikin-wide, cubic-wide or cdf97",
            )),
        }
    }
}

impl FromStr for Boundary {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s.to_ascii_lowercase().as_str() {
            "interpolating" | "open" => Ok(Boundary::Interpolating),
            "periodic" | "closed" => Ok(Boundary::Periodic),
            "symmetric" | "mirror" => Ok(Boundary::Symmetric),
            _ => Err(Error::parameter(
                "boundary",
                s,
                "interpolating, periodic or symmetric",
            )),
        }
    }
}
