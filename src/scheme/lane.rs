//! Multilevel decomposition of one lane (a curve, a signal): REDUCE-RESOLUTION and
//! FIND-DETAILS repeated on the coarse part. The packed layout after `L` levels is
//! `[C_L | D_L | D_{L−1} | … | D_1]`, coarsest first.

use super::{lane_levels, Boundary, Sample, Scheme, TwoScale};
use crate::{Error, Result};

/// Sizes of a lane's pyramid: `lengths[0]` is the fine length, `lengths[l]` the coarse
/// length after `l` levels.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LanePyramid {
    pub scheme: Scheme,
    pub boundary: Boundary,
    pub lengths: Vec<usize>,
}

impl LanePyramid {
    /// Plan `levels` levels for a lane of `m` elements; at most [`lane_levels`].
    pub fn plan(scheme: Scheme, boundary: Boundary, m: usize, levels: usize) -> Result<Self> {
        if m == 0 {
            return Err(Error::parameter("lane length", 0, "at least 1"));
        }
        let max = lane_levels(scheme, boundary, m);
        if levels > max {
            return Err(Error::Parameter {
                name: "levels",
                value: levels.to_string(),
                expected: "at most the levels the lane length allows (see lane_levels)",
            });
        }
        let mut lengths = vec![m];
        for _ in 0..levels {
            let n = TwoScale::coarse_len(scheme, boundary, *lengths.last().unwrap());
            lengths.push(n);
        }
        Ok(LanePyramid {
            scheme,
            boundary,
            lengths,
        })
    }
    pub fn levels(&self) -> usize {
        self.lengths.len() - 1
    }
    /// The element range of detail band `D_l` (l = 1 finest … L coarsest) in the packed lane.
    pub fn detail_range(&self, l: usize) -> std::ops::Range<usize> {
        self.lengths[l]..self.lengths[l - 1]
    }
}

/// Decompose `data` (elements of `width` samples) over `levels` levels.
pub fn analyze_lane<T: Sample>(
    data: &[T],
    width: usize,
    scheme: Scheme,
    boundary: Boundary,
    levels: usize,
) -> Result<(Vec<T>, LanePyramid)> {
    if width == 0 || !data.len().is_multiple_of(width) {
        return Err(Error::parameter(
            "lane data length",
            data.len(),
            "a multiple of the element width",
        ));
    }
    let plan = LanePyramid::plan(scheme, boundary, data.len() / width, levels)?;
    let mut packed = data.to_vec();
    let mut scratch = vec![T::default(); data.len()];
    for l in 0..plan.levels() {
        let m = plan.lengths[l];
        let level = TwoScale::new(scheme, boundary, m);
        level.decompose(&packed[..m * width], width, &mut scratch[..m * width]);
        packed[..m * width].copy_from_slice(&scratch[..m * width]);
    }
    Ok((packed, plan))
}

/// Invert [`analyze_lane`].
pub fn synthesize_lane<T: Sample>(
    packed: &[T],
    width: usize,
    plan: &LanePyramid,
) -> Result<Vec<T>> {
    if width == 0 || packed.len() != plan.lengths[0] * width {
        return Err(Error::parameter(
            "packed lane length",
            packed.len(),
            "fine length × element width of the plan",
        ));
    }
    let mut data = packed.to_vec();
    let mut scratch = vec![T::default(); packed.len()];
    for l in (0..plan.levels()).rev() {
        let m = plan.lengths[l];
        let level = TwoScale::new(plan.scheme, plan.boundary, m);
        level.reconstruct(&data[..m * width], width, &mut scratch[..m * width]);
        data[..m * width].copy_from_slice(&scratch[..m * width]);
    }
    Ok(data)
}
