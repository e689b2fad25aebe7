//! The finest level's gain (`mra terrain synth --finest-gain`): the result's finest level
//! is `F = P C₁ + g₁ Q D₁`, with `g₁` chosen so that the spectral slope of `F` over its
//! finest octave is the example's ([`super::spectrum`]). `P C₁` and `Q D₁` are
//! reconstructed from a sub-block of the Mallat block that covers the measured square,
//! so the fit costs a small fraction of the level.

use rayon::prelude::*;

use super::spectrum::{self, Complex, Rings};
use super::Grid;
use crate::scheme::{max_levels, Boundary, Scheme, TwoScale};
use crate::Result;
/// The example's spectral slope over the finest octave ([`spectrum::spectral_slope`] of
/// its channel means).
pub(super) fn example_slope(example: &Grid) -> f64 {
    let means: Vec<f64>;
    let h: &[f64] = if example.c() == 1 {
        example.data()
    } else {
        means = (0..example.h() * example.w())
            .map(|i| example.mean_at(i / example.w(), i % example.w()))
            .collect();
        &means
    };
    spectrum::spectral_slope(h, example.h(), example.w())
}

/// Fine samples past the square that a sub-block of the finest level keeps, so that the
/// square is clear of the sub-block's end filters.
const SUB_MARGIN: usize = 16;

/// The fine and coarse lengths `(m_s, n_s)` along one axis of a block, starting at index 0
/// of its coarse and detail parts, whose reconstruction gives the first `s` fine samples
/// of the whole axis (`m` fine, `n` coarse): `s + SUB_MARGIN` samples (or one more, for
/// the length rule), or the whole axis when that is not shorter.
pub(super) fn sub_axis(
    scheme: Scheme,
    boundary: Boundary,
    m: usize,
    n: usize,
    s: usize,
) -> (usize, usize) {
    for m_s in [s + SUB_MARGIN, s + SUB_MARGIN + 1] {
        if m_s >= m {
            break;
        }
        let n_s = TwoScale::coarse_len(scheme, boundary, m_s);
        // the same length relation as the whole axis (so the same start filters), the
        // coarse part inside `n` and the details inside `m − n`
        if max_levels(scheme, boundary, m_s) >= 1
            && 2 * n_s + m == 2 * n + m_s
            && n_s <= n
            && m_s - n_s <= m - n
        {
            return (m_s, n_s);
        }
    }
    (m, n)
}

/// The channel-mean part of the top-left `(m_y, m_x)` sub-block of a Mallat block `packed`
/// (coarse part `n_y × n_x`) with coarse part `(c_y, c_x)`: its coarse quadrant when
/// `coarse`, else its three detail quadrants, the rest zero.
pub(super) fn sub_block(
    packed: &Grid,
    (n_y, n_x): (usize, usize),
    (m_y, c_y): (usize, usize),
    (m_x, c_x): (usize, usize),
    coarse: bool,
) -> Grid {
    let mut g = Grid::zeros(m_y, m_x, 1);
    for y in 0..m_y {
        let (hy, py) = if y < c_y {
            (false, y)
        } else {
            (true, n_y + y - c_y)
        };
        for x in 0..m_x {
            let (hx, px) = if x < c_x {
                (false, x)
            } else {
                (true, n_x + x - c_x)
            };
            if (!hy && !hx) == coarse {
                g.data_mut()[y * m_x + x] = packed.mean_at(py, px);
            }
        }
    }
    g
}

/// The finest details' gain `g₁` for which the spectral slope of `F = P C₁ + g₁ Q D₁`
/// over its finest octave is `target` ([`Rings::fit_gain`]), taken on the top-left square
/// of side `min(m_y, m_x, 512)` (the definition of [`spectrum::spectral_slope`]). `P C₁`
/// and `Q D₁` are reconstructed separately from a sub-block of the Mallat block that
/// covers the square ([`sub_axis`]) by `synthesize` (one level of `scheme` with
/// `boundary`): the square's samples are the whole result's.
pub(super) fn fit_finest_gain(
    packed: &Grid,
    (n_y, n_x): (usize, usize),
    target: f64,
    (scheme, boundary): (Scheme, Boundary),
    synthesize: impl Fn(Grid) -> Result<Grid>,
) -> Result<f64> {
    if !target.is_finite() {
        return Ok(1.0);
    }
    let s = packed.h().min(packed.w()).min(spectrum::MAX_SIDE);
    let ay = sub_axis(scheme, boundary, packed.h(), n_y, s);
    let ax = sub_axis(scheme, boundary, packed.w(), n_x, s);
    // `P C₁` into the real parts and `Q D₁` into the imaginary parts, one at a time
    let mut z = vec![Complex::default(); s * s];
    for coarse in [true, false] {
        let f = synthesize(sub_block(packed, (n_y, n_x), ay, ax, coarse))?;
        // the square's mean is taken out in f64 before the f32 store
        let at = |i: usize| f.data()[(i / s) * f.w() + i % s];
        let mean = (0..s * s).map(at).sum::<f64>() / (s * s) as f64;
        for (i, v) in z.iter_mut().enumerate() {
            let a = (at(i) - mean) as f32;
            if coarse {
                v.re = a;
            } else {
                v.im = a;
            }
        }
    }
    Ok(Rings::packed(z, s).fit_gain(target))
}

/// Multiply the three detail quadrants of a Mallat block (coarse part `n_y × n_x`) by `g`.
pub(super) fn scale_details(packed: &mut Grid, (n_y, n_x): (usize, usize), g: f64) {
    if g == 1.0 {
        return;
    }
    let (w, c) = (packed.w(), packed.c());
    packed
        .data_mut()
        .par_chunks_mut(w * c)
        .enumerate()
        .for_each(|(y, row)| {
            let from = if y < n_y { n_x * c } else { 0 };
            row[from..].iter_mut().for_each(|v| *v *= g);
        });
}
