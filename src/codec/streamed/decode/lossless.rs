//! The streamed whole decode of a one-piece lossless file: its band rows (indices, the
//! transform's values) read a batch of stripes of code-blocks at a time
//! ([`super::BandSource`]) and pulled through the integer synthesis
//! ([`super::super::lift`]), the channels in parallel, the rows taken to samples a slab
//! at a time: the samples of the whole-array decode, exactly.

use super::super::lift::LiftPlan;
use super::{BandSource, Failed};
use crate::codec::container::Parsed;
use crate::codec::lossless;
use crate::format::header::Colour;
use crate::format::{Header, Mode};
use crate::io::{SampleType, Samples};
use crate::scheme::Scheme;
use crate::Result;
use rayon::prelude::*;

/// Whether the streamed synthesis decodes the lossless file of header `h`: the 5/3
/// lifting, 8- or 16-bit samples (what the streamed lossless encoder writes).
pub(in crate::codec::streamed) fn decodes(h: &Header) -> bool {
    h.mode == Mode::Lossless && h.scheme == Scheme::Linear && lossless::narrow(h.sample_type)
}

/// Start the synthesis of the read file `p` on a thread of its own; its slabs come
/// through the returned receiver (an error when the stream does not lay out its bands).
pub(in crate::codec::streamed) fn start(
    p: Parsed,
) -> Result<std::sync::mpsc::Receiver<Result<Samples>>> {
    // the plan is checked here, before the thread starts
    LiftPlan::new(&p.plan.pyr, &p.plan.bands)?;
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    std::thread::spawn(move || {
        if let Err(e) = synthesize(&p, &mut |s| tx.send(Ok(s)).is_ok()) {
            let _ = tx.send(Err(e));
        }
    });
    Ok(rx)
}

/// Pull every row of the lossless file `p` through the integer synthesis and hand its
/// samples to `send` a slab at a time (until it returns false).
fn synthesize(p: &Parsed, send: &mut dyn FnMut(Samples) -> bool) -> Result<()> {
    let h = &p.header;
    let lp = LiftPlan::new(&p.plan.pyr, &p.plan.bands)?;
    let nc = h.channels;
    let errs: Vec<Failed> = (0..nc).map(|_| Failed::default()).collect();
    let mut sources = (0..nc)
        .map(|c| BandSource::new(p, c, errs[c].clone()))
        .collect::<Result<Vec<_>>>()?;
    let mut syn: Vec<_> = sources
        .iter_mut()
        .map(|s| lp.synthesis(move |j, r, out: &mut [i64]| s.fill_indices(j, r, out)))
        .collect();
    let (d0, row_len) = (h.dims[0], lp.row_len());
    // about 2^16 positions a slab
    let rows = ((1usize << 16) / row_len.max(1)).clamp(1, d0.max(1));
    for r0 in (0..d0).step_by(rows) {
        let n = (r0 + rows).min(d0) - r0;
        let planes = syn
            .par_iter_mut()
            .zip(&errs)
            .map(|(s, err)| {
                let mut v = Vec::with_capacity(n * row_len);
                for _ in 0..n {
                    v.extend_from_slice(&s.pull()?);
                    if let Some(e) = err.take() {
                        return Err(e);
                    }
                }
                Ok(v)
            })
            .collect::<Result<Vec<Vec<i64>>>>()?;
        if !send(samples(&planes, h.colour == Colour::YCoCgR, h.sample_type)) {
            return Ok(());
        }
    }
    Ok(())
}

/// Interleaved samples of the 8- or 16-bit type `ty` from the channel planes (the first
/// three taken back from YCoCg-R when `ycocg`), clamped to the type's range, as the
/// whole-array lossless decode makes them.
fn samples(planes: &[Vec<i64>], ycocg: bool, ty: SampleType) -> Samples {
    let npos = planes.first().map_or(0, |p| p.len());
    let mut out = Samples::zeros(ty, npos * planes.len());
    let views: Vec<&[i64]> = planes.iter().map(|p| p.as_slice()).collect();
    lossless::interleave(&views, 0..npos, ycocg, &mut out);
    out
}
