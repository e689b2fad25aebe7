//! One level of a scheme for a lane of any length, and the rule for lengths the
//! scheme's filters do not fit.
//!
//! **Length rule.** Each scheme × boundary has *native* lengths:
//!
//! | scheme  | interpolating        | periodic        | symmetric        |
//! |---------|----------------------|-----------------|------------------|
//! | haar    | even ≥ 2             | even ≥ 2        | even ≥ 2         |
//! | chaikin | even ≥ 8 (n = m/2+1) | even ≥ 4 (m/2)  | any ≥ 3 (⌊m/2⌋+1)|
//! | cubic   | odd ≥ 13 (n=(m+3)/2) | even ≥ 8 (m/2)  | any ≥ 3 (⌈m/2⌉)  |
//! | linear  | odd ≥ 5 (n=(m+1)/2)  | even ≥ 6 (m/2)  | any ≥ 3 (⌈m/2⌉)  |
//! | linear-wide | odd ≥ 17 ((m+1)/2) | even ≥ 10 (m/2) | any ≥ 3 (⌈m/2⌉) |
//! | chaikin-wide | even ≥ 22 (m/2+1) | even ≥ 12 (m/2) | any ≥ 3 (⌊m/2⌋+1) |
//! | cubic-wide | odd ≥ 35 ((m+3)/2) | even ≥ 20 (m/2) | any ≥ 3 (⌈m/2⌉) |
//! | cdf97   | as symmetric         | even ≥ 10 (m/2) | any ≥ 3 (⌈m/2⌉)  |
//!
//! A length of the wrong parity whose predecessor is native is reduced by *carrying*
//! the last sample: the first `m − 1` samples are transformed, the last one is appended
//! unchanged to the coarse part (so an interpolated end stays interpolated). A lane
//! still too short for the scheme falls back to Haar (with the same carry for odd
//! lengths); a lane of length 1 is its own coarse part. Every length ≥ 1 therefore
//! reconstructs exactly. [`max_levels`] counts the levels done with the scheme's own
//! filters: a multilevel decomposition stops there.
//!
//! **Wide schemes on short lanes.** A lane too short for the ends of `linear-wide`,
//! `chaikin-wide` or `cubic-wide` (neither native nor carried) takes the level of the
//! narrow scheme of the same refinement (`linear`, `chaikin`, `cubic`): its own ends,
//! its carry, or its Haar fallback ([`LevelKind::Narrow`], [`LevelKind::HaarFallback`]).
//! So a lane of points takes every level down to one sample with a wide scheme
//! ([`lane_levels`]); the lengths their own filters take build the same levels as
//! without the fallback, and the axes of an array's pyramid still stop at
//! [`max_levels`].

use super::regular::{self, LevelTriplets};
use super::sparse::{Csr, Triplets};
use super::{
    cdf97, chaikin, chaikin_wide, cubic, cubic_wide, haar, linear, linear_wide, Boundary, Sample,
    Scheme,
};

/// How a level was built for its length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelKind {
    /// The scheme's own filters.
    Native,
    /// The scheme's filters on `m − 1` samples, the last one carried into the coarse part.
    Carry,
    /// The lane was too short for the scheme: Haar (with carry for odd lengths).
    HaarFallback,
    /// The lane was too short for a wide scheme's ends: the narrow scheme's level
    /// ([`narrow_of`]), native or carried.
    Narrow,
    /// `m = 1`: nothing to reduce.
    Identity,
}

/// One level: `[A; B]` and `[P | Q]` for `fine` elements, `coarse` of which are coarse.
#[derive(Clone, Debug)]
pub struct TwoScale {
    pub fine: usize,
    pub coarse: usize,
    pub kind: LevelKind,
    pub analysis: Csr,
    pub synthesis: Csr,
}

/// The coarse length of a lane of `m` if `m` is native for the scheme, else `None`.
fn native_len(scheme: Scheme, boundary: Boundary, m: usize) -> Option<usize> {
    use Boundary::*;
    let even = m.is_multiple_of(2);
    match (scheme, boundary) {
        (Scheme::Haar, _) => (m >= 2 && even).then_some(m / 2),
        (Scheme::Chaikin, Interpolating) => {
            (m >= chaikin::MIN_INTERPOLATING && even).then_some(m / 2 + 1)
        }
        (Scheme::Chaikin, Periodic) => (m >= 4 && even).then_some(m / 2),
        (Scheme::Chaikin, Symmetric) => (m >= 3).then_some(m / 2 + 1),
        (Scheme::Cubic, Interpolating) => {
            (m >= cubic::MIN_INTERPOLATING && !even).then_some((m + 3) / 2)
        }
        (Scheme::Cubic, Periodic) => (m >= 8 && even).then_some(m / 2),
        (Scheme::Cubic, Symmetric) => (m >= 3).then_some(m.div_ceil(2)),
        (Scheme::Linear, Interpolating) => linear::OPEN.coarse_len(m),
        (Scheme::LinearWide, Interpolating) => linear_wide::OPEN.coarse_len(m),
        (Scheme::ChaikinWide, Interpolating) => chaikin_wide::OPEN.coarse_len(m),
        (Scheme::CubicWide, Interpolating) => cubic_wide::OPEN.coarse_len(m),
        (Scheme::Linear, Periodic) => (m >= 6 && even).then_some(m / 2),
        (Scheme::LinearWide, Periodic) => (m >= 10 && even).then_some(m / 2),
        (Scheme::ChaikinWide, Periodic) => (m >= 12 && even).then_some(m / 2),
        (Scheme::CubicWide, Periodic) => (m >= 20 && even).then_some(m / 2),
        (Scheme::Cdf97, Periodic) => (m >= 10 && even).then_some(m / 2),
        (Scheme::ChaikinWide, Symmetric) => (m >= 3).then_some(m / 2 + 1),
        (Scheme::Linear | Scheme::LinearWide | Scheme::CubicWide | Scheme::Cdf97, Symmetric)
        | (Scheme::Cdf97, Interpolating) => (m >= 3).then_some(m.div_ceil(2)),
    }
}

fn native(scheme: Scheme, boundary: Boundary, m: usize) -> Option<LevelTriplets> {
    use Boundary::*;
    native_len(scheme, boundary, m)?;
    Some(match (scheme, boundary) {
        (Scheme::Haar, _) => haar::level(m),
        (Scheme::Chaikin, Interpolating) => chaikin::interpolating(m),
        (Scheme::Chaikin, Periodic) => regular::periodic(&chaikin::REGULAR, m),
        (Scheme::Chaikin, Symmetric) => regular::symmetric(&chaikin::REGULAR, m, false),
        (Scheme::Cubic, Interpolating) => cubic::interpolating(m),
        (Scheme::Cubic, Periodic) => regular::periodic(&cubic::REGULAR, m),
        (Scheme::Cubic, Symmetric) => regular::symmetric(&cubic::REGULAR, m, true),
        (Scheme::Linear, Interpolating) => linear::OPEN.level(m),
        (Scheme::LinearWide, Interpolating) => linear_wide::OPEN.level(m),
        (Scheme::ChaikinWide, Interpolating) => chaikin_wide::OPEN.level(m),
        (Scheme::CubicWide, Interpolating) => cubic_wide::OPEN.level(m),
        (Scheme::Linear, Periodic) => regular::periodic(&linear::REGULAR, m),
        (Scheme::LinearWide, Periodic) => regular::periodic(&linear_wide::REGULAR, m),
        (Scheme::ChaikinWide, Periodic) => regular::periodic(&chaikin_wide::REGULAR, m),
        (Scheme::CubicWide, Periodic) => regular::periodic(&cubic_wide::REGULAR, m),
        (Scheme::Cdf97, Periodic) => regular::periodic(&cdf97::REGULAR, m),
        (Scheme::Linear, Symmetric) => regular::symmetric(&linear::REGULAR, m, true),
        (Scheme::LinearWide, Symmetric) => regular::symmetric(&linear_wide::REGULAR, m, true),
        (Scheme::ChaikinWide, Symmetric) => regular::symmetric(&chaikin_wide::REGULAR, m, false),
        (Scheme::CubicWide, Symmetric) => regular::symmetric(&cubic_wide::REGULAR, m, true),
        (Scheme::Cdf97, Symmetric | Interpolating) => regular::symmetric(&cdf97::REGULAR, m, true),
    })
}

/// The narrow scheme whose level a wide scheme takes on a lane too short for its own
/// ends: `linear` for `linear-wide`, `chaikin` for `chaikin-wide`, `cubic` for
/// `cubic-wide` (the same refinement, shorter end blocks); `None` for the others.
pub fn narrow_of(scheme: Scheme) -> Option<Scheme> {
    match scheme {
        Scheme::LinearWide => Some(Scheme::Linear),
        Scheme::ChaikinWide => Some(Scheme::Chaikin),
        Scheme::CubicWide => Some(Scheme::Cubic),
        _ => None,
    }
}

/// Whether the scheme's own filters reduce a lane of length `m` (natively or by carry).
pub fn reducible(scheme: Scheme, boundary: Boundary, m: usize) -> bool {
    m >= 2
        && (native_len(scheme, boundary, m).is_some()
            || native_len(scheme, boundary, m - 1).is_some())
}

/// How many levels the scheme's own filters can take a lane of length `m` down.
pub fn max_levels(scheme: Scheme, boundary: Boundary, m: usize) -> usize {
    levels_down(scheme, boundary, m, |m| reducible(scheme, boundary, m))
}

/// The levels from a lane of `m` while `reduces` says its length is reduced (and the
/// coarse length falls).
fn levels_down(
    scheme: Scheme,
    boundary: Boundary,
    m: usize,
    reduces: impl Fn(usize) -> bool,
) -> usize {
    let mut m = m;
    let mut levels = 0;
    while reduces(m) {
        let n = TwoScale::coarse_len(scheme, boundary, m);
        if n >= m {
            break;
        }
        m = n;
        levels += 1;
    }
    levels
}

/// How many levels a lane of points of length `m` takes: for a wide scheme, every level
/// down to one sample (its narrow scheme's levels where its own ends do not fit,
/// [`narrow_of`]); for the others, [`max_levels`]. The axes of an array's pyramid stop
/// at [`max_levels`] (the rule the file format's level lengths follow).
pub fn lane_levels(scheme: Scheme, boundary: Boundary, m: usize) -> usize {
    if narrow_of(scheme).is_none() {
        return max_levels(scheme, boundary, m);
    }
    levels_down(scheme, boundary, m, |m| m >= 2)
}

/// Carry the last sample of a lane of `m` past a level built for `m − 1`.
fn carry(t: LevelTriplets, m: usize) -> (usize, Triplets, Triplets) {
    let n1 = t.n;
    let mut an = t
        .analysis
        .remap(m, m, |r, c| (if r < n1 { r } else { r + 1 }, c));
    an.add(n1, m - 1, 1.0);
    let mut sy = t
        .synthesis
        .remap(m, m, |r, c| (r, if c < n1 { c } else { c + 1 }));
    sy.add(m - 1, n1, 1.0);
    (n1 + 1, an, sy)
}

impl TwoScale {
    /// The level for a lane of `m ≥ 1` elements (see the length rule above).
    pub fn new(scheme: Scheme, boundary: Boundary, m: usize) -> TwoScale {
        assert!(m >= 1, "a lane has at least one element");
        let (kind, n, an, sy) = if m == 1 {
            let mut an = Triplets::new(1, 1);
            an.add(0, 0, 1.0);
            let mut sy = Triplets::new(1, 1);
            sy.add(0, 0, 1.0);
            (LevelKind::Identity, 1, an, sy)
        } else if let Some(t) = native(scheme, boundary, m) {
            (LevelKind::Native, t.n, t.analysis, t.synthesis)
        } else if let Some(t) = native(scheme, boundary, m - 1) {
            let (n, an, sy) = carry(t, m);
            (LevelKind::Carry, n, an, sy)
        } else if let Some(narrow) = narrow_of(scheme) {
            let t = TwoScale::new(narrow, boundary, m);
            let kind = match t.kind {
                LevelKind::Native | LevelKind::Carry => LevelKind::Narrow,
                other => other,
            };
            return TwoScale { kind, ..t };
        } else if m.is_multiple_of(2) {
            let t = haar::level(m);
            (LevelKind::HaarFallback, t.n, t.analysis, t.synthesis)
        } else {
            let (n, an, sy) = carry(haar::level(m - 1), m);
            (LevelKind::HaarFallback, n, an, sy)
        };
        TwoScale {
            fine: m,
            coarse: n,
            kind,
            analysis: an.into_csr(),
            synthesis: sy.into_csr(),
        }
    }

    /// Coarse length after one level, without building the operators.
    pub fn coarse_len(scheme: Scheme, boundary: Boundary, m: usize) -> usize {
        if m <= 1 {
            m
        } else if let Some(n) = native_len(scheme, boundary, m) {
            n
        } else if let Some(n) = native_len(scheme, boundary, m - 1) {
            n + 1
        } else if let Some(narrow) = narrow_of(scheme) {
            TwoScale::coarse_len(narrow, boundary, m)
        } else {
            m.div_ceil(2)
        }
    }

    pub fn details(&self) -> usize {
        self.fine - self.coarse
    }

    /// `[C; D] = [A; B] F` on a lane of contiguous elements of `width` samples.
    pub fn decompose<T: Sample>(&self, fine: &[T], width: usize, packed: &mut [T]) {
        assert_eq!(fine.len(), self.fine * width);
        assert_eq!(packed.len(), self.fine * width);
        self.analysis.apply(fine, width, packed, width, width);
    }

    /// `F = P C + Q D` on a packed lane `[C; D]`.
    pub fn reconstruct<T: Sample>(&self, packed: &[T], width: usize, fine: &mut [T]) {
        assert_eq!(fine.len(), self.fine * width);
        assert_eq!(packed.len(), self.fine * width);
        self.synthesis.apply(packed, width, fine, width, width);
    }
}
