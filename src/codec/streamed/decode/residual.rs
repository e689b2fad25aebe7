//! The residual layer of a `--max-error` file (formats/MRA.md §11) added to the
//! streamed decode's base slab by slab: each channel's `RESI` stream decoded a row at a
//! time as the slabs come ([`RowDecoder`]), every sample set to `x̂ + q·s` taken to the
//! sample type, then the exceptions that fall in the slab written: the samples of the
//! whole-array decode (`decode::add_residuals`), never the whole layer at once.

use crate::codec::container::Parsed;
use crate::codec::decode::{add_row, set_sample};
use crate::entropy::band::RowDecoder;
use crate::io::Samples;
use crate::{Error, Result};
use rayon::prelude::*;

/// The residual layers of a file, read as its slabs are handed over.
pub(super) struct Residuals<'a> {
    channels: usize,
    /// Per channel: its rows' decoder and step (none for a file without `RESI`, a base).
    layers: Vec<Option<(RowDecoder<'a>, f64)>>,
    /// Every exception, `(sample index with channels interleaved, value)`, in order.
    exceptions: Vec<(usize, f64)>,
    /// The first exception not yet written.
    next: usize,
    /// Positions handed over so far.
    at: usize,
}

impl<'a> Residuals<'a> {
    /// The layers of the read file `p`; an error for a complete `--max-error` file
    /// whose `RESI` chunks were not read (a reader that skipped them would hand over the
    /// base alone). A file read as truncated (a base alone, before its layer is coded)
    /// has none.
    pub(super) fn new(p: &'a Parsed) -> Result<Residuals<'a>> {
        let h = &p.header;
        let c = h.channels.max(1);
        if h.mode == crate::format::Mode::MaxError
            && p.complete
            && (0..c).any(|ch| p.resi.get(ch).is_none_or(|r| r.is_none()))
        {
            return Err(Error::format(
                "a --max-error file read without its RESI chunks",
                "every channel's residual layer read for the streamed decode",
            ));
        }
        let coding = crate::codec::plan::coding_of(h);
        let layers = (0..c)
            .map(|ch| {
                let r = p.resi.get(ch)?.as_ref()?;
                Some((RowDecoder::new(&r.data, &h.dims, coding), r.step))
            })
            .collect();
        let mut exceptions: Vec<(usize, f64)> = p
            .resi
            .iter()
            .enumerate()
            .filter_map(|(ch, r)| r.as_ref().map(|r| (ch, r)))
            .flat_map(|(ch, r)| {
                r.exceptions
                    .iter()
                    .map(move |&(i, v)| (i as usize * c + ch, v))
            })
            .collect();
        exceptions.sort_by_key(|&(i, _)| i);
        Ok(Residuals {
            channels: c,
            layers,
            exceptions,
            next: 0,
            at: 0,
        })
    }

    /// Add the residual of the next slab `s` of the output (whole rows of the slowest
    /// axis, channels interleaved): the channels' rows decoded in parallel.
    pub(super) fn add(&mut self, s: &mut Samples) -> Result<()> {
        if self.layers.iter().all(Option::is_none) && self.exceptions.is_empty() {
            return Ok(()); // a lossy file, or a base alone
        }
        let c = self.channels;
        let npos = s.len() / c;
        let rows: Vec<Option<(Vec<i64>, f64)>> = self
            .layers
            .par_iter_mut()
            .enumerate()
            .map(|(ch, layer)| {
                let Some((d, step)) = layer else {
                    return Ok(None);
                };
                let failed = |e: Error| {
                    Error::format(format!("RESI of channel {ch}: {e}"), "a valid residual")
                };
                let cols = d.cols().max(1);
                let mut q = Vec::with_capacity(npos);
                for _ in 0..npos / cols {
                    q.extend_from_slice(d.next_row().map_err(failed)?);
                }
                Ok(Some((q, *step)))
            })
            .collect::<Result<_>>()?;
        for (ch, layer) in rows.into_iter().enumerate() {
            if let Some((q, step)) = layer {
                add_row(s, c, ch, 0, &q, step);
            }
        }
        let (lo, hi) = (self.at * c, (self.at + npos) * c);
        while let Some(&(i, x)) = self.exceptions.get(self.next) {
            if i >= hi {
                break;
            }
            if i >= lo {
                set_sample(s, i - lo, x);
            }
            self.next += 1;
        }
        self.at += npos;
        Ok(())
    }
}
