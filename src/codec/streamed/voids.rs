//! Voids (NaN samples, samples equal to `meta.nodata`) in the one-transform stream.
//!
//! **Encode.** [`FilledSlabs`] stands between the raster's slabs and the stream. The
//! raster is read in blocks of rows one default tile tall
//! ([`crate::codec::tiles::default_tile`]); the first time a block is read (the first
//! pass reads them all, in order) its void flags are coded into the mask
//! ([`MaskCoder`], the whole-array encoder's coded mask, a few rows at a time), and
//! once the last block is read the mask is listed in the metadata (`VOID_RUNS`, so the
//! header says the file has voids). Every read fills a block's voids window by window,
//! the windows the default tiles (the fill of each is the pull-push of
//! [`crate::io::nodata::Voids::fill`] over that window alone, the values the tiled
//! encoder fills its tiles with); a window void throughout takes the mean of the
//! block's finite valid samples, else that of the blocks before it, else 0. The fill
//! only changes the bits: the decoder marks the voids again.
//!
//! **Decode.** [`marking`] puts the flags of the coded mask, decoded a slab at a time
//! ([`MaskDecoder`]) on a thread of its own, over the slabs of the streamed decode: a
//! void sample takes the nodata value, else NaN, as the whole-array decode marks it at
//! the full resolution.

use crate::codec::tiles::default_tile;
use crate::codec::voids::{MaskCoder, MaskDecoder};
use crate::format::meta::VOID_RUNS;
use crate::io::nodata::{is_void, Value, Voids};
use crate::io::slab::{Shape, SlabSource};
use crate::io::Samples;
use crate::{Error, Result};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::mpsc::{sync_channel, Receiver};

/// Whether a raster of `shape` can hold voids: float samples (NaN) or a nodata value.
pub(super) fn may_hold(shape: &Shape) -> bool {
    shape.sample_type.is_float() || shape.meta.nodata.is_some()
}

/// What the first read of a block found.
#[derive(Clone, Copy, Debug)]
struct Block {
    voids: bool,
    /// the value of a window void throughout
    constant: f64,
}

/// The raster of `src` with its voids filled (module doc).
pub(super) struct FilledSlabs<'s, S: SlabSource + ?Sized> {
    src: &'s mut S,
    shape: Shape,
    /// the fill windows' extents; axis 0: the rows of a block
    window: Vec<usize>,
    /// the blocks read so far (all of them once the mask is listed)
    blocks: Vec<Block>,
    coder: Option<MaskCoder>,
    /// the last block read in part, filled
    cache: Option<(usize, Samples)>,
    /// sum and count of the finite valid samples of the blocks read
    sum: f64,
    count: usize,
}

impl<'s, S: SlabSource + ?Sized> FilledSlabs<'s, S> {
    pub(super) fn new(src: &'s mut S) -> FilledSlabs<'s, S> {
        let shape = src.shape().clone();
        let window = default_tile(&shape.dims, shape.channels);
        let mut mshape = shape.dims.clone();
        mshape.push(shape.channels);
        FilledSlabs {
            src,
            window,
            blocks: Vec::new(),
            coder: Some(MaskCoder::new(&mshape)),
            cache: None,
            sum: 0.0,
            count: 0,
            shape,
        }
    }

    fn nblocks(&self) -> usize {
        self.shape.dims[0].div_ceil(self.window[0])
    }

    fn block_rows(&self, b: usize) -> Range<usize> {
        let t = self.window[0];
        b * t..((b + 1) * t).min(self.shape.dims[0])
    }

    /// The void flags of `s` (samples of whole rows).
    fn flags(&self, s: &Samples) -> Vec<bool> {
        let nodata = self.shape.meta.nodata;
        crate::io::with_samples!(s, v => v.iter().map(|&x| is_void(Value::to_f64(x), nodata)).collect())
    }

    /// Block `b` read (every block before it read first, so that the mask is coded in
    /// raster order) and filled.
    fn load(&mut self, b: usize, parallel: bool) -> Result<Samples> {
        while self.blocks.len() < b {
            let k = self.blocks.len();
            self.load(k, parallel)?;
        }
        let rows = self.block_rows(b);
        let mut s = if parallel {
            self.src.read_rows_parallel(rows.clone())?
        } else {
            self.src.read_rows(rows.clone())?
        };
        if s.len() != rows.len() * self.shape.row_samples() {
            return Err(Error::format("a slab", "the samples of its rows"));
        }
        let known = self.blocks.get(b).copied();
        if known.is_some_and(|k| !k.voids) {
            return Ok(s);
        }
        let flags = self.flags(&s);
        let block = match known {
            Some(k) => k,
            None => self.found(&s, &flags),
        };
        if block.voids {
            self.fill(&mut s, &flags, rows.len(), block.constant);
        }
        Ok(s)
    }

    /// Record the first read of the next block (samples `s`, void flags `flags`): its
    /// flags coded, and the mask listed after the last block.
    fn found(&mut self, s: &Samples, flags: &[bool]) -> Block {
        let coder = self.coder.as_mut().expect("a block not yet found");
        let before = coder.voids();
        coder.push(flags);
        let voids = coder.voids() > before;
        let (mut sum, mut count) = (0.0, 0usize);
        for (i, _) in flags.iter().enumerate().filter(|(_, &f)| !f) {
            let x = s.get_f64(i);
            if x.is_finite() {
                sum += x;
                count += 1;
            }
        }
        let constant = if count > 0 {
            sum / count as f64
        } else if self.count > 0 {
            self.sum / self.count as f64
        } else {
            0.0
        };
        (self.sum, self.count) = (self.sum + sum, self.count + count);
        let block = Block { voids, constant };
        self.blocks.push(block);
        if self.blocks.len() == self.nblocks() {
            if let Some(text) = self.coder.take().and_then(MaskCoder::finish) {
                self.shape.meta.extra.insert(VOID_RUNS.into(), text);
            }
        }
        block
    }

    /// Fill the voids of a block of `rows` rows (samples `s`, flags `flags`) window by
    /// window, in parallel.
    fn fill(&self, s: &mut Samples, flags: &[bool], rows: usize, constant: f64) {
        let mut dims = self.shape.dims.clone();
        dims[0] = rows;
        let c = self.shape.channels;
        let counts: Vec<usize> = dims
            .iter()
            .zip(&self.window)
            .map(|(&d, &t)| d.div_ceil(t))
            .collect();
        let n: usize = counts.iter().product();
        let (s_ref, window) = (&*s, &self.window);
        let filled: Vec<Vec<(usize, f64)>> = (0..n)
            .into_par_iter()
            .map(|w| {
                let bx = window_box(w, &counts, window, &dims);
                let idx = box_indices(&bx, &dims, c);
                let mask: Vec<bool> = idx.iter().map(|&i| flags[i]).collect();
                let voids = mask.iter().filter(|&&f| f).count();
                if voids == 0 {
                    return Vec::new();
                }
                if voids == mask.len() {
                    return idx.iter().map(|&i| (i, constant)).collect();
                }
                let mut v: Vec<f64> = idx.iter().map(|&i| s_ref.get_f64(i)).collect();
                let mut shape: Vec<usize> = bx.iter().map(|r| r.len()).collect();
                shape.push(c);
                let vs = Voids {
                    mask,
                    marker: f64::NAN,
                    range: (f64::NEG_INFINITY, f64::INFINITY),
                };
                vs.fill(&mut v, &shape, dims.len())
                    .expect("a window with a valid sample");
                idx.iter()
                    .zip(&vs.mask)
                    .zip(&v)
                    .filter(|((_, &m), _)| m)
                    .map(|((&i, _), &x)| (i, x))
                    .collect()
            })
            .collect();
        crate::io::with_samples!(s, v => {
            for (i, x) in filled.into_iter().flatten() {
                v[i] = Value::from_f64(x);
            }
        });
    }

    /// Rows `rows` of the filled raster.
    fn read(&mut self, rows: Range<usize>, parallel: bool) -> Result<Samples> {
        let d0 = self.shape.dims[0];
        if rows.start >= rows.end || rows.end > d0 {
            return Err(Error::parameter(
                "rows",
                format!("{}..{} of {d0}", rows.start, rows.end),
                "a non-empty range within the slowest axis",
            ));
        }
        let t = self.window[0];
        let (b0, b1) = (rows.start / t, (rows.end - 1) / t);
        let clean = (b0..=b1).all(|b| self.blocks.get(b).is_some_and(|k| !k.voids));
        if self.coder.is_none() && clean {
            return if parallel {
                self.src.read_rows_parallel(rows)
            } else {
                self.src.read_rows(rows)
            };
        }
        if b0 == b1 && rows == self.block_rows(b0) && self.cache.as_ref().is_none_or(|c| c.0 != b0)
        {
            // a whole block (the first pass): not kept
            return self.load(b0, parallel);
        }
        let per = self.shape.row_samples();
        let mut out = Samples::zeros(self.shape.sample_type, rows.len() * per);
        for b in b0..=b1 {
            if self.cache.as_ref().is_none_or(|c| c.0 != b) {
                self.cache = None;
                let s = self.load(b, parallel)?;
                self.cache = Some((b, s));
            }
            let br = self.block_rows(b);
            let (a, e) = (rows.start.max(br.start), rows.end.min(br.end));
            let cached = &self.cache.as_ref().expect("the block just read").1;
            out.copy_from(
                (a - rows.start) * per,
                cached,
                (a - br.start) * per,
                (e - a) * per,
            )?;
        }
        Ok(out)
    }
}

impl<S: SlabSource + ?Sized> SlabSource for FilledSlabs<'_, S> {
    /// The raster's shape; its metadata lists the voids once every block has been read.
    fn shape(&self) -> &Shape {
        &self.shape
    }

    fn read_rows(&mut self, rows: Range<usize>) -> Result<Samples> {
        self.read(rows, false)
    }

    fn read_rows_parallel(&mut self, rows: Range<usize>) -> Result<Samples> {
        self.read(rows, true)
    }
}

/// The box of window `w` (row-major over `counts` windows of extents `window`) in an
/// array of `dims`.
fn window_box(w: usize, counts: &[usize], window: &[usize], dims: &[usize]) -> Vec<Range<usize>> {
    let mut bx = vec![0..0; dims.len()];
    let mut rest = w;
    for a in (0..dims.len()).rev() {
        let k = rest % counts[a];
        rest /= counts[a];
        bx[a] = k * window[a]..((k + 1) * window[a]).min(dims[a]);
    }
    bx
}

/// The indices of the samples of box `bx` (each position's `c` channels) in a row-major
/// array of `dims` × `c`, in the box's raster order.
fn box_indices(bx: &[Range<usize>], dims: &[usize], c: usize) -> Vec<usize> {
    let nd = dims.len();
    let n: usize = bx.iter().map(|r| r.len()).product::<usize>() * c;
    let mut out = Vec::with_capacity(n);
    let run = bx[nd - 1].len() * c;
    let mut at: Vec<usize> = bx[..nd - 1].iter().map(|r| r.start).collect();
    loop {
        let mut start = 0;
        for a in 0..nd - 1 {
            start = start * dims[a] + at[a];
        }
        start = (start * dims[nd - 1] + bx[nd - 1].start) * c;
        out.extend(start..start + run);
        // the next position over the box's leading axes
        let mut a = nd - 1;
        loop {
            if a == 0 {
                return out;
            }
            a -= 1;
            at[a] += 1;
            if at[a] < bx[a].end {
                break;
            }
            at[a] = bx[a].start;
        }
    }
}

/// A slab of a streamed decode and its void flags.
pub(super) type Marked = Result<(Samples, Vec<bool>)>;

/// The slabs of `rx` (a streamed decode of a raster of `dims` × `channels`) with the
/// voids of the coded mask `coded` marked by `marker` (module doc), and each slab's
/// flags; on a thread of its own.
pub(super) fn marking(
    rx: Receiver<Result<Samples>>,
    dims: &[usize],
    channels: usize,
    coded: Vec<u8>,
    marker: f64,
) -> Receiver<Marked> {
    let mut shape = dims.to_vec();
    shape.push(channels);
    let (tx, out) = sync_channel(1);
    std::thread::spawn(move || {
        let mut mask = MaskDecoder::new(&coded, &shape);
        for slab in rx {
            let sent = match slab {
                Ok(mut s) => {
                    let flags = mask.next_flags(s.len());
                    crate::io::with_samples!(&mut s, v => {
                        for (x, _) in v.iter_mut().zip(&flags).filter(|(_, &f)| f) {
                            *x = Value::from_f64(marker);
                        }
                    });
                    tx.send(Ok((s, flags)))
                }
                Err(e) => tx.send(Err(e)),
            };
            if sent.is_err() {
                return;
            }
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_indices_walk_the_box_in_raster_order() {
        let dims = [4, 5, 3];
        let bx = [1..3, 2..4, 1..3];
        let mut want = Vec::new();
        for z in 1..3 {
            for y in 2..4 {
                for x in 1..3 {
                    for ch in 0..2 {
                        want.push(((z * 5 + y) * 3 + x) * 2 + ch);
                    }
                }
            }
        }
        assert_eq!(box_indices(&bx, &dims, 2), want);
        assert_eq!(box_indices(&[0..2], &[5], 1), vec![0, 1]);
        assert_eq!(window_box(4, &[2, 3], &[2, 2], &[3, 5]), vec![2..3, 2..4]);
    }
}
