//! Which code-blocks a region needs: the window's exact support in every band (the
//! coefficients its synthesis reads, level by level), joined with the parent boxes of
//! the blocks a child band decodes, block-aligned. Read by the sparse reader (which
//! chunks to fetch), the region decode (which blocks to decode) and the whole-band
//! decode of a window.

use super::container::Parsed;
use super::int_window::IntWindow;
use crate::entropy::codeblocks::parent_box;
use crate::format::Mode;
use crate::scheme::Boundary;
use std::ops::Range;

/// Band samples added on each side of a region's span in a band when choosing its
/// code-blocks where the window's exact support is not known (a pyramid
/// [`crate::tensor::WindowPlan`] does not plan): more than the synthesis support of
/// every scheme summed over the coarser levels (the longest synthesis filter reaches 4
/// samples a level, and `4·(1 + ½ + ¼ + …) < 8`).
const SUPPORT: usize = 16;

/// Whether a box is empty (an empty range on some axis).
fn is_empty_box(b: &[Range<usize>]) -> bool {
    b.iter().any(|r| r.is_empty())
}

/// The smallest box holding boxes `a` and `b` (either possibly empty).
fn hull(a: &[Range<usize>], b: &[Range<usize>]) -> Vec<Range<usize>> {
    if is_empty_box(a) {
        return b.to_vec();
    }
    if is_empty_box(b) {
        return a.to_vec();
    }
    a.iter()
        .zip(b)
        .map(|(a, b)| a.start.min(b.start)..a.end.max(b.end))
        .collect()
}

/// The box a band's synthesis reads at a level, from the box it must give.
type Reads<'a> = &'a dyn Fn(usize, &[Range<usize>]) -> Vec<Range<usize>>;

/// The exact support of the window (`p.out_box`, the box of level `k` that `p.window` maps to) in each
/// band (band coordinates; `None` where the window synthesis does not plan the
/// pyramid): the coefficients the window's synthesis reads
/// ([`crate::tensor::WindowPlan::reads`]: on each axis the span of the columns its
/// operator rows touch inside the band, level by level from the window down to the
/// coarse block, whose box is [`crate::tensor::WindowPlan::coarse_box`]; of a lossless
/// file the integer lifting's, [`IntWindow::reads`]); the bands of the levels a decode
/// at `k` skips need nothing.
fn exact_support(p: &Parsed, k: usize) -> Option<Vec<Vec<Range<usize>>>> {
    let (h, plan) = (&p.header, &p.plan);
    let k = k.min(plan.pyr.depth());
    let out = p.out_box.as_deref()?;
    let nd = h.dims.len();
    let support = |coarse: &[Range<usize>], reads: Reads<'_>| {
        plan.bands
            .iter()
            .map(|b| match b.level {
                0 => coarse.to_vec(),
                l if l <= k => vec![0..0; nd],
                l => reads(l - k - 1, &b.ranges),
            })
            .collect()
    };
    if h.mode == Mode::Lossless {
        let iw = IntWindow::new(&plan.sub(k), out)?;
        return Some(support(&iw.coarse_box, &|l, r| iw.reads(l, r)));
    }
    let wp = crate::tensor::WindowPlan::new(&plan.sub(k), out)?;
    Some(support(&wp.coarse_box, &|l, r| wp.reads(l, r)))
}

/// The box of each band (in the band's coordinates) whose code-blocks a decode of
/// `p.window` at level `k` needs (`None`: every block): the window's exact support in
/// the band ([`exact_support`]; where that is not planned, its span widened by
/// [`SUPPORT`]), joined with the parent boxes of the blocks its child band needs (a
/// band's only child is the next one in its chain, [`Plan::chains`]). Every block is
/// needed without a window, in files before format 3, and with periodic ends (whose
/// synthesis wraps around) where the support is not planned.
pub(super) fn band_windows(p: &Parsed, k: usize) -> Vec<Option<Vec<Range<usize>>>> {
    let (h, plan) = (&p.header, &p.plan);
    let nb = plan.bands.len();
    let win = match &p.window {
        Some(w)
            if h.version.has_blocks()
                && w.len() == h.dims.len()
                && plan.block(0).len() == w.len() =>
        {
            w
        }
        _ => return vec![None; nb],
    };
    let exact = exact_support(p, k);
    if exact.is_none() && h.boundary == Boundary::Periodic {
        return vec![None; nb];
    }
    let mut out = vec![None; nb];
    for chain in plan.chains() {
        // the block-aligned box the band after in the chain decodes
        let mut child: Option<Vec<Range<usize>>> = None;
        for &j in chain.iter().rev() {
            let bd = &plan.dims[j];
            let mut w: Vec<Range<usize>> = match &exact {
                Some(e) => e[j].clone(),
                None => bd
                    .iter()
                    .zip(&h.dims)
                    .zip(win)
                    .map(|((&b, &d), r)| {
                        let (b, d) = (b as u128, d.max(1) as u128);
                        let lo = (r.start as u128 * b / d) as usize;
                        let hi = (r.end as u128 * b).div_ceil(d) as usize;
                        lo.saturating_sub(SUPPORT)..hi.saturating_add(SUPPORT).min(b as usize)
                    })
                    .collect(),
            };
            if let Some(cw) = &child {
                if !is_empty_box(cw) {
                    w = hull(&w, &parent_box(cw, bd));
                }
            }
            child = Some(
                w.iter()
                    .zip(plan.block(j))
                    .zip(bd)
                    .map(|((r, &b), &e)| {
                        if r.is_empty() {
                            return 0..0;
                        }
                        (r.start / b * b)..r.end.div_ceil(b).saturating_mul(b).min(e)
                    })
                    .collect(),
            );
            out[j] = Some(w);
        }
    }
    out
}
