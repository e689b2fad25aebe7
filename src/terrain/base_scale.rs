//! Trusting the base only down to a scale (`--base-scale S`): the base is kept at `1/S` of
//! the output's resolution and every finer level comes from the example.
//!
//! With `L` levels the output has `M = n·2^L` samples per axis, so the base already sits
//! at `1/2^L` of it. For `S = 2^K ≥ 2^L` the base is first reduced by its
//! `r × r` block means, `r = S/2^L` (`n/r` cells), and the synthesis of
//! [`super::synthesize`] runs `K` levels from it: the coarse-to-fine patch matching and
//! detail transfer (notes §9.7.4) start `K − L` levels above the base's own resolution,
//! so the example supplies the landforms between the scale `S` and the finest cell, at
//! the example's physical scale (the output's cell is unchanged). The back-projection
//! then holds the result's `S × S` block means to the reduced base.
//!
//! `S = 1` (the default) keeps the base at its own resolution (the same bytes as
//! before); `S = 2^L` is the same synthesis.

use super::grid::block_means;
use super::{Grid, SynthOptions};
use crate::{Error, Result};

/// The largest base scale, `2^8` (8 levels of synthesis at most).
pub const MAX_BASE_SCALE: usize = 256;

/// The base at the trusted scale and the options that synthesize from it: the base
/// itself and `o` with `base_scale` 1 when `o.base_scale` is 1 or `2^L`; else the base's `r × r` block means
/// (`r = S/2^L`) and `K = log2 S` levels. Errors: `S` not a power of two in
/// `[2^L, 256]`, a base side not a multiple of `r`, or an output size other than
/// base × 2^L.
pub fn trusted_base<'a>(
    base: &'a Grid,
    o: &SynthOptions,
) -> Result<(std::borrow::Cow<'a, Grid>, SynthOptions)> {
    let s = o.base_scale;
    let own = 1usize.checked_shl(o.levels as u32).unwrap_or(usize::MAX);
    if s == 1 || s == own {
        let same = SynthOptions {
            base_scale: 1,
            ..o.clone()
        };
        return Ok((std::borrow::Cow::Borrowed(base), same));
    }
    if !s.is_power_of_two() || s < own || s > MAX_BASE_SCALE {
        return Err(Error::parameter(
            "base scale",
            s,
            "1, or a power of two from 2^levels (the base's own scale) to 256",
        ));
    }
    let r = s / own;
    if !base.h().is_multiple_of(r) || !base.w().is_multiple_of(r) {
        return Err(Error::parameter(
            "base scale",
            format!(
                "{s} for a {}x{} base with {} levels",
                base.w(),
                base.h(),
                o.levels
            ),
            "base sides that are multiples of base scale / 2^levels",
        ));
    }
    if let Some(size) = o.size {
        if size != (base.h() * own, base.w() * own) {
            return Err(Error::parameter(
                "base scale",
                format!("{s} with an output size of {}x{}", size.1, size.0),
                "the default output size (base × 2^levels) when the base scale is above 1",
            ));
        }
    }
    let reduced = block_means(base, base.h() / r, base.w() / r, (r, r));
    let k = s.trailing_zeros() as usize;
    let opts = SynthOptions {
        levels: k,
        size: None,
        ..o.clone()
    };
    Ok((std::borrow::Cow::Owned(reduced), opts))
}
